//! The stress family (scenes::stress) on both backends: every invariant holds on every case,
//! and the cases with a closed form meet it.

use harness::stress::{run_case, table};
use ppm_core::passes::Backend;
use scenes::stress::STRESS;
use std::process::ExitCode;
use tests::{BackendTrials, Suite, figure};

fn every_stress_case_holds_on_every_backend(name: &str, mut backend: Box<dyn Backend + Send>) {
    let results: Vec<_> = STRESS
        .iter()
        .map(|c| run_case(backend.as_mut(), c))
        .collect();
    figure!("{name}:\n{}", table(&results));
    assert!(
        results.iter().all(|r| r.passed),
        "{name}:\n{}",
        table(&results)
    );
}

/// Radiance is scale-invariant when the radius scales with the scene, and linear in the
/// light: the furnace at 1e-4 and 1e4 units, and at 1e-20 and 1e20 radiance, gives the unit
/// furnace's image, scaled, to rounding.
fn scale_and_power_cases_reproduce_the_unit_furnace() {
    let mean = |name: &str| {
        let case = scenes::stress::stress_case(name).unwrap();
        run_case(&mut backend_cpu::CpuBackend::new(), case)
            .worst
            .mean_radiance
    };
    let unit = mean("scale-1");
    for (name, factor) in [
        ("scale-1e-4", 1.0),
        ("scale-1e4", 1.0),
        ("power-1e-20", 1e-20),
        ("power-1e20", 1e20),
    ] {
        let m = mean(name) / factor;
        assert!((m / unit - 1.0).abs() < 1e-3, "{name}: {m} vs {unit}");
    }
}

/// Every backend agrees with the CPU on every case by the harness's independent-seed test.
/// The false-alarm rate 0.01 is split among the cases (Bonferroni), so the whole family keeps
/// it.
fn every_backend_agrees_with_the_cpu_on_every_stress_case(
    name: &str,
    mut other: Box<dyn Backend + Send>,
) {
    let alpha = 0.01 / STRESS.len() as f64;
    let mut failures = Vec::new();
    for case in STRESS {
        let mut cpu = backend_cpu::CpuBackend::new();
        match harness::stress::agreement(&mut cpu, other.as_mut(), case, alpha) {
            Ok(Some(r)) => {
                figure!(
                    "{name} {:<24} {} of {} tests rejected, smallest p {:.2e}",
                    case.name,
                    r.rejected,
                    r.tests,
                    r.min_p
                );
                if !r.agree {
                    failures.push(format!(
                        "{name} {}: {} rejected, min p {:.2e}",
                        case.name, r.rejected, r.min_p
                    ));
                }
            }
            Ok(None) => figure!(
                "{name} {:<24} refused on the f32 limit: nothing to compare",
                case.name
            ),
            Err(e) => failures.push(format!("{name} {}: {e}", case.name)),
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

fn main() -> ExitCode {
    Suite::new()
        .on_every_backend(
            "every_stress_case_holds_on_every_backend",
            every_stress_case_holds_on_every_backend,
        )
        .test(
            "scale_and_power_cases_reproduce_the_unit_furnace",
            scale_and_power_cases_reproduce_the_unit_furnace,
        )
        .against_the_cpu(
            "every_backend_agrees_with_the_cpu_on_every_stress_case",
            every_backend_agrees_with_the_cpu_on_every_stress_case,
        )
        .run()
}
