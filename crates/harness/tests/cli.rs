//! The `ppm` command as a user meets it: listing scenes, rendering, and clear errors on bad
//! input that name the option and the value.

use std::path::PathBuf;
use std::process::{Command, Output};

fn ppm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ppm"))
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .env_remove("RUST_LIB_BACKTRACE")
        .output()
        .expect("ppm runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn scenes_lists_the_canonical_scene() {
    let out = ppm(&["scenes"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("cornell-box"));
}

#[test]
fn render_writes_exr_png_and_a_report() {
    let dir = scratch("render");
    let exr = dir.join("cb.exr");
    let out = ppm(&[
        "render",
        "cornell-box",
        "--width",
        "24",
        "--height",
        "20",
        "--passes",
        "2",
        "--photons-per-pass",
        "5000",
        "-o",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(exr.is_file() && dir.join("cb.png").is_file());
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("cb.json")).unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    insta::assert_json_snapshot!(report, {
        ".times" => "[seconds per pass kind]",
    });
}

#[test]
fn bad_alpha_is_refused_with_option_and_value() {
    let out = ppm(&[
        "render",
        "cornell-box",
        "--alpha",
        "1.5",
        "-o",
        "unused.exr",
    ]);
    assert!(!out.status.success());
    insta::assert_snapshot!(stderr(&out).trim_end());
}

#[test]
fn unknown_scene_lists_the_builtin_ones() {
    let out = ppm(&["render", "cornel-box", "-o", "unused.exr"]);
    assert!(!out.status.success());
    insta::assert_snapshot!(stderr(&out).trim_end());
}

#[test]
fn output_must_be_exr() {
    let out = ppm(&["render", "cornell-box", "-o", "picture.png"]);
    assert!(!out.status.success());
    insta::assert_snapshot!(stderr(&out).trim_end());
}

#[test]
fn bad_scene_file_is_named_in_the_error() {
    let dir = scratch("bad-scene");
    let file = dir.join("bad.toml");
    let text = scenes::CORNELL_BOX_TOML.replace(
        "red = { type = \"diffuse\", albedo = [0.63,",
        "red = { type = \"diffuse\", albedo = [1.63,",
    );
    std::fs::write(&file, text).unwrap();
    let out = ppm(&[
        "render",
        file.to_str().unwrap(),
        "-o",
        dir.join("x.exr").to_str().unwrap(),
    ]);
    std::fs::remove_dir_all(&dir).ok();
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("bad.toml: materials.red.albedo[0] = 1.63: above 1"),
        "{err}"
    );
}
