// #import layout rng qmc geometry grid
// Testing photons (docs/algorithm.md 2.6): flags the paths of the current map's photons that lie
// within the radius of an updated hit point (every writer stores the same 1: no atomics).

@group(0) @binding(0) var<storage, read> photons: array<Photon>;
@group(0) @binding(1) var<storage, read> grid: GridParams;
@group(0) @binding(2) var<storage, read> bucket_start: array<u32>;
@group(0) @binding(3) var<storage, read> order: array<u32>;
@group(0) @binding(4) var<storage, read> hit_points: array<HitPoint>;
@group(0) @binding(5) var<storage, read_write> landed: array<u32>;
@group(0) @binding(6) var<storage, read> sorted: array<GridPhoton>;

fn mark(hp: HitPoint, k: u32) {
    let p = sorted[k];
    let d = p.position - hp.position;
    let path = photons[order[k]].path;
    if dot(d, d) < hp.r2 && oct_faces(p.normal_oct, hp.normal) && path < arrayLength(&landed) {
        landed[path] = 1u;
    }
}

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
    let r = sqrt(hp.r2);
    let lo = cell_of(hp.position - vec3<f32>(r), g.cell_size);
    let hi = cell_of(hp.position + vec3<f32>(r), g.cell_size);
    if scan_instead(lo, hi, g.photon_count) {
        for (var k = 0u; k < g.photon_count; k++) {
            mark(hp, k);
        }
        return;
    }
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            for (var x = lo.x; x <= hi.x; x++) {
                let key = cell_key(vec3<i32>(x, y, z));
                let b = key & (g.bucket_count - 1u);
                for (var k = bucket_start[b]; k < bucket_start[b + 1u]; k++) {
                    if sorted[k].cell == key {
                        mark(hp, k);
                    }
                }
            }
        }
    }
}
