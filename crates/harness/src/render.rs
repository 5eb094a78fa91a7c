//! The progressive render loop, written once against the pass traits so that every backend is
//! driven the same way: eye pass, direct light, then photon and gather passes until the pass
//! count or the time budget runs out, then resolve.

use crate::clock::Stopwatch;
use crate::report::{PassTimes, RenderReport, left_out};
use ppm_core::compile::compile_scene;
use ppm_core::image::Image;
use ppm_core::layout::{
    DirectLightParams, EyePassParams, GatherParams, PhotonPassParams, ResolveParams, first_hit,
};
use ppm_core::params::{DirectMode, RenderParams};
use ppm_core::passes::{Backend, BackendError};
use ppm_core::scene::Scene;
use std::time::Instant;

/// Where a render stands, for progress displays.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Photon passes finished.
    pub pass: u32,
    /// Photon passes planned (`u32::MAX` when only a time budget bounds the render).
    pub passes: u32,
    /// Seconds of photon passes so far (time spent in the observer is not counted).
    pub elapsed: f64,
}

/// A finished (or stopped) render.
pub struct RenderOutcome {
    /// The resolved image; non-finite pixels, if a pass failed, are set to zero.
    pub image: Image,
    /// What ran, how long it took, and what was left out.
    pub report: RenderReport,
    /// The pass error that stopped the render early, if any.
    pub error: Option<BackendError>,
}

/// Offset of secondary ray origins, relative to the scene's extent: ~150 f32 ulps at the
/// largest coordinate, far below any feature of the canonical scenes.
const RAY_EPSILON_RELATIVE: f32 = 1e-5;

/// Called after direct light (pass 0) and after every photon pass, with the backend, so an
/// observer can read buffers back between passes (the diff harness records histories so).
pub type PassObserver<'a> = &'a mut dyn FnMut(Progress, &mut dyn Backend);

/// Renders `scene` at `frame` on `backend`, calling `on_pass` as each pass completes.
///
/// A pass that fails (a non-finite value, a device error) stops the loop; the image resolved
/// from what was rendered so far is still returned, with the error beside it.
pub fn render(
    backend: &mut dyn Backend,
    scene: &Scene,
    frame: u32,
    params: &RenderParams,
    on_pass: PassObserver,
) -> Result<RenderOutcome, BackendError> {
    let total = Instant::now();
    let posed = scene.at_frame(frame);
    let compiled = compile_scene(&posed, params.width, params.height);
    let ray_epsilon = RAY_EPSILON_RELATIVE * compiled.extent;
    let mut times = PassTimes {
        bvh_build: compiled.bvh_build_time.as_secs_f64(),
        ..PassTimes::default()
    };
    let mut report = RenderReport::new(backend.name(), &posed, frame, params, &compiled);
    report.left_out = left_out(&compiled.features, params, true);

    let t = Instant::now();
    backend.load_scene(&compiled)?;
    times.upload = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let eye = backend.eye_pass(&EyePassParams {
        seed: params.seed,
        spp: params.spp,
        max_depth: params.max_eye_depth,
        frame,
        r2_initial: params.initial_radius * params.initial_radius,
        ray_epsilon,
        _pad0: 0,
        _pad1: 0,
    })?;
    times.eye = t.elapsed().as_secs_f64();
    report.hit_points = eye.hit_points;
    report.rays.eye = eye.rays;

    let t = Instant::now();
    let direct_samples = match params.direct {
        DirectMode::Explicit => params.direct_samples,
        DirectMode::Photons => 0,
    };
    let direct = backend.direct_light(&DirectLightParams {
        seed: params.seed,
        samples: direct_samples,
        frame,
        ray_epsilon,
    })?;
    times.direct = t.elapsed().as_secs_f64();
    report.rays.shadow = direct.rays;
    on_pass(
        Progress {
            pass: 0,
            passes: params.passes,
            elapsed: 0.0,
        },
        &mut *backend,
    );

    let error = photon_loop(
        backend,
        params,
        ray_epsilon,
        &mut report,
        &mut times,
        on_pass,
    )
    .err();

    let t = Instant::now();
    let mut image = backend.resolve(&ResolveParams {
        width: params.width,
        height: params.height,
        spp: params.spp,
        _pad0: 0,
    })?;
    times.resolve = t.elapsed().as_secs_f64();
    for p in image.pixels.iter_mut().flatten().filter(|v| !v.is_finite()) {
        *p = 0.0;
        report.non_finite_pixels_zeroed += 1;
    }
    times.total = total.elapsed().as_secs_f64();
    report.times = times;
    report.error = error.as_ref().map(ToString::to_string);
    Ok(RenderOutcome {
        image,
        report,
        error,
    })
}

/// Photon and gather passes until the pass count or the time budget is spent; the budget
/// counts rendering only, not the observer.
fn photon_loop(
    backend: &mut dyn Backend,
    params: &RenderParams,
    ray_epsilon: f32,
    report: &mut RenderReport,
    times: &mut PassTimes,
    on_pass: PassObserver,
) -> Result<(), BackendError> {
    let mut clock = Stopwatch::start();
    for pass in 0..params.passes {
        if let Some(budget) = params.time_budget
            && clock.seconds() >= budget
        {
            break;
        }
        let t = Instant::now();
        let photons = backend.photon_pass(&PhotonPassParams {
            seed: params.seed,
            pass_index: pass,
            photon_count: params.photons_per_pass,
            max_depth: params.max_photon_depth,
            first_hit: match params.direct {
                DirectMode::Explicit => first_hit::SKIP,
                DirectMode::Photons => first_hit::DEPOSIT,
            },
            ray_epsilon,
            power_scale: 1.0,
            first_path: 0,
        })?;
        times.photon += t.elapsed().as_secs_f64();
        report.photons_emitted += photons.emitted;
        report.photons_deposited += photons.deposited;
        report.rays.photon += photons.rays;

        let t = Instant::now();
        let gathered = backend.gather_pass(&GatherParams {
            alpha: params.alpha,
            emitted_increment: params.photons_per_pass as f32,
            kind: ppm_core::layout::gather_kind::ORDINARY,
            region_photons: 0.0,
        })?;
        times.gather += t.elapsed().as_secs_f64();
        report.photons_gathered += gathered.photons_gathered;
        report.passes += 1;
        clock.pause();
        on_pass(
            Progress {
                pass: pass + 1,
                passes: params.passes,
                elapsed: clock.seconds(),
            },
            &mut *backend,
        );
        clock.resume();
    }
    Ok(())
}
