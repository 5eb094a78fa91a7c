//! Same seed, same backend: the same buffers whatever the thread count (ALGORITHM.md 5).

use ppm_core::params::RenderParams;
use ppm_core::passes::ReadBack;
use tests::render_cpu;

#[test]
fn cpu_buffers_are_bit_identical_across_thread_counts() {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    params.width = 48;
    params.height = 40;
    params.spp = 2;
    params.passes = 3;
    params.photons_per_pass = 30_000;
    params.seed = 5;
    let mut reference = None;
    for threads in [1, 2, 3, 8] {
        let (outcome, mut backend) = render_cpu(&scene, 0, &params, threads);
        let hit_points = backend.read_hit_points().unwrap();
        let photons = backend.read_photons().unwrap();
        let bytes = (
            bytemuck::cast_slice::<_, u8>(&hit_points).to_vec(),
            bytemuck::cast_slice::<_, u8>(&photons).to_vec(),
            outcome.image.pixels,
        );
        match &reference {
            None => reference = Some(bytes),
            Some(r) => assert!(r == &bytes, "{threads} threads gave different buffers"),
        }
    }
}

#[test]
fn a_different_seed_gives_different_photons() {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    params.width = 16;
    params.height = 16;
    params.passes = 1;
    params.photons_per_pass = 1000;
    let (_, mut a) = render_cpu(&scene, 0, &params, 2);
    params.seed = 1;
    let (_, mut b) = render_cpu(&scene, 0, &params, 2);
    assert_ne!(a.read_photons().unwrap(), b.read_photons().unwrap());
}
