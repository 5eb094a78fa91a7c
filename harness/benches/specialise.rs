//! What specialising the wgpu pipelines to the scene buys: each canonical scene rendered by a
//! specialised and a general backend (every pipeline with mirror, glass and mover-box code
//! compiled in), iteration by iteration in turn, side by side in one run.
//!
//! `cargo bench -p harness --bench specialise` prints, per scene and build, the first
//! iteration (which compiles the eye and photon pipelines the scene needs), milliseconds per
//! iteration over the next `PPM_BENCH_ITERATIONS` (default 20) at `PPM_BENCH_SIZE` (default
//! 256), and the largest pixel difference between the two images (zero: the same seed renders
//! the same image). Buffers do not depend on the build, so neither does memory. Figures only,
//! no threshold. The CPU backend decides the same branches per ray: it has no build to compare.

mod common;

use common::{backends, setting, wgpu_if_wanted};
use harness::driver::Renderer;
use ppm_core::params::{MoveParams, RenderParams};
use std::time::Instant;

fn main() {
    let iterations: u32 = setting("PPM_BENCH_ITERATIONS", 20);
    let size: u32 = setting("PPM_BENCH_SIZE", 256);
    // Only the wgpu backend is specialised; PPM_BENCH_BACKENDS=cpu leaves nothing to run.
    let wanted = backends();
    let start = |general: bool| {
        let mut b = wgpu_if_wanted(&wanted)?;
        b.set_general(general);
        Some(b)
    };
    let (Some(mut special), Some(mut general)) = (start(false), start(true)) else {
        return;
    };
    println!(
        "wgpu on {}, {size}x{size}, {iterations} iterations after the first",
        special.adapter_name()
    );
    println!(
        "{:<14} {:<12} {:>16} {:>13} {:>14}",
        "scene", "build", "first (ms)", "ms/iteration", "max |diff|"
    );
    for name in ["cornell-box", "cornell-bunny", "wedding-band"] {
        let scene = scenes::builtin(name)
            .and_then(|s| s.load().ok())
            .expect("built-in scene");
        let mut p = RenderParams::for_scene(&scene);
        (p.width, p.height) = (size, size);
        let moves = MoveParams::default();
        let mut renders = [&mut special, &mut general]
            .map(|b| Renderer::start(b, scene.clone(), &p, &moves).expect("the scene loads"));
        let mut first = [0.0; 2];
        let mut total = [0.0; 2];
        for (k, r) in renders.iter_mut().enumerate() {
            let t = Instant::now();
            r.iteration().expect("an iteration runs");
            first[k] = t.elapsed().as_secs_f64() * 1e3;
        }
        for _ in 0..iterations {
            for (k, r) in renders.iter_mut().enumerate() {
                let t = Instant::now();
                r.iteration().expect("an iteration runs");
                total[k] += t.elapsed().as_secs_f64();
            }
        }
        let [a, b] = renders.map(|mut r| r.resolve().expect("the image resolves"));
        let diff = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs()))
            .fold(0.0f32, f32::max);
        for (k, build) in ["specialised", "general"].iter().enumerate() {
            println!(
                "{:<14} {:<12} {:>16.1} {:>13.1} {:>14}",
                name,
                build,
                first[k],
                total[k] * 1e3 / f64::from(iterations.max(1)),
                if k == 0 {
                    format!("{diff:e}")
                } else {
                    String::new()
                }
            );
        }
    }
}
