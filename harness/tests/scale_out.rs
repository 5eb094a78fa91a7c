//! Work split across processes: reference shards that merge into one run bit for bit, render
//! shards averaged by their iterations, merges refused when the files do not belong together,
//! and checkpoints that resume a render bit for bit on both backends, Ctrl-C included.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Output};
use test_support::{Need, Suite};

fn ppm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ppm"))
        .args(args)
        .output()
        .expect("ppm runs")
}

fn ok(args: &[&str]) -> Output {
    let out = ppm(args);
    assert!(
        out.status.success(),
        "ppm {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn refused(args: &[&str]) -> String {
    let out = ppm(args);
    assert!(!out.status.success(), "ppm {args:?} was accepted");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-scale-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn same_bytes(a: &Path, b: &Path) -> bool {
    std::fs::read(a).unwrap() == std::fs::read(b).unwrap()
}

fn reference_shards_merge_into_one_run_bit_for_bit() {
    let dir = scratch("reference");
    let reference = |spp: &str, extra: &[&str], out: &Path| {
        let out = s(out);
        let mut args = vec![
            "reference",
            "cornell-box",
            "--width",
            "160",
            "--height",
            "136",
            "--spp",
            spp,
            "-o",
            &out,
        ];
        args.extend(extra);
        ok(&args);
    };
    let whole = dir.join("whole.exr");
    reference("32", &[], &whole);
    let shards: Vec<PathBuf> = (0..4).map(|i| dir.join(format!("shard{i}.exr"))).collect();
    for (i, shard) in shards.iter().enumerate() {
        reference("32", &["--shard", &format!("{i}/4")], shard);
    }
    // Any order of the inputs.
    let merged = dir.join("merged.exr");
    let mut args = vec!["merge".to_owned()];
    args.extend([3, 1, 0, 2].map(|i| s(&shards[i])));
    args.extend(["-o".to_owned(), s(&merged)]);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(
        same_bytes(&merged, &whole),
        "the merged mean is the single run's"
    );
    assert!(
        same_bytes(
            &merged.with_extension("var.exr"),
            &whole.with_extension("var.exr")
        ),
        "the merged variance is the single run's"
    );

    // What does not belong together is refused, naming the file and what differs.
    let other_spp = dir.join("other.exr");
    reference("16", &["--shard", "3/4"], &other_spp);
    let (a, b, c) = (s(&shards[0]), s(&shards[1]), s(&shards[2]));
    let mismatch = refused(&[
        "merge",
        &a,
        &b,
        &c,
        &s(&other_spp),
        "-o",
        &s(&dir.join("x.exr")),
    ]);
    assert!(
        mismatch.contains("other.exr: spp = 16") && mismatch.contains("32"),
        "{mismatch}"
    );
    let missing = refused(&["merge", &a, &b, &c, "-o", &s(&dir.join("x.exr"))]);
    assert!(missing.contains("shards 3 of 4 are missing"), "{missing}");
    let twice = refused(&["merge", &a, &b, &c, &a, "-o", &s(&dir.join("x.exr"))]);
    assert!(twice.contains("both shard 0/4"), "{twice}");
    let not_shard = refused(&["merge", &a, &s(&whole), "-o", &s(&dir.join("x.exr"))]);
    assert!(not_shard.contains("whole.exr: not a shard"), "{not_shard}");
}

fn render_shards_average_by_their_iterations() {
    let dir = scratch("render");
    let render = |shard: &str, passes: &str, extra: &[&str], out: &Path| {
        let out = s(out);
        let mut args = vec![
            "render",
            "cornell-box",
            "--width",
            "24",
            "--height",
            "24",
            "--passes",
            passes,
            "--shard",
            shard,
            "-o",
            &out,
        ];
        args.extend(extra);
        ok(&args);
    };
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    render("0/2", "3", &[], &a);
    render("1/2", "5", &[], &b);
    let merged = dir.join("merged.exr");
    ok(&["merge", &s(&a), &s(&b), "-o", &s(&merged)]);
    let read = |p: &Path| scenes::file::image::read_exr(p, 24, 24).unwrap();
    let (ia, ib, im) = (read(&a), read(&b), read(&merged));
    assert_ne!(ia.pixels, ib.pixels, "independent seeds");
    for ((pa, pb), pm) in ia.pixels.iter().zip(&ib.pixels).zip(&im.pixels) {
        for c in 0..3 {
            let expected = (3.0 * f64::from(pa[c]) + 5.0 * f64::from(pb[c])) / 8.0;
            assert!((f64::from(pm[c]) - expected).abs() <= 1e-6 * expected.abs().max(1e-3));
        }
    }
    let summary = std::fs::read_to_string(merged.with_extension("json")).unwrap();
    assert!(
        summary.contains("\"passes\": 8") && summary.contains("bias"),
        "{summary}"
    );
    let c = dir.join("c.exr");
    render("1/2", "3", &["--alpha", "0.5"], &c);
    let other = refused(&["merge", &s(&a), &s(&c), "-o", &s(&dir.join("x.exr"))]);
    assert!(other.contains("c.exr: params.alpha = 0.5"), "{other}");
}

fn render_args<'a>(backend: &'a str, passes: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "render",
        "cornell-box",
        "--backend",
        backend,
        "--width",
        "48",
        "--height",
        "48",
        "--passes",
        passes,
        "-o",
        out,
    ]
}

/// A render stopped after 3 of 7 iterations and resumed from its checkpoint writes the image
/// of the uninterrupted render, bit for bit; returns the folder that holds the checkpoint.
fn a_resumed_render_equals_an_uninterrupted_one(backend: &str) -> PathBuf {
    let dir = scratch(&format!("resume-{backend}"));
    let (full, part, resumed) = (
        s(&dir.join(format!("full-{backend}.exr"))),
        s(&dir.join(format!("part-{backend}.exr"))),
        s(&dir.join(format!("resumed-{backend}.exr"))),
    );
    let checkpoint = s(&dir.join(format!("checkpoint-{backend}")));
    ok(&render_args(backend, "7", &full));
    let mut first = render_args(backend, "3", &part);
    first.extend(["--checkpoint", &checkpoint]);
    ok(&first);
    let mut rest = render_args(backend, "7", &resumed);
    rest.extend(["--resume", &checkpoint]);
    ok(&rest);
    assert!(
        same_bytes(Path::new(&full), Path::new(&resumed)),
        "{backend}: the resumed image is the uninterrupted one"
    );
    let report = std::fs::read_to_string(dir.join(format!("resumed-{backend}.json"))).unwrap();
    assert!(report.contains("\"passes\": 7"), "{report}");
    dir
}

/// Resuming with another setting, or from a torn checkpoint, is refused before anything
/// renders.
fn a_checkpoint_of_other_settings_or_torn_is_refused(dir: &Path) {
    let checkpoint = dir.join("checkpoint-cpu");
    let out = s(&dir.join("x.exr"));
    let mut other = render_args("cpu", "7", &out);
    other.extend(["--alpha", "0.5", "--resume", checkpoint.to_str().unwrap()]);
    let why = refused(&other);
    assert!(why.contains("another scene or other settings"), "{why}");
    let mut slots = std::fs::read(checkpoint.join("slots.bin")).unwrap();
    slots[100] ^= 1;
    std::fs::write(checkpoint.join("slots.bin"), slots).unwrap();
    let mut torn = render_args("cpu", "7", &out);
    torn.extend(["--resume", checkpoint.to_str().unwrap()]);
    let why = refused(&torn);
    assert!(why.contains("caught between two writes"), "{why}");
}

/// Ctrl-C (as a scheduler's preemption sends SIGTERM) keeps the state; resuming it finishes
/// the render exactly as if it had never stopped.
fn an_interrupted_render_resumes_bit_for_bit() {
    let dir = scratch("interrupt");
    let (full, stopped, resumed) = (
        s(&dir.join("full.exr")),
        s(&dir.join("stopped.exr")),
        s(&dir.join("resumed.exr")),
    );
    let checkpoint = dir.join("checkpoint");
    ok(&render_args("cpu", "400", &full));
    let mut args = render_args("cpu", "400", &stopped);
    let every = "0.05";
    args.extend([
        "--checkpoint",
        checkpoint.to_str().unwrap(),
        "--checkpoint-every",
        every,
    ]);
    let mut command = Command::new(env!("CARGO_BIN_EXE_ppm"));
    command.args(&args);
    let (status, stderr) = common::interrupted(command, "checkpoint:");
    assert_eq!(status, Some(130), "stopped by the interrupt: {stderr}");
    let state = std::fs::read_to_string(checkpoint.join("state.json")).unwrap();
    let state: serde_json::Value = serde_json::from_str(&state).unwrap();
    let done = state["report"]["passes"].as_u64().unwrap();
    assert!(done < 400, "the interrupt came before the end ({done})");
    let mut rest = render_args("cpu", "400", &resumed);
    rest.extend(["--resume", checkpoint.to_str().unwrap()]);
    ok(&rest);
    assert!(same_bytes(Path::new(&full), Path::new(&resumed)));
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| {
        backend_wgpu::GpuContext::new()
            .map(drop)
            .map_err(|e| e.to_string())
    });
    Suite::new()
        .test(
            "reference_shards_merge_into_one_run_bit_for_bit",
            reference_shards_merge_into_one_run_bit_for_bit,
        )
        .test(
            "render_shards_average_by_their_iterations",
            render_shards_average_by_their_iterations,
        )
        .test("a_resumed_render_equals_an_uninterrupted_one::cpu", || {
            let dir = a_resumed_render_equals_an_uninterrupted_one("cpu");
            a_checkpoint_of_other_settings_or_torn_is_refused(&dir);
        })
        .test_needing(
            &[&adapter],
            "a_resumed_render_equals_an_uninterrupted_one::wgpu",
            || {
                a_resumed_render_equals_an_uninterrupted_one("wgpu");
            },
        )
        .test(
            "an_interrupted_render_resumes_bit_for_bit",
            an_interrupted_render_resumes_bit_for_bit,
        )
        .run()
}
