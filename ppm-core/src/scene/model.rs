//! The scene model: what a scene is, independent of any file format or backend.

use crate::layout::GpuBounds;
use crate::params::Estimator;
use glam::{Quat, Vec3};

/// A complete scene: camera, materials, named objects, render defaults and the move of frame 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Name shown in reports.
    pub name: String,
    /// Pinhole camera.
    pub camera: Camera,
    /// Materials, indexed by [`Object::material`].
    pub materials: Vec<Material>,
    /// Named triangle meshes in world space (frame 0).
    pub objects: Vec<Object>,
    /// Render settings the scene suggests; command-line options override them.
    pub render: RenderDefaults,
    /// Rigid moves that turn frame 0 into frame 1.
    pub moves: Vec<Move>,
}

/// Pinhole camera; `fov_deg` is the full vertical field of view.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point the camera looks at.
    pub look_at: Vec3,
    /// Up hint.
    pub up: Vec3,
    /// Full vertical field of view in degrees.
    pub fov_deg: f32,
    /// Default image width.
    pub width: u32,
    /// Default image height.
    pub height: u32,
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name objects refer to.
    pub name: String,
    /// What the surface does with light.
    pub kind: MaterialKind,
}

/// Surface behaviours (SCENES.md conventions).
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// Lambertian reflector.
    Diffuse {
        /// Reflectance per channel, in [0, 1].
        albedo: Vec3,
    },
    /// Perfect specular reflector.
    Mirror {
        /// Reflectance per channel, in [0, 1].
        reflectance: Vec3,
    },
    /// Smooth dielectric.
    Glass {
        /// Index of refraction, positive.
        ior: f32,
    },
    /// One-sided Lambertian area light, emitting along the triangle normal (`(v1-v0) x (v2-v0)`).
    Light {
        /// Emitted radiance `Le`, non-negative.
        radiance: Vec3,
        /// Diffuse reflectance of the light's surface (black by default).
        albedo: Vec3,
    },
}

impl MaterialKind {
    /// Whether the surface bends light (mirror or glass): eye and photon paths continue through it.
    pub fn is_specular(&self) -> bool {
        matches!(self, Self::Mirror { .. } | Self::Glass { .. })
    }
}

/// A named triangle mesh with one material.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Name moves refer to.
    pub name: String,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Triangles, vertices in world space.
    pub triangles: Vec<[Vec3; 3]>,
}

/// A rigid transform of one named object: rotation about the object's bounding-box centre, then
/// translation.
#[derive(Clone, Debug, PartialEq)]
pub struct Move {
    /// Index into [`Scene::objects`].
    pub object: usize,
    /// Translation.
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
}

/// Render settings a scene suggests.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderDefaults {
    /// Initial gather radius (not squared), in scene units.
    pub initial_radius: f32,
    /// Fraction of new photons kept per pass.
    pub alpha: f32,
    /// Photons emitted per photon pass.
    pub photons_per_pass: u32,
    /// Iterations (photon passes) in a render.
    pub passes: u32,
    /// The progressive estimator.
    pub estimator: Estimator,
}

impl Default for RenderDefaults {
    fn default() -> Self {
        Self {
            initial_radius: 1.0,
            alpha: 0.7,
            photons_per_pass: 100_000,
            passes: 16,
            estimator: Estimator::Sppm,
        }
    }
}

impl Scene {
    /// The scene as it stands in `frame`: frame 0 is as loaded, frame 1 has every move applied.
    pub fn at_frame(&self, frame: u32) -> Scene {
        self.at_time(if frame >= 1 { 1.0 } else { 0.0 })
    }

    /// The scene a fraction `t` of the way through its moves: translations scale by `t`,
    /// rotations turn by `t` of their angle (0 is frame 0, 1 is frame 1).
    pub fn at_time(&self, t: f32) -> Scene {
        let mut scene = self.clone();
        if t == 0.0 {
            return scene;
        }
        for m in &self.moves {
            let rotation = Quat::IDENTITY.slerp(m.rotation, t);
            let object = &mut scene.objects[m.object];
            let centre = object.bounds_centre();
            for tri in &mut object.triangles {
                for v in tri.iter_mut() {
                    *v = rotation * (*v - centre) + centre + m.translation * t;
                }
            }
        }
        scene
    }

    /// Vertices of every moving object, as posed in `self`.
    pub fn moving_vertices(&self) -> Vec<Vec3> {
        self.moves
            .iter()
            .flat_map(|m| self.objects[m.object].triangles.iter().flatten().copied())
            .collect()
    }

    /// A box per move that its object stays inside for every pose `at_time(t)`,
    /// `0 <= t <= 1`, of this (unmoved) scene, widened by `margin` on every side: for a
    /// translation, the box around both poses' boxes; with a rotation about the box centre,
    /// the centre's path widened by the object's largest distance from it.
    pub fn swept_bounds(&self, margin: f32) -> Vec<GpuBounds> {
        self.moves
            .iter()
            .map(|m| {
                let object = &self.objects[m.object];
                let (lo, hi) = object.bounds();
                let (lo, hi) = if m.rotation == Quat::IDENTITY {
                    (lo.min(lo + m.translation), hi.max(hi + m.translation))
                } else {
                    let centre = (lo + hi) * 0.5;
                    let reach = object
                        .triangles
                        .iter()
                        .flatten()
                        .map(|v| v.distance(centre))
                        .fold(0.0f32, f32::max);
                    let end = centre + m.translation;
                    (
                        centre.min(end) - Vec3::splat(reach),
                        centre.max(end) + Vec3::splat(reach),
                    )
                };
                GpuBounds::new(lo - Vec3::splat(margin), hi + Vec3::splat(margin))
            })
            .collect()
    }

    /// Index of the object called `name`.
    pub fn object_index(&self, name: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name == name)
    }

    /// Number of triangles over all objects.
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.triangles.len()).sum()
    }
}

impl Object {
    /// Smallest and largest corner of the axis-aligned bounding box of the object's vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for v in self.triangles.iter().flatten() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        (lo, hi)
    }

    /// Centre of the axis-aligned bounding box of the object's vertices.
    pub fn bounds_centre(&self) -> Vec3 {
        let (lo, hi) = self.bounds();
        (lo + hi) * 0.5
    }

    /// Total surface area.
    pub fn area(&self) -> f32 {
        self.triangles.iter().map(triangle_area).sum()
    }
}

/// Area of a triangle.
pub fn triangle_area(t: &[Vec3; 3]) -> f32 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// Splits a quad `(v0, v1, v2, v3)` into `(v0, v1, v2)` and `(v0, v2, v3)` (SCENES.md).
pub fn quad_triangles(q: [Vec3; 4]) -> [[Vec3; 3]; 2] {
    [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
}
