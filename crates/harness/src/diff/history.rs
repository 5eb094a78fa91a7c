//! One pixel's hit points, pass by pass, on two backends: where a disagreement starts.

use super::Recording;
use ppm_core::params::RenderParams;
use serde::Serialize;

/// One hit point's state after one pass on one backend.
#[derive(Clone, Debug, Serialize)]
pub struct HistoryRow {
    /// Pass (0 = after eye pass and direct light).
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
                    pass: pass as u32,
                    backend: rec.backend.clone(),
                    sample: s as u32,
                    valid: hp.is_valid(),
                    position: hp.position,
                    normal: hp.normal,
                    n: hp.n,
                    r2: hp.r2,
                    flux: hp.tau,
                });
            }
        }
    }
    rows
}
