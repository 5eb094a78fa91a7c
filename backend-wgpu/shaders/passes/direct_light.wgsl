// #import layout rng qmc sampling geometry bsdf bvh lights tables scene materials direct_light
// Direct light (docs/algorithm.md 1.2): the twin of backend-cpu's direct_light.rs and
// ppm_core::direct_light::slot_direct_light. Adds each slot's estimate (the shared
// direct_light.wgsl's slot_direct) to its direct sum, or replaces the sum with it.

@group(0) @binding(0) var<uniform> params: DirectLightParams;
@group(0) @binding(1) var scene_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(2) var<uniform> scene: SceneIndex;
@group(0) @binding(3) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>, 4>;
// What each slot's eye path found at glossy bounces (eye_pass.wgsl), in a scene with glossy
// surfaces; else one placeholder element.
@group(0) @binding(5) var<storage, read> chain_light: array<ChainLight>;
// The slots the focus eye pass before listed (focus.wgsl), while the others rest: walked
// alone where `list.focus` says so.
@group(0) @binding(6) var<storage, read> listed: array<u32>;
@group(0) @binding(7) var<uniform> list: ListParams;

@compute @workgroup_size(64)
fn direct_light_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    var slot = item_index(gid, groups);
    if list.focus != 0u {
        if slot >= list.count {
            return;
        }
        slot = listed[slot];
    } else if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = hit_points[slot];
    if (hp.flags & HIT_RESTING) != 0u {
        return;
    }
    var chain = ChainLight(vec3<f32>(0.0), 1.0);
    if arrayLength(&chain_light) == arrayLength(&hit_points) {
        chain = chain_light[slot];
    }
    let found = slot_direct(params, hp, chain, slot);
    if found.rays > 0u {
        atomicAdd(&counters[COUNTER_RAYS], found.rays);
    }
    let estimate = found.radiance;
    var direct = estimate;
    var iterations = 1u;
    if params.accumulate == DIRECT_ADD {
        direct = hp.direct + estimate;
        iterations = hp.iterations + 1u;
    }
    // Only the fields this pass changes are written back (a whole slot is 24 word stores,
    // which lavapipe makes one invocation at a time).
    hit_points[slot].direct = direct;
    hit_points[slot].iterations = iterations;
}
