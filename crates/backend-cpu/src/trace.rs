//! Ray queries against the scene: obvhs traverses its BVH, ppm-core's test intersects triangles.
//! Public so that other CPU code over a compiled scene (the harness's reference path tracer)
//! asks the same questions of the same geometry.

use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::ray::{Ray, RayHit};
use ppm_core::compile::CompiledScene;
use ppm_core::geometry::{intersect_triangle, segment_meets_box};
use ppm_core::layout::{GpuBounds, GpuLight, GpuMaterial, GpuTriangle};

/// The scene as the CPU passes read it: the same flat buffers a GPU backend binds.
#[derive(Clone)]
pub struct SceneData {
    /// Triangles in BVH leaf order.
    pub triangles: Vec<GpuTriangle>,
    /// obvhs's BVH over `triangles`.
    pub bvh: Bvh2,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Emitting triangles.
    pub lights: Vec<GpuLight>,
    /// Boxes the moving objects stay inside ([`CompiledScene::movers`]).
    pub movers: Vec<GpuBounds>,
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
        Self {
            triangles: scene.triangles.clone(),
            bvh: scene.bvh.clone(),
            materials: scene.materials.clone(),
            lights: scene.lights.clone(),
            movers: scene.movers.clone(),
        }
    }

    /// Whether the segment from `origin` along `dir` to `tmax` (may be infinite) crosses the
    /// box of a moving object.
    #[inline]
    pub fn near_mover(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        self.movers
            .iter()
            .any(|b| segment_meets_box(origin, dir, tmax, b.min.into(), b.max.into()))
    }

    /// Whether `p` lies in the box of a moving object.
    #[inline]
    pub fn in_mover(&self, p: Vec3) -> bool {
        self.movers
            .iter()
            .any(|b| p.cmpge(b.min.into()).all() && p.cmple(b.max.into()).all())
    }

    /// Nearest hit with `tmin < t < tmax`.
    #[inline]
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
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

    /// Whether anything lies between `origin` and `origin + dir * tmax`.
    #[inline]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        !self.bvh.ray_traverse_miss(ray, |r, id| {
            intersect_triangle(origin, dir, &self.triangles[id], r.tmin, r.tmax)
        })
    }
}
