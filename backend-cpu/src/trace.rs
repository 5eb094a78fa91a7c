//! Ray queries against the scene: obvhs traverses its BVH, ppm-core's test intersects triangles.
//! Public so that other CPU code over a compiled scene (the harness's reference path tracer)
//! asks the same questions of the same geometry.

use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::ray::{Ray, RayHit};
use ppm_core::compile::CompiledScene;
use ppm_core::geometry::{Frame, intersect_triangle, segment_meets_box};
use ppm_core::layout::{GpuBounds, GpuLight, GpuMaterial, GpuTriangle};
use ppm_core::textures::SurfaceTextures;
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

    /// The nearest hit with `0 < t` when it is on an emitting triangle, `None` otherwise: the
    /// emitters tested one by one, then one shadow query up to the nearest. Cheaper than
    /// [`Self::closest_hit`] when emitters are few and most rays meet none.
    #[inline]
    pub fn closest_hit_if_emitter(&self, origin: Vec3, dir: Vec3) -> Option<Hit> {
        let nearest = self
            .emitters
            .iter()
            .map(|&i| Hit {
                t: intersect_triangle(origin, dir, &self.triangles[i as usize], 0.0, f32::INFINITY),
                triangle: i,
            })
            .reduce(|a, b| if b.t < a.t { b } else { a })?;
        (nearest.t < f32::INFINITY && !self.occluded(origin, dir, nearest.t)).then_some(nearest)
    }

    /// The material of triangle `hit.triangle` at `position`, its colour scaled by its
    /// texture there, and that factor (one where it has none).
    #[inline]
    pub fn surface(&self, hit: &Hit, position: Vec3) -> (GpuMaterial, Vec3) {
        let tri = &self.triangles[hit.triangle as usize];
        let material = &self.materials[tri.material as usize];
        self.textures.shaded(material, hit.triangle, tri, position)
    }

    /// The frame of `material`'s lobe at `hit`, seen from the side of `facing`
    /// ([`SurfaceTextures::frame`](ppm_core::textures::SurfaceTextures::frame)).
    #[inline]
    pub fn frame(&self, hit: &Hit, material: &GpuMaterial, facing: Vec3) -> Frame {
        let tri = &self.triangles[hit.triangle as usize];
        self.textures.frame(material, hit.triangle, tri, facing)
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
