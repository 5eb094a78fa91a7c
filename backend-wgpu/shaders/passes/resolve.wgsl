// #import layout sampling update
// Resolve (docs/algorithm.md 1.5): the twin of backend-cpu's resolve.rs.

@group(0) @binding(0) var<uniform> params: ResolveParams;
@group(0) @binding(1) var<storage, read> hit_points: array<HitPoint>;
@group(0) @binding(2) var<storage, read_write> image: array<f32>;

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let pixel = item_index(gid, groups);
    if pixel >= params.width * params.height {
        return;
    }
    var sum = vec3<f32>(0.0);
    for (var s = 0u; s < params.spp; s++) {
        let hp = hit_points[pixel * params.spp + s];
        sum += hp.direct / f32(max(hp.iterations, 1u)) + radiance(hp.tau, hp.r2, hp.emitted);
    }
    let c = sum / f32(params.spp);
    image[3u * pixel] = c.x;
    image[3u * pixel + 1u] = c.y;
    image[3u * pixel + 2u] = c.z;
}
