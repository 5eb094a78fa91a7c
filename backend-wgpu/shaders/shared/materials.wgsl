// Materials, eight texels each, from the start of the scene table (scene.wgsl imported).

fn scene_material(i: u32) -> GpuMaterial {
    let a = scene_texel(8u * i);
    let b = scene_texel(8u * i + 1u);
    let c = scene_texel(8u * i + 2u);
    let d = scene_texel(8u * i + 3u);
    let e = scene_texel(8u * i + 4u);
    return GpuMaterial(
        bitcast<vec3<f32>>(a.xyz), a.w,
        bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w),
        bitcast<vec3<f32>>(c.xyz), bitcast<f32>(c.w),
        bitcast<vec3<f32>>(d.xyz), d.w,
        bitcast<f32>(e.x), e.y, bitcast<f32>(e.z), bitcast<f32>(e.w),
        array<vec4<f32>, 3>(
            bitcast<vec4<f32>>(scene_texel(8u * i + 5u)),
            bitcast<vec4<f32>>(scene_texel(8u * i + 6u)),
            bitcast<vec4<f32>>(scene_texel(8u * i + 7u)),
        ),
    );
}
