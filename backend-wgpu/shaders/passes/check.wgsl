// #import layout
// Finiteness check after every pass that writes slots: records the lowest slot holding
// NaN or infinity, so the host reports it (with ppm_core::check) instead of rendering it.

@group(0) @binding(0) var<storage, read> hit_points: array<HitPoint>;
@group(0) @binding(1) var<storage, read_write> counters: array<atomic<u32>, 4>;

@compute @workgroup_size(64)
fn check_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = hit_points[slot];
    // Statistics outlive the visible point: checked in every slot; the visible point where
    // there is one.
    var finite = is_finite_vec3(hp.direct) && is_finite_vec3(hp.tau) && is_finite_f32(hp.r2)
        && is_finite_f32(hp.n) && is_finite_f32(hp.emitted);
    if (hp.flags & HIT_VALID) != 0u {
        finite = finite && is_finite_vec3(hp.position) && is_finite_vec3(hp.throughput);
    }
    if !finite {
        atomicMin(&counters[COUNTER_FIRST_BAD], slot);
    }
}
