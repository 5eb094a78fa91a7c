//! The WGSL generator reproduces ppm-core's fixed vectors bit for bit, on the device.

use backend_wgpu::{GpuContext, WgpuBackend};
use ppm_core::passes::RandomSource;
use ppm_core::rng::{TEST_VECTORS, random_bits};
use std::process::ExitCode;
use test_support::{Need, Suite};

fn wgsl_generator_reproduces_the_fixed_vectors() {
    let mut gpu = WgpuBackend::new().unwrap();
    let keys: Vec<[u32; 5]> = TEST_VECTORS.iter().map(|(k, _)| *k).collect();
    let expected: Vec<u32> = TEST_VECTORS.iter().map(|(_, b)| *b).collect();
    assert_eq!(gpu.random_bits(&keys).unwrap(), expected);
}

/// Beyond the vectors: a thousand keys spread over every argument agree with the CPU.
fn wgsl_generator_matches_the_cpu_on_many_keys() {
    let mut gpu = WgpuBackend::new().unwrap();
    let keys: Vec<[u32; 5]> = (0..1000u32)
        .map(|i| {
            [
                i.wrapping_mul(2_654_435_761),
                i % 4,
                i / 7,
                i.wrapping_mul(40_503),
                i % 64,
            ]
        })
        .collect();
    let cpu: Vec<u32> = keys
        .iter()
        .map(|k| random_bits(k[0], k[1], k[2], k[3], k[4]))
        .collect();
    assert_eq!(gpu.random_bits(&keys).unwrap(), cpu);
}

/// The WGSL stratified sequences reproduce ppm-core's vectors and agree with the CPU on a
/// thousand keys.
fn wgsl_stratified_sequences_match_the_cpu() {
    let mut gpu = WgpuBackend::new().unwrap();
    let vectors: Vec<[u32; 2]> = ppm_core::qmc::TEST_VECTORS
        .iter()
        .map(|(k, _)| *k)
        .collect();
    let expected: Vec<[u32; 2]> = ppm_core::qmc::TEST_VECTORS
        .iter()
        .map(|(_, b)| *b)
        .collect();
    assert_eq!(gpu.stratified_bits(&vectors).unwrap(), expected);
    let keys: Vec<[u32; 2]> = (0..1000u32)
        .map(|i| [i.wrapping_mul(2_654_435_761), i * 37 % 4096])
        .collect();
    let cpu: Vec<[u32; 2]> = keys
        .iter()
        .map(|k| ppm_core::qmc::sobol_pair_bits(k[0], k[1]))
        .collect();
    assert_eq!(gpu.stratified_bits(&keys).unwrap(), cpu);
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "wgsl_generator_reproduces_the_fixed_vectors",
            wgsl_generator_reproduces_the_fixed_vectors,
        )
        .test_needing(
            &[&adapter],
            "wgsl_generator_matches_the_cpu_on_many_keys",
            wgsl_generator_matches_the_cpu_on_many_keys,
        )
        .test_needing(
            &[&adapter],
            "wgsl_stratified_sequences_match_the_cpu",
            wgsl_stratified_sequences_match_the_cpu,
        )
        .run()
}
