//! The minimal backend passes the conformance suite's local tier: the checks any backend that
//! renders still frames must pass, and those of local moves (their passes, the correction's
//! photons and apply, and the moves against the CPU backend with the same seed and with
//! independent seeds). It gives none of the thesis's passes, so the dynamic tier refuses it
//! there.

use harness::conformance::{ConformanceOptions, Tier, run_conformance};
use minimal_backend::MinimalBackend;

#[test]
fn the_minimal_backend_passes_the_local_tier() {
    let verdict = run_conformance(
        &mut || Ok(Box::new(MinimalBackend::new())),
        &ConformanceOptions::quick(),
        Tier::Local,
    );
    println!("{verdict}");
    assert!(verdict.passed(), "{verdict}");
}
