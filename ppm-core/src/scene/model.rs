//! The scene model: what a scene is, independent of any file format or backend.

use super::texture::Texture;
use crate::params::Estimator;
use glam::{Quat, Vec2, Vec3};
use std::sync::Arc;

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

impl Camera {
    /// The camera turned by `degrees` about the up hint through its look-at point, then
    /// brought `nearer` of the way to it (0.1: a tenth nearer; negative backs away).
    pub fn orbited(&self, degrees: f32, nearer: f32) -> Camera {
        let turn = Quat::from_axis_angle(self.up.normalize_or(Vec3::Y), degrees.to_radians());
        Camera {
            eye: self.look_at + turn * (self.eye - self.look_at) * (1.0 - nearer),
            ..self.clone()
        }
    }
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name objects refer to.
    pub name: String,
    /// What the surface does with light.
    pub kind: MaterialKind,
    /// An image that scales the kind's colour (a diffuse albedo, a mirror's or conductor's
    /// reflectance) point by point; `None` for a uniform colour. Glass and lights take none.
    pub texture: Option<Arc<Texture>>,
}

impl Material {
    /// A material of uniform colour.
    pub fn new(name: impl Into<String>, kind: MaterialKind) -> Self {
        Self {
            name: name.into(),
            kind,
            texture: None,
        }
    }
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
    /// Dielectric: Fresnel reflection and refraction of index `ior`, on GGX microfacets of
    /// roughness `alpha` along the surface's tangent and `alpha_v` across it (both 0: smooth;
    /// docs/materials.md, "Anisotropic roughness").
    Glass {
        /// Index of refraction, positive.
        ior: f32,
        /// GGX roughness along the tangent (the direction of increasing `u`), in [0, 1].
        alpha: f32,
        /// GGX roughness across the tangent, in [0, 1]; `alpha` when isotropic.
        alpha_v: f32,
    },
    /// Metal: Fresnel reflection of complex index `eta + i k` (per channel), times
    /// `reflectance`, on GGX microfacets of roughness `alpha` along the surface's tangent and
    /// `alpha_v` across it (both 0: smooth).
    Conductor {
        /// Real part of the index, non-negative.
        eta: Vec3,
        /// Imaginary part (absorption), non-negative.
        k: Vec3,
        /// Factor on the Fresnel term, in [0, 1] (Mitsuba 3's `specular_reflectance`).
        reflectance: Vec3,
        /// GGX roughness along the tangent, in [0, 1]: the microfacet slopes' spread.
        alpha: f32,
        /// GGX roughness across the tangent, in [0, 1]; `alpha` when isotropic.
        alpha_v: f32,
    },
    /// A diffuse base under a clear dielectric coat (Mitsuba 3's `plastic` and `roughplastic`,
    /// pbrt-v4's `coateddiffuse` without a medium in the layer): the coat reflects as a
    /// smooth or GGX-rough dielectric of index `ior`, and light it lets through reaches the
    /// base, reflecting between base and coat before it leaves (docs/materials.md, "Coated
    /// diffuse").
    Coated {
        /// The base's reflectance per channel, in [0, 1].
        albedo: Vec3,
        /// The coat's index of refraction over the outside's, above 1.
        ior: f32,
        /// GGX roughness of the coat, in [0, 1] (0: smooth).
        alpha: f32,
        /// Whether light reflected inside the coat meets the base's colour at each return
        /// (`albedo / (1 - albedo F_int)`, Mitsuba 3's `nonlinear`, what pbrt-v4's random
        /// walk in the layer computes) rather than once (`albedo / (1 - F_int)`).
        nonlinear: bool,
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
    /// The kind with its colour set to one where a texture gives it (a diffuse albedo, a
    /// coated base's, a mirror's or conductor's reflectance), as the importers read a
    /// textured reflectance; any other kind as is.
    pub fn white_under_texture(self) -> Self {
        match self {
            Self::Diffuse { .. } => Self::Diffuse { albedo: Vec3::ONE },
            Self::Mirror { .. } => Self::Mirror {
                reflectance: Vec3::ONE,
            },
            Self::Conductor {
                eta,
                k,
                alpha,
                alpha_v,
                ..
            } => Self::Conductor {
                eta,
                k,
                reflectance: Vec3::ONE,
                alpha,
                alpha_v,
            },
            Self::Coated {
                ior,
                alpha,
                nonlinear,
                ..
            } => Self::Coated {
                albedo: Vec3::ONE,
                ior,
                alpha,
                nonlinear,
            },
            kind => kind,
        }
    }

    /// Whether the lobe's roughness differs along and across the surface's tangent (a
    /// conductor's or glass's), so that the surface's texture coordinates orient it.
    pub fn is_anisotropic(&self) -> bool {
        match self {
            Self::Conductor { alpha, alpha_v, .. } | Self::Glass { alpha, alpha_v, .. } => {
                alpha != alpha_v
            }
            _ => false,
        }
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
    /// Texture coordinates of each triangle's vertices, or empty: a triangle without them
    /// reads `(0, 0)`, `(1, 0)`, `(1, 1)` at its vertices (pbrt-v4's default).
    pub uvs: Vec<[Vec2; 3]>,
}

/// A rigid transform of one named object: rotation about the object's bounding-box centre, then
/// translation.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
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
            // Frame 1 applies each move exactly as declared (as a path of them does).
            let partial = Move {
                rotation: Quat::IDENTITY.slerp(m.rotation, t),
                translation: m.translation * t,
                ..*m
            };
            scene.apply(if t == 1.0 { m } else { &partial });
        }
        scene
    }

    /// Moves one object rigidly: rotation about the centre of its bounding box as it stands,
    /// then translation. Any move, declared in the scene or not.
    pub fn apply(&mut self, m: &Move) {
        let object = &mut self.objects[m.object];
        let centre = object.bounds_centre();
        for v in object.triangles.iter_mut().flatten() {
            *v = m.rotation * (*v - centre) + centre + m.translation;
        }
    }

    /// Why `m` cannot be applied to this pose, if it cannot: an object that does not exist, a
    /// translation or rotation that is not finite (or not a unit quaternion), or vertices
    /// beyond [`MAX_COORDINATE`](super::MAX_COORDINATE) afterwards.
    pub fn check_move(&self, m: &Move) -> Result<(), String> {
        let Some(object) = self.objects.get(m.object) else {
            return Err(format!(
                "object {} does not exist (the scene has {})",
                m.object,
                self.objects.len()
            ));
        };
        if !m.translation.is_finite() || !m.rotation.is_finite() {
            return Err(format!(
                "{}: translation {} or rotation {} is not finite",
                object.name, m.translation, m.rotation
            ));
        }
        if (m.rotation.length() - 1.0).abs() > 1e-3 {
            return Err(format!(
                "{}: rotation {} is not a unit quaternion",
                object.name, m.rotation
            ));
        }
        let (lo, hi) = object.bounds();
        let reach = (hi - lo).length() + m.translation.abs().max_element();
        if lo.abs().max(hi.abs()).max_element() + reach > super::MAX_COORDINATE {
            return Err(format!(
                "{}: the move takes its vertices beyond {:e}",
                object.name,
                super::MAX_COORDINATE
            ));
        }
        Ok(())
    }

    /// The objects whose geometry differs between `self` and `other`, two poses of one
    /// scene (the same objects in the same order).
    pub fn changed_objects(&self, other: &Scene) -> Vec<usize> {
        self.objects
            .iter()
            .zip(&other.objects)
            .enumerate()
            .filter(|(_, (a, b))| a.triangles != b.triangles)
            .map(|(i, _)| i)
            .collect()
    }

    /// [`Self::changed_objects`] among `objects` alone (the others known to be the same).
    pub fn changed_among(&self, other: &Scene, objects: &[usize]) -> Vec<usize> {
        let mut changed: Vec<usize> = objects
            .iter()
            .copied()
            .filter(|&o| match (self.objects.get(o), other.objects.get(o)) {
                (Some(a), Some(b)) => a.triangles != b.triangles,
                _ => false,
            })
            .collect();
        changed.sort_unstable();
        changed.dedup();
        changed
    }

    /// Smallest and largest corner of the box around every object.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.objects
            .iter()
            .filter(|o| !o.triangles.is_empty())
            .map(Object::bounds)
            .fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
            )
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

/// Whether any triangle of the scene has zero area (reported, not rejected: they are never hit).
pub fn degenerate_triangle_count(scene: &Scene) -> usize {
    scene
        .objects
        .iter()
        .flat_map(|o| &o.triangles)
        .filter(|t| triangle_area(t) == 0.0)
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::testing::{object, room};

    /// Among the objects a move names, the changed ones are those `changed_objects` finds:
    /// an object moved by nothing, or named twice, is not counted.
    #[test]
    fn the_changed_among_named_objects_are_the_changed_objects() {
        let tile = |x: f32| {
            quad_triangles([
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x, 0.0, 1.0),
                Vec3::new(x + 1.0, 0.0, 1.0),
                Vec3::new(x + 1.0, 0.0, 0.0),
            ])
            .to_vec()
        };
        let before = room(vec![object("a", 0, tile(0.0)), object("b", 0, tile(2.0))]);
        let mut after = before.clone();
        let shift = |object: usize, x: f32| Move {
            object,
            translation: Vec3::new(x, 0.0, 0.0),
            rotation: glam::Quat::IDENTITY,
        };
        after.apply(&shift(1, 0.5));
        after.apply(&shift(0, 0.0));
        assert_eq!(before.changed_objects(&after), vec![1]);
        assert_eq!(before.changed_among(&after, &[1, 0, 1]), vec![1]);
        assert_eq!(before.changed_among(&after, &[0]), Vec::<usize>::new());
    }
}
