//! A scene for unit tests: the objects given, a white material (0) and a lamp (1), a camera
//! looking at the origin from the front.

use super::{Camera, Material, MaterialKind, Object, RenderDefaults, Scene};
use glam::Vec3;

/// `objects` (material 0 white, 1 a lamp) in a scene of their own.
pub(crate) fn room(objects: Vec<Object>) -> Scene {
    Scene {
        name: "room".into(),
        camera: Camera {
            eye: Vec3::new(0.0, 5.0, -15.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_deg: 40.0,
            width: 8,
            height: 8,
        },
        materials: vec![
            Material::new(
                "white",
                MaterialKind::Diffuse {
                    albedo: Vec3::splat(0.5),
                },
            ),
            Material::new(
                "lamp",
                MaterialKind::Light {
                    radiance: Vec3::ONE,
                    albedo: Vec3::ZERO,
                },
            ),
        ],
        objects,
        render: RenderDefaults::default(),
        moves: Vec::new(),
    }
}

/// An object named `name` of `material` made of `triangles`.
pub(crate) fn object(name: &str, material: usize, triangles: Vec<[Vec3; 3]>) -> Object {
    Object {
        name: name.into(),
        material,
        triangles,
        uvs: Vec::new(),
    }
}
