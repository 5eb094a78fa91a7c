// Materials as a table (backend-wgpu's table.rs): two texels each. Needs the binding
// `material_table` in the importing pass, and tables.wgsl imported.

fn scene_material(i: u32) -> GpuMaterial {
    let a = textureLoad(material_table, table_texel(2u * i), 0);
    let b = textureLoad(material_table, table_texel(2u * i + 1u), 0);
    return GpuMaterial(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w));
}
