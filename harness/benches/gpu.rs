//! The wgpu backend on whatever adapter wgpu finds, with the figures a machine with a real GPU
//! reports: photons per second, iteration times at three sizes, and a drag step in
//! iterations.
//!
//! `cargo bench -p harness --bench gpu` prints the adapter, then, for a built-in scene
//! (`PPM_BENCH_SCENE`, default `cornell-box`; it must declare a move), per size
//! (`PPM_BENCH_SIZES`, default `256,768,1920x1080`; `N` is `NxN`) photons per second over
//! the whole iteration and milliseconds per iteration and per pass kind on the wall clock,
//! then, where the adapter has timestamp queries, each pass's milliseconds on the device.
//! Then a drag at `PPM_BENCH_DRAG_SIZE` (default 768): the scene's first move in thirtieths,
//! `PPM_BENCH_MOVES` times (default 30), an iteration after each, local mode; its cost is a
//! move's milliseconds over an iteration's before the drag. Each render runs
//! `PPM_BENCH_WARMUP` iterations first (default 10: pipelines compile, buffers grow), then
//! `PPM_BENCH_ITERATIONS` timed (default 20), of `PPM_BENCH_PHOTONS` photons each (default
//! 1,000,000). Where the device measures its times, they are read back once an iteration,
//! which the wall times include; `PPM_BENCH_KERNELS=1` also prints them kernel by kernel.
//! Figures only, no threshold. Without an adapter it says so and prints nothing else; a size
//! the adapter cannot bind gets a line that says why. On lavapipe (wgpu on the CPU) it runs,
//! slowly: shrink it, e.g. `PPM_BENCH_SIZES=64
//! PPM_BENCH_ITERATIONS=2 PPM_BENCH_PHOTONS=20000 PPM_BENCH_WARMUP=1 PPM_BENCH_MOVES=2`.

mod common;
#[path = "common/drag.rs"]
mod drag;

use common::{backends, setting, wgpu_if_wanted};
use drag::{drag, step_of, warm_up};
use harness::driver::Renderer;
use harness::report::RenderReport;
use ppm_core::device_time::{DeviceTime, per_pass, since};
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::scene::Scene;
use std::time::Instant;

fn main() {
    // Only the wgpu backend runs here; PPM_BENCH_BACKENDS=cpu leaves nothing to run.
    let Some(mut gpu) = wgpu_if_wanted(&backends()) else {
        return;
    };
    let iterations: u32 = setting("PPM_BENCH_ITERATIONS", 20);
    let photons: u32 = setting("PPM_BENCH_PHOTONS", 1_000_000);
    let warmup: u32 = setting("PPM_BENCH_WARMUP", 10);
    let moves: u32 = setting("PPM_BENCH_MOVES", 30);
    let drag_size: u32 = setting("PPM_BENCH_DRAG_SIZE", 768);
    let sizes: Vec<(u32, u32)> = std::env::var("PPM_BENCH_SIZES")
        .unwrap_or_else(|_| "256,768,1920x1080".into())
        .split(',')
        .filter_map(|s| match s.trim().split_once('x') {
            Some((w, h)) => Some((w.parse().ok()?, h.parse().ok()?)),
            None => s.trim().parse().ok().map(|n| (n, n)),
        })
        .collect();
    let name = std::env::var("PPM_BENCH_SCENE").unwrap_or_else(|_| "cornell-box".into());
    let Some(scene) = scenes::builtin(&name).and_then(|s| s.load().ok()) else {
        println!("PPM_BENCH_SCENE={name}: no built-in scene of that name loads");
        return;
    };
    let Some(&declared) = scene.moves.first() else {
        println!("PPM_BENCH_SCENE={name}: the scene declares no move to drag");
        return;
    };
    println!("adapter: {}", gpu.adapter_name());
    println!(
        "device times: {}",
        if gpu.has_device_times() {
            "timestamp queries"
        } else {
            "not measured (the adapter offers no timestamp queries)"
        }
    );
    println!("{name}, sppm, {iterations} iterations x {photons} photons after {warmup} of warm-up");
    println!(
        "{:<10} {:>12} {:>8} {:>7} {:>7} {:>7} {:>7}",
        "size", "photons/s", "iter ms", "eye", "direct", "photon", "gather"
    );
    let moving = MoveParams::default();
    for (width, height) in sizes {
        let params = render_params(&scene, width, height, photons);
        let mut r =
            Renderer::start(&mut gpu, scene.clone(), &params, &moving).expect("the scene loads");
        // An image too large for the adapter's binding limit is refused at its first
        // iteration (lavapipe binds 128 MiB: 1920x1080's slots are 232 MB).
        if let Err(e) = r.iteration() {
            println!("{width}x{height}: {e}");
            continue;
        }
        warm_up(&mut r, warmup.saturating_sub(1));
        let before = r.report().clone();
        let wall = timed(&mut r, iterations);
        let (now, n) = (r.report(), f64::from(iterations.max(1)));
        let (a, b) = (&now.times, &before.times);
        let ms = |now: f64, before: f64| 1e3 * (now - before) / n;
        println!(
            "{:<10} {:>12.4e} {:>8.2} {:>7.2} {:>7.2} {:>7.2} {:>7.2}",
            format!("{width}x{height}"),
            (now.photons_emitted - before.photons_emitted) as f64 / wall,
            1e3 * wall / n,
            ms(a.eye, b.eye),
            ms(a.direct, b.direct),
            ms(a.photon, b.photon),
            ms(a.gather, b.gather),
        );
        if let Some(line) = device_line(now, &before, n) {
            println!("  device ms/iteration: {line}");
        }
    }

    let params = render_params(&scene, drag_size, drag_size, photons);
    let step = step_of(declared);
    let mut r =
        Renderer::start(&mut gpu, scene.clone(), &params, &moving).expect("the scene loads");
    r.expect_local_moves().expect("the moves are prepared");
    warm_up(&mut r, warmup);
    let per_iteration = 1e3 * timed(&mut r, iterations) / f64::from(iterations.max(1));
    let before = r.report().clone();
    let d = drag(&mut r, step, moves);
    println!(
        "drag at {drag_size}x{drag_size}: {moves} moves of a thirtieth of {name}'s, an \
         iteration after each"
    );
    println!(
        "  a move costs {:.2} iterations ({:.2} the median move): {:.2} ms/move (median {:.2}, \
         largest {:.2}), {:.2} ms/iteration before the drag, {:.2} in it; {} slots reset, {} \
         corrected per move",
        d.move_ms / per_iteration,
        d.median_ms / per_iteration,
        d.move_ms,
        d.median_ms,
        d.largest_ms,
        per_iteration,
        d.iteration_ms,
        d.reset,
        d.corrected
    );
    println!("  where a move goes, median ms: {}", d.parts_line());
    if let Some(line) = device_line(r.report(), &before, f64::from(moves.max(1))) {
        println!("  device ms per move and its iteration: {line}");
    }
}

/// Seconds `iterations` iterations take.
fn timed(r: &mut Renderer, iterations: u32) -> f64 {
    let t = Instant::now();
    for _ in 0..iterations {
        r.iteration().expect("an iteration runs");
    }
    t.elapsed().as_secs_f64()
}

/// The scene's settings at `width` x `height`, `photons` per iteration.
fn render_params(scene: &Scene, width: u32, height: u32, photons: u32) -> RenderParams {
    let mut p = RenderParams::for_scene(scene);
    (p.width, p.height, p.photons_per_pass) = (width, height, photons);
    p
}

/// Each pass's device milliseconds between two reports of one render, over `n`; `None`
/// where the device measures nothing.
fn device_line(now: &RenderReport, before: &RenderReport, n: f64) -> Option<String> {
    let empty: Vec<DeviceTime> = Vec::new();
    let ran = since(
        now.device_times.as_ref()?,
        before.device_times.as_ref().unwrap_or(&empty),
    );
    if std::env::var("PPM_BENCH_KERNELS").as_deref() == Ok("1") {
        for t in &ran {
            let ms = 1e3 * t.seconds / n;
            let line = format!("{} / {}: {ms:.3} ms", t.pass, t.kernel);
            println!("    {line} ({} dispatches)", t.dispatches);
        }
    }
    let passes = per_pass(&ran);
    let total: f64 = passes.iter().map(|(_, s)| s).sum();
    let mut parts: Vec<String> = passes
        .iter()
        .map(|(pass, s)| format!("{pass} {:.3}", 1e3 * s / n))
        .collect();
    parts.push(format!("sum {:.3}", 1e3 * total / n));
    Some(parts.join(", "))
}
