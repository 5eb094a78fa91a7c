//! Ray queries against the scene: obvhs traverses its BVH, ppm-core's test intersects triangles.
//! [`SceneData`] answers ppm-core's [`PoseQueries`] so, faster on the CPU than the flattened
//! tree's walk ([`ppm_core::trace::FlatPose`], the WGSL twin, which finds the same surfaces);
//! public so that other CPU code over a compiled scene (the harness's reference path tracer)
//! asks the same questions of the same geometry.

use glam::Vec3;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};
use obvhs::fast_stack;
use obvhs::ray::{Ray, RayHit};
use ppm_core::compile::CompiledScene;
use ppm_core::geometry::{intersect_triangle, segment_meets_box};
use ppm_core::layout::{BvhNode, GpuBounds, GpuLight, GpuMaterial, GpuTriangle};
use ppm_core::scene_tree::ObjectSpan;
use ppm_core::textures::SurfaceTextures;
pub use ppm_core::trace::Hit;
use ppm_core::trace::{PoseQueries, box_reach, nearer, tie_bound};
use std::sync::Arc;

/// The scene as the CPU passes read it: the same flat buffers a GPU backend binds. Its
/// triangles and tree are the compiled pose's own (shared, not copied).
#[derive(Clone)]
pub struct SceneData {
    /// Triangles in BVH leaf order.
    pub triangles: Arc<Vec<GpuTriangle>>,
    /// obvhs's BVH over `triangles`.
    pub bvh: Arc<Bvh2>,
    /// The same tree flattened, as ppm-core's walks read it.
    pub nodes: Arc<Vec<BvhNode>>,
    /// Where each object's triangles and subtree lie in them.
    pub spans: Vec<ObjectSpan>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Emitting triangles.
    pub lights: Vec<GpuLight>,
    /// Index in `triangles` of each emitting triangle.
    pub emitters: Arc<Vec<u32>>,
    /// Boxes the moving objects stay inside ([`CompiledScene::movers`]).
    pub movers: Vec<GpuBounds>,
    /// Texture coordinates and images (their texels shared, not copied).
    pub textures: SurfaceTextures,
    /// The pose's number ([`CompiledScene::pose`]): names its geometry, materials and lights.
    pub pose: u64,
}

impl SceneData {
    /// The buffers of `scene`: its triangles and tree shared, the rest copied.
    pub fn new(scene: &CompiledScene) -> Self {
        Self {
            triangles: Arc::clone(&scene.triangles),
            bvh: Arc::clone(&scene.bvh),
            nodes: Arc::clone(&scene.nodes),
            spans: scene.spans.clone(),
            materials: scene.materials.clone(),
            lights: scene.lights.clone(),
            emitters: Arc::clone(&scene.emitters),
            movers: scene.movers.clone(),
            textures: scene.textures.clone(),
            pose: scene.pose,
        }
    }

    /// Whether `scene` holds the same surfaces as these buffers, whatever its movers' boxes:
    /// the same triangles, tree, materials, lights and textures, byte for byte.
    pub fn same_pose(&self, scene: &CompiledScene) -> bool {
        fn same<T: bytemuck::Pod>(a: &[T], b: &[T]) -> bool {
            bytemuck::cast_slice::<T, u8>(a) == bytemuck::cast_slice::<T, u8>(b)
        }
        let (a, b) = (&self.textures, &scene.textures);
        let shared =
            Arc::ptr_eq(&self.triangles, &scene.triangles) && Arc::ptr_eq(&self.bvh, &scene.bvh);
        (shared
            || same(&self.triangles, &scene.triangles)
                && same(&self.bvh.nodes, &scene.bvh.nodes)
                && self.bvh.primitive_indices == scene.bvh.primitive_indices)
            && same(&self.materials, &scene.materials)
            && same(&self.lights, &scene.lights)
            && same(&a.uvs, &b.uvs)
            && same(&a.headers, &b.headers)
            && (std::sync::Arc::ptr_eq(&a.texels, &b.texels) || a.texels == b.texels)
    }

    /// Whether the segment from `origin` along `dir` to `tmax` (may be infinite) crosses the
    /// box of a moving object.
    #[inline]
    pub fn near_mover(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        self.movers
            .iter()
            .any(|b| segment_meets_box(origin, dir, tmax, b.min.into(), b.max.into()))
    }
}

impl PoseQueries for SceneData {
    /// obvhs's walk with ppm-core's tie rule ([`nearer`]): the ray's end stays a little past
    /// the nearest hit ([`box_reach`]), so that boxes holding triangles as near are still
    /// visited, and an equally near triangle of lower index replaces it.
    #[inline]
    fn closest_hit(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        let mut nearest = Hit {
            t: tmax,
            triangle: u32::MAX,
        };
        let mut leaf = |node: &Bvh2Node, ray: &mut Ray, _: &mut RayHit| {
            for i in node.first_index..node.first_index + node.prim_count {
                let bound = tie_bound(&nearest);
                let t = intersect_triangle(origin, dir, &self.triangles[i as usize], 0.0, bound);
                if t < bound && nearer(t, i, &nearest) {
                    nearest = Hit { t, triangle: i };
                    ray.tmax = box_reach(&nearest);
                }
            }
            true
        };
        let mut unused = RayHit::none();
        fast_stack!(u32, (96, 192), self.bvh.max_depth, stack, {
            self.bvh
                .ray_traverse_dynamic(&mut stack, ray, &mut unused, &mut leaf)
        });
        (nearest.triangle != u32::MAX).then_some(nearest)
    }

    #[inline]
    fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        !self.bvh.ray_traverse_miss(ray, |r, id| {
            intersect_triangle(origin, dir, &self.triangles[id], r.tmin, r.tmax)
        })
    }

    fn triangles(&self) -> &[GpuTriangle] {
        &self.triangles
    }

    fn materials(&self) -> &[GpuMaterial] {
        &self.materials
    }

    fn lights(&self) -> &[GpuLight] {
        &self.lights
    }

    fn emitters(&self) -> &[u32] {
        &self.emitters
    }

    fn textures(&self) -> &SurfaceTextures {
        &self.textures
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ppm_core::compile::compile_scene;
    use ppm_core::rng::{PassKind, StreamKey};
    use ppm_core::trace::FlatPose;

    /// obvhs's walk (this backend's) and the flattened tree's (ppm-core's, the WGSL twin)
    /// find the same nearest triangle at the same distance, and the same blocked segments, on
    /// random rays through scenes of a few triangles and of 70,000 (cornell-bunny's tree).
    #[test]
    fn obvhs_and_the_flattened_tree_find_the_same_surfaces() {
        for name in ["cornell-box", "cornell-bunny", "wedding-band"] {
            let compiled = compile_scene(&scenes::builtin(name).unwrap().load().unwrap(), 8, 8);
            let (ours, flat) = (SceneData::new(&compiled), FlatPose::new(&compiled));
            let (lo, hi) = compiled.object_bounds.iter().fold(
                (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                |(lo, hi), [a, b]| (lo.min(*a), hi.max(*b)),
            );
            let (mut hits, mut blocked) = (0, 0);
            for i in 0..20_000 {
                let key = StreamKey {
                    seed: 1,
                    kind: PassKind::Eye,
                    pass_index: 0,
                    path: i,
                };
                let u = |d| key.uniform(d);
                let origin = lo + (hi - lo) * Vec3::new(u(0), u(1), u(2));
                let dir = Vec3::new(u(3) - 0.5, u(4) - 0.5, u(5) - 0.5).normalize();
                let tmax = (hi - lo).length() * u(6);
                let (a, b) = (
                    ours.closest_hit(origin, dir, f32::INFINITY),
                    flat.closest_hit(origin, dir, f32::INFINITY),
                );
                assert_eq!(a, b, "{name}, ray {i}");
                hits += usize::from(a.is_some());
                let occluded = ours.occluded(origin, dir, tmax);
                assert_eq!(
                    occluded,
                    flat.occluded(origin, dir, tmax),
                    "{name}, ray {i}"
                );
                blocked += usize::from(occluded);
            }
            assert!(
                hits > 5_000 && blocked > 1_000,
                "{name}: {hits} hits, {blocked} blocked"
            );
        }
    }

    /// Eye paths through pixel centres of the specular furnace, whose glass cube sits
    /// square before the eye, meet its edges exactly on the image's diagonals: both walks
    /// resolve each such tie alike ([`ppm_core::trace::nearer`]), so every slot finds the
    /// same visible point (35 of 2304 did not when each kept the first it found).
    #[test]
    fn both_walks_break_ties_alike() {
        use ppm_core::eye_path::slot_eye_path;
        use ppm_core::layout::{EyePassParams, HitPoint};
        let scene = scenes::builtin("specular-furnace").unwrap().load().unwrap();
        let compiled = compile_scene(&scene, 48, 48);
        let (ours, flat) = (SceneData::new(&compiled), FlatPose::new(&compiled));
        let params = EyePassParams {
            spp: 1,
            max_depth: 24,
            r2_initial: 0.01,
            ray_epsilon: 1e-4 * compiled.extent,
            ..EyePassParams::default()
        };
        for slot in 0..48 * 48 {
            let (mut a, mut b) = (HitPoint::default(), HitPoint::default());
            slot_eye_path(&params, &compiled.camera, &ours, slot, &mut a);
            slot_eye_path(&params, &compiled.camera, &flat, slot, &mut b);
            assert_eq!(
                bytemuck::bytes_of(&a),
                bytemuck::bytes_of(&b),
                "slot {slot}"
            );
        }
    }
}
