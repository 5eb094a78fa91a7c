// Counter-based random generator: the twin of ppm_core::rng, bit for bit.

const PASS_EYE: u32 = 1u;
const PASS_DIRECT_LIGHT: u32 = 2u;
const PASS_PHOTON: u32 = 3u;
const PASS_REGION: u32 = 4u;
const PASS_GUIDED: u32 = 5u;

// An eye path's dimensions (ppm_core::rng::EYE_GLASS_DIM, EYE_GLOSSY_DIM): depth d picks at
// glass with EYE_GLASS_DIM + d and draws a glossy bounce from EYE_GLOSSY_DIM + 2 d and the next.
const EYE_GLASS_DIM: u32 = 2u;
const EYE_GLOSSY_DIM: u32 = 65536u;
// A light sample at a glossy bounce at depth d: EYE_LIGHT_DIM + 3 d picks the light, the
// next two the point on it (ppm_core::rng::EYE_LIGHT_DIM).
const EYE_LIGHT_DIM: u32 = 131072u;

struct StreamKey {
    seed: u32,
    kind: u32,
    pass_index: u32,
    path: u32,
}

fn pcg4d_mix(v: vec4<u32>) -> vec4<u32> {
    var m = v;
    m.x += m.y * m.w;
    m.y += m.z * m.x;
    m.z += m.x * m.y;
    m.w += m.y * m.z;
    return m;
}

fn pcg4d(v: vec4<u32>) -> vec4<u32> {
    var m = pcg4d_mix(v * 1664525u + 1013904223u);
    m = m ^ (m >> vec4<u32>(16u));
    return pcg4d_mix(m);
}

fn random_bits(seed: u32, kind: u32, pass_index: u32, path: u32, dimension: u32) -> u32 {
    let key = pcg4d(vec4<u32>(seed, kind, pass_index, path));
    return pcg4d(vec4<u32>(key.x, key.y ^ dimension, key.z, key.w)).x;
}

fn bits_to_unit(bits: u32) -> f32 {
    return f32(bits >> 8u) * (1.0 / 16777216.0);
}

fn stream_bits(key: StreamKey, dimension: u32) -> u32 {
    return random_bits(key.seed, key.kind, key.pass_index, key.path, dimension);
}

fn stream_uniform(key: StreamKey, dimension: u32) -> f32 {
    return bits_to_unit(stream_bits(key, dimension));
}
