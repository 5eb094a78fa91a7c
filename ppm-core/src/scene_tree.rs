//! The scene's tree in two levels, flattened into one: each object's triangles under a
//! subtree of their own, and a top tree over the objects' roots. Every backend walks the
//! result as one binary tree (backend-cpu with obvhs, the others over [`BvhNode`]s), so
//! nothing about the two levels reaches a traversal.
//!
//! What the two levels buy is a move's cost: an object's triangles, and the nodes below its
//! root, lie in one block each, children after parents. A rigid move of an object rewrites
//! its triangles and refits its subtree in one sweep of its blocks, from the last node to
//! the first, and lays out the top tree, a node or two per object, anew. A drag step then
//! touches what moved and nothing else of the scene, and the top tree never wanders from
//! the objects' boxes: only a moved object's own subtree may fit its triangles less tightly
//! as it rotates (docs/algorithm.md 3b).
//!
//! [`BvhNode`]: crate::layout::BvhNode

use crate::compile::EMPTY_BOX;
use glam::Vec3;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};
use obvhs::triangle::Triangle;
use std::ops::Range;
use std::time::Duration;

/// Where one object lives in the flattened tree.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectSpan {
    /// Its triangles, a block of the leaf-ordered triangles.
    pub triangles: Range<u32>,
    /// The nodes below its root, children after parents.
    pub nodes: Range<u32>,
    /// Its root among the top tree's nodes (`u32::MAX` for an object without triangles,
    /// which the tree leaves out). Each pose's top tree places it anew.
    pub root: u32,
    /// Levels of its subtree, its root's included.
    pub depth: u32,
    /// The summed half areas of the boxes below its root: its share of the tree's cost
    /// ([`tree_cost`](crate::compile::tree_cost)), which a refit of it replaces.
    pub cost: f64,
}

impl ObjectSpan {
    /// The object's box in `bvh` (`[min, max]`), its root's: exactly its vertices' box, as
    /// obvhs boxes triangles; empty for an object without triangles.
    pub fn bounds(&self, bvh: &Bvh2) -> [Vec3; 2] {
        match bvh.nodes.get(self.root as usize) {
            Some(root) => [root.aabb.min.into(), root.aabb.max.into()],
            None => EMPTY_BOX,
        }
    }
}

/// A scene's tree and where each object lies in it.
pub struct SceneTree {
    /// The flattened tree: the top tree's nodes first, then each object's nodes below its
    /// root; `primitive_indices` maps a leaf's triangle to its index in scene order.
    pub bvh: Bvh2,
    /// One per object, in scene order.
    pub spans: Vec<ObjectSpan>,
    /// Levels of the whole tree.
    pub depth: usize,
}

/// Nodes of the top tree over `objects` placed objects: one per object's root, and the
/// inner nodes above them.
pub fn top_nodes(objects: usize) -> usize {
    (2 * objects).saturating_sub(1)
}

/// Builds the tree of `objects` (each object's triangles, in scene order) with `params`.
pub fn build_scene_tree(objects: &[Vec<Triangle>], params: BvhBuildParams) -> SceneTree {
    let placed = objects.iter().filter(|t| !t.is_empty()).count();
    if placed == 0 {
        // obvhs's tree of nothing: what a backend uploads for an empty scene.
        let bvh = build_bvh2_from_tris(&[], params, &mut Duration::default());
        let depth = usize::from(!bvh.nodes.is_empty());
        let spans = objects.iter().map(|_| empty_span(0, 0)).collect();
        return SceneTree { bvh, spans, depth };
    }
    let total: usize = objects.iter().map(Vec::len).sum();
    let mut nodes = vec![Bvh2Node::default(); top_nodes(placed)];
    let mut primitive_indices = Vec::with_capacity(total);
    let mut roots = Vec::with_capacity(placed);
    let mut spans = Vec::with_capacity(objects.len());
    let mut first = 0u32;
    for triangles in objects {
        let (node_base, triangle_base) = (nodes.len() as u32, primitive_indices.len() as u32);
        if triangles.is_empty() {
            spans.push(empty_span(node_base, triangle_base));
            continue;
        }
        let mut own = build_bvh2_from_tris(triangles, params, &mut Duration::default());
        if !own.children_are_ordered_after_parents {
            own.reorder_in_stack_traversal_order();
        }
        // Node j > 0 of the object's tree goes to node_base + j - 1; its root to the top.
        let relocate = |n: &Bvh2Node| Bvh2Node {
            first_index: if n.is_leaf() {
                triangle_base + n.first_index
            } else {
                node_base + n.first_index - 1
            },
            ..*n
        };
        roots.push(relocate(&own.nodes[0]));
        nodes.extend(own.nodes[1..].iter().map(relocate));
        primitive_indices.extend(own.primitive_indices.iter().map(|&p| first + p));
        spans.push(ObjectSpan {
            triangles: triangle_base..primitive_indices.len() as u32,
            nodes: node_base..nodes.len() as u32,
            root: 0,
            depth: subtree_depth(&own.nodes) as u32,
            cost: half_areas(&own.nodes[1..]),
        });
        first += triangles.len() as u32;
    }
    let mut bvh = Bvh2 {
        nodes,
        primitive_indices,
        children_are_ordered_after_parents: true,
        ..Bvh2::default()
    };
    let depth = lay_out_top(&mut bvh, &mut spans, &roots);
    bvh.max_depth = bvh.max_depth.max(depth + 1);
    SceneTree { bvh, spans, depth }
}

/// The span of an object without triangles, where the next object's blocks begin.
fn empty_span(node_base: u32, triangle_base: u32) -> ObjectSpan {
    ObjectSpan {
        triangles: triangle_base..triangle_base,
        nodes: node_base..node_base,
        root: u32::MAX,
        depth: 0,
        cost: 0.0,
    }
}

/// The summed half areas of `nodes`' boxes.
pub fn half_areas(nodes: &[Bvh2Node]) -> f64 {
    nodes.iter().map(|n| f64::from(n.aabb.half_area())).sum()
}

/// Lays out the top tree over `roots` (the placed objects' roots, in scene order) in the
/// first [`top_nodes`] nodes of `bvh`: node 0 the root, each inner node's children side by
/// side after it, split where the summed areas of the two sides' boxes, weighed by how many
/// objects each holds, are least. Sets each placed span's `root` and returns the tree's
/// depth.
pub fn lay_out_top(bvh: &mut Bvh2, spans: &mut [ObjectSpan], roots: &[Bvh2Node]) -> usize {
    let placed: Vec<usize> = (0..spans.len())
        .filter(|&o| spans[o].root != u32::MAX)
        .collect();
    let mut depth = 0;
    let mut pending = vec![(0usize, (0..roots.len()).collect::<Vec<_>>(), 1usize)];
    let mut next = 1;
    while let Some((slot, mut items, level)) = pending.pop() {
        if let [only] = items[..] {
            bvh.nodes[slot] = roots[only];
            let span = &mut spans[placed[only]];
            span.root = slot as u32;
            depth = depth.max(level + span.depth as usize - 1);
            continue;
        }
        let aabb = items
            .iter()
            .fold(Aabb::empty(), |a, &i| a.union(&roots[i].aabb));
        let cut = split(&mut items, roots);
        bvh.nodes[slot] = Bvh2Node {
            aabb,
            prim_count: 0,
            first_index: next as u32,
            ..Bvh2Node::default()
        };
        let right = items.split_off(cut);
        pending.push((next, items, level + 1));
        pending.push((next + 1, right, level + 1));
        next += 2;
    }
    depth
}

/// Orders `items` along the axis and at the cut (returned) where the two sides' boxes cost
/// least (surface area heuristic over the roots' boxes, by their centres).
fn split(items: &mut [usize], roots: &[Bvh2Node]) -> usize {
    let centre = |i: usize, axis: usize| roots[i].aabb.center()[axis];
    let mut best = (f32::INFINITY, 0, items.len() / 2);
    for axis in 0..3 {
        items.sort_by(|&a, &b| centre(a, axis).total_cmp(&centre(b, axis)));
        // Area of the boxes after each cut, from the right.
        let mut right = vec![0.0f32; items.len()];
        let mut acc = Aabb::empty();
        for k in (1..items.len()).rev() {
            acc = acc.union(&roots[items[k]].aabb);
            right[k] = acc.half_area();
        }
        let mut left = Aabb::empty();
        for k in 1..items.len() {
            left = left.union(&roots[items[k - 1]].aabb);
            let cost = left.half_area() * k as f32 + right[k] * (items.len() - k) as f32;
            if cost < best.0 {
                best = (cost, axis, k);
            }
        }
    }
    let axis = best.1;
    items.sort_by(|&a, &b| centre(a, axis).total_cmp(&centre(b, axis)));
    best.2
}

/// Levels of an obvhs tree, walked iteratively.
fn subtree_depth(nodes: &[Bvh2Node]) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        let n = &nodes[i];
        if !n.is_leaf() {
            stack.push((n.first_index as usize, depth + 1));
            stack.push((n.first_index as usize + 1, depth + 1));
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    /// A unit square of two triangles at height `y`, shifted by `x`, in `cells` x `cells` tiles.
    fn tiles(x: f32, y: f32, cells: usize) -> Vec<Triangle> {
        let s = 1.0 / cells as f32;
        (0..cells * cells)
            .flat_map(|i| {
                let (u, v) = ((i % cells) as f32 * s + x, (i / cells) as f32 * s);
                let p = |du: f32, dv: f32| Vec3A::new(u + du, y, v + dv);
                [
                    Triangle {
                        v0: p(0.0, 0.0),
                        v1: p(s, 0.0),
                        v2: p(s, s),
                    },
                    Triangle {
                        v0: p(0.0, 0.0),
                        v1: p(s, s),
                        v2: p(0.0, s),
                    },
                ]
            })
            .collect()
    }

    /// Each object's triangles are one block and every leaf under its root holds only
    /// them; its nodes below the root are one block, children after parents; obvhs
    /// validates the whole tree; an object without triangles is left out of it; the depth
    /// is the deepest leaf's level.
    #[test]
    fn objects_lie_in_blocks_under_a_top_tree() {
        let objects = vec![
            tiles(0.0, 0.0, 8),
            Vec::new(),
            tiles(3.0, 1.0, 1),
            tiles(-2.0, 0.5, 3),
        ];
        let params = BvhBuildParams {
            max_prims_per_leaf: 2,
            ..BvhBuildParams::medium_build()
        };
        let tree = build_scene_tree(&objects, params);
        let all: Vec<Triangle> = objects.iter().flatten().copied().collect();
        assert_eq!(tree.bvh.validate(&all, false, true).prim_count, all.len());
        assert_eq!(tree.spans[1].root, u32::MAX);
        assert_eq!(tree.spans[1].triangles.len(), 0);
        let top = top_nodes(3);
        let mut first = 0u32;
        let mut deepest = 0usize;
        for (o, span) in tree.spans.iter().enumerate() {
            let count = objects[o].len() as u32;
            assert_eq!(span.triangles.len() as u32, count);
            let mut slots: Vec<u32> = tree.bvh.primitive_indices
                [span.triangles.start as usize..span.triangles.end as usize]
                .to_vec();
            slots.sort_unstable();
            assert_eq!(
                slots,
                (first..first + count).collect::<Vec<_>>(),
                "object {o}"
            );
            first += count;
            if span.root == u32::MAX {
                continue;
            }
            assert!((span.root as usize) < top && span.nodes.start as usize >= top);
            // Walk the subtree: inner nodes in the block, after their parents; leaves in the
            // object's triangles.
            let mut stack = vec![(span.root, 1u32)];
            while let Some((i, level)) = stack.pop() {
                let n = &tree.bvh.nodes[i as usize];
                deepest = deepest.max(level as usize);
                if n.is_leaf() {
                    assert!(span.triangles.contains(&n.first_index));
                    assert!(span.triangles.contains(&(n.first_index + n.prim_count - 1)));
                    continue;
                }
                for child in [n.first_index, n.first_index + 1] {
                    assert!(span.nodes.contains(&child) && child > i, "object {o}");
                    stack.push((child, level + 1));
                }
            }
        }
        assert!(deepest > 1);
        assert_eq!(tree.depth, subtree_depth(&tree.bvh.nodes));
    }

    /// A scene of nothing compiles to obvhs's tree of nothing.
    #[test]
    fn a_scene_without_triangles_has_no_spans_in_its_tree() {
        let tree = build_scene_tree(&[Vec::new()], BvhBuildParams::medium_build());
        assert_eq!(tree.spans[0].root, u32::MAX);
        assert!(tree.bvh.primitive_indices.is_empty());
    }
}
