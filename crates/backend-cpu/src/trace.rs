//! Ray queries against the scene: obvhs traverses its BVH, ppm-core's test intersects triangles.
//! Public so that other CPU code over a compiled scene (the harness's reference path tracer)
//! asks the same questions of the same geometry.

use glam::Vec3;
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use ppm_core::compile::CompiledScene;
use ppm_core::geometry::intersect_triangle;
use ppm_core::layout::{GpuLight, GpuMaterial, GpuTriangle};

/// The scene as the CPU passes read it: the same flat buffers a GPU backend binds, and for
/// traversal obvhs's compressed wide BVH (eight children a node, SIMD node tests), with the
/// triangles copied in its leaf order.
#[derive(Clone)]
pub struct SceneData {
    /// Triangles in the compiled scene's order (its binary BVH's leaf order): hits index them.
    pub triangles: Vec<GpuTriangle>,
    /// The wide BVH.
    bvh: CwBvh,
    /// `triangles` in the wide BVH's leaf order, for the intersection tests.
    leaf_triangles: Vec<GpuTriangle>,
    /// Index in `triangles` of each of `leaf_triangles`.
    leaf_to_triangle: Vec<u32>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Emitting triangles.
    pub lights: Vec<GpuLight>,
}

/// The nearest surface a ray meets.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the (unit) direction.
    pub t: f32,
    /// Index into [`SceneData::triangles`].
    pub triangle: u32,
}

impl SceneData {
    /// The buffers of `scene`, copied.
    pub fn new(scene: &CompiledScene) -> Self {
        let tris: Vec<Triangle> = scene
            .triangles
            .iter()
            .map(|t| {
                let v0 = Vec3A::from(t.v0);
                Triangle {
                    v0,
                    v1: v0 + Vec3A::from(t.e1),
                    v2: v0 + Vec3A::from(t.e2),
                }
            })
            .collect();
        let mut build_time = std::time::Duration::ZERO;
        let bvh = build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut build_time);
        let leaf_to_triangle = bvh.primitive_indices.clone();
        Self {
            triangles: scene.triangles.clone(),
            leaf_triangles: leaf_to_triangle
                .iter()
                .map(|&k| scene.triangles[k as usize])
                .collect(),
            leaf_to_triangle,
            bvh,
            materials: scene.materials.clone(),
            lights: scene.lights.clone(),
        }
    }

    /// Nearest hit with `tmin < t < tmax`.
    #[inline]
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(ray, &mut hit, |r, id| {
            intersect_triangle(origin, dir, &self.leaf_triangles[id], r.tmin, r.tmax)
        });
        found.then(|| Hit {
            t: hit.t,
            triangle: self.leaf_to_triangle[hit.primitive_id as usize],
        })
    }

    /// Whether anything lies between `origin` and `origin + dir * tmax`.
    #[inline]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        !self.bvh.ray_traverse_miss(ray, |r, id| {
            intersect_triangle(origin, dir, &self.leaf_triangles[id], r.tmin, r.tmax)
        })
    }
}
