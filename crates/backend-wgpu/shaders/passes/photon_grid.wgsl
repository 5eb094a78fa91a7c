// #import layout grid
// The per-pass photon map: the twin of backend-cpu's photon_grid.rs. Same cells, same
// buckets, and within each bucket photon indices in ascending order, so gathers sum in the
// CPU's order. Steps, one dispatch each: bounds, params, count, (scan), scatter, sort.

struct GridBuildParams {
    photon_count: u32,
    bucket_count: u32,
    hit_point_count: u32,
    _pad0: u32,
}

@group(0) @binding(0) var<uniform> params: GridBuildParams;
@group(0) @binding(1) var<storage, read> photons: array<Photon>;
@group(0) @binding(2) var<storage, read> hit_points: array<HitPoint>;
// Order-preserving integer keys of: min x, y, z; max x, y, z; largest r2.
@group(0) @binding(3) var<storage, read_write> bounds: array<atomic<u32>, 7>;
@group(0) @binding(4) var<storage, read_write> grid: GridParams;
@group(0) @binding(5) var<storage, read_write> bucket_counts: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> bucket_cursor: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> order: array<u32>;

// Maps a float to a u32 whose unsigned order is the float order.
fn order_key(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_order_key(k: u32) -> f32 {
    return bitcast<f32>(select(~k, k & 0x7fffffffu, (k & 0x80000000u) != 0u));
}

@compute @workgroup_size(64)
fn grid_bounds_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i < params.photon_count {
        let p = photons[i].position;
        atomicMin(&bounds[0], order_key(p.x));
        atomicMin(&bounds[1], order_key(p.y));
        atomicMin(&bounds[2], order_key(p.z));
        atomicMax(&bounds[3], order_key(p.x));
        atomicMax(&bounds[4], order_key(p.y));
        atomicMax(&bounds[5], order_key(p.z));
    }
    if i < params.hit_point_count && (hit_points[i].flags & HIT_VALID) != 0u {
        atomicMax(&bounds[6], order_key(hit_points[i].r2));
    }
}

const MAX_CELLS_PER_AXIS: f32 = 1048576.0;

@compute @workgroup_size(1)
fn grid_params_main() {
    var lo = vec3<f32>(0.0);
    var hi = vec3<f32>(0.0);
    if params.photon_count > 0u {
        lo = vec3<f32>(from_order_key(atomicLoad(&bounds[0])), from_order_key(atomicLoad(&bounds[1])), from_order_key(atomicLoad(&bounds[2])));
        hi = vec3<f32>(from_order_key(atomicLoad(&bounds[3])), from_order_key(atomicLoad(&bounds[4])), from_order_key(atomicLoad(&bounds[5])));
    }
    let max_r2 = max(from_order_key(atomicLoad(&bounds[6])), 0.0);
    let extent = max(hi - lo, vec3<f32>(0.0));
    var cell = max(2.0 * sqrt(max_r2), max(extent.x, max(extent.y, extent.z)) / MAX_CELLS_PER_AXIS);
    if !(cell > 0.0 && is_finite_f32(cell)) {
        cell = 1.0;
    }
    let dims = floor(extent / cell) + vec3<f32>(1.0);
    grid = GridParams(lo, cell, vec3<u32>(dims), params.bucket_count, params.photon_count, 0u, 0u, 0u);
}

@compute @workgroup_size(64)
fn grid_count_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= params.photon_count {
        return;
    }
    let g = grid;
    atomicAdd(&bucket_counts[bucket_of(cell_of(photons[i].position, g), g)], 1u);
}

@compute @workgroup_size(64)
fn grid_scatter_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= params.photon_count {
        return;
    }
    let g = grid;
    let b = bucket_of(cell_of(photons[i].position, g), g);
    order[atomicAdd(&bucket_cursor[b], 1u)] = i;
}

// Scattering by atomics leaves each bucket in arbitrary order: sort it by photon index.
// `bucket_counts` holds the bucket starts by now (scanned in place).
@compute @workgroup_size(64)
fn grid_sort_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let b = item_index(gid, groups);
    if b >= params.bucket_count {
        return;
    }
    let start = atomicLoad(&bucket_counts[b]);
    let end = atomicLoad(&bucket_counts[b + 1u]);
    for (var i = start + 1u; i < end; i++) {
        let v = order[i];
        var j = i;
        while j > start && order[j - 1u] > v {
            order[j] = order[j - 1u];
            j--;
        }
        order[j] = v;
    }
}
