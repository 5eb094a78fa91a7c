// Materials, four texels each, from the start of the scene table (scene.wgsl imported).

fn scene_material(i: u32) -> GpuMaterial {
    let a = scene_texel(4u * i);
    let b = scene_texel(4u * i + 1u);
    let c = scene_texel(4u * i + 2u);
    let d = scene_texel(4u * i + 3u);
    return GpuMaterial(
        bitcast<vec3<f32>>(a.xyz), a.w,
        bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w),
        bitcast<vec3<f32>>(c.xyz), bitcast<f32>(c.w),
        bitcast<vec3<f32>>(d.xyz), d.w,
    );
}
