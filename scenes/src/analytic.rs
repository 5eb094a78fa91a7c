//! Scenes with a closed-form answer, for tests that must be able to fail.

use glam::{Quat, Vec3};
use ppm_core::scene::{
    Camera, Material, MaterialKind, Move, Object, RenderDefaults, Scene, quad_triangles,
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
        .map(facing_the_centre)
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
            texture: None,
        }],
        objects: vec![Object {
            name: "walls".into(),
            material: 0,
            triangles,
            uvs: Vec::new(),
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
        texture: None,
    });
    scene.materials.push(Material {
        name: "glass".into(),
        kind: MaterialKind::Glass {
            ior: 1.5,
            alpha: 0.0,
            alpha_v: 0.0,
        },
        texture: None,
    });
    scene.objects.push(Object {
        name: "mirror".into(),
        material: 1,
        triangles: mirror,
        uvs: Vec::new(),
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
        uvs: Vec::new(),
    });
    scene.camera.eye = Vec3::new(0.0, 0.0, -0.8);
    scene
}

/// The furnace half full of water: a glass surface of index `ior` across the whole box at
/// `y = -0.25`, the walls below it emitting `ior^2 * le` and those above `le` (all with
/// `albedo`), a lossless white block (albedo 1, no emission) under the water, seen from the air
/// above at `(0, 0.6, -0.9)`. Frame 1 moves the block by `(0.5, 0, -0.3)`, still under water.
///
/// Radiance is not invariant across a refractive boundary, `L / n^2` is, so the uniform field
/// `L = le / (1 - albedo)` in air and `ior^2 * L` in water solves the rendering equation: a
/// wall in water sees `ior^2 * L` everywhere and gives `ior^2 * le + albedo * ior^2 * L`; the
/// block gives back what it sees; looking up from the water, the surface shows
/// `R * ior^2 * L + T * ior^2 * L` (refraction into the denser medium multiplies radiance by
/// `ior^2`), and looking down from the air `R * L + T * ior^2 * L / ior^2`. Every pixel is
/// therefore `L`, whether it sees a wall above the water, the water's reflection, or a wall,
/// the floor or the block through the water, in both frames. A renderer that forgets the
/// `1 / ior^2` of radiance refracted out of the water shows the pixels under water
/// `ior^2` times too bright.
pub fn water_furnace(albedo: Vec3, le: f32, ior: f32) -> Scene {
    const LEVEL: f32 = -0.25;
    let c = Vec3::new;
    let side_walls = |y0: f32, y1: f32| {
        [
            [
                c(-1., y0, -1.),
                c(1., y0, -1.),
                c(1., y1, -1.),
                c(-1., y1, -1.),
            ],
            [c(-1., y0, 1.), c(1., y0, 1.), c(1., y1, 1.), c(-1., y1, 1.)],
            [
                c(-1., y0, -1.),
                c(-1., y0, 1.),
                c(-1., y1, 1.),
                c(-1., y1, -1.),
            ],
            [c(1., y0, -1.), c(1., y0, 1.), c(1., y1, 1.), c(1., y1, -1.)],
        ]
    };
    let horizontal = |y: f32| [c(-1., y, -1.), c(-1., y, 1.), c(1., y, 1.), c(1., y, -1.)];
    let inwards = |quads: Vec<[Vec3; 4]>| -> Vec<[Vec3; 3]> {
        quads
            .into_iter()
            .flat_map(quad_triangles)
            .map(facing_the_centre)
            .collect()
    };
    let mut above = side_walls(LEVEL, 1.0).to_vec();
    above.push(horizontal(1.0));
    let mut below = side_walls(-1.0, LEVEL).to_vec();
    below.push(horizontal(-1.0));
    let glow = |name: &str, radiance: f32| Material {
        name: name.into(),
        kind: MaterialKind::Light {
            radiance: Vec3::splat(radiance),
            albedo,
        },
        texture: None,
    };
    let object = |name: &str, material, triangles| Object {
        name: String::from(name),
        material,
        triangles,
        uvs: Vec::new(),
    };
    let mut scene = furnace(albedo, le);
    scene.name = format!("water-furnace(albedo={albedo:?}, le={le}, ior={ior})");
    scene.materials = vec![
        glow("glow", le),
        glow("glow-under-water", ior * ior * le),
        Material {
            name: "water".into(),
            kind: MaterialKind::Glass {
                ior,
                alpha: 0.0,
                alpha_v: 0.0,
            },
            texture: None,
        },
        Material {
            name: "lossless-white".into(),
            kind: MaterialKind::Diffuse { albedo: Vec3::ONE },
            texture: None,
        },
    ];
    scene.objects = vec![
        object("walls-above", 0, inwards(above)),
        object("walls-below", 1, inwards(below)),
        // Its normal points up, into the air: a path from above enters the water.
        object(
            "water-surface",
            2,
            quad_triangles(horizontal(LEVEL)).to_vec(),
        ),
        object(
            "block",
            3,
            box_triangles(c(-0.5, -0.9, 0.1), c(-0.1, -0.5, 0.5)),
        ),
    ];
    scene.camera.eye = c(0.0, 0.6, -0.9);
    scene.camera.look_at = c(0.0, -0.7, 0.6);
    scene.render.initial_radius = 0.05;
    scene.moves = vec![Move {
        object: 3,
        translation: c(0.5, 0.0, -0.3),
        rotation: Quat::IDENTITY,
    }];
    scene
}

/// The closed box from `lo` to `hi`, its twelve triangles facing outwards.
pub fn box_triangles(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let (a, b) = (lo, hi);
    [
        [
            c(a.x, a.y, a.z),
            c(b.x, a.y, a.z),
            c(b.x, a.y, b.z),
            c(a.x, a.y, b.z),
        ],
        [
            c(a.x, b.y, a.z),
            c(a.x, b.y, b.z),
            c(b.x, b.y, b.z),
            c(b.x, b.y, a.z),
        ],
        [
            c(a.x, a.y, a.z),
            c(a.x, b.y, a.z),
            c(b.x, b.y, a.z),
            c(b.x, a.y, a.z),
        ],
        [
            c(a.x, a.y, b.z),
            c(b.x, a.y, b.z),
            c(b.x, b.y, b.z),
            c(a.x, b.y, b.z),
        ],
        [
            c(a.x, a.y, a.z),
            c(a.x, a.y, b.z),
            c(a.x, b.y, b.z),
            c(a.x, b.y, a.z),
        ],
        [
            c(b.x, a.y, a.z),
            c(b.x, b.y, a.z),
            c(b.x, b.y, b.z),
            c(b.x, a.y, b.z),
        ],
    ]
    .into_iter()
    .flat_map(quad_triangles)
    .collect()
}

/// `t` wound so that its normal points towards the origin, where the furnaces' walls emit.
fn facing_the_centre(t: [Vec3; 3]) -> [Vec3; 3] {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    if n.dot(t[0] + t[1] + t[2]) > 0.0 {
        [t[0], t[2], t[1]]
    } else {
        t
    }
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
    fn the_water_furnace_has_its_surface_facing_the_air_and_its_block_under_water() {
        let scene = water_furnace(Vec3::splat(0.5), 1.0, 1.8);
        let object = |name: &str| scene.objects.iter().find(|o| o.name == name).unwrap();
        for t in &object("water-surface").triangles {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            assert!(n.y > 0.0 && n.x == 0.0 && n.z == 0.0);
        }
        for frame in [0, 1] {
            let moved = scene.at_frame(frame);
            let block = moved.objects.iter().find(|o| o.name == "block").unwrap();
            for v in block.triangles.iter().flatten() {
                assert!(
                    v.y < -0.25 && v.abs().max_element() < 1.0,
                    "frame {frame}: {v}"
                );
            }
        }
        for t in &object("walls-below").triangles {
            assert!(t.iter().all(|v| v.y <= -0.25));
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
