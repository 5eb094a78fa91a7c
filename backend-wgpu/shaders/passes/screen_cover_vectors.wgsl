// #import layout screen_cover
// Runs screen_cover.wgsl's marking of a triangle on given cases, so that a test pins it to
// ppm_core::screen_cover::covered_pixels (backend-wgpu's tests/local_move.rs).

// One input of the marking (backend_wgpu::layout::CoverCase): a projection onto an image of
// at most 256 pixels, and a triangle.
struct CoverCase {
    cover: CoverParams,
    v0: vec3<f32>,
    _pad0: u32,
    v1: vec3<f32>,
    _pad1: u32,
    v2: vec3<f32>,
    _pad2: u32,
}

// The pixels it may cover, a bit each, row-major (backend_wgpu::layout::CoverOutcome).
struct CoverOutcome {
    words: array<u32, 8>,
}

@group(0) @binding(0) var<storage, read> cover_cases: array<CoverCase>;
@group(0) @binding(1) var<storage, read_write> covers: array<CoverOutcome>;

@compute @workgroup_size(64)
fn cover_vectors_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= arrayLength(&covers) {
        return;
    }
    let c = cover_cases[i];
    let pixels = c.cover.width * c.cover.height;
    var out: CoverOutcome;
    let t = cover_triangle(c.cover, c.v0, c.v1, c.v2);
    if t.everything {
        for (var p = 0u; p < pixels; p++) {
            out.words[p / 32u] |= 1u << (p % 32u);
        }
    } else if !t.nothing {
        for (var y = t.first.y; y <= t.last.y; y++) {
            for (var x = t.first.x; x <= t.last.x; x++) {
                if cover_pixel(t, x, y) {
                    let p = y * c.cover.width + x;
                    out.words[p / 32u] |= 1u << (p % 32u);
                }
            }
        }
    }
    covers[i] = out;
}
