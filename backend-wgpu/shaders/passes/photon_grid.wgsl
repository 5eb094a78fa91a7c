// #import layout rng qmc sampling update grid
// The per-pass photon map: the twin of backend-cpu's photon_grid.rs. Same cells (sized from a
// histogram of the visible points' squared radii), same buckets, and the photons copied into
// bucket order with ascending rank (the CPU's path order) within each bucket, held deposits
// of an earlier pass first, so gathers sum in the CPU's order. Steps, one dispatch each:
// histogram, params, count, (scan), scatter, sort, copy (and the deposits' words, where the
// pass wrote some). A map that joins a pairing pose B's deposits to pose A's held ones leaves
// out both deposits of each pair that cancels (marked CANCELLED_PARTNER by the photon pass):
// the scan's total is then the deposits filed, which the sort writes into `grid`.

struct GridBuildParams {
    photon_count: u32,
    bucket_count: u32,
    hit_point_count: u32,
    r2_floor: f32,
    held: u32,
    leave_out: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: GridBuildParams;
@group(0) @binding(1) var<storage, read> photons: array<Photon>;
@group(0) @binding(2) var<storage, read> hit_points: array<HitPoint>;
@group(0) @binding(3) var<storage, read_write> histogram: array<atomic<u32>, 1024>;
@group(0) @binding(4) var<storage, read_write> grid: GridParams;
@group(0) @binding(5) var<storage, read_write> bucket_counts: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> bucket_cursor: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> order: array<u32>;
@group(0) @binding(8) var<storage, read_write> keys: array<u32>;
@group(0) @binding(9) var<storage, read_write> sorted: array<GridPhoton>;
// Each deposit's rank in path order (photon_pass.wgsl).
@group(0) @binding(10) var<storage, read> ranks: array<u32>;
// The words a pass wrote beside each deposit (a path weight, or a pose-A partner's four), and
// the same in bucket order, so that a gather reads them where it reads the photons.
@group(0) @binding(11) var<storage, read> words: array<f32>;
@group(0) @binding(12) var<storage, read_write> sorted_words: array<f32>;

// Words per deposit of grid_copy_words_main.
override WORDS: u32 = 1u;

// Radii cluster in a few bins: each workgroup counts a strided share of the hit points in
// workgroup memory, then adds its non-zero bins to the global histogram, so few atomics
// contend for one address.
const HISTOGRAM_GROUPS: u32 = 64u;
var<workgroup> local_histogram: array<atomic<u32>, 1024>;

@compute @workgroup_size(64)
fn grid_histogram_main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>) {
    for (var b = lid.x; b < RADIUS_BINS; b += 64u) {
        atomicStore(&local_histogram[b], 0u);
    }
    workgroupBarrier();
    for (var i = wid.x * 64u + lid.x; i < params.hit_point_count; i += HISTOGRAM_GROUPS * 64u) {
        if (hit_points[i].flags & HIT_VALID) != 0u {
            atomicAdd(&local_histogram[radius_bin(search_r2(hit_points[i], params.r2_floor))], 1u);
        }
    }
    workgroupBarrier();
    for (var b = lid.x; b < RADIUS_BINS; b += 64u) {
        let count = atomicLoad(&local_histogram[b]);
        if count > 0u {
            atomicAdd(&histogram[b], count);
        }
    }
}

// ppm_core::grid::cell_size: the radius at the top of the quantile's bin.
@compute @workgroup_size(1)
fn grid_params_main() {
    var total = 0u;
    for (var b = 0u; b < RADIUS_BINS; b++) {
        total += atomicLoad(&histogram[b]);
    }
    var cell = 1.0;
    if total > 0u {
        let wanted = max((total * CELL_QUANTILE_NUM + CELL_QUANTILE_DEN - 1u) / CELL_QUANTILE_DEN, 1u);
        var cumulative = 0u;
        var bin = RADIUS_BINS - 1u;
        for (var b = 0u; b < RADIUS_BINS; b++) {
            cumulative += atomicLoad(&histogram[b]);
            if cumulative >= wanted {
                bin = b;
                break;
            }
        }
        let r2 = min(bitcast<f32>((bin + 1u) << RADIUS_BIN_SHIFT), 3.4028235e38);
        cell = sqrt(r2);
        if !(cell > 0.0 && is_finite_f32(cell)) {
            cell = 1.0;
        }
        cell = max(cell, 1.1754944e-38);
    }
    grid = GridParams(cell, params.bucket_count, params.photon_count, 0u);
}

// Whether deposit `i` stays out of the map: one of a pair that cancels, where the build
// leaves those out (four words beside each deposit, CANCELLED_PARTNER's luminance positive).
fn left_out(i: u32) -> bool {
    return params.leave_out != 0u && words[4u * i + 3u] > 0.0;
}

@compute @workgroup_size(64)
fn grid_count_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= params.photon_count || left_out(i) {
        return;
    }
    let key = cell_key(cell_of(photons[i].position, grid.cell_size));
    keys[i] = key;
    atomicAdd(&bucket_counts[key & (params.bucket_count - 1u)], 1u);
}

@compute @workgroup_size(64)
fn grid_scatter_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= params.photon_count || left_out(i) {
        return;
    }
    order[atomicAdd(&bucket_cursor[keys[i] & (params.bucket_count - 1u)], 1u)] = i;
}

// Appending and scattering by atomics leave each bucket in arbitrary order: each deposit
// counts the deposits of its bucket that sort before it (the keys are distinct: held ones
// first, then by rank) and writes itself at its bucket's start plus that count, into
// `bucket_cursor`, free once the scatter is done; the host copies the result over `order`.
// `bucket_counts` holds the bucket starts by now (scanned in place). Every deposit of a bucket
// counts over the same entries, so neighbouring invocations stay in step: an insertion sort
// by the invocation at each bucket's start left its group's other lanes idle, and the wide
// cells of a local correction's map hold dozens of deposits a bucket (cornell-box's drag:
// 8.1 ms of device time a step on lavapipe). The first invocation writes the deposits filed
// (all but those left out) into `grid`, for the copies and the gathers.
@compute @workgroup_size(64)
fn grid_sort_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = item_index(gid, groups);
    let filed = atomicLoad(&bucket_counts[params.bucket_count]);
    if k == 0u {
        grid.photon_count = filed;
    }
    if k >= filed {
        return;
    }
    let v = order[k];
    let b = keys[v] & (params.bucket_count - 1u);
    let start = atomicLoad(&bucket_counts[b]);
    let end = atomicLoad(&bucket_counts[b + 1u]);
    let key = sort_key(v);
    var place = start;
    for (var j = start; j < end; j++) {
        place += u32(after(key, sort_key(order[j])));
    }
    atomicStore(&bucket_cursor[place], v);
}

// Deposit `i`'s place in its bucket: the held deposits of an earlier pass first, then by rank.
fn sort_key(i: u32) -> vec2<u32> {
    return vec2<u32>(u32(i >= params.held), ranks[i]);
}

// Whether key `a` sorts after key `b`.
fn after(a: vec2<u32>, b: vec2<u32>) -> bool {
    return a.x > b.x || (a.x == b.x && a.y > b.y);
}

@compute @workgroup_size(64)
fn grid_copy_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = item_index(gid, groups);
    if k >= grid.photon_count {
        return;
    }
    let i = order[k];
    let p = photons[i];
    sorted[k] = GridPhoton(p.position, keys[i], p.power, p.normal_oct);
}

@compute @workgroup_size(64)
fn grid_copy_words_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = item_index(gid, groups);
    if k >= grid.photon_count {
        return;
    }
    let i = order[k];
    for (var w = 0u; w < WORDS; w++) {
        sorted_words[WORDS * k + w] = words[WORDS * i + w];
    }
}
