//! A moved pose's flat buffers without a new BVH: a drag sends many small moves in a row,
//! and rebuilding the whole tree for each cost cornell-bunny's local moves a quarter of their
//! time (34 ms of 148 at 256x256, its 70k triangles). A rigid move changes only the moved
//! objects' triangles: they are rewritten where the tree keeps them, and the node boxes are
//! refitted from the leaves up, in time linear in the nodes and without a new leaf order. A
//! refit keeps the tree's topology while the objects wander away from where it was built,
//! so its boxes grow: once they cost [`REFIT_LIMIT`] times the last build's, the scene is
//! compiled anew.

use crate::compile::{CompiledScene, bounds, compile_scene, flat_nodes, gpu_triangle, tree_cost};
use crate::scene::{MaterialKind, Scene};
use obvhs::aabb::Aabb;
use std::time::Instant;

/// How much more a refitted tree's boxes may cost than the last built one's
/// ([`tree_cost`]) before a move rebuilds it: tracing slows in proportion, and a quarter is
/// about what a rebuild of the largest canonical scene costs against a move.
pub const REFIT_LIMIT: f32 = 1.25;

/// `before`, the flattened scene of the pose before a move, with the `changed` objects posed
/// as in `after`: their triangles rewritten in the BVH's leaf order and the tree refitted, or
/// `after` compiled anew where a refit cannot stand for it (a light or a triangle count
/// changed, or the boxes grew past [`REFIT_LIMIT`]). Everything else (camera, materials,
/// lights, their distribution) is `before`'s: a rigid move of objects that do not emit
/// leaves it as it was.
pub fn recompile_moved(before: &CompiledScene, after: &Scene, changed: &[usize]) -> CompiledScene {
    let (width, height) = (before.camera.width, before.camera.height);
    match refit(before, after, changed) {
        Some(refitted) => refitted,
        None => compile_scene(after, width, height),
    }
}

/// The refitted scene, or `None` where only a full compile stands for `after`.
fn refit(before: &CompiledScene, after: &Scene, changed: &[usize]) -> Option<CompiledScene> {
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
    let mut triangles = before.triangles.clone();
    let mut bvh = before.bvh.clone();
    for (leaf, t) in triangles.iter_mut().enumerate() {
        let o = t.object as usize;
        if !moved.get(o).copied().unwrap_or(false) {
            continue;
        }
        let index = bvh.primitive_indices[leaf] as usize - first[o];
        let light = t.light;
        *t = gpu_triangle(&after.objects[o].triangles[index], t.material, t.object);
        t.light = light;
    }
    // Leaf boxes from the original vertices, as obvhs built them.
    let posed = |leaf: usize| {
        let o = triangles[leaf].object as usize;
        let [a, b, c] = after.objects[o].triangles[bvh.primitive_indices[leaf] as usize - first[o]];
        Aabb::from_points(&[a.into(), b.into(), c.into()])
    };
    for node in bvh.nodes.iter_mut().filter(|n| n.is_leaf()) {
        let leaves = node.first_index as usize..(node.first_index + node.prim_count) as usize;
        if leaves.clone().any(|l| moved[triangles[l].object as usize]) {
            node.aabb = leaves.map(posed).reduce(|a, b| a.union(&b))?;
        }
    }
    bvh.refit_all();
    if tree_cost(&bvh) > REFIT_LIMIT * before.bvh_built_cost {
        return None;
    }
    let (lo, hi) = bounds(&triangles);
    Some(CompiledScene {
        camera: before.camera,
        triangles,
        nodes: flat_nodes(&bvh),
        bvh,
        materials: before.materials.clone(),
        lights: before.lights.clone(),
        features: before.features,
        extent: (hi - lo).length(),
        light_power: before.light_power,
        bvh_build_time: start.elapsed(),
        bvh_built_cost: before.bvh_built_cost,
        bvh_depth: before.bvh_depth,
        movers: Vec::new(),
        textures: before.textures.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
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
    /// most REFIT_LIMIT times the last build; the long drag rebuilds at least once, and the
    /// small steps mostly refit.
    #[test]
    fn a_drag_refits_tight_trees_and_rebuilds_when_they_grow() {
        let mut scene = drag_room();
        let mut compiled = compile_scene(&scene, 8, 8);
        let (mut refits, mut rebuilds) = (0, 0);
        for i in 0..60 {
            scene.apply(&step(1, Vec3::new(0.25, 0.1, 0.05), 3.0 * i as f32));
            let next = recompile_moved(&compiled, &scene, &[1]);
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

    /// A moved light changes what compile_scene derives from the lights: a full compile.
    #[test]
    fn a_moved_light_is_compiled_anew() {
        let mut scene = drag_room();
        let compiled = compile_scene(&scene, 8, 8);
        scene.apply(&step(2, Vec3::new(0.0, -1.0, 0.0), 0.0));
        let next = recompile_moved(&compiled, &scene, &[2]);
        assert_eq!(next.lights, compile_scene(&scene, 8, 8).lights);
        assert_ne!(next.lights, compiled.lights);
    }
}
