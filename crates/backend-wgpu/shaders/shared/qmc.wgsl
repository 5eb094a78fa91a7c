// Stratified sample sequences: the twin of ppm_core::qmc and ppm_core::rng::stratified_pair,
// bit for bit. Needs rng.wgsl imported before it.

const STRATIFIED_PASS: u32 = 0xffffffffu;

fn qmc_hash(v: u32) -> u32 {
    var x = v;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

fn owen_scramble(x: u32, seed: u32) -> u32 {
    var v = reverseBits(x);
    v += seed;
    v ^= v * 0x6c50b47cu;
    v ^= v * 0xb82f1e52u;
    v ^= v * 0xc7afe638u;
    v ^= v * 0x8d22f6e6u;
    return reverseBits(v);
}

fn sobol_second(i: u32) -> u32 {
    var index = i;
    var v = 0x80000000u;
    var out = 0u;
    while index != 0u {
        if (index & 1u) != 0u {
            out ^= v;
        }
        index >>= 1u;
        v ^= v >> 1u;
    }
    return out;
}

fn sobol_pair_bits(scramble: u32, i: u32) -> vec2<u32> {
    let seed = qmc_hash(scramble);
    let index = owen_scramble(i, seed);
    return vec2<u32>(
        owen_scramble(reverseBits(index), qmc_hash(seed ^ 1u)),
        owen_scramble(sobol_second(index), qmc_hash(seed ^ 2u)),
    );
}

fn stratified_pair(seed: u32, kind: u32, path: u32, pair: u32, index: u32) -> vec2<f32> {
    let b = sobol_pair_bits(random_bits(seed, kind, STRATIFIED_PASS, path, pair), index);
    return vec2<f32>(bits_to_unit(b.x), bits_to_unit(b.y));
}
