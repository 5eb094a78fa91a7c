// #import layout geometry sampling update grid
// Gather pass (ALGORITHM.md 1.4): the twin of backend-cpu's gather_pass.rs, in two steps so
// that a photon pass split into batches still makes one update: `gather_accumulate_main`
// adds each batch's photons within the radius to a per-hit-point accumulator (count in w,
// power in xyz), and `gather_apply_main` folds the accumulator into the statistics with the
// stable update, then clears it.

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(2) var<storage, read> photons: array<Photon>;
@group(0) @binding(3) var<storage, read> grid: GridParams;
@group(0) @binding(4) var<storage, read> bucket_start: array<u32>;
@group(0) @binding(5) var<storage, read> order: array<u32>;
@group(0) @binding(6) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(7) var<storage, read_write> accumulated: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 4>;

@compute @workgroup_size(64)
fn gather_accumulate_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = hit_points[slot];
    if (hp.flags & HIT_VALID) == 0u {
        return;
    }
    let g = grid;
    let buckets = buckets_around(hp.position, sqrt(hp.r2), g);
    var m = 0u;
    var flux = vec3<f32>(0.0);
    for (var k = 0u; k < buckets.count; k++) {
        let b = buckets.ids[k];
        for (var i = bucket_start[b]; i < bucket_start[b + 1u]; i++) {
            let p = photons[order[i]];
            let d = p.position - hp.position;
            if dot(d, d) < hp.r2 && dot(oct_decode(p.normal_oct), hp.normal) > 0.0 {
                m++;
                flux += p.power;
            }
        }
    }
    accumulated[slot] += vec4<f32>(flux, f32(m));
}

@compute @workgroup_size(64)
fn gather_apply_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    var hp = hit_points[slot];
    if (hp.flags & HIT_VALID) == 0u {
        return;
    }
    let acc = accumulated[slot];
    accumulated[slot] = vec4<f32>(0.0);
    let brdf = materials[hp.material].albedo * (1.0 / PI);
    let s = ppm_update(Statistics(hp.n, hp.r2, hp.tau), acc.w, acc.xyz * brdf, params.alpha);
    hp.n = s.n;
    hp.r2 = s.r2;
    hp.tau = s.tau;
    hp.emitted += params.emitted_increment;
    hit_points[slot] = hp;
    if acc.w > 0.0 {
        atomicAdd(&counters[COUNTER_ITEMS], 1u);
        atomicAdd(&counters[COUNTER_GATHERED], u32(acc.w));
    }
}
