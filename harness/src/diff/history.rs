//! One pixel's hit points, pass by pass, on two backends: where a disagreement starts.

use super::Recording;
use ppm_core::params::RenderParams;
use serde::Serialize;
use std::fmt::Write as _;

/// One hit point's state after one pass on one backend.
#[derive(Clone, Debug, Serialize)]
pub struct HistoryRow {
    /// Iteration (from 1).
    pub pass: u32,
    /// Backend.
    pub backend: String,
    /// Eye sample within the pixel.
    pub sample: u32,
    /// Whether the slot holds a hit point.
    pub valid: bool,
    /// Position.
    pub position: [f32; 3],
    /// Normal.
    pub normal: [f32; 3],
    /// Photon count.
    pub n: f32,
    /// Squared radius.
    pub r2: f32,
    /// Flux.
    pub flux: [f32; 3],
    /// Mean direct radiance over the slot's iterations.
    pub direct: [f32; 3],
}

/// The history of pixel `(x, y)` on both recordings, interleaved pass by pass.
pub fn pixel_history(
    recordings: &[&Recording],
    params: &RenderParams,
    x: u32,
    y: u32,
) -> Vec<HistoryRow> {
    let pixel = (y * params.width + x) as usize;
    let passes = recordings.iter().map(|r| r.passes.len()).min().unwrap_or(0);
    let mut rows = Vec::new();
    for pass in 0..passes {
        for rec in recordings {
            for s in 0..params.spp as usize {
                let hp = &rec.passes[pass][pixel * params.spp as usize + s];
                rows.push(HistoryRow {
                    pass: pass as u32 + 1,
                    backend: rec.backend.clone(),
                    sample: s as u32,
                    valid: hp.is_valid(),
                    position: hp.position,
                    normal: hp.normal,
                    n: hp.n,
                    r2: hp.r2,
                    flux: hp.tau,
                    direct: hp.direct_mean(),
                });
            }
        }
    }
    rows
}

/// The pixel-history table.
pub fn format(rows: &[HistoryRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:>4} {:<6} {:>2} {:<34} {:<24} {:>10} {:>11} flux",
        "pass", "back", "s", "position", "normal", "n", "r2"
    );
    for r in rows {
        let v3 = |v: [f32; 3]| format!("{:.4} {:.4} {:.4}", v[0], v[1], v[2]);
        if !r.valid {
            let _ = writeln!(
                s,
                "{:>4} {:<6} {:>2} (no hit point)",
                r.pass, r.backend, r.sample
            );
            continue;
        }
        let _ = writeln!(
            s,
            "{:>4} {:<6} {:>2} {:<34} {:<24} {:>10.3} {:>11.5e} {:.5e} {:.5e} {:.5e}",
            r.pass,
            r.backend,
            r.sample,
            v3(r.position),
            format!("{:.3} {:.3} {:.3}", r.normal[0], r.normal[1], r.normal[2]),
            r.n,
            r.r2,
            r.flux[0],
            r.flux[1],
            r.flux[2]
        );
    }
    s
}
