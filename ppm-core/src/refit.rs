//! A moved pose's flat buffers without a new BVH: a drag sends many small moves in a row,
//! and rebuilding the whole tree for each would cost a scene of many triangles (cornell-bunny's
//! 70,000) a quarter of every local move. A rigid move changes only the moved objects'
//! triangles, and each object's triangles and subtree are blocks of their own
//! ([`crate::scene_tree`]): a move rewrites the moved objects' blocks, refits their subtrees
//! in one sweep from the last node to the first, and lays out the top tree over the objects
//! anew, without reading the rest of the scene (a drag writes into the buffers of the pose
//! before last). A subtree keeps its topology while its object rotates away from the pose it
//! was built in, so its boxes may grow: once the tree costs [`REFIT_LIMIT`] times the last
//! build's, the scene is compiled anew.

use crate::compile::{
    CompiledScene, RefitWrites, compile_scene, extent_of, flat_node, gpu_triangle, next_pose,
};
use crate::layout::{BvhNode, GpuTriangle};
use crate::scene::{MaterialKind, Scene};
use crate::scene_tree::{ObjectSpan, half_areas, lay_out_top, top_nodes};
use glam::Vec3;
use obvhs::aabb::Aabb;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;
use std::time::Instant;

/// How much more a refitted tree's boxes may cost than the last built one's
/// ([`tree_cost`](crate::compile::tree_cost)) before a move rebuilds it: tracing slows in
/// proportion, and a quarter is about what a rebuild of the largest canonical scene costs
/// against a move.
pub const REFIT_LIMIT: f32 = 1.25;

/// Triangles or nodes a thread takes at a time: a moved mesh of tens of thousands would
/// otherwise be a drag step's largest serial part.
const CHUNK: usize = 4096;

/// `before`, the flattened scene of the pose before a move, with the `changed` objects posed
/// as in `after`: their triangles rewritten and their subtrees refitted, or `after` compiled
/// anew where a refit cannot stand for it (a light or a triangle count changed, or the boxes
/// grew past [`REFIT_LIMIT`]). Everything else (camera, materials, lights, their
/// distribution) is `before`'s: a rigid move of objects that do not emit leaves it as it was.
///
/// `spare`, the pose `before` was refitted from if the caller kept it, lends its buffers:
/// they become `before`'s by copying what that refit wrote, then this pose's, so that a
/// drag copies no buffer whole, however large the scene.
pub fn recompile_moved(
    before: &CompiledScene,
    after: &Scene,
    changed: &[usize],
    spare: Option<CompiledScene>,
) -> CompiledScene {
    let (width, height) = (before.camera.width, before.camera.height);
    match refit(before, after, changed, spare) {
        Some(refitted) => refitted,
        None => compile_scene(after, width, height),
    }
}

/// The refitted scene, or `None` where only a full compile stands for `after`. Apart from
/// copying the pose's arrays when no spare lends them, it touches only the moved objects'
/// blocks and the top tree, so a small object dragged through a large scene costs in
/// proportion to the object.
fn refit(
    before: &CompiledScene,
    after: &Scene,
    changed: &[usize],
    spare: Option<CompiledScene>,
) -> Option<CompiledScene> {
    let start = Instant::now();
    let emits = |o: usize| {
        let material = after.objects[o].material;
        matches!(after.materials[material].kind, MaterialKind::Light { .. })
    };
    let spans = &before.spans;
    if changed
        .iter()
        .any(|&o| o >= after.objects.len() || emits(o))
        || spans.len() != after.objects.len()
        || spans
            .iter()
            .zip(&after.objects)
            .any(|(s, o)| s.triangles.len() != o.triangles.len())
    {
        return None;
    }
    // Each object's first triangle in scene order, which `primitive_indices` numbers.
    let first: Vec<u32> = spans
        .iter()
        .scan(0u32, |next, s| {
            let at = *next;
            *next += s.triangles.len() as u32;
            Some(at)
        })
        .collect();
    let mut moved: Vec<usize> = changed.to_vec();
    moved.sort_unstable();
    moved.dedup();
    let placed = spans.iter().filter(|s| s.root != u32::MAX).count();
    let top = top_nodes(placed) as u32;
    // What this refit writes whole: the moved objects' blocks and the top tree.
    let rewritten = |r: &Range<u32>| {
        r.end <= top
            || moved.iter().any(|&o| {
                let s = &spans[o];
                s.triangles.start <= r.start && r.end <= s.triangles.end
                    || s.nodes.start <= r.start && r.end <= s.nodes.end
            })
    };
    let lent = spare.and_then(|s| lent(s, before, rewritten));
    let (mut triangles, mut bvh, mut nodes) = match lent {
        Some(buffers) => buffers,
        None => (
            Vec::clone(&before.triangles),
            Bvh2::clone(&before.bvh),
            Vec::clone(&before.nodes),
        ),
    };
    let mut spans = spans.clone();
    let top = top as usize;
    let mut cost = f64::from(before.bvh_cost) - half_areas(&before.bvh.nodes[..top]);
    let mut written = RefitWrites {
        pose: before.pose,
        triangles: Vec::new(),
        nodes: Vec::new(),
    };
    let mut fitted = vec![None; spans.len()];
    let mut object_bounds = before.object_bounds.clone();
    for &o in &moved {
        let span = &mut spans[o];
        if span.root == u32::MAX {
            continue;
        }
        let posed = Posed {
            corners: &after.objects[o].triangles,
            first: first[o],
            root: before.bvh.nodes[span.root as usize],
        };
        let (root, refitted) = posed.write(span, &mut triangles, &mut bvh, &mut nodes);
        cost += refitted - span.cost;
        span.cost = refitted;
        object_bounds[o] = [root.aabb.min.into(), root.aabb.max.into()];
        fitted[o] = Some(root);
        written.triangles.push(span.triangles.clone());
        written.nodes.push(span.nodes.clone());
    }
    // The top tree over the objects' roots as they now lie.
    let roots: Vec<Bvh2Node> = (spans.iter().zip(fitted))
        .filter(|(s, _)| s.root != u32::MAX)
        .map(|(s, root)| root.unwrap_or(before.bvh.nodes[s.root as usize]))
        .collect();
    let depth = lay_out_top(&mut bvh, &mut spans, &roots);
    for (flat, node) in nodes.iter_mut().zip(&bvh.nodes[..top]) {
        *flat = flat_node(node);
    }
    written.nodes.push(0..top as u32);
    cost += half_areas(&bvh.nodes[..top]);
    let bvh_cost = cost as f32;
    if bvh_cost > REFIT_LIMIT * before.bvh_built_cost {
        return None;
    }
    bvh.max_depth = bvh.max_depth.max(depth + 1);
    Some(CompiledScene {
        camera: before.camera,
        triangles: Arc::new(triangles),
        nodes: Arc::new(nodes),
        bvh: Arc::new(bvh),
        emitters: Arc::clone(&before.emitters),
        materials: before.materials.clone(),
        lights: before.lights.clone(),
        features: before.features,
        extent: extent_of(&object_bounds),
        light_power: before.light_power,
        bvh_build_time: start.elapsed(),
        bvh_built_cost: before.bvh_built_cost,
        bvh_cost,
        bvh_depth: depth,
        movers: Vec::new(),
        textures: before.textures.clone(),
        object_bounds,
        spans,
        pose: next_pose(),
        refit_from: Some(written),
    })
}

/// One moved object as `after` poses it.
struct Posed<'a> {
    /// Its triangles' corners, in scene order.
    corners: &'a [[Vec3; 3]],
    /// Its first triangle's index in scene order (`primitive_indices` numbers them so).
    first: u32,
    /// Its root as the pose before holds it (lent buffers hold another pose's top tree).
    root: Bvh2Node,
}

impl Posed<'_> {
    /// Writes the object's blocks (`span`): its triangles, its subtree's boxes from the
    /// leaves up, and their flat nodes. Returns its root refitted (its box is the object's)
    /// and its subtree's cost below the root, summed chunk by chunk in order: the same
    /// whatever the threads.
    fn write(
        &self,
        span: &ObjectSpan,
        triangles: &mut [GpuTriangle],
        bvh: &mut Bvh2,
        nodes: &mut [BvhNode],
    ) -> (Bvh2Node, f64) {
        let Bvh2 {
            nodes: tree,
            primitive_indices,
            ..
        } = bvh;
        let corners =
            |slot: u32| &self.corners[(primitive_indices[slot as usize] - self.first) as usize];
        // A leaf's box from its triangles' vertices, as obvhs boxes them at a build.
        let leaf_box = |n: &Bvh2Node| {
            (n.first_index..n.first_index + n.prim_count).fold(Aabb::empty(), |a, slot| {
                let [p, q, r] = corners(slot).map(Into::into);
                a.union(&Aabb::from_points(&[p, q, r]))
            })
        };
        let block = |r: &Range<u32>| r.start as usize..r.end as usize;
        let (slots, below) = (block(&span.triangles), block(&span.nodes));
        triangles[slots.clone()]
            .par_chunks_mut(CHUNK)
            .zip(slots.into_par_iter().step_by(CHUNK))
            .for_each(|(part, first_slot)| {
                for (t, slot) in part.iter_mut().zip(first_slot as u32..) {
                    *t = GpuTriangle {
                        light: t.light,
                        ..gpu_triangle(corners(slot), t.material, t.object)
                    };
                }
            });
        // The leaves in parallel, then the inner nodes from the last to the first.
        tree[below.clone()].par_chunks_mut(CHUNK).for_each(|part| {
            for n in part.iter_mut().filter(|n| n.is_leaf()) {
                n.aabb = leaf_box(n);
            }
        });
        for i in below.clone().rev() {
            if !tree[i].is_leaf() {
                let children = tree[i].first_index as usize;
                tree[i].aabb = tree[children].aabb.union(&tree[children + 1].aabb);
            }
        }
        let costs: Vec<f64> = nodes[below.clone()]
            .par_chunks_mut(CHUNK)
            .zip(tree[below].par_chunks(CHUNK))
            .map(|(flat, part)| {
                flat.iter_mut()
                    .zip(part)
                    .for_each(|(f, node)| *f = flat_node(node));
                half_areas(part)
            })
            .collect();
        let mut root = self.root;
        root.aabb = if root.is_leaf() {
            leaf_box(&root)
        } else {
            let children = root.first_index as usize;
            tree[children].aabb.union(&tree[children + 1].aabb)
        };
        (root, costs.iter().sum())
    }
}

/// The buffers of `spare` made `before`'s, if `before` was refitted from it and nothing
/// else holds them: the blocks that refit wrote copied from `before`, except those the
/// caller will write whole (`rewritten`).
fn lent(
    spare: CompiledScene,
    before: &CompiledScene,
    rewritten: impl Fn(&Range<u32>) -> bool,
) -> Option<(Vec<GpuTriangle>, Bvh2, Vec<BvhNode>)> {
    let writes = before
        .refit_from
        .as_ref()
        .filter(|w| w.pose == spare.pose)?;
    let mut triangles = Arc::try_unwrap(spare.triangles).ok()?;
    let mut bvh = Arc::try_unwrap(spare.bvh).ok()?;
    let mut nodes = Arc::try_unwrap(spare.nodes).ok()?;
    let copied = |r: &&Range<u32>| !rewritten(r);
    let range = |r: &Range<u32>| r.start as usize..r.end as usize;
    for r in writes.triangles.iter().filter(copied).map(range) {
        triangles[r.clone()].copy_from_slice(&before.triangles[r]);
    }
    for r in writes.nodes.iter().filter(copied).map(range) {
        bvh.nodes[r.clone()].copy_from_slice(&before.bvh.nodes[r.clone()]);
        nodes[r.clone()].copy_from_slice(&before.nodes[r]);
    }
    bvh.max_depth = before.bvh.max_depth;
    Some((triangles, bvh, nodes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::{flat_nodes, tree_cost};
    use crate::scene::testing::{object, room};
    use crate::scene::{Move, quad_triangles};
    use glam::{Quat, Vec3, Vec3A};
    use obvhs::triangle::Triangle;

    /// A floor of 20x20 tiles, a cube on it and a lamp above.
    fn drag_room() -> Scene {
        let quad = |lo: Vec3, hi: Vec3| {
            quad_triangles([
                lo,
                Vec3::new(lo.x, lo.y, hi.z),
                hi,
                Vec3::new(hi.x, lo.y, lo.z),
            ])
        };
        let floor = (0..400)
            .flat_map(|i| {
                let (x, z) = ((i % 20) as f32 - 10.0, (i / 20) as f32 - 10.0);
                quad(Vec3::new(x, 0.0, z), Vec3::new(x + 1.0, 0.0, z + 1.0))
            })
            .collect();
        let cube = (0..6)
            .flat_map(|face| {
                let axis = face % 3;
                let side = if face < 3 { -0.5 } else { 0.5 };
                let at = |u: f32, v: f32| {
                    let mut p = [0.0; 3];
                    p[axis] = side;
                    p[(axis + 1) % 3] = u;
                    p[(axis + 2) % 3] = v;
                    Vec3::from(p) + Vec3::new(0.0, 0.5, 0.0)
                };
                quad_triangles([at(-0.5, -0.5), at(-0.5, 0.5), at(0.5, 0.5), at(0.5, -0.5)])
            })
            .collect();
        room(vec![
            object("floor", 0, floor),
            object("cube", 0, cube),
            object(
                "lamp",
                1,
                quad(Vec3::new(-1.0, 6.0, -1.0), Vec3::new(1.0, 6.0, 1.0)).to_vec(),
            ),
        ])
    }

    fn step(object: usize, translation: Vec3, degrees: f32) -> Move {
        Move {
            object,
            translation,
            rotation: Quat::from_rotation_y(degrees.to_radians()),
        }
    }

    /// The triangles of `scene` as obvhs numbers them, to validate a tree against.
    fn primitives(scene: &Scene) -> Vec<Triangle> {
        let corners = scene.objects.iter().flat_map(|o| o.triangles.iter());
        corners
            .map(|t| Triangle {
                v0: Vec3A::from(t[0]),
                v1: Vec3A::from(t[1]),
                v2: Vec3A::from(t[2]),
            })
            .collect()
    }

    /// What a ray query reads: each leaf's triangles, sorted, for comparing two compiles.
    fn sorted_triangles(c: &CompiledScene) -> Vec<[u32; 12]> {
        let mut t: Vec<[u32; 12]> = c
            .triangles
            .iter()
            .map(|t| {
                let f = [t.v0, t.e1, t.e2, t.normal].concat();
                std::array::from_fn(|i| f[i].to_bits())
            })
            .collect();
        t.sort_unstable();
        t
    }

    /// A drag of the cube in small steps, far across the floor and turning: each pose's
    /// refitted tree bounds its triangles tightly, holds exactly the triangles a full compile
    /// of the pose holds, and costs at most REFIT_LIMIT times the last build; its flat nodes,
    /// cost, depth, extent and the cube's box, updated where the cube moved, are what full
    /// passes over the tree and the triangles give. The top tree follows the cube, so no step rebuilds; the
    /// floor's own subtree turned by 45 degrees grows past the limit, and is built anew.
    #[test]
    fn a_drag_refits_tight_trees_and_rebuilds_when_they_grow() {
        let mut scene = drag_room();
        let mut compiled = compile_scene(&scene, 8, 8);
        for i in 0..60 {
            scene.apply(&step(1, Vec3::new(0.25, 0.1, 0.05), 3.0 * i as f32));
            let next = recompile_moved(&compiled, &scene, &[1], None);
            // obvhs asserts every box contains its children's and its triangles, tightly.
            let posed = primitives(&scene);
            assert_eq!(
                next.bvh.validate(&posed, false, true).prim_count,
                posed.len()
            );
            assert_eq!(
                sorted_triangles(&next),
                sorted_triangles(&compile_scene(&scene, 8, 8))
            );
            assert!(tree_cost(&next.bvh) <= REFIT_LIMIT * next.bvh_built_cost);
            // What the refit updated node by node is what a full pass over the tree finds.
            assert_eq!(*next.nodes, flat_nodes(&next.bvh));
            let mut refitted = Bvh2::clone(&next.bvh);
            refitted.refit_all();
            assert_eq!(flat_nodes(&refitted), *next.nodes);
            approx::assert_relative_eq!(next.bvh_cost, tree_cost(&next.bvh), max_relative = 1e-5);
            assert_eq!(next.bvh_depth, depth(&next.nodes));
            let (lo, hi) = scene.objects[1].bounds();
            assert_eq!(next.object_bounds[1], [lo, hi]);
            assert_eq!(next.extent, compile_scene(&scene, 8, 8).extent);
            assert_eq!(
                next.bvh_built_cost, compiled.bvh_built_cost,
                "step {i} rebuilt"
            );
            compiled = next;
        }
        let fresh = compile_scene(&scene, 8, 8);
        for o in 0..scene.objects.len() {
            let (lo, hi) = scene.objects[o].bounds();
            assert_eq!(fresh.object_bounds[o], [lo, hi]);
        }
        scene.apply(&step(0, Vec3::ZERO, 45.0));
        let turned = recompile_moved(&compiled, &scene, &[0], None);
        assert!(turned.refit_from.is_none(), "the turned floor refitted");
        assert_eq!(turned.bvh_cost, tree_cost(&turned.bvh));
    }

    /// Levels of a flattened tree, walked from the root.
    fn depth(nodes: &[BvhNode]) -> usize {
        let mut deepest = 0;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, level)) = stack.pop() {
            deepest = deepest.max(level);
            if nodes[i].count == 0 {
                stack.push((nodes[i].first as usize, level + 1));
                stack.push((nodes[i].first as usize + 1, level + 1));
            }
        }
        deepest
    }

    /// A drag of two cubes in turns that lends each pose's buffers to the pose after next,
    /// as the driver keeps them, makes bit for bit the poses a drag copying them makes, and
    /// after its first refit copies no buffer: each pose's triangles live where the pose
    /// before last's did.
    #[test]
    fn a_drag_reuses_the_buffers_of_the_pose_before_last() {
        fn bytes(c: &CompiledScene) -> Vec<u8> {
            let mut b = bytemuck::cast_slice::<_, u8>(&c.triangles).to_vec();
            b.extend_from_slice(bytemuck::cast_slice(&c.nodes));
            b.extend_from_slice(bytemuck::cast_slice(&flat_nodes(&c.bvh)));
            b.extend_from_slice(bytemuck::bytes_of(&[c.extent, c.bvh_cost]));
            b
        }
        // Two cubes dragged in turns: each refit rewrites what the one before did not.
        let mut scene = drag_room();
        let mut second = scene.objects[1].clone();
        second
            .triangles
            .iter_mut()
            .flatten()
            .for_each(|v| v.x += 4.0);
        scene.objects.push(second);
        let mut lent = compile_scene(&scene, 8, 8);
        let mut copied = compile_scene(&scene, 8, 8);
        let mut spare: Option<CompiledScene> = None;
        let mut reused = 0;
        for i in 0..30 {
            let cube = [1, 3][i % 2];
            scene.apply(&step(cube, Vec3::new(0.02, 0.0, 0.01), 1.0));
            let spare_at = spare.as_ref().map(|s| s.triangles.as_ptr());
            let next = recompile_moved(&lent, &scene, &[cube], spare.take());
            copied = recompile_moved(&copied, &scene, &[cube], None);
            assert_eq!(bytes(&next), bytes(&copied));
            reused += usize::from(spare_at == Some(next.triangles.as_ptr()));
            let refitted_from = next.refit_from.as_ref().map(|w| w.pose);
            let before = std::mem::replace(&mut lent, next);
            spare = Some(before).filter(|b| refitted_from == Some(b.pose));
        }
        assert_eq!(reused, 29);
    }

    /// A moved light changes what compile_scene derives from the lights: a full compile.
    #[test]
    fn a_moved_light_is_compiled_anew() {
        let mut scene = drag_room();
        let compiled = compile_scene(&scene, 8, 8);
        scene.apply(&step(2, Vec3::new(0.0, -1.0, 0.0), 0.0));
        let next = recompile_moved(&compiled, &scene, &[2], None);
        assert_eq!(next.lights, compile_scene(&scene, 8, 8).lights);
        assert_ne!(next.lights, compiled.lights);
    }
}
