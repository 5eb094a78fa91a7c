// The scene's records in one table (backend-wgpu's buffers.rs): materials from texel 0, then
// triangles, BVH nodes, lights, mover boxes, triangles' texture coordinates and texture
// headers, each kind from the texel `SceneIndex` names.
// One table rather than one per kind keeps every pass within baseline WebGPU's four storage
// textures per shader stage. Needs the binding `scene_table` in the importing pass (and
// `scene`, a uniform SceneIndex, for any record but a material), and tables.wgsl imported.

struct SceneIndex {
    triangles: u32,
    nodes: u32,
    lights: u32,
    movers: u32,
    light_count: u32,
    mover_count: u32,
    uvs: u32,
    textures: u32,
}

fn scene_texel(i: u32) -> vec4<u32> {
    return textureLoad(scene_table, table_texel(i));
}
