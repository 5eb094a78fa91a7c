// #import layout rng qmc geometry sampling bsdf update grid tables scene materials
// Gather pass (docs/algorithm.md 1.4, and 3 "Who gathers what"): the twin of backend-cpu's
// gather_pass.rs, in two steps so that a photon pass split into batches still makes one
// update. `gather_accumulate_main` (per batch, inside the photon pass) adds the photons within
// each gathering hit point's radius to its accumulator: power and count, and path weight. Then
// `gather_apply_main` (the gather pass) folds the accumulator in by update.wgsl's
// `gather_rule` (ppm_core::update::gather's twin), and clears it.

@group(0) @binding(0) var<uniform> params: GatherParams;
// The scene table, of which the gather reads only the materials (scene.wgsl).
@group(0) @binding(1) var scene_table: texture_storage_2d<rgba32uint, read>;
// The photons in bucket order, two texels each, and the bucket starts (table.rs).
@group(0) @binding(2) var sorted_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(3) var<storage, read> grid: GridParams;
@group(0) @binding(4) var bucket_table: texture_storage_2d<r32uint, read>;
@group(0) @binding(6) var<storage, read_write> hit_points: array<HitPoint>;
// Per hit point, two rows: (power, count) and (weight sum, squared power luminance, 0, 0).
@group(0) @binding(7) var<storage, read_write> accumulated: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 4>;
// The words beside the deposits in bucket order (photon_grid.wgsl's sorted_words), as a table
// of four-word texels: a path weight each (region passes), or a texel each, the pose-A
// partner's position and luminance (a pairing pose B; zero for none).
@group(0) @binding(9) var words_table: texture_storage_2d<rgba32uint, read>;
// Per hit point: deferred region flux (times BRDF and scale) and signed count.
@group(0) @binding(10) var<storage, read_write> pending: array<vec4<f32>>;
// x: the initial squared radius; y: the photon pass's gather_r2_floor (accumulate only).
@group(0) @binding(11) var<uniform> radii: vec4<f32>;

// Whether deposits carry path weights (region passes): one accumulate pipeline each way, so
// other passes skip the extra reads.
override WEIGHTED: bool = false;

// Whether deposits carry their pose-A partners (a local correction's pose B,
// PHOTON_PAIR_DEPOSITS), whose cross term joins the variance where both lie in the disc.
override PAIRED: bool = false;

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
struct Search {
    m: u32,
    weight: f32,
    flux: vec3<f32>,
    power_sq: f32,
}

fn visit(found: ptr<function, Search>, hp: HitPoint, r2: f32, p: GridPhoton, k: u32) {
    let d = p.position - hp.position;
    if dot(d, d) < r2 && oct_faces(p.normal_oct, hp.normal) {
        (*found).m++;
        if WEIGHTED {
            (*found).weight += bitcast<vec4<f32>>(textureLoad(words_table, table_texel(k / 4u)))[k % 4u];
        }
        (*found).flux += p.power;
        let own = luminance(p.power);
        var both = false;
        var cancels = false;
        var partner = 0.0;
        if PAIRED {
            let words = bitcast<vec4<f32>>(textureLoad(words_table, table_texel(k)));
            let at = words.xyz;
            let a = at - hp.position;
            partner = words.w;
            both = dot(a, a) < r2;
            cancels = partner_cancels(words, p.position, own);
        }
        (*found).power_sq += variance_term(own, partner, both, cancels);
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
    if !gathers(hp.flags, params.kind) {
        return;
    }
    let g = grid;
    let r2 = search_r2(hp, radii.y);
    let r = sqrt(r2);
    let lo = cell_of(hp.position - vec3<f32>(r), g.cell_size);
    let hi = cell_of(hp.position + vec3<f32>(r), g.cell_size);
    var found = Search(0u, 0.0, vec3<f32>(0.0), 0.0);
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
    // Photons found in a disc wider than the slot's stand for their density over the slot's
    // own disc (as the CPU, weight and flux scaled, the count kept; a slot's own disc, even of
    // radius 0, scales nothing).
    let shrink = disc_shrink(hp.r2, r2);
    weight *= shrink;
    accumulated[2u * slot] += vec4<f32>(found.flux * shrink, f32(found.m));
    accumulated[2u * slot + 1u] += vec4<f32>(weight, found.power_sq * shrink * shrink, 0.0, 0.0);
}

// Writes a slot's new statistics: only the fields an update changes (a whole slot is 28
// word stores, which lavapipe makes one invocation at a time).
fn store(slot: u32, hp: HitPoint, s: SlotState) {
    let changed = s.n != hp.n || s.r2 != hp.r2 || any(s.tau != hp.tau);
    if changed || s.emitted != hp.emitted || s.discounted != hp.discounted {
        hit_points[slot].n = s.n;
        hit_points[slot].r2 = s.r2;
        hit_points[slot].tau = s.tau;
        hit_points[slot].emitted = s.emitted;
        hit_points[slot].discounted = s.discounted;
    }
}

@compute @workgroup_size(64)
fn gather_apply_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = hit_points[slot];
    let acc = accumulated[2u * slot];
    let extra = accumulated[2u * slot + 1u];
    accumulated[2u * slot] = vec4<f32>(0.0);
    accumulated[2u * slot + 1u] = vec4<f32>(0.0);
    let found = Found(acc.xyz, acc.w, extra.x, extra.y, vec2<f32>(0.0));
    let gathering = gathers(hp.flags, params.kind);
    if gathering && found.count > 0.0 {
        atomicAdd(&counters[COUNTER_ITEMS], 1u);
        atomicAdd(&counters[COUNTER_GATHERED], u32(found.count));
    }
    var reflectance = vec3<f32>(0.0);
    if gathering {
        reflectance = hp.throughput * visible_point_f(scene_material(hp.material));
    }
    // The pending sums may be a placeholder until a pass defers: read and written only by
    // the kinds that use them.
    let deferring = uses_pending(params.kind);
    var pending_before = vec4<f32>(0.0);
    if deferring {
        pending_before = pending[slot];
    }
    let before = SlotState(hp.tau, hp.n, pending_before, hp.r2, hp.emitted, hp.flags, hp.discounted);
    let after = gather_rule(params, radii.x, reflectance, before, found);
    store(slot, hp, after);
    if deferring && any(after.pending != pending_before) {
        pending[slot] = after.pending;
    }
}
