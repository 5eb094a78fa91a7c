// Emitting triangles, four texels each in the scene table (scene.wgsl imported),
// and their selection by power.

fn scene_light(i: u32) -> GpuLight {
    let a = scene_texel(scene.lights + 4u * i);
    let b = scene_texel(scene.lights + 4u * i + 1u);
    let c = scene_texel(scene.lights + 4u * i + 2u);
    let d = scene_texel(scene.lights + 4u * i + 3u);
    return GpuLight(
        bitcast<vec3<f32>>(a.xyz), bitcast<f32>(a.w),
        bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w),
        bitcast<vec3<f32>>(c.xyz), bitcast<f32>(c.w),
        bitcast<vec3<f32>>(d.xyz), d.w,
    );
}

// The light whose cumulative share of the power first exceeds `u` (reads only the cdf word).
fn sample_light(u: f32) -> u32 {
    var lo = 0u;
    var hi = max(scene.light_count, 1u) - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if u < bitcast<f32>(scene_texel(scene.lights + 4u * mid + 1u).w) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}
