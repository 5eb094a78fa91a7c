// #import layout geometry grid
// Testing photons (ALGORITHM.md 2.6): flags the paths of the current map's photons that lie
// within the radius of an updated hit point (every writer stores the same 1: no atomics).

@group(0) @binding(0) var<storage, read> photons: array<Photon>;
@group(0) @binding(1) var<storage, read> grid: GridParams;
@group(0) @binding(2) var<storage, read> bucket_start: array<u32>;
@group(0) @binding(3) var<storage, read> order: array<u32>;
@group(0) @binding(4) var<storage, read> hit_points: array<HitPoint>;
@group(0) @binding(5) var<storage, read_write> landed: array<u32>;

@compute @workgroup_size(64)
fn landing_paths_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = hit_points[slot];
    if (hp.flags & HIT_VALID) == 0u || (hp.flags & HIT_UPDATED) == 0u {
        return;
    }
    let g = grid;
    let buckets = buckets_around(hp.position, sqrt(hp.r2), g);
    for (var k = 0u; k < buckets.count; k++) {
        let b = buckets.ids[k];
        for (var i = bucket_start[b]; i < bucket_start[b + 1u]; i++) {
            let p = photons[order[i]];
            let d = p.position - hp.position;
            if dot(d, d) < hp.r2 && dot(oct_decode(p.normal_oct), hp.normal) > 0.0 && p.path < arrayLength(&landed) {
                landed[p.path] = 1u;
            }
        }
    }
}
