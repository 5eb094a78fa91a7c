//! The minimal backend passes the conformance suite's static tier: the checks any backend
//! that renders still frames must pass, against the CPU backend with the same seed and with
//! independent seeds. It gives no dynamic passes, so the dynamic tier refuses it there.

use harness::conformance::{ConformanceOptions, Tier, run_conformance};
use minimal_backend::MinimalBackend;

#[test]
fn the_minimal_backend_passes_the_static_tier() {
    let verdict = run_conformance(
        &mut || Ok(Box::new(MinimalBackend::new())),
        &ConformanceOptions::quick(),
        Tier::Static,
    );
    println!("{verdict}");
    assert!(verdict.passed(), "{verdict}");
}
