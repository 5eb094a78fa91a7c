//! update.wgsl's gather rule reproduces ppm_core::update::gather's on every test case, kind
//! for kind, within a few units in the last place (WGSL may fuse or reorder a multiply-add).

use backend_wgpu::{GpuContext, WgpuBackend};
use ppm_core::update::gather::{SlotState, test_cases};
use std::process::ExitCode;
use test_support::{Need, Suite};

/// Units in the last place allowed between the two rules, per field.
const ULPS: u32 = 4;

fn ulps_apart(a: f32, b: f32) -> u32 {
    if a == b {
        return 0;
    }
    if a.is_nan() || b.is_nan() || a.signum() != b.signum() {
        return u32::MAX;
    }
    a.to_bits().abs_diff(b.to_bits())
}

fn fields(s: &SlotState) -> [f32; 10] {
    [
        s.tau[0],
        s.tau[1],
        s.tau[2],
        s.n,
        s.pending[0],
        s.pending[1],
        s.pending[2],
        s.pending[3],
        s.r2,
        s.emitted,
    ]
}

fn the_wgsl_gather_rule_reproduces_the_core_s_on_every_kind() {
    let gpu = WgpuBackend::new().unwrap();
    let cases = test_cases();
    let got = gpu.gather_rule_vectors(&cases).unwrap();
    assert_eq!(got.len(), cases.len());
    let mut unchanged_kinds: std::collections::BTreeSet<u32> =
        cases.iter().map(|c| c.params.kind).collect();
    for (case, wgsl) in cases.iter().zip(&got) {
        let core = case.expected();
        if core != case.slot {
            unchanged_kinds.remove(&case.params.kind);
        }
        assert_eq!(wgsl.flags, core.flags, "{case:?}");
        for (w, c) in fields(wgsl).into_iter().zip(fields(&core)) {
            assert!(
                ulps_apart(w, c) <= ULPS,
                "kind {:#x}: WGSL {wgsl:?}, core {core:?}, case {case:?}",
                case.params.kind
            );
        }
    }
    // The vectors exercise the rule: every kind changes some slot.
    assert!(
        unchanged_kinds.is_empty(),
        "kinds that changed no slot: {unchanged_kinds:x?}"
    );
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "the_wgsl_gather_rule_reproduces_the_core_s_on_every_kind",
            the_wgsl_gather_rule_reproduces_the_core_s_on_every_kind,
        )
        .run()
}
