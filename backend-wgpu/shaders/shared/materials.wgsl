// Materials, two texels each, from the start of the scene table (scene.wgsl imported).

fn scene_material(i: u32) -> GpuMaterial {
    let a = scene_texel(2u * i);
    let b = scene_texel(2u * i + 1u);
    return GpuMaterial(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w));
}
