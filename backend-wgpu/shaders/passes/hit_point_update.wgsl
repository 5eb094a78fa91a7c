// #import layout
// Hit-point update (docs/algorithm.md 2.4): the twin of backend-cpu's hit_point_update.rs. The eye
// pass has written `fresh` for the new pose; slots whose visible point changed take it,
// reset; every slot's direct sum restarts.

struct UpdateParams {
    epsilon: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: UpdateParams;
@group(0) @binding(1) var<storage, read> fresh: array<HitPoint>;
@group(0) @binding(2) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(3) var<storage, read_write> pending: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>, 4>;

@compute @workgroup_size(64)
fn hit_point_update_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    var old = hit_points[slot];
    let now = fresh[slot];
    let old_valid = (old.flags & HIT_VALID) != 0u;
    let new_valid = (now.flags & HIT_VALID) != 0u;
    var same = old_valid == new_valid;
    if same && new_valid {
        same = (old.flags >> HIT_OBJECT_SHIFT) == (now.flags >> HIT_OBJECT_SHIFT)
            && distance(old.position, now.position) <= params.epsilon;
    }
    if same {
        old.flags &= ~HIT_UPDATED;
        old.direct = vec3<f32>(0.0);
        old.iterations = 0u;
        hit_points[slot] = old;
        return;
    }
    var reset = now;
    if new_valid {
        reset.flags |= HIT_UPDATED;
    }
    hit_points[slot] = reset;
    pending[slot] = vec4<f32>(0.0);
    atomicAdd(&counters[COUNTER_ITEMS], 1u);
}
