//! Independent-seed comparison: each backend renders `runs` times with its own seeds, so the
//! two sets are samples of the same estimator if the backends agree.
//!
//! The image is cut into tiles; for each tile and each quantity (mean radiance R, G, B, mean
//! `r2`, mean `n` and mean direct luminance over its slots) Welch's t-test compares the two sets of per-run tile
//! means. Holm's step-down correction over all those tests keeps the probability of declaring
//! agreeing backends different at most `alpha` (the stated false-alarm rate), whatever the
//! number of tiles. Runs are independent samples, so the test is exact up to the normal
//! approximation of a tile mean, which averages hundreds of pixels.

use super::heat_map;
use ppm_core::image::Image;
use ppm_core::layout::HitPoint;
use ppm_core::params::RenderParams;
use ppm_core::stats::{holm_rejections, t_two_sided_p, welch_t};
use serde::Serialize;
use std::fmt::Write as _;

/// Family-wise false-alarm rate of the comparison.
pub const ALPHA: f64 = 0.01;

/// Floor on a run's relative spread: a tile mean is never trusted to better than 1% per run.
/// Tiles with few photons can come out nearly identical in a handful of runs by chance (or
/// all zero), and the t-test would then read a negligible difference as certain; with the
/// floor, differences below a few percent of a tile's mean are simply not resolved.
pub const RELATIVE_SPREAD_FLOOR: f64 = 0.01;

/// Welch's t of two sets of tile means, with the spread floor.
fn tile_t(a: &[f64], b: &[f64]) -> (f64, f64) {
    let scale = a.iter().chain(b).map(|x| x.abs()).sum::<f64>() / (a.len() + b.len()) as f64;
    welch_t(a, b, (RELATIVE_SPREAD_FLOOR * scale).powi(2))
}

/// The tile means of one run: `[tile][quantity]`.
pub type TileMeans = Vec<[f64; QUANTITIES]>;

/// Quantities tested per tile.
pub const QUANTITIES: usize = 6;
const QUANTITY_NAMES: [&str; QUANTITIES] = [
    "radiance.r",
    "radiance.g",
    "radiance.b",
    "r2",
    "n",
    "direct",
];

/// Tiles per image side (fewer for tiny images).
fn tiles_per_side(pixels: u32) -> u32 {
    pixels.clamp(1, 4)
}

/// Means of each quantity over each tile of one run.
pub fn tile_means(image: &Image, hit_points: &[HitPoint], params: &RenderParams) -> TileMeans {
    let (tx, ty) = (tiles_per_side(params.width), tiles_per_side(params.height));
    let mut sums = vec![[0.0f64; QUANTITIES]; (tx * ty) as usize];
    let mut pixels = vec![0.0f64; sums.len()];
    let mut slots = vec![0.0f64; sums.len()];
    let tile = |x: u32, y: u32| ((y * ty / params.height) * tx + x * tx / params.width) as usize;
    for y in 0..params.height {
        for x in 0..params.width {
            let t = tile(x, y);
            let c = image.at(x, y);
            for k in 0..3 {
                sums[t][k] += f64::from(c[k]);
            }
            pixels[t] += 1.0;
        }
    }
    for hp in hit_points {
        let (x, y) = (hp.pixel % params.width, hp.pixel / params.width);
        let t = tile(x, y);
        sums[t][3] += f64::from(hp.r2);
        sums[t][4] += f64::from(hp.n);
        sums[t][5] += super::luminance(hp.direct_mean());
        slots[t] += 1.0;
    }
    sums.iter()
        .enumerate()
        .map(|(t, s)| {
            let p = pixels[t].max(1.0);
            let v = slots[t].max(1.0);
            [s[0] / p, s[1] / p, s[2] / p, s[3] / v, s[4] / v, s[5] / v]
        })
        .collect()
}

/// One tile's test of one quantity.
#[derive(Clone, Debug, Serialize)]
pub struct TileTest {
    /// Tile column.
    pub tile_x: u32,
    /// Tile row.
    pub tile_y: u32,
    /// Quantity tested.
    pub quantity: &'static str,
    /// Mean over the reference runs.
    pub reference_mean: f64,
    /// Mean over the other runs.
    pub other_mean: f64,
    /// Welch's t.
    pub t: f64,
    /// Its degrees of freedom.
    pub df: f64,
    /// Two-sided p-value.
    pub p: f64,
    /// Rejected after Holm's correction.
    pub rejected: bool,
}

/// The independent-seed verdict.
#[derive(Clone, Debug, Serialize)]
pub struct IndependentReport {
    /// Reference backend.
    pub reference: String,
    /// Compared backend.
    pub other: String,
    /// Runs per backend.
    pub runs: usize,
    /// Family-wise false-alarm rate.
    pub alpha: f64,
    /// Tests made (tiles times quantities).
    pub tests: usize,
    /// Tests rejected after Holm's correction.
    pub rejected: usize,
    /// Smallest p-value.
    pub min_p: f64,
    /// The tests with the smallest p-values.
    pub worst: Vec<TileTest>,
    /// Whether the backends agree.
    pub agree: bool,
}

/// Tests the runs of two backends against each other.
pub fn compare(
    reference: (&str, &[TileMeans]),
    other: (&str, &[TileMeans]),
    params: &RenderParams,
    worst_count: usize,
) -> IndependentReport {
    compare_at(reference, other, params, worst_count, ALPHA)
}

/// As [`compare`], at family-wise false-alarm rate `alpha` (a caller testing many scenes
/// divides its own rate among them).
pub fn compare_at(
    reference: (&str, &[TileMeans]),
    other: (&str, &[TileMeans]),
    params: &RenderParams,
    worst_count: usize,
    alpha: f64,
) -> IndependentReport {
    let tx = tiles_per_side(params.width);
    let tiles = reference.1[0].len();
    let mut tests = Vec::new();
    for t in 0..tiles {
        for q in 0..QUANTITIES {
            let a: Vec<f64> = reference.1.iter().map(|run| run[t][q]).collect();
            let b: Vec<f64> = other.1.iter().map(|run| run[t][q]).collect();
            let (tstat, df) = tile_t(&a, &b);
            tests.push(TileTest {
                tile_x: t as u32 % tx,
                tile_y: t as u32 / tx,
                quantity: QUANTITY_NAMES[q],
                reference_mean: a.iter().sum::<f64>() / a.len() as f64,
                other_mean: b.iter().sum::<f64>() / b.len() as f64,
                t: tstat,
                df,
                p: t_two_sided_p(tstat, df),
                rejected: false,
            });
        }
    }
    let p: Vec<f64> = tests.iter().map(|t| t.p).collect();
    for (test, rejected) in tests.iter_mut().zip(holm_rejections(&p, alpha)) {
        test.rejected = rejected;
    }
    let rejected = tests.iter().filter(|t| t.rejected).count();
    let min_p = p.iter().copied().fold(1.0, f64::min);
    let count = tests.len();
    tests.sort_by(|a, b| a.p.total_cmp(&b.p));
    tests.truncate(worst_count);
    IndependentReport {
        reference: reference.0.to_owned(),
        other: other.0.to_owned(),
        runs: reference.1.len().min(other.1.len()),
        alpha,
        tests: count,
        rejected,
        min_p,
        worst: tests,
        agree: rejected == 0,
    }
}

/// Heat map: each tile painted with `-log10(p)` of its most significant quantity.
pub fn heat(reference: &[TileMeans], other: &[TileMeans], params: &RenderParams) -> Image {
    let (tx, ty) = (tiles_per_side(params.width), tiles_per_side(params.height));
    let mut tile_score = vec![0.0f64; (tx * ty) as usize];
    for (t, score) in tile_score.iter_mut().enumerate() {
        for q in 0..QUANTITIES {
            let a: Vec<f64> = reference.iter().map(|run| run[t][q]).collect();
            let b: Vec<f64> = other.iter().map(|run| run[t][q]).collect();
            let (tstat, df) = tile_t(&a, &b);
            *score = score.max(-t_two_sided_p(tstat, df).max(1e-300).log10());
        }
    }
    let mut values = Vec::with_capacity((params.width * params.height) as usize);
    for y in 0..params.height {
        for x in 0..params.width {
            values
                .push(tile_score[((y * ty / params.height) * tx + x * tx / params.width) as usize]);
        }
    }
    heat_map(params.width, params.height, &values)
}

/// The independent-seed table.
pub fn format(r: &IndependentReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "independent seeds: {} vs {}, {} runs each",
        r.reference, r.other, r.runs
    );
    let _ = writeln!(
        s,
        "{} tile tests (Welch t, Holm-corrected), false-alarm rate {}: {} rejected, smallest p {:.3e}",
        r.tests, r.alpha, r.rejected, r.min_p
    );
    let _ = writeln!(
        s,
        "{:>5} {:>5} {:<11} {:>13} {:>13} {:>9} {:>10}",
        "tx", "ty", "quantity", "reference", "other", "t", "p"
    );
    for t in &r.worst {
        let _ = writeln!(
            s,
            "{:>5} {:>5} {:<11} {:>13.5e} {:>13.5e} {:>9.3} {:>10.3e}{}",
            t.tile_x,
            t.tile_y,
            t.quantity,
            t.reference_mean,
            t.other_mean,
            t.t,
            t.p,
            if t.rejected { "  rejected" } else { "" }
        );
    }
    let _ = writeln!(s, "verdict: {}", if r.agree { "agree" } else { "DISAGREE" });
    s
}
