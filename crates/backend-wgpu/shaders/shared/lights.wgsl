// Emitting triangles as a table (four texels each) and their selection by power: needs the
// bindings `light_table` and `counts` in the importing pass, and tables.wgsl and counts.wgsl.

fn scene_light(i: u32) -> GpuLight {
    let a = textureLoad(light_table, table_texel(4u * i), 0);
    let b = textureLoad(light_table, table_texel(4u * i + 1u), 0);
    let c = textureLoad(light_table, table_texel(4u * i + 2u), 0);
    let d = textureLoad(light_table, table_texel(4u * i + 3u), 0);
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
    var hi = max(counts.lights, 1u) - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if u < bitcast<f32>(textureLoad(light_table, table_texel(4u * mid + 1u), 0).w) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}
