//! The photon map's bucket order (photon_grid.wgsl): every deposit once, buckets ascending
//! and ranks ascending within a bucket, the order the CPU's grid sums in, with cells wide
//! enough that a bucket holds dozens of deposits (a local correction's map).

use backend_wgpu::{GpuContext, WgpuBackend};
use ppm_core::compile::compile_scene;
use ppm_core::passes::{ReadBack, SceneUpload};
use std::process::ExitCode;
use test_support::{Need, Suite};

mod common;

fn wide_cells_are_sorted_by_bucket_then_rank() {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut backend = WgpuBackend::new().unwrap();
    backend.load_scene(&compile_scene(&scene, 16, 16)).unwrap();
    // Radii of 60 units: cells a ninth of the box wide.
    common::eye_pass(&mut backend, 3600.0);
    common::photon_pass(&mut backend);
    let order = backend.map_order().unwrap();
    let deposits = backend.read_photons().unwrap();
    assert_eq!(order.len(), deposits.len());
    let first_unsorted = order
        .windows(2)
        .position(|w| (w[0].0, w[0].1) >= (w[1].0, w[1].1));
    assert_eq!(first_unsorted, None, "(bucket, rank) must rise strictly");
    let mut largest = 0;
    for bucket in order.chunk_by(|a, b| a.0 == b.0) {
        largest = largest.max(bucket.len());
    }
    assert!(largest >= 32, "a bucket of {largest} deposits at most");
    // The same deposits, each once: sorted by rank, the photons are the pass's in path order.
    let mut by_rank: Vec<_> = order.iter().map(|(_, rank, p)| (*rank, *p)).collect();
    by_rank.sort_unstable_by_key(|(rank, _)| *rank);
    for ((_, p), d) in by_rank.iter().zip(&deposits) {
        assert_eq!((p.position, p.power), (d.position, d.power));
    }
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "wide_cells_are_sorted_by_bucket_then_rank",
            wide_cells_are_sorted_by_bucket_then_rank,
        )
        .run()
}
