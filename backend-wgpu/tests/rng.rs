//! The WGSL generator reproduces ppm-core's fixed vectors bit for bit, on the device.

use ppm_core::passes::RandomSource;
use ppm_core::rng::{TEST_VECTORS, random_bits};

#[test]
fn wgsl_generator_reproduces_the_fixed_vectors() {
    let Some(mut gpu) =
        backend_wgpu::backend_or_skip("wgsl_generator_reproduces_the_fixed_vectors")
    else {
        return;
    };
    let keys: Vec<[u32; 5]> = TEST_VECTORS.iter().map(|(k, _)| *k).collect();
    let expected: Vec<u32> = TEST_VECTORS.iter().map(|(_, b)| *b).collect();
    assert_eq!(gpu.random_bits(&keys).unwrap(), expected);
}

/// Beyond the vectors: a thousand keys spread over every argument agree with the CPU.
#[test]
fn wgsl_generator_matches_the_cpu_on_many_keys() {
    let Some(mut gpu) =
        backend_wgpu::backend_or_skip("wgsl_generator_matches_the_cpu_on_many_keys")
    else {
        return;
    };
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
#[test]
fn wgsl_stratified_sequences_match_the_cpu() {
    let Some(mut gpu) = backend_wgpu::backend_or_skip("wgsl_stratified_sequences_match_the_cpu")
    else {
        return;
    };
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
