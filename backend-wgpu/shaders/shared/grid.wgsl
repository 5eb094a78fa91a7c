// Photon hash grid: the twin of ppm_core::grid. Needs qmc.wgsl (qmc_hash) imported before it.

const RADIUS_BINS: u32 = 1024u;
const RADIUS_BIN_SHIFT: u32 = 21u;
const CELL_QUANTILE_NUM: u32 = 3u;
const CELL_QUANTILE_DEN: u32 = 4u;
const I32_MAX_F32: f32 = 2147483520.0;

fn radius_bin(r2: f32) -> u32 {
    return min(bitcast<u32>(max(r2, 0.0)) >> RADIUS_BIN_SHIFT, RADIUS_BINS - 1u);
}

fn cell_of(p: vec3<f32>, cell: f32) -> vec3<i32> {
    return vec3<i32>(clamp(floor(p / cell), vec3<f32>(-2147483648.0), vec3<f32>(I32_MAX_F32)));
}

fn cell_key(c: vec3<i32>) -> u32 {
    let u = bitcast<vec3<u32>>(c);
    return qmc_hash(u.x * 73856093u + u.y * 19349663u + u.z * 83492791u);
}

fn scan_instead(lo: vec3<i32>, hi: vec3<i32>, photon_count: u32) -> bool {
    let e = vec3<f32>(hi) - vec3<f32>(lo) + vec3<f32>(1.0);
    return e.x * e.y * e.z > f32(photon_count);
}
