//! Same-seed comparison: both backends trace the same paths up to rounding, so hit points are
//! compared field by field.
//!
//! Tolerance: a field agrees when `|a - b| <= 1e-3 * max(|a|, |b|) + floor`, with `floor` one
//! millionth of the field's mean magnitude. The backends differ only by rounding (FMA
//! contraction, sqrt/sin/cos within a few ulps, sums in the same order), which moves a value
//! by ~1e-6 relative per operation and ~1e-5 after hundreds of photons and several passes, so
//! 1e-3 leaves a hundredfold margin. A photon found by one backend and missed by the other
//! moves `n` by `alpha` and the flux by that photon's share, far beyond it at the counts of a
//! short comparison. Where rounding sends a whole path elsewhere, a few hit points disagree
//! outright: the verdict requires `required_share` of hit points to agree on each field.

use super::{Recording, heat_map, luminance, slot_pixel};
use ppm_core::image::Image;
use ppm_core::layout::HitPoint;
use ppm_core::metrics::relative_rmse;
use ppm_core::params::RenderParams;
use serde::Serialize;
use std::fmt::Write as _;

/// Relative tolerance of a field.
pub const RELATIVE_TOLERANCE: f64 = 1e-3;
/// Share of hit points that must agree on each field.
pub const REQUIRED_SHARE: f64 = 0.99;
/// Largest relative RMSE between the two resolved images.
pub const IMAGE_TOLERANCE: f64 = 1e-2;

/// Agreement of one field over all compared slots.
#[derive(Clone, Debug, Serialize)]
pub struct FieldAgreement {
    /// `flux`, `r2`, `n`, `direct`, `iterations` or `valid`.
    pub field: &'static str,
    /// Share of slots within tolerance after the last pass.
    pub share: f64,
    /// Largest relative difference seen.
    pub worst_relative: f64,
}

/// A hit point that disagrees.
#[derive(Clone, Debug, Serialize)]
pub struct Divergence {
    /// Slot index.
    pub slot: usize,
    /// Pixel column.
    pub x: u32,
    /// Pixel row.
    pub y: u32,
    /// Worst field.
    pub field: &'static str,
    /// Reference backend's value.
    pub reference: f64,
    /// Other backend's value.
    pub other: f64,
    /// Relative difference.
    pub relative: f64,
    /// First step (an iteration or a move, from 1) after which any field left tolerance.
    pub first_pass: u32,
}

/// How many hit points first diverged at a step.
#[derive(Clone, Debug, Serialize)]
pub struct PassCount {
    /// Step (an iteration or a move, from 1).
    pub pass: u32,
    /// What the step was: `iteration` or `move`.
    pub step: &'static str,
    /// Hit points that first diverged there.
    pub hit_points: usize,
}

/// The same-seed verdict.
#[derive(Clone, Debug, Serialize)]
pub struct SameSeedReport {
    /// Reference backend.
    pub reference: String,
    /// Compared backend.
    pub other: String,
    /// Slots compared.
    pub slots: usize,
    /// The steps compared, in order: `iteration` or `move`.
    pub steps: Vec<&'static str>,
    /// Relative tolerance per field.
    pub relative_tolerance: f64,
    /// Share required per field.
    pub required_share: f64,
    /// Per-field agreement after the last pass.
    pub fields: Vec<FieldAgreement>,
    /// Share of slots agreeing on every field.
    pub all_fields_share: f64,
    /// Where hit points first diverged.
    pub first_divergence: Vec<PassCount>,
    /// The worst hit points.
    pub worst: Vec<Divergence>,
    /// Relative RMSE between the resolved images.
    pub image_relative_rmse: f64,
    /// Whether the backends agree.
    pub agree: bool,
}

/// One slot's comparable fields: flux and direct sum (three channels each), r2, n, the
/// direct sum's iteration count, and whether it has a visible point.
fn fields(hp: &HitPoint) -> [(&'static str, f64); 10] {
    [
        ("flux", f64::from(hp.tau[0])),
        ("flux", f64::from(hp.tau[1])),
        ("flux", f64::from(hp.tau[2])),
        ("r2", f64::from(hp.r2)),
        ("n", f64::from(hp.n)),
        ("direct", f64::from(hp.direct[0])),
        ("direct", f64::from(hp.direct[1])),
        ("direct", f64::from(hp.direct[2])),
        ("iterations", f64::from(hp.iterations)),
        ("valid", f64::from(u8::from(hp.is_valid()))),
    ]
}

/// The compared field groups.
const FIELD_NAMES: [&str; GROUPS] = ["flux", "r2", "n", "direct", "iterations", "valid"];
const GROUPS: usize = 6;

fn field_slot(name: &str) -> usize {
    FIELD_NAMES.iter().position(|f| *f == name).unwrap_or(0)
}

/// Per-field absolute floors: a millionth of each field's mean magnitude in the reference.
fn floors(hps: &[HitPoint]) -> [f64; GROUPS] {
    let mut sum = [0.0f64; GROUPS];
    for hp in hps {
        for (name, v) in fields(hp) {
            sum[field_slot(name)] += v.abs();
        }
    }
    sum.map(|s| 1e-6 * s / hps.len().max(1) as f64)
}

/// Per field group of one slot: (largest relative difference, within tolerance, reference
/// value, other value), the flux group taking its worst channel.
fn differences(
    a: &HitPoint,
    b: &HitPoint,
    floor: &[f64; GROUPS],
) -> [(f64, bool, f64, f64); GROUPS] {
    let mut out = [(0.0, true, 0.0, 0.0); GROUPS];
    for ((name, x), (_, y)) in fields(a).into_iter().zip(fields(b)) {
        let k = field_slot(name);
        let scale = x.abs().max(y.abs());
        let relative = if scale > 0.0 {
            (x - y).abs() / scale
        } else {
            0.0
        };
        let ok = (x - y).abs() <= RELATIVE_TOLERANCE * scale + floor[k];
        let entry = &mut out[k];
        if relative >= entry.0 {
            *entry = (relative, entry.1, x, y);
        }
        entry.1 &= ok;
    }
    out
}

/// Compares two same-seed recordings of one render.
pub fn compare(
    reference: &Recording,
    other: &Recording,
    params: &RenderParams,
    worst_count: usize,
) -> SameSeedReport {
    let last = reference.passes.len().min(other.passes.len()) - 1;
    let (ra, rb) = (&reference.passes[last], &other.passes[last]);
    let floor = floors(ra);
    let slots = ra.len().min(rb.len());
    let mut within = [0usize; GROUPS];
    let mut worst_rel = [0.0f64; GROUPS];
    let mut all = 0usize;
    let mut worst = Vec::new();
    for i in 0..slots {
        let d = differences(&ra[i], &rb[i], &floor);
        for k in 0..GROUPS {
            within[k] += usize::from(d[k].1);
            worst_rel[k] = worst_rel[k].max(d[k].0);
        }
        if d.iter().all(|x| x.1) {
            all += 1;
        } else {
            let (k, (rel, _, x, y)) = d
                .iter()
                .enumerate()
                .filter(|(_, x)| !x.1)
                .max_by(|a, b| a.1.0.total_cmp(&b.1.0))
                .map(|(k, x)| (k, *x))
                .unwrap_or((0, d[0]));
            let (px, py) = slot_pixel(i, params);
            worst.push(Divergence {
                slot: i,
                x: px,
                y: py,
                field: FIELD_NAMES[k],
                reference: x,
                other: y,
                relative: rel,
                first_pass: first_divergence(reference, other, i, &floor),
            });
        }
    }
    let mut histogram: Vec<PassCount> = Vec::new();
    for d in &worst {
        match histogram.iter_mut().find(|p| p.pass == d.first_pass) {
            Some(p) => p.hit_points += 1,
            None => histogram.push(PassCount {
                pass: d.first_pass,
                step: reference
                    .steps
                    .get(d.first_pass as usize - 1)
                    .copied()
                    .unwrap_or("end"),
                hit_points: 1,
            }),
        }
    }
    histogram.sort_by_key(|p| p.pass);
    worst.sort_by(|a, b| b.relative.total_cmp(&a.relative).then(a.slot.cmp(&b.slot)));
    worst.truncate(worst_count);
    let share = |n: usize| n as f64 / slots.max(1) as f64;
    let fields: Vec<FieldAgreement> = (0..GROUPS)
        .map(|k| FieldAgreement {
            field: FIELD_NAMES[k],
            share: share(within[k]),
            worst_relative: worst_rel[k],
        })
        .collect();
    let image_relative_rmse = relative_rmse(&other.image, &reference.image);
    let agree =
        fields.iter().all(|f| f.share >= REQUIRED_SHARE) && image_relative_rmse <= IMAGE_TOLERANCE;
    SameSeedReport {
        reference: reference.backend.clone(),
        other: other.backend.clone(),
        slots,
        steps: reference.steps.clone(),
        relative_tolerance: RELATIVE_TOLERANCE,
        required_share: REQUIRED_SHARE,
        fields,
        all_fields_share: share(all),
        first_divergence: histogram,
        worst,
        image_relative_rmse,
        agree,
    }
}

/// The first step (counted from 1) after which fewer than [`REQUIRED_SHARE`] of the slots
/// agree on every field, if any: where two same-seed recordings part (`ppm diff
/// --save-state` keeps the state just before it).
pub fn first_disagreement(a: &Recording, b: &Recording) -> Option<u32> {
    a.passes
        .iter()
        .zip(&b.passes)
        .position(|(pa, pb)| {
            let floor = floors(pa);
            let agreeing = pa
                .iter()
                .zip(pb)
                .filter(|(x, y)| differences(x, y, &floor).iter().all(|d| d.1))
                .count();
            pa.len() != pb.len() || (agreeing as f64) < REQUIRED_SHARE * pa.len() as f64
        })
        .map(|k| k as u32 + 1)
}

/// First iteration (counted from 1) after which slot `i` left tolerance on any field.
fn first_divergence(a: &Recording, b: &Recording, i: usize, floor: &[f64; GROUPS]) -> u32 {
    for (pass, (pa, pb)) in a.passes.iter().zip(&b.passes).enumerate() {
        // A backend that lost slots (or gained some) parts from the reference there.
        if pb.len() != pa.len() || differences(&pa[i], &pb[i], floor).iter().any(|d| !d.1) {
            return pass as u32 + 1;
        }
    }
    a.passes.len() as u32 + 1
}

/// Per-pixel heat map: luminance difference relative to the reference image's mean luminance.
pub fn heat(reference: &Image, other: &Image) -> Image {
    let mean = reference.pixels.iter().map(|p| luminance(*p)).sum::<f64>()
        / reference.pixels.len().max(1) as f64;
    let values: Vec<f64> = reference
        .pixels
        .iter()
        .zip(&other.pixels)
        .map(|(a, b)| (luminance(*a) - luminance(*b)).abs() / mean.max(f64::MIN_POSITIVE))
        .collect();
    heat_map(reference.width, reference.height, &values)
}

/// The same-seed table.
pub fn format(r: &SameSeedReport) -> String {
    let mut s = String::new();
    let moves = r.steps.iter().filter(|&&s| s == "move").count();
    let _ = writeln!(
        s,
        "same seed: {} (reference) vs {}, {} hit-point slots, compared after {} iterations and {moves} {}",
        r.reference,
        r.other,
        r.slots,
        r.steps.len() - moves,
        if moves == 1 { "move" } else { "moves" }
    );
    let _ = writeln!(
        s,
        "tolerance: relative {:e}; required share per field {:.1}%",
        r.relative_tolerance,
        100.0 * r.required_share
    );
    let _ = writeln!(
        s,
        "{:<10} {:>12} {:>16}",
        "field", "within tol.", "worst relative"
    );
    for f in &r.fields {
        let _ = writeln!(
            s,
            "{:<10} {:>11.4}% {:>16.3e}",
            f.field,
            100.0 * f.share,
            f.worst_relative
        );
    }
    let _ = writeln!(
        s,
        "all fields: {:.4}%   image relative RMSE: {:.3e}",
        100.0 * r.all_fields_share,
        r.image_relative_rmse
    );
    if !r.first_divergence.is_empty() {
        let passes: Vec<String> = r
            .first_divergence
            .iter()
            .map(|p| format!("step {} ({}): {}", p.pass, p.step, p.hit_points))
            .collect();
        let _ = writeln!(s, "first divergence: {}", passes.join(", "));
    }
    if !r.worst.is_empty() {
        let _ = writeln!(
            s,
            "{:>6} {:>6} {:<6} {:>14} {:>14} {:>10} {:>6}",
            "x", "y", "field", "reference", "other", "relative", "from"
        );
        for w in &r.worst {
            let _ = writeln!(
                s,
                "{:>6} {:>6} {:<6} {:>14.6e} {:>14.6e} {:>10.3e} {:>6}",
                w.x, w.y, w.field, w.reference, w.other, w.relative, w.first_pass
            );
        }
    }
    let _ = writeln!(s, "verdict: {}", if r.agree { "agree" } else { "DISAGREE" });
    s
}
