// Photon hash-grid mapping: the twin of ppm_core::grid.

fn cell_axis(v: f32, dim: u32) -> u32 {
    return min(u32(max(floor(v), 0.0)), dim - 1u);
}

fn cell_of(p: vec3<f32>, g: GridParams) -> vec3<u32> {
    let rel = (p - g.origin) / g.cell_size;
    return vec3<u32>(cell_axis(rel.x, g.dims.x), cell_axis(rel.y, g.dims.y), cell_axis(rel.z, g.dims.z));
}

fn bucket_of(cell: vec3<u32>, g: GridParams) -> u32 {
    return ((cell.x * 73856093u) ^ (cell.y * 19349663u) ^ (cell.z * 83492791u)) & (g.bucket_count - 1u);
}

struct Buckets {
    ids: array<u32, 8>,
    count: u32,
}

fn buckets_around(p: vec3<f32>, r: f32, g: GridParams) -> Buckets {
    let lo = cell_of(p - vec3<f32>(r), g);
    let hi = min(cell_of(p + vec3<f32>(r), g), lo + vec3<u32>(1u));
    var out: Buckets;
    out.count = 0u;
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            for (var x = lo.x; x <= hi.x; x++) {
                let b = bucket_of(vec3<u32>(x, y, z), g);
                var seen = false;
                for (var i = 0u; i < out.count; i++) {
                    seen = seen || out.ids[i] == b;
                }
                if !seen {
                    out.ids[out.count] = b;
                    out.count++;
                }
            }
        }
    }
    return out;
}
