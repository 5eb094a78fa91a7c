// The boxes of the objects a local move moves, in both poses
// (ppm_core::compile::CompiledScene::movers), for the photon passes that store or trace only
// what follows a crossing: two texels a box in the scene table (scene.wgsl imported). Outside
// a move there are none. The twin of backend-cpu's SceneData::near_mover, over geometry.wgsl's
// segment_meets_box.

fn mover_bounds(i: u32) -> GpuBounds {
    let a = scene_texel(scene.movers + 2u * i);
    let b = scene_texel(scene.movers + 2u * i + 1u);
    return GpuBounds(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
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
