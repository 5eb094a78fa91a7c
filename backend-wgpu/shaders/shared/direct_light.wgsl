// Direct light (docs/algorithm.md 1.2) at one slot: the twin of ppm_core::direct_light, for
// every caller: the direct-light pass, and a local move's paired samples. Each sample is a
// shadow ray to a light and a ray drawn from the BSDF that may meet one, weighted by the
// power heuristic. Needs the bindings `scene_table` and `scene` in the importing pass.

// Stratified pairs of each sample (ppm_core::direct_light::PAIR_*).
const PAIR_LIGHT_POINT: u32 = 0u;
const PAIR_DIRECTION: u32 = 1u;
const PAIR_LIGHT_CHOICE: u32 = 2u;
const RAYS_PER_SAMPLE: u32 = 2u;

// ppm_core::direct_light::sequence_start.
fn sequence_start(p: DirectLightParams, hp: HitPoint) -> u32 {
    return select(p.iteration, hp.iterations, p.accumulate == DIRECT_ADD);
}

// Light from the lights reflected towards the eye (ppm_core::direct_light's
// estimate_reflected).
fn estimate_reflected(p: DirectLightParams, material: GpuMaterial, hp: HitPoint, slot: u32) -> vec3<f32> {
    let f = visible_point_f(material);
    let origin = hp.position + hp.normal * p.ray_epsilon;
    var sum = vec3<f32>(0.0);
    let start = sequence_start(p, hp) * p.samples;
    for (var s = 0u; s < p.samples; s++) {
        let index = start + s;
        let choice = stratified_pair(p.seed, PASS_DIRECT_LIGHT, slot, PAIR_LIGHT_CHOICE, index);
        let light = scene_light(sample_light(choice.x));
        let u = stratified_pair(p.seed, PASS_DIRECT_LIGHT, slot, PAIR_LIGHT_POINT, index);
        let b = uniform_triangle(u.x, u.y);
        let y = light.v0 + light.e1 * b.x + light.e2 * b.y;
        let to_light = y - origin;
        let dist2 = dot(to_light, to_light);
        if dist2 > 0.0 {
            let dist = sqrt(dist2);
            let w = to_light / dist;
            let cos_x = dot(hp.normal, w);
            let cos_l = -dot(light.normal, w);
            if cos_x > 0.0 && cos_l > 0.0 && !occluded(origin, w, dist - 2.0 * p.ray_epsilon) {
                let le = scene_material(light.material).emission;
                let pl = light_pdf(light.pdf, light.area, dist2, cos_l);
                let pb = visible_point_pdf(hp.normal, w);
                // A coat lets through a share of the light (one on a bare surface).
                let cos_through = cos_x * bsdf_arrival(material, cos_x);
                sum += f * le * (cos_through / pl * power_heuristic(pl, pb));
            }
        }
        let v = stratified_pair(p.seed, PASS_DIRECT_LIGHT, slot, PAIR_DIRECTION, index);
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
    return sum / f32(p.samples);
}

// One eye path's direct radiance towards the eye, throughput included, and the rays traced
// for it (ppm_core::direct_light::slot_direct).
struct SlotDirect {
    radiance: vec3<f32>,
    rays: u32,
}

// What the eye path that left `hp` found at its glossy bounces (`chain`) and, where it has a
// visible point, the light seen there; `slot` keys its random numbers.
fn slot_direct(p: DirectLightParams, hp: HitPoint, chain: ChainLight, slot: u32) -> SlotDirect {
    var out = SlotDirect(chain.radiance, 0u);
    if (hp.flags & HIT_VALID) == 0u {
        return out;
    }
    let material = scene_material(hp.material);
    let emission = material.emission * chain.emission_weight;
    var direct = select(vec3<f32>(0.0), emission, (hp.flags & HIT_FRONT) != 0u);
    let f = visible_point_f(material);
    if p.samples > 0u && max(f.x, max(f.y, f.z)) > 0.0 && scene.light_count > 0u {
        direct += estimate_reflected(p, material, hp, slot);
        out.rays = p.samples * RAYS_PER_SAMPLE;
    }
    out.radiance += hp.throughput * direct;
    return out;
}
