//! A real single-node Slurm cluster (Debian's slurm-wlm and munge, started and stopped by
//! `scripts/slurm/cluster.sh`): a 4-task array of reference shards and the merge that depends
//! on it give one single-process run's image, bit for bit.
//!
//! Needs root and Slurm installed (`scripts/slurm/cluster.sh install`); otherwise shown as
//! ignored, unless `PPM_REQUIRE_SLURM=1` (as `.ci/run` sets it) makes that a failure.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::{Duration, Instant};
use test_support::{Need, Suite};

fn scripts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/slurm")
}

/// The cluster, stopped when dropped.
struct Cluster {
    state: PathBuf,
}

impl Cluster {
    /// Starts the cluster (the suite has checked that this process can).
    fn start() -> Self {
        let state = std::env::temp_dir().join(format!("ppm-slurm-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&state);
        let started = Command::new(scripts().join("cluster.sh"))
            .arg("start")
            .arg(&state)
            .status()
            .unwrap();
        let cluster = Self { state };
        assert!(started.success(), "the cluster did not start");
        cluster
    }

    fn conf(&self) -> PathBuf {
        self.state.join("slurm.conf")
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new(scripts().join("cluster.sh"))
            .arg("stop")
            .arg(&self.state)
            .status();
    }
}

fn a_slurm_array_of_reference_shards_merges_into_one_run_bit_for_bit() {
    let cluster = Cluster::start();
    let out = std::env::temp_dir().join(format!("ppm-slurm-out-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let ppm = env!("CARGO_BIN_EXE_ppm");
    let submitted = Command::new(scripts().join("submit.sh"))
        .arg("reference")
        .env("SLURM_CONF", cluster.conf())
        .env("PPM", ppm)
        .env("SCENE", "cornell-box")
        .env("WIDTH", "64")
        .env("HEIGHT", "64")
        .env("SPP", "32")
        .env("SHARDS", "4")
        .env("OUT", &out)
        .output()
        .unwrap();
    assert!(
        submitted.status.success(),
        "{}",
        String::from_utf8_lossy(&submitted.stderr)
    );
    let ids = String::from_utf8_lossy(&submitted.stdout).into_owned();
    let merge_id = ids
        .split_whitespace()
        .nth(1)
        .expect("two job ids")
        .to_owned();
    let start = Instant::now();
    loop {
        let queued = Command::new("squeue")
            .args(["-h", "-j", &merge_id, "-o", "%T %r"])
            .env("SLURM_CONF", cluster.conf())
            .output()
            .unwrap();
        let state = String::from_utf8_lossy(&queued.stdout).trim().to_owned();
        if state.is_empty() {
            break;
        }
        assert!(
            !state.contains("DependencyNeverSatisfied"),
            "a shard failed: {}",
            logs(&out)
        );
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "the jobs did not finish: {state}\n{}",
            logs(&out)
        );
        std::thread::sleep(Duration::from_millis(250));
    }
    let merged = out.join("merged.exr");
    assert!(merged.exists(), "no merged image: {}", logs(&out));

    let single = out.join("single.exr");
    let rendered = Command::new(ppm)
        .args([
            "reference",
            "cornell-box",
            "--width",
            "64",
            "--height",
            "64",
        ])
        .args(["--spp", "32", "-o"])
        .arg(&single)
        .output()
        .unwrap();
    assert!(rendered.status.success());
    for (a, b) in [
        (merged.clone(), single.clone()),
        (
            merged.with_extension("var.exr"),
            single.with_extension("var.exr"),
        ),
    ] {
        assert!(
            std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
            "{} differs from {}",
            a.display(),
            b.display()
        );
    }
}

/// The jobs' logs, for a failure's message.
fn logs(out: &Path) -> String {
    let mut text = String::new();
    for entry in std::fs::read_dir(out.join("logs"))
        .into_iter()
        .flatten()
        .flatten()
    {
        text += &format!("== {}\n", entry.path().display());
        text += &std::fs::read_to_string(entry.path()).unwrap_or_default();
    }
    text
}

fn main() -> ExitCode {
    Suite::new()
        .test_needing(
            &[&Need::slurm()],
            "a_slurm_array_of_reference_shards_merges_into_one_run_bit_for_bit",
            a_slurm_array_of_reference_shards_merges_into_one_run_bit_for_bit,
        )
        .run()
}
