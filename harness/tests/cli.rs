//! The `ppm` command as a user meets it: listing scenes, rendering, and clear errors on bad
//! input that name the option and the value.

mod common;

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

/// A reader that closes stdout early (`ppm ... | head -0`) costs the render nothing: it
/// finishes, writes its files and exits cleanly, without a panic.
#[test]
fn a_closed_stdout_does_not_stop_a_render() {
    let dir = scratch("closed-stdout");
    let exr = dir.join("cb.exr");
    let mut child = Command::new(env!("CARGO_BIN_EXE_ppm"))
        .args(["render", "cornell-box", "--width", "16", "--height", "16"])
        .args(["--passes", "2", "--photons-per-pass", "2000", "-o"])
        .arg(&exr)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("ppm runs");
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
    assert!(exr.is_file() && dir.join("cb.json").is_file());
    std::fs::remove_dir_all(&dir).ok();
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

#[test]
fn reference_writes_image_variance_preview_and_summary() {
    let dir = scratch("reference");
    let exr = dir.join("ref.exr");
    let out = ppm(&[
        "reference",
        "cornell-box",
        "--width",
        "12",
        "--height",
        "10",
        "--spp",
        "16",
        "-o",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    for name in ["ref.exr", "ref.var.exr", "ref.png", "ref.json"] {
        assert!(dir.join(name).is_file(), "{name} missing");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("ref.json")).unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(summary["spp"], 16);
    assert!(summary["relative_noise"].as_f64().unwrap() > 0.0);
}

/// A reference of another size cannot judge a render: the report stops before rendering and
/// says which file, which size, and which size it needed.
#[test]
fn a_report_refuses_a_reference_of_the_wrong_size() {
    let dir = scratch("wrong-size");
    let reference = dir.join("small.exr");
    let made = ppm(&[
        "reference",
        "cornell-box",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "8",
        "-o",
        reference.to_str().unwrap(),
    ]);
    assert!(made.status.success(), "{}", stderr(&made));
    let out = ppm(&[
        "report",
        "convergence",
        "cornell-box",
        "--width",
        "16",
        "--height",
        "12",
        "--seconds",
        "0.1",
        "--reference",
        reference.to_str().unwrap(),
        "-o",
        dir.join("report").to_str().unwrap(),
    ]);
    std::fs::remove_dir_all(&dir).ok();
    assert!(!out.status.success());
    let err = stderr(&out).replace(dir.to_str().unwrap(), "DIR");
    insta::assert_snapshot!(err.trim_end());
}

/// `ppm export` writes a scene file and its meshes, says what it could not express, and the
/// file renders back through `ppm render`.
#[test]
fn export_writes_scene_and_meshes_that_render_back() {
    for (format, file) in [("mitsuba", "cornell-box.xml"), ("pbrt", "cornell-box.pbrt")] {
        let dir = scratch(&format!("export-{format}"));
        let out = ppm(&[
            "export",
            "cornell-box",
            "--frame",
            "1",
            "--format",
            format,
            "-o",
            dir.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains("frame 1, 8 meshes, 32 triangles"),
            "{stdout}"
        );
        assert!(stdout.contains("not expressed exactly"), "{stdout}");
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        assert!(text.contains("frame 1"), "{text}");
        assert!(
            text.contains("photon mapping settings have no equivalent"),
            "{text}"
        );
        let meshes = std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| e.as_ref().unwrap().path().extension() == Some("ply".as_ref()))
            .count();
        assert_eq!(meshes, 8);
        let render = ppm(&[
            "render",
            dir.join(file).to_str().unwrap(),
            "--width",
            "16",
            "--height",
            "16",
            "--passes",
            "1",
            "--photons-per-pass",
            "2000",
            "-o",
            dir.join("back.exr").to_str().unwrap(),
        ]);
        assert!(render.status.success(), "{}", stderr(&render));
        assert!(dir.join("back.exr").is_file());
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[test]
fn export_refuses_a_third_frame() {
    let out = ppm(&[
        "export",
        "cornell-box",
        "--frame",
        "2",
        "--format",
        "pbrt",
        "-o",
        "unused",
    ]);
    assert!(!out.status.success());
    insta::assert_snapshot!(stderr(&out).trim_end());
}

/// The error of `ppm ARGS`, which must fail.
fn refusal(args: &[&str]) -> String {
    let out = ppm(args);
    assert!(!out.status.success(), "accepted {args:?}");
    stderr(&out).trim_end().to_owned()
}

/// Options that parse but mean nothing are refused before rendering, naming option and value.
#[test]
fn nonsense_options_are_refused_with_option_and_value() {
    let cases: &[&[&str]] = &[
        &["render", "cornell-box", "--passes", "0", "-o", "unused.exr"],
        &[
            "render",
            "cornell-box",
            "--time-budget",
            "NaN",
            "-o",
            "unused.exr",
        ],
        &[
            "render",
            "cornell-box",
            "--time-budget=-3",
            "-o",
            "unused.exr",
        ],
        &[
            "render",
            "cornell-box",
            "--radius",
            "1e20",
            "-o",
            "unused.exr",
        ],
        &[
            "render",
            "cornell-box",
            "--threads",
            "0",
            "-o",
            "unused.exr",
        ],
        &[
            "animate",
            "cornell-box",
            "--time-per-frame",
            "0",
            "-o",
            "unused",
        ],
        &[
            "animate",
            "cornell-box",
            "--time-per-frame",
            "NaN",
            "-o",
            "unused",
        ],
        &[
            "animate",
            "cornell-box",
            "--cone-deg",
            "NaN",
            "-o",
            "unused",
        ],
        &[
            "animate",
            "cornell-box",
            "--region-photons",
            "0",
            "-o",
            "unused",
        ],
        &[
            "report",
            "error-vs-time",
            "cornell-box",
            "--warmup",
            "NaN",
            "-o",
            "unused",
        ],
        &[
            "report",
            "convergence",
            "cornell-box",
            "--seconds",
            "0",
            "-o",
            "unused",
        ],
        &["diff", "cornell-box", "--independent", "--runs", "1"],
        &["diff", "cornell-box", "--independent", "--runs", "0"],
    ];
    let report: Vec<String> = cases
        .iter()
        .map(|args| format!("ppm {}\n  {}", args.join(" "), refusal(args)))
        .collect();
    insta::assert_snapshot!(report.join("\n"));
}

/// `--threads` beyond the ceiling names it (the core count in the message varies).
#[test]
fn thousands_of_threads_are_refused_naming_the_ceiling() {
    let err = refusal(&[
        "render",
        "cornell-box",
        "--threads",
        "100000",
        "-o",
        "unused.exr",
    ]);
    assert!(
        err.starts_with("error: --threads = 100000: at most 1024 (this machine has "),
        "{err}"
    );
}

/// A device never ends: it is refused at once, not read.
#[test]
fn a_device_as_scene_file_is_refused_at_once() {
    insta::assert_snapshot!(refusal(&["render", "/dev/zero", "-o", "unused.exr"]));
}

/// Sizes that cannot fit in memory are refused before allocation, saying what was asked,
/// what fits and which option to change (what fits depends on the machine).
#[test]
fn renders_beyond_memory_are_refused_before_allocation() {
    let slots = refusal(&[
        "render",
        "cornell-box",
        "--width",
        "60000",
        "--height",
        "60000",
        "-o",
        "unused.exr",
    ]);
    assert!(
        slots.starts_with(
            "error: command line: width * height * spp = 60000 * 60000 * 1 = 3600000000: \
             hit points of 112 bytes need 403.2 GB; "
        ) && slots.ends_with(": lower --width, --height or --spp"),
        "{slots}"
    );
    let photons = refusal(&[
        "render",
        "cornell-box",
        "--photons-per-pass",
        "4000000000",
        "-o",
        "unused.exr",
    ]);
    assert!(
        photons.starts_with("error: command line: photons_per_pass = 4000000000: ")
            && photons
                .contains(" deposits of 32 bytes (3.6 per path for albedo 0.725) need 465.5 GB; ")
            && photons.ends_with(": lower --photons-per-pass"),
        "{photons}"
    );
}

/// A folder where no file can be created is refused before rendering (procfs refuses
/// everyone, root included).
#[test]
fn an_unwritable_output_folder_is_refused_before_rendering() {
    let err = refusal(&["render", "cornell-box", "-o", "/proc/self/out.exr"]);
    assert!(
        err.starts_with(
            "error: -o /proc/self/out.exr: cannot write files in /proc/self (nothing was \
             rendered): "
        ),
        "{err}"
    );
}

#[test]
fn an_output_that_is_a_folder_is_refused() {
    let dir = scratch("output-folder");
    std::fs::create_dir_all(dir.join("x.png")).unwrap();
    let exr = dir.join("x.exr");
    let err = refusal(&["render", "cornell-box", "-o", exr.to_str().unwrap()]);
    std::fs::remove_dir_all(&dir).ok();
    insta::assert_snapshot!(err.replace(dir.to_str().unwrap(), "DIR"));
}

/// [`common::interrupted`] for `ppm ARGS`.
fn interrupted(args: &[&str], started: &str) -> (Option<i32>, String) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_ppm"));
    command.args(args);
    common::interrupted(command, started)
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Ctrl-C during a render: the iteration in progress finishes, the image of every completed
/// iteration is written with a report that says so, and the command exits with 130.
#[test]
fn an_interrupted_render_writes_what_it_completed_and_exits_130() {
    let dir = scratch("interrupt-render");
    let exr = dir.join("cb.exr");
    let (code, err) = interrupted(
        &[
            "render",
            "cornell-box",
            "--width",
            "32",
            "--height",
            "32",
            "--passes",
            "1000000",
            "--photons-per-pass",
            "20000",
            "-o",
            exr.to_str().unwrap(),
        ],
        "rendering",
    );
    let report = json(&dir.join("cb.json"));
    let written = exr.is_file() && dir.join("cb.png").is_file();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(code, Some(130), "{err}");
    assert!(written, "{err}");
    assert!(err.contains("interrupted: the image holds the"), "{err}");
    assert_eq!(report["interrupted"], true);
    let passes = report["passes"].as_u64().unwrap();
    assert!((1..1_000_000).contains(&passes), "{passes}");
}

/// Ctrl-C during a reference: the samples of the completed rounds are written, marked.
#[test]
fn an_interrupted_reference_writes_its_completed_rounds() {
    let dir = scratch("interrupt-reference");
    let exr = dir.join("ref.exr");
    let (code, err) = interrupted(
        &[
            "reference",
            "cornell-box",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "100000000",
            "-o",
            exr.to_str().unwrap(),
        ],
        "rendering",
    );
    let summary = json(&dir.join("ref.json"));
    let written = exr.is_file() && dir.join("ref.var.exr").is_file();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(code, Some(130), "{err}");
    assert!(written, "{err}");
    assert_eq!(summary["interrupted"], true);
    let spp = summary["spp"].as_u64().unwrap();
    assert!((8..100_000_000).contains(&spp), "{spp}");
}

/// Ctrl-C during an animation keeps the frames completed and writes no partial one.
#[test]
fn an_interrupted_animation_keeps_its_completed_frames() {
    let dir = scratch("interrupt-animate");
    let out = dir.join("frames");
    let (code, err) = interrupted(
        &[
            "animate",
            "cornell-box",
            "--width",
            "16",
            "--height",
            "16",
            "--photons-per-pass",
            "5000",
            "--steps",
            "1000",
            "--time-per-frame",
            "0.05",
            "-o",
            out.to_str().unwrap(),
        ],
        "rendering",
    );
    let frames = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension() == Some("json".as_ref()))
        .count();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(code, Some(130), "{err}");
    assert!((1..1001).contains(&frames), "{frames} frames");
    assert!(
        err.contains(&format!("interrupted: the {frames} frames completed")),
        "{err}"
    );
}

/// Ctrl-C during a convergence report: the rows measured so far are written, marked.
#[test]
fn an_interrupted_report_writes_the_rows_measured() {
    let dir = scratch("interrupt-report");
    let out = dir.join("report");
    let (code, err) = interrupted(
        &[
            "report",
            "convergence",
            "cornell-box",
            "--width",
            "16",
            "--height",
            "16",
            "--photons-per-pass",
            "5000",
            "--seconds",
            "1000",
            "--reference-spp",
            "8",
            "--cache",
            dir.join("cache").to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        "rendering",
    );
    let report = json(&out.join("convergence.json"));
    let rows = std::fs::read_to_string(out.join("convergence.csv"))
        .unwrap()
        .lines()
        .count();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(code, Some(130), "{err}");
    assert_eq!(report["interrupted"], true);
    assert!(rows >= 2, "{rows} lines");
}

/// `ppm animate --path FILE` follows moves the scene never declared: a frame before the
/// first step and one after each step (two steps at the same time make one), each JSON
/// saying what its move did in local mode, the default.
#[test]
fn animate_follows_a_path_file() {
    let dir = scratch("path");
    let path = dir.join("path.toml");
    std::fs::write(
        &path,
        "[[step]]\nafter_iterations = 2\nobject = \"short-block\"\ntranslate = [-60.0, 0.0, 200.0]\n\
         rotate = [0.0, 25.0, 0.0]\n[[step]]\nobject = \"tall-block\"\ntranslate = [0.0, 0.0, -50.0]\n\
         [[step]]\nafter_iterations = 1\nobject = \"short-block\"\ntranslate = [20.0, 0.0, 0.0]\n",
    )
    .unwrap();
    let frames = dir.join("frames");
    let out = ppm(&[
        "animate",
        "cornell-box",
        "--path",
        path.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--photons-per-pass",
        "2000",
        "--time-per-frame",
        "0.05",
        "-o",
        frames.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    for frame in 0..3 {
        let stem = frames.join(format!("frame-{frame:03}"));
        assert!(stem.with_extension("exr").is_file(), "frame {frame}");
        let report = json(&stem.with_extension("json"));
        assert_eq!(report["mode"], "local");
        if frame > 0 {
            assert!(report["move"]["restarted"].is_null(), "{report}");
            assert!(report["move"]["updated"].as_u64().unwrap() > 0, "{report}");
        }
        // An animation's frames do not claim that no move runs.
        let left_out = report["left_out"].to_string();
        assert!(
            !left_out.contains("a single frame is rendered"),
            "{left_out}"
        );
        assert!(
            left_out.contains("no mirror, glass, conductor or coat"),
            "{left_out}"
        );
    }
    assert!(!frames.join("frame-003.exr").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// A path file that names no object of the scene, or gives a number that is not one, is
/// refused before rendering, naming the file, the step, the field and the value.
#[test]
fn a_bad_path_file_names_its_step_field_and_value() {
    let dir = scratch("bad-path");
    let path = dir.join("path.toml");
    let refused = |text: &str| {
        std::fs::write(&path, text).unwrap();
        let out = ppm(&[
            "animate",
            "cornell-box",
            "--path",
            path.to_str().unwrap(),
            "-o",
            dir.join("frames").to_str().unwrap(),
        ]);
        assert!(!out.status.success());
        stderr(&out)
    };
    let unknown = refused("[[step]]\nafter_seconds = 1.0\nobject = \"chair\"\n");
    assert!(
        unknown.contains("path.toml: step[0].object = \"chair\": no object has this name"),
        "{unknown}"
    );
    let outside = refused("[[step]]\nobject = \"tall-block\"\ntranslate = [0.0, 900.0, 0.0]\n");
    assert!(
        outside.contains("step[0] = \"tall-block\": moves the object to"),
        "{outside}"
    );
    assert!(!dir.join("frames").exists(), "nothing rendered");
    std::fs::remove_dir_all(&dir).ok();
}

/// `ppm diff` follows a path file's moves on any pair of backends: the CPU backend against
/// itself agrees on every field of every slot after each of the 10 iterations and 2 moves; a
/// path timed in seconds, which would move the two backends at different iterations, is
/// refused naming the file and the step.
#[test]
fn diff_follows_a_path_on_any_pair_of_backends() {
    let dir = scratch("diff-path");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("path.toml");
    let step = |after: &str, object: &str, by: &str| {
        format!("[[step]]\n{after}\nobject = \"{object}\"\ntranslate = {by}\n")
    };
    std::fs::write(
        &path,
        step("after_iterations = 4", "tall-block", "[-50.0, 0.0, 60.0]")
            + &step("after_iterations = 3", "short-block", "[60.0, 0.0, 40.0]"),
    )
    .unwrap();
    let out_dir = dir.join("out");
    let args = |path: &std::path::Path| {
        [
            "diff",
            "cornell-box",
            "--width",
            "24",
            "--height",
            "24",
            "--passes",
            "3",
            "--photons-per-pass",
            "5000",
            "--backends",
            "cpu,cpu",
            "--path",
            path.to_str().unwrap(),
            "-o",
            out_dir.to_str().unwrap(),
        ]
        .map(str::to_owned)
    };
    let a = args(&path);
    let out = ppm(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(out.status.success(), "{}", stderr(&out));
    let report = json(&out_dir.join("diff.json"));
    assert_eq!(report["all_fields_share"], 1.0, "{report}");
    assert_eq!(report["image_relative_rmse"], 0.0, "{report}");
    let steps: Vec<&str> = report["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    assert_eq!(steps.len(), 12, "{steps:?}");
    assert_eq!(steps.iter().filter(|&&s| s == "move").count(), 2);
    assert_eq!((steps[4], steps[8]), ("move", "move"), "{steps:?}");

    let timed = dir.join("timed.toml");
    std::fs::write(
        &timed,
        step("after_seconds = 1.0", "tall-block", "[-50.0, 0.0, 60.0]"),
    )
    .unwrap();
    let a = args(&timed);
    let out = ppm(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("timed.toml: step 1 waits seconds"), "{err}");
}

/// A local-mode correction too large for one pass, or for this machine's memory, is refused
/// naming the option before anything renders (the memory figures vary by machine).
#[test]
fn an_oversized_correction_is_refused_naming_the_option() {
    let args = |passes: &'static str| {
        [
            "animate",
            "cornell-box",
            "--correction-passes",
            passes,
            "--photons-per-pass",
            "1000000",
            "-o",
            "unused",
        ]
    };
    assert_eq!(
        refusal(&args("100000")),
        "error: --correction-passes = 100000: 100000 passes' worth of 1000000 photons exceed \
         2^32 photons in one pass"
    );
    let memory = refusal(&args("2000"));
    assert!(
        memory.starts_with(
            "error: command line: photons_per_pass * correction_passes = 2000000000: "
        ) && memory.ends_with("lower --correction-passes"),
        "{memory}"
    );
}
