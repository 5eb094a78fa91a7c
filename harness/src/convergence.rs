//! Error against run time of a from-scratch render (docs/algorithm.md 6): how fast its image
//! approaches the truth, measured as a viewer would see it (pixel relative RMSE), with the
//! noise averaged out (8x8-block relative RMSE: bias, blur and missing light stay), and as
//! energy (the ratio of the means).

use crate::chart::{ChartError, Series, write_loglog_chart};
use crate::driver::schedule::EachIteration;
use crate::driver::{Budget, Progress, Renderer, RunError, Schedule, Stoppable, run};
use crate::reference::Truth;
use crate::report::RenderReport;
use ppm_core::image::Image;
use ppm_core::metrics::{block_relative_rmse, mean_ratio, relative_rmse};
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::Backend;
use ppm_core::scene::Scene;
use serde::Serialize;
use std::path::Path;

/// Side of the blocks of the block metric, in pixels.
pub const BLOCK: u32 = 8;

/// Measurements are taken when rendering time has grown by this factor since the last one:
/// evenly spaced on a log axis, about fifty per decade of time.
const CHECKPOINT_GROWTH: f64 = 1.05;

/// One measurement of the render against the truth.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// Seconds of rendering (measuring not counted).
    pub seconds: f64,
    /// Iterations so far.
    pub passes: u32,
    /// Pixel relative RMSE against the truth.
    pub rel_rmse: f64,
    /// The same with the truth's own noise taken out (`sqrt(rel_rmse^2 - noise^2)`), when the
    /// truth's variance is known.
    pub rel_rmse_corrected: Option<f64>,
    /// Relative RMSE of the 8x8-block means.
    pub block_rel_rmse: f64,
    /// Mean of the image over the mean of the truth.
    pub mean_ratio: f64,
}

/// The measurement of `image` against `truth`.
pub fn measure(image: &Image, truth: &Truth, seconds: f64, passes: u32) -> Point {
    let rel_rmse = relative_rmse(image, &truth.image);
    Point {
        seconds,
        passes,
        rel_rmse,
        rel_rmse_corrected: truth
            .noise()
            .map(|noise| (rel_rmse * rel_rmse - noise * noise).max(0.0).sqrt()),
        block_rel_rmse: block_relative_rmse(image, &truth.image, BLOCK),
        mean_ratio: mean_ratio(image, &truth.image),
    }
}

/// Renders `scene` at `frame` from scratch on `backend` for `seconds` of rendering, measuring
/// against `truth` after the first iteration, whenever rendering time has grown by
/// `CHECKPOINT_GROWTH`, and after the last; ends early, with the points measured so far,
/// when `stop` says so (the report says `interrupted`).
pub fn run_from_scratch(
    backend: &mut dyn Backend,
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
    seconds: f64,
    truth: &Truth,
    stop: &dyn Fn() -> bool,
) -> Result<(Vec<Point>, RenderReport), RunError> {
    let mut points = Vec::new();
    let mut next = 0.0;
    let mut last = (0.0, 0);
    let mut observer = EachIteration(|at: &Progress, r: &mut Renderer| {
        last = (at.seconds, at.iterations);
        if at.seconds >= next {
            next = at.seconds * CHECKPOINT_GROWTH;
            points.push(measure(&r.resolve()?, truth, at.seconds, at.iterations));
        }
        Ok(())
    });
    let schedule = Schedule::frame(frame, Budget::seconds(seconds));
    let outcome = run(
        backend,
        scene,
        params,
        &MoveParams::default(),
        &schedule,
        &mut Stoppable {
            observer: &mut observer,
            stop,
        },
    )?;
    if let Some(e) = outcome.error {
        return Err(e.into());
    }
    if points.last().is_none_or(|p| p.passes != last.1) {
        points.push(measure(&outcome.image, truth, last.0, last.1));
    }
    Ok((points, outcome.report))
}

/// Least-squares slope of `log(rel_rmse)` against `log(seconds)` over the points from
/// `from_seconds` on: -0.5 for an estimator whose error is pure noise falling as `1/sqrt(t)`,
/// 0 for one that has stopped converging. `None` with fewer than three such points.
pub fn fitted_slope(points: &[Point], from_seconds: f64) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.seconds >= from_seconds)
        .map(|p| (p.seconds, p.rel_rmse))
        .collect();
    log_log_slope(&xy)
}

/// Least-squares slope of `log(y)` against `log(x)` over the points where both are positive;
/// `None` with fewer than three of them.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
        .map(|p| (p.0.ln(), p.1.ln()))
        .collect();
    if xy.len() < 3 {
        return None;
    }
    let n = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / n,
        xy.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The CSV of the measurements.
pub fn csv(points: &[Point]) -> String {
    let mut s =
        String::from("seconds,passes,rel_rmse,rel_rmse_corrected,block_rel_rmse,mean_ratio\n");
    for p in points {
        s.push_str(&format!(
            "{:.6},{},{:.6},{},{:.6},{:.6}\n",
            p.seconds,
            p.passes,
            p.rel_rmse,
            p.rel_rmse_corrected
                .map_or(String::new(), |v| format!("{v:.6}")),
            p.block_rel_rmse,
            p.mean_ratio
        ));
    }
    s
}

/// The log-log chart, `stem.png` and `stem.svg`: pixel and block errors against time, and the
/// truth's own noise as a dashed grey floor where it is known.
pub fn chart(
    stem: &Path,
    title: &str,
    points: &[Point],
    noise: Option<f64>,
) -> Result<(), ChartError> {
    let curve = |f: fn(&Point) -> f64| points.iter().map(|p| (p.seconds, f(p))).collect();
    let mut series = vec![
        Series {
            name: "pixel relative rmse",
            colour: [0.8, 0.1, 0.1],
            points: curve(|p| p.rel_rmse),
            dashed: false,
        },
        Series {
            name: "8x8 block relative rmse",
            colour: [0.1, 0.3, 0.9],
            points: curve(|p| p.block_rel_rmse),
            dashed: false,
        },
    ];
    if let (Some(noise), Some(first), Some(last)) = (noise, points.first(), points.last()) {
        series.push(Series {
            name: "reference noise",
            colour: [0.55; 3],
            points: vec![(first.seconds, noise), (last.seconds, noise)],
            dashed: true,
        });
    }
    write_loglog_chart(
        stem,
        title,
        "seconds of rendering",
        "relative rmse",
        &series,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(seconds: f64, rel_rmse: f64) -> Point {
        Point {
            seconds,
            passes: 1,
            rel_rmse,
            rel_rmse_corrected: None,
            block_rel_rmse: rel_rmse,
            mean_ratio: 1.0,
        }
    }

    #[test]
    fn slope_of_pure_noise_is_minus_a_half_and_of_a_floor_zero() {
        let noise: Vec<Point> = (1..40)
            .map(|i| point(f64::from(i), 0.3 / f64::from(i).sqrt()))
            .collect();
        let s = fitted_slope(&noise, 1.0).unwrap();
        assert!((s + 0.5).abs() < 1e-9, "{s}");
        let flat: Vec<Point> = (1..40).map(|i| point(f64::from(i), 1.12)).collect();
        assert!(fitted_slope(&flat, 1.0).unwrap().abs() < 1e-12);
        assert!(fitted_slope(&noise[..2], 0.0).is_none());
    }

    /// A truth with known noise: the corrected error takes exactly that noise out.
    #[test]
    fn corrected_error_removes_the_truths_noise_in_quadrature() {
        let truth = Truth {
            image: Image {
                pixels: vec![[1.0; 3]; 4],
                width: 2,
                height: 2,
            },
            variance: Some(Image {
                pixels: vec![[0.0009; 3]; 4],
                width: 2,
                height: 2,
            }),
            source: "test".into(),
        };
        let mut image = truth.image.clone();
        image.pixels.iter_mut().for_each(|p| *p = [1.05; 3]);
        let p = measure(&image, &truth, 1.0, 1);
        assert!((p.rel_rmse - 0.05).abs() < 1e-6);
        assert!((p.rel_rmse_corrected.unwrap() - 0.04).abs() < 1e-6);
    }
}
