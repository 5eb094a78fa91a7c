//! A moved pose's flat buffers without a new BVH: a drag sends many small moves in a row,
//! and rebuilding the whole tree for each would cost a scene of many triangles (cornell-bunny's
//! 70,000) a quarter of every local move. A rigid move changes only the moved
//! objects' triangles: they are rewritten where the tree keeps them, and the boxes of their
//! leaves and of the leaves' ancestors are refitted, without a new leaf order and without
//! reading the rest of the scene (a drag writes into the buffers of the pose before last). A
//! refit keeps the tree's topology while the objects wander away from where it was built,
//! so its boxes grow: once they cost [`REFIT_LIMIT`] times the last build's, the scene is
//! compiled anew.

use crate::compile::{
    CompiledScene, EMPTY_BOX, RefitWrites, add_to_box, compile_scene, extent_of, flat_node,
    gpu_triangle, next_pose,
};
use crate::layout::{BvhNode, GpuTriangle};
use crate::scene::{MaterialKind, Scene};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use std::sync::Arc;
use std::time::Instant;

/// How much more a refitted tree's boxes may cost than the last built one's
/// ([`tree_cost`](crate::compile::tree_cost)) before a move rebuilds it: tracing slows in
/// proportion, and a quarter is about what a rebuild of the largest canonical scene costs
/// against a move.
pub const REFIT_LIMIT: f32 = 1.25;

/// `before`, the flattened scene of the pose before a move, with the `changed` objects posed
/// as in `after`: their triangles rewritten in the BVH's leaf order and the tree refitted, or
/// `after` compiled anew where a refit cannot stand for it (a light or a triangle count
/// changed, or the boxes grew past [`REFIT_LIMIT`]). Everything else (camera, materials,
/// lights, their distribution) is `before`'s: a rigid move of objects that do not emit
/// leaves it as it was.
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
/// copying the pose's arrays, it touches only the moved objects' leaves and their ancestors
/// (`Bvh2::primitives_to_nodes` and `Bvh2::parents`, kept since the build), so a small
/// object dragged through a large scene costs in proportion to the object.
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
    // Each object's first triangle in the order compile_scene numbers them.
    let mut first = Vec::with_capacity(after.objects.len() + 1);
    first.push(0usize);
    for object in &after.objects {
        first.push(first.last()? + object.triangles.len());
    }
    if changed
        .iter()
        .any(|&o| o >= after.objects.len() || emits(o))
        || *first.last()? != before.triangles.len()
    {
        return None;
    }
    let mut moved = vec![false; after.objects.len()];
    for &o in changed {
        moved[o] = true;
    }
    let (mut triangles, mut bvh, mut nodes) = match spare.and_then(|s| lent(s, before)) {
        Some(buffers) => buffers,
        None => (
            Vec::clone(&before.triangles),
            Bvh2::clone(&before.bvh),
            Vec::clone(&before.nodes),
        ),
    };
    // The leaves that hold a moved triangle.
    let mut leaves: Vec<usize> = changed
        .iter()
        .flat_map(|&o| first[o]..first[o + 1])
        .map(|p| bvh.primitives_to_nodes.get(p).map(|&n| n as usize))
        .collect::<Option<_>>()?;
    leaves.sort_unstable();
    leaves.dedup();
    // Leaf boxes from the original vertices, as obvhs built them.
    let posed = |leaf: usize, triangles: &[GpuTriangle]| {
        let o = triangles[leaf].object as usize;
        let [a, b, c] = after.objects[o].triangles[bvh.primitive_indices[leaf] as usize - first[o]];
        Aabb::from_points(&[a.into(), b.into(), c.into()])
    };
    let mut cost = f64::from(before.bvh_cost);
    let mut written = Vec::new();
    for &leaf in &leaves {
        let node = bvh.nodes[leaf];
        let slots = node.first_index as usize..(node.first_index + node.prim_count) as usize;
        for slot in slots.clone() {
            let t = &mut triangles[slot];
            let o = t.object as usize;
            if moved.get(o).copied().unwrap_or(false) {
                written.push(slot as u32);
                let index = bvh.primitive_indices[slot] as usize - first[o];
                *t = GpuTriangle {
                    light: t.light,
                    ..gpu_triangle(&after.objects[o].triangles[index], t.material, t.object)
                };
            }
        }
        let aabb = slots
            .map(|l| posed(l, &triangles))
            .reduce(|a, b| a.union(&b))?;
        cost += f64::from(aabb.half_area()) - f64::from(node.aabb.half_area());
        bvh.nodes[leaf].aabb = aabb;
    }
    // Their ancestors, each once, children before parents.
    let above = ancestors(&bvh, &leaves);
    for &node in &above {
        let n = bvh.nodes[node];
        let first_child = n.first_index as usize;
        let aabb = bvh.nodes[first_child]
            .aabb
            .union(&bvh.nodes[first_child + 1].aabb);
        cost += f64::from(aabb.half_area()) - f64::from(n.aabb.half_area());
        bvh.nodes[node].aabb = aabb;
        nodes[node] = flat_node(&bvh.nodes[node]);
    }
    for &leaf in &leaves {
        nodes[leaf] = flat_node(&bvh.nodes[leaf]);
    }
    let bvh_cost = cost as f32;
    if bvh_cost > REFIT_LIMIT * before.bvh_built_cost {
        return None;
    }
    let mut object_bounds = before.object_bounds.clone();
    for &o in changed {
        object_bounds[o] = EMPTY_BOX;
    }
    for &t in &written {
        let t = &triangles[t as usize];
        add_to_box(&mut object_bounds[t.object as usize], t);
    }
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
        bvh_depth: before.bvh_depth,
        movers: Vec::new(),
        textures: before.textures.clone(),
        object_bounds,
        pose: next_pose(),
        refit_from: Some(RefitWrites {
            pose: before.pose,
            triangles: written,
            nodes: leaves.iter().chain(&above).map(|&n| n as u32).collect(),
        }),
    })
}

/// The buffers of `spare` made `before`'s, if `before` was refitted from it and nothing
/// else holds them.
fn lent(
    spare: CompiledScene,
    before: &CompiledScene,
) -> Option<(Vec<GpuTriangle>, Bvh2, Vec<BvhNode>)> {
    let writes = before
        .refit_from
        .as_ref()
        .filter(|w| w.pose == spare.pose)?;
    let mut triangles = Arc::try_unwrap(spare.triangles).ok()?;
    let mut bvh = Arc::try_unwrap(spare.bvh).ok()?;
    let mut nodes = Arc::try_unwrap(spare.nodes).ok()?;
    for &t in &writes.triangles {
        triangles[t as usize] = before.triangles[t as usize];
    }
    for &n in &writes.nodes {
        bvh.nodes[n as usize] = before.bvh.nodes[n as usize];
        nodes[n as usize] = before.nodes[n as usize];
    }
    Some((triangles, bvh, nodes))
}

/// The inner nodes above `leaves`, each once, ordered so that a node's children come
/// before it: deepest first. Each walk up stops at a node an earlier walk reached, whose
/// depth it knows, so the cost follows the nodes returned.
fn ancestors(bvh: &Bvh2, leaves: &[usize]) -> Vec<usize> {
    // 1 + depth of each node reached so far; 0 for the others.
    let mut level = vec![0u32; bvh.nodes.len()];
    level[0] = 1;
    let mut by_level: Vec<Vec<usize>> = vec![vec![0]];
    let mut chain = Vec::new();
    for &leaf in leaves {
        chain.clear();
        let mut node = leaf;
        while node != 0 {
            node = bvh.parents[node] as usize;
            if level[node] != 0 {
                break;
            }
            chain.push(node);
        }
        // `node` is known: the chain below it, from the top down.
        let mut depth = level[node];
        for &n in chain.iter().rev() {
            depth += 1;
            level[n] = depth;
            if by_level.len() < depth as usize {
                by_level.resize_with(depth as usize, Vec::new);
            }
            by_level[depth as usize - 1].push(n);
        }
    }
    // A root that is itself a leaf has nothing above it.
    if leaves.is_empty() || bvh.nodes[0].is_leaf() {
        return Vec::new();
    }
    by_level.into_iter().rev().flatten().collect()
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

    /// A drag of the cube in small steps: each pose's refitted tree bounds its triangles
    /// tightly, holds exactly the triangles a full compile of the pose holds, and costs at
    /// most REFIT_LIMIT times the last build; its flat nodes, cost and extent, updated where
    /// the cube moved, are what full passes over the tree and the triangles give; the long
    /// drag rebuilds at least once, and the small steps mostly refit.
    #[test]
    fn a_drag_refits_tight_trees_and_rebuilds_when_they_grow() {
        let mut scene = drag_room();
        let mut compiled = compile_scene(&scene, 8, 8);
        let (mut refits, mut rebuilds) = (0, 0);
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
            assert_eq!(next.extent, compile_scene(&scene, 8, 8).extent);
            if next.bvh_built_cost == compiled.bvh_built_cost {
                refits += 1;
            } else {
                rebuilds += 1;
            }
            compiled = next;
        }
        assert!(
            rebuilds >= 1 && refits > 4 * rebuilds,
            "{refits} refits, {rebuilds} rebuilds"
        );
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
