// #import layout rng qmc geometry sampling update grid tables scene materials
// Gather pass (docs/algorithm.md 1.4, and 3 "Who gathers what"): the twin of backend-cpu's
// gather_pass.rs, in two steps so that a photon pass split into batches still makes one
// update. `gather_accumulate_main` (per batch, inside the photon pass) adds the photons within
// each gathering hit point's radius to its accumulator: power and count, and path weight. Then
// `gather_apply_main` (the gather pass) folds the accumulator in as the pass's kind says:
// who gathers, the region scale `emitted / N_c`, eqs 1-3 or 5-7, or a deferred pending sum;
// and clears it.

@group(0) @binding(0) var<uniform> params: GatherParams;
// The scene table, of which the gather reads only the materials (scene.wgsl).
@group(0) @binding(1) var scene_table: texture_storage_2d<rgba32uint, read>;
// The photons in bucket order, two texels each, and the bucket starts (table.rs).
@group(0) @binding(2) var sorted_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(3) var<storage, read> grid: GridParams;
@group(0) @binding(4) var bucket_table: texture_storage_2d<r32uint, read>;
@group(0) @binding(5) var<storage, read> order: array<u32>;
@group(0) @binding(6) var<storage, read_write> hit_points: array<HitPoint>;
// Per hit point, two rows: (power, count) and (weight sum, squared power luminance, 0, 0).
@group(0) @binding(7) var<storage, read_write> accumulated: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(9) var<storage, read> weights: array<f32>;
// Per hit point: deferred region flux (times BRDF and scale) and signed count.
@group(0) @binding(10) var<storage, read_write> pending: array<vec4<f32>>;
// x: the initial squared radius; y: the photon pass's gather_r2_floor (accumulate only).
@group(0) @binding(11) var<uniform> radii: vec4<f32>;

// Whether deposits carry path weights (region passes): one accumulate pipeline each way, so
// other passes skip the extra reads.
override WEIGHTED: bool = false;

fn sorted_photon(k: u32) -> GridPhoton {
    let a = textureLoad(sorted_table, table_texel(2u * k));
    let b = textureLoad(sorted_table, table_texel(2u * k + 1u));
    return GridPhoton(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

fn bucket_start(b: u32) -> u32 {
    return textureLoad(bucket_table, table_texel(b)).x;
}

// Running sums of the photons a slot found: count, path weight, power, and squared power
// luminance (the variance of a local move's correction).
struct Found {
    m: u32,
    weight: f32,
    flux: vec3<f32>,
    power_sq: f32,
}

fn visit(found: ptr<function, Found>, hp: HitPoint, r2: f32, p: GridPhoton, k: u32) {
    let d = p.position - hp.position;
    if dot(d, d) < r2 && oct_faces(p.normal_oct, hp.normal) {
        (*found).m++;
        if WEIGHTED {
            (*found).weight += weights[order[k]];
        }
        (*found).flux += p.power;
        let lum = luminance(p.power);
        (*found).power_sq += lum * lum;
    }
}

@compute @workgroup_size(64)
fn gather_accumulate_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    // Only hit points that gather the pass's kind search: a guided pass touches the updated
    // ones alone, as on the CPU.
    let hp = hit_points[slot];
    if !gathers(hp, params.kind) {
        return;
    }
    let g = grid;
    let r2 = max(hp.r2, radii.y);
    let r = sqrt(r2);
    let lo = cell_of(hp.position - vec3<f32>(r), g.cell_size);
    let hi = cell_of(hp.position + vec3<f32>(r), g.cell_size);
    var found = Found(0u, 0.0, vec3<f32>(0.0), 0.0);
    if scan_instead(lo, hi, g.photon_count) {
        for (var k = 0u; k < g.photon_count; k++) {
            visit(&found, hp, r2, sorted_photon(k), k);
        }
    } else {
        // One flat loop, one photon or one cell a step (z, y, x order, as the CPU's nested
        // loops): neighbouring invocations stay in step whatever their cells hold.
        var cell = lo;
        var key = 0u;
        var k = 0u;
        var end = 0u;
        var cells_done = false;
        loop {
            if k < end {
                let p = sorted_photon(k);
                if p.cell == key {
                    visit(&found, hp, r2, p, k);
                }
                k++;
                continue;
            }
            if cells_done {
                break;
            }
            key = cell_key(cell);
            let b = key & (g.bucket_count - 1u);
            k = bucket_start(b);
            end = bucket_start(b + 1u);
            cell.x++;
            if cell.x > hi.x {
                cell.x = lo.x;
                cell.y++;
                if cell.y > hi.y {
                    cell.y = lo.y;
                    cell.z++;
                    cells_done = cell.z > hi.z;
                }
            }
        }
    }
    var weight = found.weight;
    if !WEIGHTED {
        weight = f32(found.m);
    }
    // Photons found in a floor disc wider than the slot's stand for their density over the
    // slot's own disc (as the CPU, weight and flux scaled, the count kept; a slot's own disc,
    // even of radius 0, scales nothing).
    let shrink = select(1.0, hp.r2 / radii.y, radii.y > hp.r2);
    weight *= shrink;
    accumulated[2u * slot] += vec4<f32>(found.flux * shrink, f32(found.m));
    accumulated[2u * slot + 1u] += vec4<f32>(weight, found.power_sq * shrink * shrink, 0.0, 0.0);
}

// Whether a slot belongs to the set the pass kind serves, visible point or not.
fn serves(hp: HitPoint, kind: u32) -> bool {
    let updated = (hp.flags & HIT_UPDATED) != 0u;
    switch kind & GATHER_KIND_MASK {
        case GATHER_REGION_NEGATIVE, GATHER_REGION_POSITIVE: {
            return !updated;
        }
        case GATHER_GUIDED: {
            return updated;
        }
        default: {
            return true;
        }
    }
}

// Whether a slot gathers the pass: served, with a visible point.
fn gathers(hp: HitPoint, kind: u32) -> bool {
    return (hp.flags & HIT_VALID) != 0u && serves(hp, kind);
}

// Writes a slot's new statistics: only the fields an update changes (a whole slot is 24
// word stores, which lavapipe makes one invocation at a time).
fn store(slot: u32, s: Statistics, emitted: f32) {
    hit_points[slot].n = s.n;
    hit_points[slot].r2 = s.r2;
    hit_points[slot].tau = s.tau;
    hit_points[slot].emitted = emitted;
}

@compute @workgroup_size(64)
fn gather_apply_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = hit_points[slot];
    let acc = accumulated[2u * slot];
    let weight_sum = accumulated[2u * slot + 1u].x;
    let power_sq = accumulated[2u * slot + 1u].y;
    accumulated[2u * slot] = vec4<f32>(0.0);
    accumulated[2u * slot + 1u] = vec4<f32>(0.0);
    let kind = params.kind & GATHER_KIND_MASK;
    let s0 = Statistics(hp.n, hp.r2, hp.tau);
    if kind == GATHER_REGION_APPLY {
        let p = pending[slot];
        pending[slot] = vec4<f32>(0.0);
        if (hp.flags & HIT_VALID) == 0u || all(p == vec4<f32>(0.0)) {
            return;
        }
        if (params.kind & GATHER_ADD_FLUX) != 0u {
            // `w` holds the correction's variance: the slot keeps the share of its history
            // worth keeping against it (backend-cpu's gather_pass.rs).
            let tau = max(hp.tau + p.xyz, vec3<f32>(0.0));
            let kept = history_kept(hp.n, tau, p.w);
            hit_points[slot].tau = tau * kept;
            hit_points[slot].emitted = hp.emitted * kept;
            return;
        }
        if p.w >= 0.0 {
            let s = ppm_update(s0, p.w, p.xyz, params.alpha);
            store(slot, Statistics(s.n, s.r2, max(s.tau, vec3<f32>(0.0))), hp.emitted);
        } else {
            let s = compensation_update(s0, -p.w, p.xyz, params.alpha, radii.x);
            store(slot, s, select(hp.emitted, 0.0, s.n == 0.0));
        }
        return;
    }
    if !gathers(hp, params.kind) {
        if serves(hp, params.kind) && params.emitted_increment != 0.0 {
            hit_points[slot].emitted = hp.emitted + params.emitted_increment;
        }
        return;
    }
    let found = acc.w;
    let region = kind == GATHER_REGION_NEGATIVE || kind == GATHER_REGION_POSITIVE;
    var scale = 1.0;
    if region {
        scale = hp.emitted / params.region_photons;
    }
    var m = found;
    if region && (params.kind & GATHER_RAW_COUNT) == 0u {
        m = weight_sum * scale;
    }
    let brdf = scene_material(hp.material).albedo * (1.0 / PI);
    let factor = hp.throughput * brdf * scale;
    let dtau = acc.xyz * factor;
    if found > 0.0 {
        atomicAdd(&counters[COUNTER_ITEMS], 1u);
        atomicAdd(&counters[COUNTER_GATHERED], u32(found));
    }
    if (params.kind & GATHER_DEFERRED) != 0u {
        let sign = select(1.0, -1.0, kind == GATHER_REGION_NEGATIVE);
        // A flux-only correction keeps the variance of its flux where the count would go.
        let lum = luminance(factor);
        let count = select(sign * m, power_sq * lum * lum, (params.kind & GATHER_ADD_FLUX) != 0u);
        pending[slot] += vec4<f32>(dtau, count);
        return;
    }
    var emitted = hp.emitted + params.emitted_increment;
    if kind == GATHER_REGION_NEGATIVE {
        let s = compensation_update(s0, m, dtau, params.alpha, radii.x);
        if m > 0.0 && s.n == 0.0 {
            emitted = 0.0;
        }
        store(slot, s, emitted);
    } else {
        store(slot, ppm_update(s0, m, dtau, params.alpha), emitted);
    }
}
