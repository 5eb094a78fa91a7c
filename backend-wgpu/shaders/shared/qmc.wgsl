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
    return reverseBits(laine_karras(reverseBits(x), seed));
}

// The multiply-xor steps of owen_scramble, on bits already reversed.
fn laine_karras(x: u32, seed: u32) -> u32 {
    var v = x + seed;
    v ^= v * 0x6c50b47cu;
    v ^= v * 0xb82f1e52u;
    v ^= v * 0xc7afe638u;
    v ^= v * 0x8d22f6e6u;
    return v;
}

// The second Sobol dimension, bit-reversed: reversed bit i is the xor of the index's bits over
// the supersets of i (its direction numbers are Pascal's triangle mod 2), five steps where a
// loop over the bits of a scrambled index took thirty-two.
fn sobol_second_reversed(index: u32) -> u32 {
    var y = index;
    y ^= (y >> 1u) & 0x55555555u;
    y ^= (y >> 2u) & 0x33333333u;
    y ^= (y >> 4u) & 0x0f0f0f0fu;
    y ^= (y >> 8u) & 0x00ff00ffu;
    y ^= (y >> 16u) & 0x0000ffffu;
    return y;
}

fn sobol_pair_bits(scramble: u32, i: u32) -> vec2<u32> {
    let seed = qmc_hash(scramble);
    let index = owen_scramble(i, seed);
    // Both dimensions come bit-reversed, which scrambling reverses again.
    return vec2<u32>(
        reverseBits(laine_karras(index, qmc_hash(seed ^ 1u))),
        reverseBits(laine_karras(sobol_second_reversed(index), qmc_hash(seed ^ 2u))),
    );
}

fn stratified_pair(seed: u32, kind: u32, path: u32, pair: u32, index: u32) -> vec2<f32> {
    let b = sobol_pair_bits(random_bits(seed, kind, STRATIFIED_PASS, path, pair), index);
    return vec2<f32>(bits_to_unit(b.x), bits_to_unit(b.y));
}
