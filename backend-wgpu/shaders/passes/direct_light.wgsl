// #import layout rng qmc sampling geometry bsdf bvh lights tables scene materials
// Direct light (docs/algorithm.md 1.2): the twin of backend-cpu's direct_light.rs. Each sample is a
// shadow ray to a light and a ray drawn from the BSDF that may meet one, weighted by the power
// heuristic.

@group(0) @binding(0) var<uniform> params: DirectLightParams;
@group(0) @binding(1) var scene_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(2) var<uniform> scene: SceneIndex;
@group(0) @binding(3) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>, 4>;
// What each slot's eye path found at glossy bounces (eye_pass.wgsl), in a scene with glossy
// surfaces; else one placeholder element.
@group(0) @binding(5) var<storage, read> chain_light: array<ChainLight>;

// Stratified pairs of each sample (see backend-cpu's direct_light.rs).
const PAIR_LIGHT_POINT: u32 = 0u;
const PAIR_DIRECTION: u32 = 1u;
const PAIR_LIGHT_CHOICE: u32 = 2u;
const RAYS_PER_SAMPLE: u32 = 2u;

// backend-cpu's direct_light::sequence_start.
fn sequence_start(hp: HitPoint) -> u32 {
    return select(params.iteration, hp.iterations, params.accumulate == DIRECT_ADD);
}

// Light from the lights reflected towards the eye (backend-cpu's estimate_reflected).
fn estimate_reflected(material: GpuMaterial, hp: HitPoint, slot: u32) -> vec3<f32> {
    let f = visible_point_f(material);
    let origin = hp.position + hp.normal * params.ray_epsilon;
    var sum = vec3<f32>(0.0);
    let start = sequence_start(hp) * params.samples;
    for (var s = 0u; s < params.samples; s++) {
        let index = start + s;
        let choice = stratified_pair(params.seed, PASS_DIRECT_LIGHT, slot, PAIR_LIGHT_CHOICE, index);
        let light = scene_light(sample_light(choice.x));
        let u = stratified_pair(params.seed, PASS_DIRECT_LIGHT, slot, PAIR_LIGHT_POINT, index);
        let b = uniform_triangle(u.x, u.y);
        let y = light.v0 + light.e1 * b.x + light.e2 * b.y;
        let to_light = y - origin;
        let dist2 = dot(to_light, to_light);
        if dist2 > 0.0 {
            let dist = sqrt(dist2);
            let w = to_light / dist;
            let cos_x = dot(hp.normal, w);
            let cos_l = -dot(light.normal, w);
            if cos_x > 0.0 && cos_l > 0.0 && !occluded(origin, w, dist - 2.0 * params.ray_epsilon) {
                let le = scene_material(light.material).emission;
                let pl = light_pdf(light.pdf, light.area, dist2, cos_l);
                let pb = visible_point_pdf(hp.normal, w);
                // A coat lets through a share of the light (one on a bare surface).
                let cos_through = cos_x * bsdf_arrival(material, cos_x);
                sum += f * le * (cos_through / pl * power_heuristic(pl, pb));
            }
        }
        let v = stratified_pair(params.seed, PASS_DIRECT_LIGHT, slot, PAIR_DIRECTION, index);
        let scattered = bsdf_sample_visible(material, hp.normal, v);
        let w = scattered.dir;
        let hit = closest_hit(origin, w, T_MISS);
        if hit.triangle != 0xffffffffu {
            let tri = scene_triangle(hit.triangle);
            let reached_light = tri.light != NO_MATERIAL;
            let cos_l = -dot(tri.normal, w);
            if reached_light && cos_l > 0.0 {
                let hit_light = scene_light(tri.light);
                let le = scene_material(hit_light.material).emission;
                let pl = light_pdf(hit_light.pdf, hit_light.area, hit.t * hit.t, cos_l);
                sum += scattered.weight * le * power_heuristic(scattered.pdf, pl);
            }
        }
    }
    return sum / f32(params.samples);
}

@compute @workgroup_size(64)
fn direct_light_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = hit_points[slot];
    if (hp.flags & HIT_RESTING) != 0u {
        return;
    }
    var chain = ChainLight(vec3<f32>(0.0), 1.0);
    if arrayLength(&chain_light) == arrayLength(&hit_points) {
        chain = chain_light[slot];
    }
    var estimate = chain.radiance;
    if (hp.flags & HIT_VALID) != 0u {
        let material = scene_material(hp.material);
        let emission = material.emission * chain.emission_weight;
        var direct = select(vec3<f32>(0.0), emission, (hp.flags & HIT_FRONT) != 0u);
        let f = visible_point_f(material);
        if params.samples > 0u && max(f.x, max(f.y, f.z)) > 0.0 && scene.light_count > 0u {
            direct += estimate_reflected(material, hp, slot);
            atomicAdd(&counters[COUNTER_RAYS], params.samples * RAYS_PER_SAMPLE);
        }
        estimate += hp.throughput * direct;
    }
    var direct = estimate;
    var iterations = 1u;
    if params.accumulate == DIRECT_ADD {
        direct = hp.direct + estimate;
        iterations = hp.iterations + 1u;
    }
    // Only the fields this pass changes are written back (a whole slot is 24 word stores,
    // which lavapipe makes one invocation at a time).
    hit_points[slot].direct = direct;
    hit_points[slot].iterations = iterations;
}
