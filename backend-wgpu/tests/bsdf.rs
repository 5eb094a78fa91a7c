//! bsdf.wgsl reproduces ppm_core::bsdf on every test case: the same lobe, and directions,
//! weights, densities and values within float rounding (WGSL's sine and cosine are not
//! correctly rounded, so directions get an absolute allowance).

use backend_wgpu::{GpuContext, WgpuBackend};
use ppm_core::bsdf::{BsdfCase, BsdfOutcome, test_cases};
use ppm_core::layout::material_kind;
use std::process::ExitCode;
use test_support::{Need, Suite};

/// Allowed difference of a direction's components and of relative weights and densities.
const TOLERANCE: f32 = 2e-5;

/// The allowance for a case: a rough conductor's, coat's or glass's density and value are
/// steep in the half vector, by about `1 / alpha`, so a last-place difference in a direction
/// grows by as much.
fn tolerance(case: &BsdfCase) -> f32 {
    let glossy = matches!(
        case.material.kind,
        material_kind::CONDUCTOR | material_kind::COATED | material_kind::GLASS
    );
    match glossy && case.material.alpha > 0.0 {
        true => TOLERANCE / case.material.alpha,
        false => TOLERANCE,
    }
}

fn close(a: f32, b: f32, tolerance: f32) -> bool {
    (a - b).abs() <= tolerance * a.abs().max(b.abs()).max(1.0)
}

fn fields(o: &BsdfOutcome) -> [f32; 15] {
    [
        o.dir[0],
        o.dir[1],
        o.dir[2],
        o.pdf,
        o.weight[0],
        o.weight[1],
        o.weight[2],
        o.f_cos[0],
        o.f_cos[1],
        o.f_cos[2],
        o.pdf_of_dir,
        o.glossy_f_cos[0],
        o.glossy_f_cos[1],
        o.glossy_f_cos[2],
        o.glossy_pdf,
    ]
}

fn the_wgsl_bsdf_reproduces_the_core_s_on_every_case() {
    let gpu = WgpuBackend::new().unwrap();
    let cases = test_cases();
    let got = gpu.bsdf_vectors(&cases).unwrap();
    assert_eq!(got.len(), cases.len());
    for (case, wgsl) in cases.iter().zip(&got) {
        let core = case.expected();
        assert_eq!(wgsl.transmitted, core.transmitted, "{case:?}");
        for (w, c) in fields(wgsl).into_iter().zip(fields(&core)) {
            assert!(
                close(w, c, tolerance(case)),
                "WGSL {wgsl:?}, core {core:?}, case {case:?}"
            );
        }
    }
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "the_wgsl_bsdf_reproduces_the_core_s_on_every_case",
            the_wgsl_bsdf_reproduces_the_core_s_on_every_case,
        )
        .run()
}
