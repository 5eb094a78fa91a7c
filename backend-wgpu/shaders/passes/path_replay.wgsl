// #import layout sampling tables scene geometry movers update crossed_mask kept_paths deposits
// A local move's pose-A correction answered from the paths the ordinary pass just traced in
// this pose kept (kept_paths.wgsl): the twin of backend-cpu's PathRecord::replay. A correction
// pass of the same random numbers meets the same surfaces, so it stores the deposits that pass
// made after the path's first segment that meets a mover's box, that segment's own included
// (photon_pass.wgsl's CHANGED_ONLY rule), with its power times the pass's sign. Testing the
// kept segments against the boxes gives, bit for bit, what tracing them again gives, at no ray.
//
// Per path: the deposits it stores are appended as photon_pass.wgsl appends them, with the
// same ranks; the crossed-path mask and pose A's first stored deposits are recorded where the
// pass asks. A path that traced more segments than were kept is listed in `listed_paths`
// (counted in COUNTER_LISTED) for photon_pass.wgsl's photon_trace_listed_main to trace.

// The correction pass, its power scale the sign that turns the kept deposits into its own.
@group(0) @binding(0) var<uniform> params: PhotonPassParams;
@group(0) @binding(1) var scene_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(2) var<uniform> scene: SceneIndex;
// The kept paths' segments.
@group(0) @binding(3) var<storage, read> segments: array<f32>;
// The ordinary pass's deposits, copied before this pass writes its own over them.
@group(0) @binding(4) var<storage, read> kept: array<Photon>;
@group(0) @binding(5) var<storage, read_write> photons: array<Photon>;
@group(0) @binding(6) var<storage, read_write> ranks: array<u32>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(8) var<storage, read_write> crossed: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> partners: array<PathDeposits>;
@group(0) @binding(10) var<storage, read_write> listed_paths: array<u32>;

@compute @workgroup_size(64)
fn path_replay_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let local = item_index(gid, groups);
    if local >= params.photon_count {
        return;
    }
    let path = params.first_path + local;
    let traced = u32(segments[kept_length(local)]);
    if traced > KEPT_SEGMENTS {
        listed_paths[atomicAdd(&counters[COUNTER_LISTED], 1u)] = path;
        return;
    }
    var stored: PathDeposits;
    var nth = 0u;
    var crossed_box = false;
    let rank_base = local * params.max_depth;
    for (var bounce = 0u; bounce < traced; bounce++) {
        let at = kept_segment(local, bounce);
        let origin = vec3<f32>(segments[at], segments[at + 1u], segments[at + 2u]);
        let dir = vec3<f32>(segments[at + 4u], segments[at + 5u], segments[at + 6u]);
        crossed_box = crossed_box || near_mover(origin, dir, segments[at + 3u]);
        let deposit = u32(segments[at + 7u]);
        if deposit == 0u || !crossed_box {
            continue;
        }
        var photon = kept[deposit - 1u];
        photon.power *= params.power_scale;
        let slot = append_deposit(photon, rank_base + bounce);
        note_stored(&stored, nth, photon, slot);
        nth++;
    }
    record_path(params.mask_offset + path, crossed_box, stored);
}
