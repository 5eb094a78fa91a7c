//! Coated materials through the Mitsuba 3 and pbrt-v4 formats: written with `export_*` and
//! read back, smooth and rough coats, textured and not, keep every field (pbrt's format has
//! no `nonlinear`: its `coateddiffuse` always is, so a coat comes back from it with
//! `nonlinear` on, and the export says so where ours is off).

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
