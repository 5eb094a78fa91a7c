// The boxes of the objects a local move moves, in both poses
// (ppm_core::compile::CompiledScene::movers), for the photon passes that store or trace only
// what follows a crossing: two texels a box in the scene table (scene.wgsl imported). Outside
// a move there are none. The twin of backend-cpu's SceneData::near_mover.

fn mover_bounds(i: u32) -> GpuBounds {
    let a = scene_texel(scene.movers + 2u * i);
    let b = scene_texel(scene.movers + 2u * i + 1u);
    return GpuBounds(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

// Whether the segment origin + t dir, 0 <= t <= t_max, meets the closed box [lo, hi]
// (ppm_core::geometry::segment_meets_box); an empty box (lo > hi) is never met.
fn segment_meets_box(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, lo: vec3<f32>, hi: vec3<f32>) -> bool {
    if any(lo > hi) {
        return false;
    }
    var t0 = 0.0;
    var t1 = t_max;
    for (var axis = 0u; axis < 3u; axis++) {
        let o = origin[axis];
        let d = dir[axis];
        if d == 0.0 {
            if o < lo[axis] || o > hi[axis] {
                return false;
            }
            continue;
        }
        let a = (lo[axis] - o) / d;
        let b = (hi[axis] - o) / d;
        t0 = max(t0, min(a, b));
        t1 = min(t1, max(a, b));
        if t0 > t1 {
            return false;
        }
    }
    return true;
}

fn near_mover(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    for (var i = 0u; i < scene.mover_count; i++) {
        let b = mover_bounds(i);
        if segment_meets_box(origin, dir, t_max, b.min, b.max) {
            return true;
        }
    }
    return false;
}
