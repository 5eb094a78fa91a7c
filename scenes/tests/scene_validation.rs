//! Bad scene files are rejected before rendering with a message naming the file, the field and
//! the value. Each message is pinned by an insta snapshot, so a change in wording is reviewed.

use ppm_core::params::RenderParams;
use scenes::file::parse_scene;
use std::path::Path;

/// A small valid scene: a lit floor seen from above.
const VALID: &str = r#"
name = "probe"

[camera]
eye = [0.0, 5.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, 1.0]
fov = 40.0
width = 8
height = 8

[materials]
white = { type = "diffuse", albedo = [0.5, 0.5, 0.5] }
lamp = { type = "light", radiance = [1.0, 1.0, 1.0] }

[[objects]]
name = "floor"
material = "white"
quads = [[[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]]]

[[objects]]
name = "lamp"
material = "lamp"
quads = [[[-0.1, 2.0, -0.1], [-0.1, 2.0, 0.1], [0.1, 2.0, 0.1], [0.1, 2.0, -0.1]]]
"#;

/// The error message for `VALID` with `from` replaced by `to`.
fn error_for(from: &str, to: &str) -> String {
    assert!(VALID.contains(from), "probe text lacks {from:?}");
    let text = VALID.replacen(from, to, 1);
    match parse_scene(&text, "probe.toml", Path::new("scenes")) {
        Ok(_) => panic!("accepted {to:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn the_probe_scene_is_valid() {
    let scene = parse_scene(VALID, "probe.toml", Path::new(".")).unwrap();
    assert_eq!(scene.triangle_count(), 4);
    RenderParams::for_scene(&scene)
        .validate("probe.toml")
        .unwrap();
}

#[test]
fn nan_vertex() {
    insta::assert_snapshot!(error_for("[1.0, 0.0, -1.0]", "[1.0, nan, -1.0]"));
}

#[test]
fn infinite_camera_position() {
    insta::assert_snapshot!(error_for("eye = [0.0, 5.0, 0.0]", "eye = [0.0, inf, 0.0]"));
}

#[test]
fn negative_albedo() {
    insta::assert_snapshot!(error_for(
        "albedo = [0.5, 0.5, 0.5]",
        "albedo = [0.5, -0.1, 0.5]"
    ));
}

#[test]
fn albedo_above_one() {
    insta::assert_snapshot!(error_for(
        "albedo = [0.5, 0.5, 0.5]",
        "albedo = [0.5, 1.3, 0.5]"
    ));
}

#[test]
fn negative_radiance() {
    insta::assert_snapshot!(error_for(
        "radiance = [1.0, 1.0, 1.0]",
        "radiance = [1.0, 1.0, -2.0]"
    ));
}

#[test]
fn zero_area_light() {
    insta::assert_snapshot!(error_for(
        "[[-0.1, 2.0, -0.1], [-0.1, 2.0, 0.1], [0.1, 2.0, 0.1], [0.1, 2.0, -0.1]]",
        "[[-0.1, 2.0, -0.1], [-0.1, 2.0, -0.1], [-0.1, 2.0, -0.1], [-0.1, 2.0, -0.1]]"
    ));
}

#[test]
fn camera_looking_at_itself() {
    insta::assert_snapshot!(error_for(
        "look_at = [0.0, 0.0, 0.0]",
        "look_at = [0.0, 5.0, 0.0]"
    ));
}

#[test]
fn camera_up_along_the_view() {
    insta::assert_snapshot!(error_for("up = [0.0, 0.0, 1.0]", "up = [0.0, 1.0, 0.0]"));
}

#[test]
fn zero_field_of_view() {
    insta::assert_snapshot!(error_for("fov = 40.0", "fov = 0.0"));
}

#[test]
fn zero_width() {
    insta::assert_snapshot!(error_for("width = 8", "width = 0"));
}

#[test]
fn missing_obj() {
    insta::assert_snapshot!(error_for(
        "quads = [[[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]]]",
        "obj = \"no-such-mesh.obj\""
    ));
}

#[test]
fn empty_scene() {
    let text = VALID.split("[[objects]]").next().unwrap();
    let err = parse_scene(text, "probe.toml", Path::new(".")).unwrap_err();
    insta::assert_snapshot!(err.to_string());
}

#[test]
fn unknown_material_name() {
    insta::assert_snapshot!(error_for("material = \"white\"", "material = \"whte\""));
}

#[test]
fn unknown_material_type() {
    insta::assert_snapshot!(error_for("type = \"diffuse\"", "type = \"velvet\""));
}

#[test]
fn misspelt_field() {
    insta::assert_snapshot!(error_for("fov = 40.0", "fov = 40.0\nfocal = 3.0"));
}

#[test]
fn scene_without_light() {
    insta::assert_snapshot!(error_for("material = \"lamp\"", "material = \"white\""));
}

#[test]
fn glass_with_negative_ior() {
    insta::assert_snapshot!(error_for(
        "lamp = { type",
        "glass = { type = \"glass\", ior = -1.5 }\nlamp = { type"
    ));
}

#[test]
fn move_of_unknown_object() {
    insta::assert_snapshot!(error_for(
        "[[objects]]\nname = \"floor\"",
        "[[moves]]\nobject = \"flor\"\ntranslate = [1.0, 0.0, 0.0]\n\n[[objects]]\nname = \"floor\""
    ));
}

#[test]
fn alpha_out_of_range() {
    insta::assert_snapshot!(error_for(
        "[materials]",
        "[render]\nalpha = 1.5\n\n[materials]"
    ));
}

#[test]
fn command_line_overrides_are_checked_too() {
    let scene = parse_scene(VALID, "probe.toml", Path::new(".")).unwrap();
    let mut params = RenderParams::for_scene(&scene);
    params.initial_radius = f32::NAN;
    insta::assert_snapshot!(params.validate("command line").unwrap_err().to_string());
}

#[test]
fn conductor_rougher_than_one() {
    insta::assert_snapshot!(error_for(
        "lamp = { type",
        "metal = { type = \"conductor\", eta = [0.2, 0.9, 1.1], k = [3.9, 2.4, 2.1], alpha = 1.5 }\nlamp = { type"
    ));
}

#[test]
fn conductor_with_negative_absorption() {
    insta::assert_snapshot!(error_for(
        "lamp = { type",
        "metal = { type = \"conductor\", eta = [0.2, 0.9, 1.1], k = [3.9, -2.4, 2.1] }\nlamp = { type"
    ));
}

/// A conductor needs its index; its reflectance factor defaults to one and its roughness to
/// zero (smooth).
#[test]
fn a_conductor_loads_with_its_defaults() {
    let text = VALID.replacen(
        "lamp = { type",
        "metal = { type = \"conductor\", eta = [0.2, 0.9, 1.1], k = [3.9, 2.4, 2.1] }\nlamp = { type",
        1,
    );
    let scene = parse_scene(&text, "probe.toml", Path::new("scenes")).unwrap();
    let metal = scene.materials.iter().find(|m| m.name == "metal").unwrap();
    assert_eq!(
        metal.kind,
        ppm_core::scene::MaterialKind::Conductor {
            eta: glam::Vec3::new(0.2, 0.9, 1.1),
            k: glam::Vec3::new(3.9, 2.4, 2.1),
            reflectance: glam::Vec3::ONE,
            alpha: 0.0,
            alpha_v: 0.0,
        }
    );
}

#[test]
fn coated_with_ior_of_one() {
    insta::assert_snapshot!(error_for(
        "lamp = { type",
        "paint = { type = \"coated\", albedo = [0.5, 0.5, 0.5], ior = 1.0 }\nlamp = { type"
    ));
}

#[test]
fn coated_rougher_than_one() {
    insta::assert_snapshot!(error_for(
        "lamp = { type",
        "paint = { type = \"coated\", albedo = [0.5, 0.5, 0.5], alpha = 1.5 }\nlamp = { type"
    ));
}

#[test]
fn coated_albedo_above_one() {
    insta::assert_snapshot!(error_for(
        "lamp = { type",
        "paint = { type = \"coated\", albedo = [0.5, 1.2, 0.5] }\nlamp = { type"
    ));
}

/// A coat's index, roughness and base colour are checked as every other material's: NaN,
/// infinity and an index below one are refused by field and value, and a coated material
/// needs a colour or a texture, as a diffuse one does.
#[test]
fn coated_values_that_cannot_be_are_refused_by_field() {
    for (coated, says) in [
        (
            "albedo = [0.5, 0.5, 0.5], ior = 0.9",
            "materials.paint.ior = 0.9: must be a number above 1",
        ),
        (
            "albedo = [0.5, 0.5, 0.5], ior = nan",
            "materials.paint.ior = NaN",
        ),
        (
            "albedo = [0.5, 0.5, 0.5], ior = inf",
            "materials.paint.ior = inf",
        ),
        (
            "albedo = [0.5, 0.5, 0.5], alpha = nan",
            "materials.paint.alpha = NaN",
        ),
        (
            "albedo = [0.5, 0.5, 0.5], alpha = -0.1",
            "materials.paint.alpha = -0.1: must be in [0, 1]",
        ),
        (
            "albedo = [0.5, -0.5, 0.5]",
            "materials.paint.albedo[1] = -0.5: negative",
        ),
        (
            "ior = 1.5",
            "materials.paint.albedo = missing: a coated material needs its albedo or a texture",
        ),
    ] {
        let e = error_for(
            "lamp = { type",
            &format!("paint = {{ type = \"coated\", {coated} }}\nlamp = {{ type"),
        );
        assert!(
            e.starts_with("probe.toml: ") && e.contains(says),
            "{coated}: {e}"
        );
    }
}

/// A coated material's index defaults to 1.5, its roughness to zero (smooth) and
/// `nonlinear` to false (Mitsuba's default); each is read when given.
#[test]
fn a_coated_material_loads_with_its_defaults() {
    let coated = |fields: &str| {
        let text = VALID.replacen(
            "lamp = { type",
            &format!("paint = {{ type = \"coated\", {fields} }}\nlamp = {{ type"),
            1,
        );
        let scene = parse_scene(&text, "probe.toml", Path::new("scenes")).unwrap();
        let paint = scene.materials.iter().find(|m| m.name == "paint").unwrap();
        assert!(paint.texture.is_none());
        paint.kind.clone()
    };
    assert_eq!(
        coated("albedo = [0.7, 0.1, 0.1]"),
        ppm_core::scene::MaterialKind::Coated {
            albedo: glam::Vec3::new(0.7, 0.1, 0.1),
            ior: 1.5,
            alpha: 0.0,
            nonlinear: false,
        }
    );
    assert_eq!(
        coated("albedo = [0.2, 0.3, 0.4], ior = 1.33, alpha = 0.25, nonlinear = true"),
        ppm_core::scene::MaterialKind::Coated {
            albedo: glam::Vec3::new(0.2, 0.3, 0.4),
            ior: 1.33,
            alpha: 0.25,
            nonlinear: true,
        }
    );
}

#[test]
fn glass_rougher_than_one() {
    insta::assert_snapshot!(error_for(
        "lamp = { type",
        "glass = { type = \"glass\", ior = 1.5, alpha = 1.5 }\nlamp = { type"
    ));
}

/// A glass's roughness is checked as a conductor's or a coat's: NaN, infinity and values
/// outside [0, 1] are refused by field and value.
#[test]
fn glass_roughness_that_cannot_be_is_refused_by_field() {
    for (alpha, says) in [
        (
            "alpha = nan",
            "materials.glass.alpha = NaN: must be in [0, 1]",
        ),
        (
            "alpha = inf",
            "materials.glass.alpha = inf: must be in [0, 1]",
        ),
        (
            "alpha = -0.1",
            "materials.glass.alpha = -0.1: must be in [0, 1]",
        ),
        (
            "alpha = 1.01",
            "materials.glass.alpha = 1.01: must be in [0, 1]",
        ),
        (
            "alpha_v = 1.5",
            "materials.glass.alpha_v = 1.5: must be in [0, 1]",
        ),
        (
            "alpha = 0.2, alpha_v = nan",
            "materials.glass.alpha_v = NaN: must be in [0, 1]",
        ),
    ] {
        let e = error_for(
            "lamp = { type",
            &format!("glass = {{ type = \"glass\", ior = 1.5, {alpha} }}\nlamp = {{ type"),
        );
        assert!(
            e.starts_with("probe.toml: ") && e.contains(says),
            "{alpha}: {e}"
        );
    }
}

/// A glass needs its index; its roughness defaults to zero (smooth) and is read when given,
/// up to one.
#[test]
fn a_glass_loads_with_its_defaults() {
    let glass = |fields: &str| {
        let text = VALID.replacen(
            "lamp = { type",
            &format!("glass = {{ type = \"glass\", {fields} }}\nlamp = {{ type"),
            1,
        );
        let scene = parse_scene(&text, "probe.toml", Path::new("scenes")).unwrap();
        let glass = scene.materials.iter().find(|m| m.name == "glass").unwrap();
        assert!(glass.texture.is_none());
        glass.kind.clone()
    };
    assert_eq!(
        glass("ior = 1.5"),
        ppm_core::scene::MaterialKind::Glass {
            ior: 1.5,
            alpha: 0.0,
            alpha_v: 0.0,
        }
    );
    assert_eq!(
        glass("ior = 1.33, alpha = 0.25"),
        ppm_core::scene::MaterialKind::Glass {
            ior: 1.33,
            alpha: 0.25,
            alpha_v: 0.25,
        }
    );
    assert_eq!(
        glass("ior = 1.5, alpha = 0.1, alpha_v = 0.4"),
        ppm_core::scene::MaterialKind::Glass {
            ior: 1.5,
            alpha: 0.1,
            alpha_v: 0.4,
        }
    );
    assert_eq!(
        glass("ior = 1.5, alpha = 1.0"),
        ppm_core::scene::MaterialKind::Glass {
            ior: 1.5,
            alpha: 1.0,
            alpha_v: 1.0,
        }
    );
}
