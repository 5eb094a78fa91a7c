//! Scenes with a closed-form answer, for tests that must be able to fail.

use glam::Vec3;
use ppm_core::scene::{
    Camera, Material, MaterialKind, Object, RenderDefaults, Scene, quad_triangles,
};

/// The furnace: a closed unit-half-size box whose every wall emits `le` (towards the inside)
/// and reflects diffusely with `albedo` (per channel), seen from its centre.
///
/// Uniform radiance `L` solves the rendering equation everywhere inside: each point sees only
/// walls of radiance `L`, so `L = le + albedo * L`, i.e. `L = le / (1 - albedo)`. Of that,
/// `le` is emission seen, `albedo * le` is direct light (one bounce), and the rest,
/// `albedo^2 * le / (1 - albedo)`, is what photons carry when direct light is explicit.
pub fn furnace(albedo: Vec3, le: f32) -> Scene {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let faces = [
        [
            c(-1., -1., -1.),
            c(1., -1., -1.),
            c(1., -1., 1.),
            c(-1., -1., 1.),
        ],
        [
            c(-1., 1., -1.),
            c(-1., 1., 1.),
            c(1., 1., 1.),
            c(1., 1., -1.),
        ],
        [
            c(-1., -1., -1.),
            c(-1., 1., -1.),
            c(1., 1., -1.),
            c(1., -1., -1.),
        ],
        [
            c(-1., -1., 1.),
            c(1., -1., 1.),
            c(1., 1., 1.),
            c(-1., 1., 1.),
        ],
        [
            c(-1., -1., -1.),
            c(-1., -1., 1.),
            c(-1., 1., 1.),
            c(-1., 1., -1.),
        ],
        [
            c(1., -1., -1.),
            c(1., 1., -1.),
            c(1., 1., 1.),
            c(1., -1., 1.),
        ],
    ];
    let triangles = faces
        .into_iter()
        .flat_map(quad_triangles)
        .map(|t| {
            // Emit towards the centre: flip any triangle whose normal points outwards.
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            if n.dot(t[0]) > 0.0 {
                [t[0], t[2], t[1]]
            } else {
                t
            }
        })
        .collect();
    Scene {
        name: format!("furnace(albedo={albedo:?}, le={le})"),
        camera: Camera {
            eye: Vec3::ZERO,
            look_at: Vec3::Z,
            up: Vec3::Y,
            fov_deg: 60.0,
            width: 32,
            height: 32,
        },
        materials: vec![Material {
            name: "glow".into(),
            kind: MaterialKind::Light {
                radiance: Vec3::splat(le),
                albedo,
            },
        }],
        objects: vec![Object {
            name: "walls".into(),
            material: 0,
            triangles,
        }],
        render: RenderDefaults {
            initial_radius: 0.1,
            alpha: 0.7,
            photons_per_pass: 50_000,
            passes: 16,
            ..RenderDefaults::default()
        },
        moves: Vec::new(),
    }
}

/// The furnace with a lossless mirror for its +z wall and a glass cube (ior 1.5, half-size 0.3)
/// at its centre, seen from `(0, 0, -0.8)`.
///
/// Neither a perfect mirror nor a smooth dielectric absorbs, so uniform radiance still solves
/// the rendering equation: every pixel, seen directly, in the mirror or through the glass, is
/// `le / (1 - albedo)` as in [`furnace`]. This pins the specular paths of eye and photon passes
/// (caustic photons included) to a closed form.
pub fn specular_furnace(albedo: Vec3, le: f32) -> Scene {
    let mut scene = furnace(albedo, le);
    scene.name = format!("specular-furnace(albedo={albedo:?}, le={le})");
    let walls = std::mem::take(&mut scene.objects[0].triangles);
    let (mirror, emitting): (Vec<_>, Vec<_>) = walls
        .into_iter()
        .partition(|t| t.iter().all(|v| v.z == 1.0));
    scene.objects[0].triangles = emitting;
    scene.materials.push(Material {
        name: "mirror".into(),
        kind: MaterialKind::Mirror {
            reflectance: Vec3::ONE,
        },
    });
    scene.materials.push(Material {
        name: "glass".into(),
        kind: MaterialKind::Glass { ior: 1.5 },
    });
    scene.objects.push(Object {
        name: "mirror".into(),
        material: 1,
        triangles: mirror,
    });
    // The furnace's walls face inwards; a closed glass body faces outwards, so the cube takes
    // them with their winding reversed.
    let cube = furnace(albedo, le).objects.remove(0).triangles;
    scene.objects.push(Object {
        name: "glass-cube".into(),
        material: 2,
        triangles: cube
            .into_iter()
            .map(|t| [t[0], t[2], t[1]].map(|v| v * 0.3))
            .collect(),
    });
    scene.camera.eye = Vec3::new(0.0, 0.0, -0.8);
    scene
}

/// Radiance everywhere inside [`furnace`], per channel.
pub fn furnace_radiance(albedo: Vec3, le: f32) -> Vec3 {
    Vec3::splat(le) / (Vec3::ONE - albedo)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_glass_cube_faces_outwards() {
        let scene = specular_furnace(Vec3::splat(0.5), 1.0);
        let cube = scene
            .objects
            .iter()
            .find(|o| o.name == "glass-cube")
            .unwrap();
        for t in &cube.triangles {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            assert!(n.dot(t[0] + t[1] + t[2]) > 0.0);
        }
    }

    #[test]
    fn furnace_walls_all_face_the_centre() {
        let scene = furnace(Vec3::splat(0.5), 1.0);
        for t in &scene.objects[0].triangles {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let centroid = (t[0] + t[1] + t[2]) / 3.0;
            assert!(n.dot(-centroid) > 0.0);
        }
    }
}
