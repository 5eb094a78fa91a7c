// #import layout tables scene materials camera_move
// A camera move's inheritance (docs/algorithm.md 3d): the twin of backend-cpu's
// camera_move.rs, over ppm_core::camera_move::inherit_slot (its twin in the shared
// camera_move.wgsl). Each slot of the new view, just traced fresh and not on an edge of it
// (`on_an_edge`, which reads its neighbours' visible points), takes over the light of the
// old view's slots near its visible point, which `begin_camera_move` copied on the device.
// No slot leaves the device; the host reads back the counters (`COUNTER_ITEMS`: the slots
// that inherited).

@group(0) @binding(0) var<uniform> params: CameraMoveParams;
@group(0) @binding(1) var scene_table: texture_storage_2d<rgba32uint, read>;
// The old view's slots and their boxes, as the move found them.
@group(0) @binding(2) var<storage, read> before_slots: array<HitPoint>;
@group(0) @binding(3) var<storage, read> before_bounds: array<GpuBounds>;
@group(0) @binding(4) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(5) var<storage, read_write> slot_bounds: array<GpuBounds>;
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>, 4>;

@compute @workgroup_size(64)
fn camera_move_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    var hp = hit_points[slot];
    var bounds = slot_bounds[slot];
    if !on_an_edge(slot, params) && inherit_slot(&hp, &bounds, params) {
        // Only what `inherited_write` sets: other invocations read this slot's visible
        // point (`on_an_edge`).
        hit_points[slot].r2 = hp.r2;
        hit_points[slot].emitted = hp.emitted;
        hit_points[slot].tau = hp.tau;
        hit_points[slot].n = hp.n;
        hit_points[slot].discounted = hp.discounted;
        hit_points[slot].iterations = hp.iterations;
        hit_points[slot].direct = hp.direct;
        hit_points[slot].correction_r2 = hp.correction_r2;
        slot_bounds[slot] = bounds;
        atomicAdd(&counters[COUNTER_ITEMS], 1u);
    }
}
