//! The minimal backend, registered from outside the repository's crates, runs under the `ppm`
//! command line: `ppm-minimal diff --backends cpu,minimal` compares it with the CPU backend
//! slot by slot, and they agree.

use std::process::Command;

fn ppm_minimal(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ppm-minimal"))
        .args(args)
        .output()
        .expect("ppm-minimal runs");
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

#[test]
fn the_command_line_lists_and_diffs_the_registered_backend() {
    let (ok, listed) = ppm_minimal(&["backends"]);
    assert!(
        ok && listed.contains("minimal") && listed.contains("cpu"),
        "{listed}"
    );
    let dir = std::env::temp_dir().join(format!("ppm-minimal-diff-{}", std::process::id()));
    let (ok, report) = ppm_minimal(&[
        "diff",
        "cornell-box",
        "--backends",
        "cpu,minimal",
        "--width",
        "32",
        "--height",
        "32",
        "--passes",
        "3",
        "--photons-per-pass",
        "10000",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(ok && report.contains("verdict: agree"), "{report}");
    let (ok, refused) = ppm_minimal(&["render", "cornell-box", "--backend", "nonesuch"]);
    assert!(
        !ok && refused.contains("registered: cpu, wgpu, minimal"),
        "{refused}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
