//! Ray queries against the scene: obvhs traverses its BVH, ppm-core's test intersects triangles.
//! [`SceneData`] answers ppm-core's [`PoseQueries`] so, faster on the CPU than the flattened
//! tree's walk ([`ppm_core::trace::FlatPose`], the WGSL twin, which finds the same surfaces);
//! public so that other CPU code over a compiled scene (the harness's reference path tracer)
//! asks the same questions of the same geometry.

use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::ray::{Ray, RayHit};
use ppm_core::compile::CompiledScene;
use ppm_core::geometry::{intersect_triangle, segment_meets_box};
use ppm_core::layout::{GpuBounds, GpuLight, GpuMaterial, GpuTriangle};
use ppm_core::textures::SurfaceTextures;
pub use ppm_core::trace::Hit;
use ppm_core::trace::PoseQueries;
use std::sync::Arc;

/// The scene as the CPU passes read it: the same flat buffers a GPU backend binds. Its
/// triangles and tree are the compiled pose's own (shared, not copied).
#[derive(Clone)]
pub struct SceneData {
    /// Triangles in BVH leaf order.
    pub triangles: Arc<Vec<GpuTriangle>>,
    /// obvhs's BVH over `triangles`.
    pub bvh: Arc<Bvh2>,
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
    #[inline]
    fn closest_hit(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(ray, &mut hit, |r, id| {
            intersect_triangle(origin, dir, &self.triangles[id], r.tmin, r.tmax)
        });
        found.then_some(Hit {
            t: hit.t,
            triangle: hit.primitive_id,
        })
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
    /// find the same nearest surface at the same distance, and the same blocked segments, on
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
                assert_eq!(a.map(|h| h.t), b.map(|h| h.t), "{name}, ray {i}");
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
}
