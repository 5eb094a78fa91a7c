//! `ppm` with the minimal backend registered beside the in-tree ones: every command that takes
//! `--backend` or `--backends` runs it, so `ppm-minimal diff SCENE --backends cpu,minimal`
//! finds where it parts from the CPU backend.

use harness::registry::Registry;
use minimal_backend::MinimalBackend;

fn main() -> std::process::ExitCode {
    let registry = Registry::in_tree().with(
        "minimal",
        "examples/minimal-backend: one thread, plain loops (the static tier)",
        || Ok(Box::new(MinimalBackend::new())),
    );
    harness::cli::main(registry)
}
