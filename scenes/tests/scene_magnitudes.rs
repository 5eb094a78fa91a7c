//! Scenes at extreme scales are judged by their true values (`f64`), and values past the
//! argued `f32` limits are refused before any pass with the file, the field and the value.

use ppm_core::compile::compile_scene;
use ppm_core::params::RenderParams;
use ppm_core::scene::{Scene, SceneError};
use scenes::file::parse_scene;
use std::path::Path;

const CORNELL: &str = include_str!("../../scenes/data/cornell-box.toml");

fn parse(text: &str) -> Result<Scene, SceneError> {
    parse_scene(text, "cornell-box.toml", Path::new("."))
}

/// cornell-box with every length (positions, moves, radius) multiplied by `factor`.
fn scaled(factor: f64) -> String {
    fn scale(v: &mut toml::Value, factor: f64) {
        match v {
            toml::Value::Float(x) => *x *= factor,
            toml::Value::Integer(i) => *v = toml::Value::Float(*i as f64 * factor),
            toml::Value::Array(a) => a.iter_mut().for_each(|x| scale(x, factor)),
            _ => {}
        }
    }
    let mut t: toml::Table = toml::from_str(CORNELL).unwrap();
    for key in ["eye", "look_at"] {
        scale(&mut t["camera"][key], factor);
    }
    scale(&mut t["render"]["initial_radius"], factor);
    for section in ["objects", "moves"] {
        for item in t[section].as_array_mut().unwrap() {
            for key in ["quads", "translate"] {
                if let Some(v) = item.get_mut(key) {
                    scale(v, factor);
                }
            }
        }
    }
    toml::to_string(&t).unwrap()
}

fn error(text: &str) -> String {
    match parse(text) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    }
}

fn replaced(from: &str, to: &str) -> String {
    assert!(CORNELL.contains(from), "cornell-box lacks {from:?}");
    CORNELL.replacen(from, to, 1)
}

/// At 1e8 every squared length stays within f32: the scene loads, and compiles to a finite
/// camera and light power (in f32, the camera's check once squared 8e10 mm into range but
/// a scene at 1e20 to infinity).
#[test]
fn a_scene_scaled_by_1e8_is_accepted_and_compiles_finite() {
    let scene = parse(&scaled(1e8)).unwrap();
    RenderParams::for_scene(&scene)
        .validate("cornell-box.toml")
        .unwrap();
    let compiled = compile_scene(&scene, 8, 8);
    assert!(compiled.light_power.is_finite() && compiled.light_power.min_element() > 0.0);
    assert!(glam::Vec3::from(compiled.camera.forward).is_finite());
    // Normals square cross products of edges ~1e10 (1e40 overflows f32): compiled in f64.
    let unit = |t: &ppm_core::layout::GpuTriangle| {
        (glam::Vec3::from(t.normal).length() - 1.0).abs() < 1e-5
    };
    assert!(compiled.triangles.iter().all(unit));
}

#[test]
fn a_scene_scaled_by_1e20_is_refused() {
    insta::assert_snapshot!(error(&scaled(1e20)));
}

/// At 1e-30 the camera is 8e-28 from what it looks at: f32 squared that to zero and called
/// it a camera looking at itself; the true reason is the scale.
#[test]
fn a_scene_scaled_by_1e_minus_30_is_refused_for_its_scale() {
    insta::assert_snapshot!(error(&scaled(1e-30)));
}

#[test]
fn a_vertex_at_1e20_is_refused() {
    insta::assert_snapshot!(error(&replaced(
        "[[[552.8, 0.0, 0.0], [0.0, 0.0, 0.0]",
        "[[[1e20, 0.0, 0.0], [0.0, 0.0, 0.0]"
    )));
}

#[test]
fn a_move_of_3e38_is_refused() {
    insta::assert_snapshot!(error(&replaced(
        "translate = [40.0, 0.0, -100.0]",
        "translate = [3e38, 0.0, -100.0]"
    )));
}

#[test]
fn radiance_1e35_is_refused_for_the_power_it_carries() {
    insta::assert_snapshot!(error(&replaced(
        "radiance = [17.0, 12.0, 4.0]",
        "radiance = [1e35, 12.0, 4.0]"
    )));
}

#[test]
fn a_radius_whose_square_overflows_is_refused() {
    insta::assert_snapshot!(error(&replaced(
        "initial_radius = 10.0",
        "initial_radius = 1e20"
    )));
}

#[test]
fn zero_passes_are_refused() {
    insta::assert_snapshot!(error(&replaced("passes = 100", "passes = 0")));
}

/// Two objects of one name: a move would apply to the first and silently leave the second.
#[test]
fn duplicate_object_names_are_refused() {
    insta::assert_snapshot!(error(&replaced(
        "name = \"short-block\"",
        "name = \"floor\""
    )));
}
