//! Coated materials and glass through the Mitsuba 3 and pbrt-v4 formats: written with
//! `export_*` and read back, smooth and rough coats, textured and not, keep every field (pbrt's
//! format has no `nonlinear`: its `coateddiffuse` always is, so a coat comes back from it with
//! `nonlinear` on, and the export says so where ours is off), as smooth and rough glass do.

use glam::Vec3;
use ppm_core::compile::compile_scene;
use ppm_core::scene::{Material, MaterialKind, Scene};
use scenes::file::{Export, ExportOptions, mitsuba, pbrt};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-coated-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    dir
}

/// cornell-textured with every textured material and both blocks coated: a rough coat
/// over the checkered floor, a smooth one over the painted back wall (both textures holding
/// the whole colour, as an export writes them), a rough coat over the tall block and a
/// smooth one over the short block; `nonlinear` in that order.
fn coated_scene(nonlinear: [bool; 4]) -> Scene {
    let mut scene = scenes::builtin("cornell-textured").unwrap().load().unwrap();
    scene.moves.clear();
    for m in &mut scene.materials {
        let (ior, alpha, nonlinear) = match m.name.as_str() {
            "checkers" => (1.5, 0.3, nonlinear[0]),
            "rings" => (1.33, 0.0, nonlinear[1]),
            _ => continue,
        };
        assert!(m.texture.is_some());
        m.kind = MaterialKind::Coated {
            albedo: Vec3::ONE,
            ior,
            alpha,
            nonlinear,
        };
    }
    for (block, albedo, ior, alpha, nonlinear) in [
        (
            "tall-block",
            Vec3::new(0.7, 0.12, 0.08),
            1.5,
            0.2,
            nonlinear[2],
        ),
        (
            "short-block",
            Vec3::new(0.1, 0.25, 0.6),
            1.6,
            0.0,
            nonlinear[3],
        ),
    ] {
        scene.materials.push(Material::new(
            format!("{block}-plastic"),
            MaterialKind::Coated {
                albedo,
                ior,
                alpha,
                nonlinear,
            },
        ));
        let object = scene.object_index(block).unwrap();
        scene.objects[object].material = scene.materials.len() - 1;
    }
    scene
}

fn round_trip(export: &Export, name: &str) -> Scene {
    let dir = scratch(name);
    let path = export.write(&dir).unwrap();
    let back = if name.starts_with("mitsuba") {
        mitsuba::load_mitsuba_file(&path)
    } else {
        pbrt::load_pbrt_file(&path)
    };
    std::fs::remove_dir_all(&dir).ok();
    back.unwrap_or_else(|e| panic!("{e}"))
}

/// Each object's material kind and texture (all but its name, which is the file's).
fn surfaces(scene: &Scene) -> Vec<(String, MaterialKind, Option<String>)> {
    scene
        .objects
        .iter()
        .map(|o| {
            let m = &scene.materials[o.material];
            let texture = m.texture.as_ref().map(|t| {
                format!(
                    "{}x{} {:?} scale {} offset {} texels {:?}",
                    t.width, t.height, t.filter, t.scale, t.offset, t.texels
                )
            });
            (o.name.clone(), m.kind.clone(), texture)
        })
        .collect()
}

/// What the backends see of the materials and textures: the compiled buffers, written out
/// (`{:?}` writes each float so that it reads back to the same bits).
fn compiled_materials(scene: &Scene) -> [String; 4] {
    let c = compile_scene(scene, scene.camera.width, scene.camera.height);
    [
        format!("{:?}", c.materials),
        format!("{:?}", c.textures.headers),
        format!("{:?}", &c.textures.texels[..]),
        format!("{:?}", c.textures.uvs),
    ]
}

#[test]
fn coated_materials_round_trip_through_mitsuba_with_every_field() {
    for nonlinear in [[false, true, false, true], [true, false, true, false]] {
        let scene = coated_scene(nonlinear);
        let export = mitsuba::export_mitsuba(&scene, &ExportOptions::default());
        assert_eq!(export.textures.len(), 2, "both coats' textures are written");
        assert!(export.text.contains("<bsdf type=\"plastic\">"));
        assert!(export.text.contains("<bsdf type=\"roughplastic\">"));
        assert!(
            export
                .text
                .contains("<texture type=\"bitmap\" name=\"diffuse_reflectance\">")
        );
        let back = round_trip(&export, &format!("mitsuba-{}", nonlinear[0]));
        assert_eq!(surfaces(&back), surfaces(&scene), "{nonlinear:?}");
        assert_eq!(compiled_materials(&back), compiled_materials(&scene));
    }
}

#[test]
fn coated_materials_round_trip_through_pbrt_with_nonlinear_on() {
    let scene = coated_scene([true; 4]);
    let export = pbrt::export_pbrt(&scene, &ExportOptions::default());
    assert_eq!(export.textures.len(), 2, "both coats' textures are written");
    assert!(
        !export.notes.iter().any(|n| n.contains("nonlinear = false")),
        "{:?}",
        export.notes
    );
    let back = round_trip(&export, "pbrt");
    assert_eq!(surfaces(&back), surfaces(&scene));
    assert_eq!(compiled_materials(&back), compiled_materials(&scene));
}

/// pbrt's `coateddiffuse` always meets the base's colour at every return: a coat with
/// `nonlinear` off comes back with it on, the rest unchanged, and the notes (and the file's
/// comment) name the material.
#[test]
fn a_linear_coat_comes_back_from_pbrt_nonlinear_and_is_named_in_the_notes() {
    let scene = coated_scene([false, true, false, true]);
    let export = pbrt::export_pbrt(&scene, &ExportOptions::default());
    for name in ["checkers", "tall-block-plastic"] {
        let note = format!("coated material \"{name}\", ours with nonlinear = false");
        assert!(
            export.notes.iter().any(|n| n.contains(&note)),
            "{:?}",
            export.notes
        );
        assert!(export.text.contains(&note), "the file's comment lists it");
    }
    assert!(
        !export.notes.iter().any(|n| n.contains("\"rings\"")),
        "a nonlinear coat needs no note"
    );
    let back = round_trip(&export, "pbrt-linear");
    assert_eq!(surfaces(&back), surfaces(&coated_scene([true; 4])));
}

/// cornell-box with its blocks of glass: the tall one of index 1.5 and GGX roughness
/// `tall_alpha`, the short one smooth, of index 1.33.
fn glass_scene(tall_alpha: f32) -> Scene {
    let mut scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    scene.moves.clear();
    for (block, ior, alpha) in [("tall-block", 1.5, tall_alpha), ("short-block", 1.33, 0.0)] {
        scene.materials.push(Material::new(
            format!("{block}-glass"),
            MaterialKind::Glass {
                ior,
                alpha,
                alpha_v: alpha,
            },
        ));
        let object = scene.object_index(block).unwrap();
        scene.objects[object].material = scene.materials.len() - 1;
    }
    scene
}

/// The note on Mitsuba's masking term for rough glass.
const ROUGH_GLASS_NOTE: &str =
    "Mitsuba's roughdielectric masks and shadows with the separable Smith term";

#[test]
fn glass_round_trips_through_mitsuba_with_every_field() {
    let scene = glass_scene(0.3);
    let export = mitsuba::export_mitsuba(&scene, &ExportOptions::default());
    assert!(
        export
            .text
            .contains("<bsdf type=\"roughdielectric\" id=\"mat-tall-block-glass\">")
    );
    assert!(
        export
            .text
            .contains("<string name=\"distribution\" value=\"ggx\"/>")
    );
    assert!(
        export
            .text
            .contains("<float name=\"alpha\" value=\"0.3\"/>")
    );
    assert!(
        export
            .text
            .contains("<bsdf type=\"dielectric\" id=\"mat-short-block-glass\">")
    );
    assert!(
        export.notes.iter().any(|n| n.contains(ROUGH_GLASS_NOTE)),
        "{:?}",
        export.notes
    );
    assert!(
        export.text.contains(ROUGH_GLASS_NOTE),
        "the file's comment lists it"
    );
    let back = round_trip(&export, "mitsuba-glass");
    assert_eq!(surfaces(&back), surfaces(&scene));
    assert_eq!(compiled_materials(&back), compiled_materials(&scene));
}

/// Smooth glass is written as Mitsuba's `dielectric`, and needs no note on the masking term.
#[test]
fn smooth_glass_goes_to_mitsuba_as_a_dielectric_without_a_note() {
    let scene = glass_scene(0.0);
    let export = mitsuba::export_mitsuba(&scene, &ExportOptions::default());
    assert!(!export.text.contains("roughdielectric"));
    assert!(
        !export.notes.iter().any(|n| n.contains("roughdielectric")),
        "{:?}",
        export.notes
    );
    let back = round_trip(&export, "mitsuba-smooth-glass");
    assert_eq!(surfaces(&back), surfaces(&scene));
}

#[test]
fn glass_round_trips_through_pbrt_with_every_field() {
    for tall_alpha in [0.3, 0.0] {
        let scene = glass_scene(tall_alpha);
        let export = pbrt::export_pbrt(&scene, &ExportOptions::default());
        assert!(export.text.contains(&format!(
            "\"dielectric\" ] \"float eta\" [ 1.5 ] \"float roughness\" [ {tall_alpha} ] \"bool remaproughness\" false"
        )));
        assert!(export.text.contains(
            "\"dielectric\" ] \"float eta\" [ 1.33 ] \"float roughness\" [ 0 ] \"bool remaproughness\" false"
        ));
        let back = round_trip(&export, &format!("pbrt-glass-{tall_alpha}"));
        assert_eq!(surfaces(&back), surfaces(&scene), "{tall_alpha}");
        assert_eq!(compiled_materials(&back), compiled_materials(&scene));
    }
}

/// The tangent that orients each anisotropic triangle's lobe, by object and triangle
/// (`ppm_core::textures::u_direction` of the compiled scene, made a unit vector), with the
/// triangle's first vertex to pair them up across files, which may reorder triangles.
fn tangents(scene: &Scene) -> Vec<([u32; 3], Vec3)> {
    let c = compile_scene(scene, scene.camera.width, scene.camera.height);
    let mut out: Vec<([u32; 3], Vec3)> = c
        .triangles
        .iter()
        .enumerate()
        .filter(|(_, t)| ppm_core::bsdf::is_anisotropic(&c.materials[t.material as usize]))
        .map(|(i, t)| {
            let d = ppm_core::textures::u_direction(&c.textures.uvs[i], t).normalize();
            // The lobe is the same along d and -d.
            let d = if d.max_element() + d.min_element() < 0.0 {
                -d
            } else {
                d
            };
            let centre = Vec3::from(t.v0) + (Vec3::from(t.e1) + Vec3::from(t.e2)) / 3.0;
            (centre.to_array().map(|x| (x * 16.0).round() as u32), d)
        })
        .collect();
    out.sort_by_key(|(k, _)| *k);
    out
}

/// cornell-brushed (anisotropic gold and glass, their coordinates brushing them upwards)
/// and the same with the blocks' coordinates dropped (each triangle's first edge then
/// orients it, pbrt-v4's default): through Mitsuba 3 and pbrt-v4, `alpha_u`/`alpha_v` and
/// `uroughness`/`vroughness` come back as written, and every anisotropic triangle keeps
/// its tangent, since the meshes carry coordinates that give it to either renderer.
#[test]
fn anisotropic_lobes_round_trip_with_their_orientation() {
    let brushed = scenes::builtin("cornell-brushed").unwrap().load().unwrap();
    let mut unmapped = brushed.clone();
    for o in &mut unmapped.objects {
        o.uvs.clear();
    }
    for (name, mut scene) in [("brushed", brushed), ("unmapped", unmapped)] {
        scene.moves.clear();
        let mitsuba = mitsuba::export_mitsuba(&scene, &ExportOptions::default());
        assert!(
            mitsuba
                .text
                .contains("<float name=\"alpha_u\" value=\"0.4\"/>")
        );
        assert!(
            mitsuba
                .text
                .contains("<float name=\"alpha_v\" value=\"0.05\"/>")
        );
        let pbrt = pbrt::export_pbrt(&scene, &ExportOptions::default());
        assert!(
            pbrt.text
                .contains("\"float uroughness\" [ 0.05 ] \"float vroughness\" [ 0.3 ]")
        );
        let expected = tangents(&scene);
        assert_eq!(expected.len(), 2 * 10, "{name}: both blocks' five faces");
        for (export, format) in [(mitsuba, "mitsuba"), (pbrt, "pbrt")] {
            let back = round_trip(&export, &format!("{format}-anisotropic-{name}"));
            let kinds = |s: &Scene| -> Vec<MaterialKind> {
                s.objects
                    .iter()
                    .map(|o| s.materials[o.material].kind.clone())
                    .filter(MaterialKind::is_anisotropic)
                    .collect()
            };
            assert_eq!(kinds(&back), kinds(&scene), "{format} {name}");
            let got = tangents(&back);
            assert_eq!(got.len(), expected.len());
            for ((ka, a), (kb, b)) in expected.iter().zip(&got) {
                assert_eq!(ka, kb, "{format} {name}: triangles pair up");
                assert!((*a - *b).length() < 1e-4, "{format} {name}: {a} became {b}");
            }
        }
    }
}

/// cornell-textured with its textured floor a rough conductor and its painted back wall a
/// mirror, each texture scaling the reflectance: Mitsuba 3 takes both as a
/// `specular_reflectance` bitmap and gives them back texel for texel; pbrt-v4, which reads a
/// conductor's textured reflectance as an index per point, gets neither, and the notes say so.
#[test]
fn textured_reflectances_round_trip_through_mitsuba_and_are_noted_for_pbrt() {
    let mut scene = scenes::builtin("cornell-textured").unwrap().load().unwrap();
    scene.moves.clear();
    for m in &mut scene.materials {
        m.kind = match m.name.as_str() {
            "checkers" => MaterialKind::Conductor {
                eta: Vec3::new(0.2, 0.9, 1.1),
                k: Vec3::new(3.9, 2.4, 2.1),
                reflectance: Vec3::ONE,
                alpha: 0.2,
                alpha_v: 0.2,
            },
            "rings" => MaterialKind::Mirror {
                reflectance: Vec3::ONE,
            },
            _ => continue,
        };
        assert!(m.texture.is_some());
    }
    let export = mitsuba::export_mitsuba(&scene, &ExportOptions::default());
    assert_eq!(
        export
            .text
            .matches("<texture type=\"bitmap\" name=\"specular_reflectance\">")
            .count(),
        2
    );
    let back = round_trip(&export, "mitsuba-textured-specular");
    assert_eq!(surfaces(&back), surfaces(&scene));
    assert_eq!(compiled_materials(&back), compiled_materials(&scene));
    let pbrt = pbrt::export_pbrt(&scene, &ExportOptions::default());
    assert!(pbrt.textures.is_empty());
    let noted = pbrt
        .notes
        .iter()
        .filter(|n| n.contains("pbrt-v4 reads a conductor's as an index per point"))
        .count();
    assert_eq!(noted, 2, "{:?}", pbrt.notes);
}
