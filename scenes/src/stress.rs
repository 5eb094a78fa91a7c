//! The stress family (docs/stability.md): small scenes that push the renderer into corners,
//! each saying in one line what it stresses, and what the result must be: a closed form where
//! one exists, or at least finite statistics.

use crate::analytic::{box_triangles, furnace, specular_furnace, water_furnace};
use glam::Vec3;
use ppm_core::layout::HitPoint;
use ppm_core::params::{MoveMode, RenderParams};
use ppm_core::scene::{
    Material, MaterialKind, Object, Scene, Texture, TextureFilter, quad_triangles,
};
use std::sync::Arc;

/// What a case must produce besides finite, in-range statistics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Expected {
    /// Only the invariants (finite fields, tau >= 0, 0 < r2 <= r2_initial, n >= 0).
    Finite,
    /// The image's mean radiance within `tolerance` (relative) of `radiance`.
    Radiance {
        /// The closed-form value.
        radiance: f32,
        /// Relative tolerance.
        tolerance: f32,
    },
    /// Either a finite image or a pass error naming a non-finite value: the case sits at the
    /// f32 limit, where refusing is the honest answer.
    FiniteOrRefused,
}

/// A move to run through compensation photons (docs/algorithm.md 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveStress {
    /// Photons per compensation pass (two passes each way).
    pub region_photons: u32,
    /// The compensating mode.
    pub mode: MoveMode,
}

/// A ready-to-render case.
pub struct StressSetup {
    /// The scene.
    pub scene: Scene,
    /// Its render settings (small, for the test suite).
    pub params: RenderParams,
    /// What must come out.
    pub expected: Expected,
    /// Overwrites every valid hit point after direct light: a state seeded into the buffers.
    pub seed: Option<fn(&mut HitPoint)>,
    /// Renders frame 0, moves with compensation photons, continues: for moving scenes.
    pub moves: Option<MoveStress>,
}

/// One named case.
pub struct StressCase {
    /// Name on the command line.
    pub name: &'static str,
    /// What it stresses, in one line.
    pub stresses: &'static str,
    /// Builds it.
    pub build: fn() -> StressSetup,
}

fn small(scene: &Scene) -> RenderParams {
    let mut p = RenderParams::for_scene(scene);
    p.width = 16;
    p.height = 16;
    p.passes = 4;
    p.photons_per_pass = 20_000;
    // Per iteration with sppm: 64 over the four iterations.
    p.direct_samples = 16;
    p
}

/// The grey furnace (albedo `rho`, Le `le`) scaled by `scale`, radius scaled alike.
fn furnace_case(rho: f32, le: f32, scale: f32, tolerance: f32) -> StressSetup {
    let mut scene = furnace(Vec3::splat(rho), le);
    for v in scene
        .objects
        .iter_mut()
        .flat_map(|o| o.triangles.iter_mut())
        .flatten()
    {
        *v *= scale;
    }
    scene.camera.eye *= scale;
    scene.camera.look_at *= scale;
    let mut params = small(&scene);
    params.initial_radius = 0.1 * scale;
    StressSetup {
        scene,
        params,
        expected: Expected::Radiance {
            radiance: le / (1.0 - rho),
            tolerance,
        },
        seed: None,
        moves: None,
    }
}

fn with<F: FnOnce(&mut StressSetup)>(mut s: StressSetup, f: F) -> StressSetup {
    f(&mut s);
    s
}

fn cornell() -> Scene {
    crate::cornell_box_file().expect("the shipped cornell-box parses")
}

fn cornell_case(
    expected: Expected,
    edit: impl FnOnce(&mut Scene, &mut RenderParams),
) -> StressSetup {
    let mut scene = cornell();
    let mut params = small(&scene);
    edit(&mut scene, &mut params);
    StressSetup {
        scene,
        params,
        expected,
        seed: None,
        moves: None,
    }
}

fn add_object(scene: &mut Scene, name: &str, kind: MaterialKind, triangles: Vec<[Vec3; 3]>) {
    scene.materials.push(Material {
        name: format!("{name}-material"),
        kind,
        texture: None,
    });
    scene.objects.push(Object {
        name: name.into(),
        material: scene.materials.len() - 1,
        triangles,
        uvs: Vec::new(),
    });
}

const WHITE: MaterialKind = MaterialKind::Diffuse {
    albedo: Vec3::splat(0.7),
};

/// Every stress case, in the order `ppm stress` runs them.
pub const STRESS: &[StressCase] = &[
    StressCase {
        name: "scale-1e-4",
        stresses: "the furnace at 1e-4 scene units: r2 near 1e-10, radiance must not change",
        build: || furnace_case(0.5, 1.0, 1e-4, 0.05),
    },
    StressCase {
        name: "scale-1",
        stresses: "the furnace at unit scale: the reference for the scale invariance",
        build: || furnace_case(0.5, 1.0, 1.0, 0.05),
    },
    StressCase {
        name: "scale-1e4",
        stresses: "the furnace at 1e4 scene units: pi * r2 * emitted past 1e15",
        build: || furnace_case(0.5, 1.0, 1e4, 0.05),
    },
    StressCase {
        name: "power-1e-20",
        stresses: "light radiance 1e-20: flux near the bottom of f32's normal range",
        build: || furnace_case(0.5, 1e-20, 1.0, 0.05),
    },
    StressCase {
        name: "power-1e20",
        stresses: "light radiance 1e20: the image scales linearly",
        build: || furnace_case(0.5, 1e20, 1.0, 0.05),
    },
    StressCase {
        name: "power-1e30",
        stresses: "light radiance 1e30: photon power 1e32, summed flux within 1e6 of f32's limit",
        build: || furnace_case(0.5, 1e30, 1.0, 0.05),
    },
    StressCase {
        name: "power-f32-limit",
        stresses: "light radiance 3e37: a photon's power overflows f32; refuse clearly, never NaN",
        build: || {
            with(furnace_case(0.5, 3e37, 1.0, 0.05), |s| {
                s.expected = Expected::FiniteOrRefused
            })
        },
    },
    StressCase {
        name: "alpha-0.01",
        stresses: "alpha 0.01: the radius collapses fastest, counts grow slowest",
        build: || with(furnace_case(0.5, 1.0, 1.0, 0.08), |s| s.params.alpha = 0.01),
    },
    StressCase {
        name: "alpha-0.99",
        stresses: "alpha 0.99: the shrink ratio within 1e-2 of one",
        build: || with(furnace_case(0.5, 1.0, 1.0, 0.05), |s| s.params.alpha = 0.99),
    },
    StressCase {
        name: "furnace-0.99",
        stresses: "albedo 0.99: photons bounce ~100 times, L = 100 Le",
        build: || {
            with(furnace_case(0.99, 1.0, 1.0, 0.08), |s| {
                s.params.max_photon_depth = 4096;
                s.params.photons_per_pass = 5_000;
            })
        },
    },
    StressCase {
        name: "coincident-triangles",
        stresses: "the Cornell floor and back wall twice, coincident: ties in the closest hit",
        build: || {
            cornell_case(Expected::Finite, |scene, _| {
                for name in ["floor", "back-wall"] {
                    let i = scene.object_index(name).expect("cornell-box object");
                    let copy = scene.objects[i].triangles.clone();
                    scene.objects[i].triangles.extend(copy);
                }
            })
        },
    },
    StressCase {
        name: "degenerate-triangles",
        stresses: "zero-area and sliver triangles floating in the furnace: never hit, never NaN",
        build: || {
            with(furnace_case(0.5, 1.0, 1.0, 0.05), |s| {
                let v = Vec3::new;
                s.scene.objects[0].triangles.extend([
                    [v(0.1, 0.1, 0.5), v(0.1, 0.1, 0.5), v(0.2, 0.3, 0.5)],
                    [v(-0.5, 0.0, 0.6), v(0.5, 0.0, 0.6), v(0.0, 0.0, 0.6)],
                    [v(-0.5, 0.2, 0.7), v(0.5, 0.2, 0.7), v(0.0, 0.2 + 1e-7, 0.7)],
                ]);
            })
        },
    },
    StressCase {
        name: "glass-ior-1.0",
        stresses: "glass with ior 1: refraction without bending, Fresnel zero",
        build: || specular_case(1.0),
    },
    StressCase {
        name: "glass-ior-3.0",
        stresses: "glass with ior 3: strong reflection and wide total internal reflection",
        build: || specular_case(3.0),
    },
    StressCase {
        name: "conductor-alpha-0",
        stresses: "a smooth lossless conductor for the furnace's mirror: its Fresnel term is one at every angle",
        build: || conductor_case((0.0, 0.0)),
    },
    StressCase {
        name: "conductor-alpha-1",
        stresses: "the roughest conductor: half its visible microfacets reflect below the surface, ending paths",
        build: || conductor_case((1.0, 1.0)),
    },
    StressCase {
        name: "conductor-alpha-1-0",
        stresses: "a conductor roughest along its tangent and smooth across it: a lobe one ten-thousandth as wide one way as the other",
        build: || conductor_case((1.0, 0.0)),
    },
    StressCase {
        name: "glass-alpha-1",
        stresses: "the roughest glass cube: refractions and reflections off microfacets that lean as far as they can, some leaving on the wrong side",
        build: || rough_glass_case((1.0, 1.0)),
    },
    StressCase {
        name: "glass-alpha-0-1",
        stresses: "a glass cube smooth along its tangent and roughest across it",
        build: || rough_glass_case((0.0, 1.0)),
    },
    StressCase {
        name: "coat-alpha-0",
        stresses: "a white base under a smooth coat for the furnace's mirror: every pixel stays 2, light returning under the coat included",
        build: || coated_case(0.0),
    },
    StressCase {
        name: "coat-alpha-1",
        stresses: "the roughest coat: half its reflection leaves below the surface, and its transmittance table spans all of it",
        build: || coated_case(1.0),
    },
    StressCase {
        name: "texture-1x1",
        stresses: "a mirror's reflectance read from a one-texel image: every lookup wraps onto it",
        build: || textured_mirror_case(1),
    },
    StressCase {
        name: "texture-16k",
        stresses: "a 16384 x 16384 image: reduced to 4096 a side as it is read, a 128 MiB texel buffer",
        build: || textured_mirror_case(16384),
    },
    StressCase {
        name: "water-furnace",
        stresses: "visible points under water seen from the air: radiance refracted out divides by ior^2",
        build: || water_case(None),
    },
    StressCase {
        name: "water-furnace-local-move",
        stresses: "a block moves under water, local mode: the dynamic passes' eye paths refract alike",
        build: || {
            water_case(Some(MoveStress {
                region_photons: 20_000,
                mode: MoveMode::Local,
            }))
        },
    },
    StressCase {
        name: "hall-of-mirrors",
        stresses: "two facing lossless mirrors: eye chains past the depth limit end empty, finitely",
        build: || {
            with(furnace_case(0.5, 1.0, 1.0, 0.0), |s| {
                let walls = std::mem::take(&mut s.scene.objects[0].triangles);
                let (mirrors, rest): (Vec<_>, Vec<_>) = walls
                    .into_iter()
                    .partition(|t| t.iter().all(|v| v.z == t[0].z));
                s.scene.objects[0].triangles = rest;
                add_object(
                    &mut s.scene,
                    "mirrors",
                    MaterialKind::Mirror {
                        reflectance: Vec3::ONE,
                    },
                    mirrors,
                );
                s.params.max_eye_depth = 8;
                s.expected = Expected::Finite;
            })
        },
    },
    StressCase {
        name: "grazing-view",
        stresses: "the floor seen at 89.9 degrees from its normal",
        build: || {
            cornell_case(Expected::Finite, |scene, _| {
                scene.camera.eye = Vec3::new(278.0, 0.5, -800.0);
                scene.camera.look_at =
                    Vec3::new(278.0, 0.5 - 1359.2 * (0.1f32).to_radians().tan(), 559.2);
            })
        },
    },
    StressCase {
        name: "grazing-light",
        stresses: "a light tilted to 89.9 degrees: emission almost parallel to its plane",
        build: || {
            cornell_case(Expected::Finite, |scene, _| {
                let light = scene.object_index("light").expect("cornell has a light");
                let centre = scene.objects[light].bounds_centre();
                let tilt = glam::Quat::from_rotation_x(89.9f32.to_radians());
                for v in scene.objects[light].triangles.iter_mut().flatten() {
                    *v = tilt * (*v - centre) + centre - Vec3::new(0.0, 60.0, 0.0);
                }
            })
        },
    },
    StressCase {
        name: "camera-inside-object",
        stresses: "the camera inside a closed box: every eye ray meets its inside",
        build: || {
            cornell_case(Expected::Finite, |scene, _| {
                let eye = scene.camera.eye;
                add_object(
                    scene,
                    "cage",
                    WHITE,
                    box_triangles(eye - Vec3::splat(10.0), eye + Vec3::splat(10.0)),
                );
            })
        },
    },
    StressCase {
        name: "thin-slab",
        stresses: "a slab 1e-3 mm thick: self-intersection at both faces",
        build: || {
            cornell_case(Expected::Finite, |scene, _| {
                add_object(
                    scene,
                    "slab",
                    WHITE,
                    box_triangles(
                        Vec3::new(100.0, 300.0, 100.0),
                        Vec3::new(450.0, 300.001, 450.0),
                    ),
                );
            })
        },
    },
    StressCase {
        name: "empty-view",
        stresses: "the camera looks away from everything: an all-empty hit-point buffer",
        build: || {
            cornell_case(Expected::Finite, |scene, _| {
                scene.camera.look_at = Vec3::new(278.0, 273.0, -2000.0);
            })
        },
    },
    StressCase {
        name: "light-blocked",
        stresses: "the light sealed in a box: photons deposit only inside it",
        build: || {
            cornell_case(Expected::Finite, |scene, _| {
                add_object(
                    scene,
                    "seal",
                    WHITE,
                    box_triangles(
                        Vec3::new(200.0, 500.0, 210.0),
                        Vec3::new(360.0, 548.75, 350.0),
                    ),
                );
            })
        },
    },
    StressCase {
        name: "image-1x1",
        stresses: "a one-pixel image",
        build: || {
            cornell_case(Expected::Finite, |_, p| {
                p.width = 1;
                p.height = 1;
            })
        },
    },
    StressCase {
        name: "image-1x4096",
        stresses: "a 1 x 4096 image: one pixel wide, aspect 1/4096",
        build: || {
            cornell_case(Expected::Finite, |_, p| {
                p.width = 1;
                p.height = 4096;
                p.photons_per_pass = 5_000;
            })
        },
    },
    StressCase {
        name: "tiny-light-caustic",
        stresses: "the wedding band lit by a light 0.01 wide: a caustic from a near-point source",
        build: || {
            let mut scene = crate::canonical::wedding_band().expect("wedding-band builds");
            let light = scene
                .object_index("light")
                .expect("wedding-band has a light");
            let centre = scene.objects[light].bounds_centre();
            for v in scene.objects[light].triangles.iter_mut().flatten() {
                *v = centre + (*v - centre) * 0.0025;
            }
            let mut params = small(&scene);
            params.width = 24;
            params.height = 24;
            StressSetup {
                scene,
                params,
                expected: Expected::Finite,
                seed: None,
                moves: None,
            }
        },
    },
    StressCase {
        name: "count-past-2^24",
        stresses: "n seeded at 3.4e7, past 2^24: n + alpha*M rounds back to n",
        build: || {
            with(furnace_case(0.5, 1.0, 1.0, 0.0), |s| {
                s.expected = Expected::Finite;
                s.seed = Some(|hp| {
                    hp.n = 3.4e7;
                    hp.emitted = 1e9;
                    hp.tau = [2e5; 3];
                });
            })
        },
    },
    StressCase {
        name: "emitted-near-2^31",
        stresses: "emitted seeded at 2.1e9 photons: the normaliser's ulp is 256",
        build: || {
            with(furnace_case(0.5, 1.0, 1.0, 0.0), |s| {
                s.expected = Expected::Finite;
                s.seed = Some(|hp| {
                    hp.n = 1e4;
                    hp.emitted = 2.1e9;
                    hp.tau = [5e5; 3];
                });
            })
        },
    },
    StressCase {
        name: "r2-underflow",
        stresses: "r2 seeded at 1e-38 (a million passes of shrinking): density past f32's range",
        build: || {
            with(furnace_case(0.5, 1.0, 1.0, 0.0), |s| {
                s.expected = Expected::Finite;
                s.seed = Some(|hp| {
                    hp.r2 = 1e-38;
                    hp.n = 1e6;
                    hp.emitted = 1e6;
                    hp.tau = [1.0; 3];
                });
            })
        },
    },
    StressCase {
        name: "negative-outnumbers-n",
        stresses: "compensation photons standing for ~5x what hit points hold: emptied, then refilled",
        build: || {
            move_case(
                MoveStress {
                    region_photons: 400_000,
                    mode: MoveMode::Area,
                },
                2_000,
            )
        },
    },
    StressCase {
        name: "region-thesis-mode",
        stresses: "the thesis's point-light region with raw counts and unweighted guides",
        build: || {
            move_case(
                MoveStress {
                    region_photons: 20_000,
                    mode: MoveMode::Thesis,
                },
                20_000,
            )
        },
    },
    StressCase {
        name: "region-degenerate-line",
        stresses: "a needle moving along the light's axis: the point light sees it as a line",
        build: || {
            let mut s = move_case(
                MoveStress {
                    region_photons: 20_000,
                    mode: MoveMode::Thesis,
                },
                20_000,
            );
            let needle = vec![[
                Vec3::new(278.0, 300.0, 279.5),
                Vec3::new(278.0, 200.0, 279.5),
                Vec3::new(278.0, 250.0, 279.5),
            ]];
            replace_mover(&mut s.scene, needle, Vec3::new(0.0, -50.0, 0.0));
            s
        },
    },
    StressCase {
        name: "region-covers-light",
        stresses: "a plate just under the light: the region spans the light's whole view",
        build: || {
            let mut s = move_case(
                MoveStress {
                    region_photons: 20_000,
                    mode: MoveMode::Area,
                },
                20_000,
            );
            let plate = quad_triangles([
                Vec3::new(100.0, 540.0, 100.0),
                Vec3::new(100.0, 540.0, 460.0),
                Vec3::new(460.0, 540.0, 460.0),
                Vec3::new(460.0, 540.0, 100.0),
            ]);
            replace_mover(&mut s.scene, plate.to_vec(), Vec3::new(0.0, -10.0, 0.0));
            s
        },
    },
    StressCase {
        name: "region-unbounded",
        stresses: "a box around the light moves: no rectangle bounds it, the move restarts",
        build: || {
            let mut s = move_case(
                MoveStress {
                    region_photons: 20_000,
                    mode: MoveMode::Area,
                },
                20_000,
            );
            let cage = box_triangles(
                Vec3::new(190.0, 520.0, 200.0),
                Vec3::new(366.0, 548.78, 360.0),
            );
            replace_mover(&mut s.scene, cage, Vec3::new(1.0, 0.0, 0.0));
            s
        },
    },
    StressCase {
        name: "difference-around-light",
        stresses: "difference mode moves a hood (open below) around the light: no rectangle, no restart",
        build: || {
            let mut s = move_case(
                MoveStress {
                    region_photons: 20_000,
                    mode: MoveMode::Difference,
                },
                20_000,
            );
            let mut hood = box_triangles(
                Vec3::new(190.0, 520.0, 200.0),
                Vec3::new(366.0, 548.78, 360.0),
            );
            hood.drain(..2); // the bottom face: light leaves through it
            replace_mover(&mut s.scene, hood, Vec3::new(1.0, 0.0, 0.0));
            s
        },
    },
];

/// The Cornell box whose tall block moves, run through a compensated move.
fn move_case(moves: MoveStress, photons: u32) -> StressSetup {
    let scene = cornell();
    let mut params = small(&scene);
    params.photons_per_pass = photons;
    params.passes = 2;
    StressSetup {
        scene,
        params,
        expected: Expected::Finite,
        seed: None,
        moves: Some(moves),
    }
}

/// Makes `triangles` the moving object, moved by `translation` in frame 1.
fn replace_mover(scene: &mut Scene, triangles: Vec<[Vec3; 3]>, translation: Vec3) {
    let object = scene.moves[0].object;
    scene.objects[object].triangles = triangles;
    scene.moves[0].translation = translation;
}

fn specular_case(ior: f32) -> StressSetup {
    let mut scene = specular_furnace(Vec3::splat(0.5), 1.0);
    for m in &mut scene.materials {
        if let MaterialKind::Glass { ior: i, .. } = &mut m.kind {
            *i = ior;
        }
    }
    radiance_two(scene, None)
}

/// The specular furnace with a lossless conductor (`eta = 0`, `k = 1`) of roughness `alpha`
/// along its tangent and `alpha_v` across it for its mirror: every pixel is 2 when it is
/// smooth; a rough one loses what single scattering cannot return, so only finiteness is
/// asked.
fn conductor_case((alpha, alpha_v): (f32, f32)) -> StressSetup {
    let mut scene = specular_furnace(Vec3::splat(0.5), 1.0);
    for m in &mut scene.materials {
        if let MaterialKind::Mirror { .. } = m.kind {
            m.kind = MaterialKind::Conductor {
                eta: Vec3::ZERO,
                k: Vec3::ONE,
                reflectance: Vec3::ONE,
                alpha,
                alpha_v,
            };
        }
    }
    let mut setup = radiance_two(scene, None);
    if alpha.max(alpha_v) > 0.0 {
        setup.expected = Expected::Finite;
    }
    setup
}

/// The specular furnace with its glass cube of roughness `alpha` along its tangent and
/// `alpha_v` across it: a rough dielectric loses what single scattering on its microfacets
/// cannot return, so only finiteness is asked.
fn rough_glass_case((alpha, alpha_v): (f32, f32)) -> StressSetup {
    let mut scene = specular_furnace(Vec3::splat(0.5), 1.0);
    for m in &mut scene.materials {
        if let MaterialKind::Glass {
            alpha: a,
            alpha_v: a_v,
            ..
        } = &mut m.kind
        {
            (*a, *a_v) = (alpha, alpha_v);
        }
    }
    let mut setup = radiance_two(scene, None);
    setup.expected = Expected::Finite;
    setup
}

/// The specular furnace with a white base under a coat of roughness `alpha` for its mirror,
/// light meeting the base at every return: a smooth coat loses nothing (the coat's
/// reflection and what the base sends back out add to one), so every pixel is 2; a rough
/// one loses what single scattering on its microfacets cannot return, so only finiteness is
/// asked.
fn coated_case(alpha: f32) -> StressSetup {
    let mut scene = specular_furnace(Vec3::splat(0.5), 1.0);
    for m in &mut scene.materials {
        if let MaterialKind::Mirror { .. } = m.kind {
            m.kind = MaterialKind::Coated {
                albedo: Vec3::ONE,
                ior: 1.5,
                alpha,
                nonlinear: true,
            };
        }
    }
    let mut setup = radiance_two(scene, None);
    if alpha > 0.0 {
        setup.expected = Expected::Finite;
    }
    setup
}

/// The specular furnace with its mirror's reflectance read from a `side` x `side` white
/// image: every lookup reads 1 (a half float holds it exactly), so every pixel stays 2.
fn textured_mirror_case(side: u32) -> StressSetup {
    let mut scene = specular_furnace(Vec3::splat(0.5), 1.0);
    let white = Texture::from_fn("white", side, side, TextureFilter::Bilinear, |_, _| {
        Vec3::ONE
    })
    .expect("a white image is a valid texture");
    let white = Arc::new(white);
    for m in &mut scene.materials {
        if let MaterialKind::Mirror { .. } = m.kind {
            m.texture = Some(white.clone());
        }
    }
    radiance_two(scene, None)
}

/// The water furnace (ior 1.8): every pixel is 2, under the water too, in both frames.
fn water_case(moves: Option<MoveStress>) -> StressSetup {
    radiance_two(water_furnace(Vec3::splat(0.5), 1.0, 1.8), moves)
}

/// A furnace variant whose every pixel is 2 (within 6%), frame 0 then the move if any
/// (two iterations each side of it).
fn radiance_two(scene: Scene, moves: Option<MoveStress>) -> StressSetup {
    let mut params = small(&scene);
    if moves.is_some() {
        params.passes = 2;
    }
    StressSetup {
        scene,
        params,
        expected: Expected::Radiance {
            radiance: 2.0,
            tolerance: 0.06,
        },
        seed: None,
        moves,
    }
}

/// The stress case called `name`.
pub fn stress_case(name: &str) -> Option<&'static StressCase> {
    STRESS.iter().find(|c| c.name == name)
}
