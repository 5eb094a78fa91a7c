// #import layout
// A focus eye pass's first kernel (eye_flags::FOCUS with KEEP_STATISTICS): the rest test of
// ppm_core::eye_path::slot_eye_path at every slot. A slot ahead of those a move reset rests,
// keeping its last visible point; the others, typically a few percent scattered over the
// image, are listed so that the eye pass and the direct light after it walk them alone
// instead of every slot (`list.focus` in eye_pass.wgsl and direct_light.wgsl).

@group(0) @binding(0) var<uniform> params: EyePassParams;
@group(0) @binding(1) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(2) var<storage, read_write> counters: array<atomic<u32>, 4>;
// The slots behind, in no particular order (COUNTER_LISTED of them).
@group(0) @binding(3) var<storage, read_write> listed: array<u32>;

@compute @workgroup_size(64)
fn focus_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    if hit_points[slot].iterations < params.rest_at {
        listed[atomicAdd(&counters[COUNTER_LISTED], 1u)] = slot;
        return;
    }
    hit_points[slot].flags |= HIT_RESTING;
    if (hit_points[slot].flags & HIT_VALID) != 0u {
        atomicAdd(&counters[COUNTER_ITEMS], 1u);
    }
}
