// #import layout rng qmc sampling geometry bsdf bvh lights tables scene materials textures
// Eye pass (docs/algorithm.md 1.1): the twin of backend-cpu's eye_pass.rs. Writes each slot's
// visible point; the slot starts fresh or keeps its statistics as `params.flags` says.

@group(0) @binding(0) var<uniform> params: EyePassParams;
@group(0) @binding(1) var<uniform> camera: GpuCamera;
@group(0) @binding(2) var scene_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(3) var<uniform> scene: SceneIndex;
@group(0) @binding(4) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(5) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(6) var<storage, read_write> slot_bounds: array<GpuBounds>;
@group(0) @binding(7) var<storage, read> scene_texels: array<vec2<u32>>;
// One per slot in a scene with glossy surfaces, else one placeholder element.
@group(0) @binding(8) var<storage, read_write> chain_light: array<ChainLight>;

// False for a scene without mirrors, glass or conductors: every surface is diffuse, and the
// bounces through them are compiled out (backend_wgpu::Specialisation).
override SPECULAR: bool = true;

// The light sample at a glossy bounce at `depth` (backend-cpu's chain_light.rs): f cos Le /
// p_light weighed against the bounce's density in xyz, before the path's throughput; w one
// when a shadow ray was traced.
fn glossy_vertex_light(material: GpuMaterial, position: vec3<f32>, frame: Frame, front: bool, wo: vec3<f32>, key: StreamKey, depth: u32) -> vec4<f32> {
    if scene.light_count == 0u {
        return vec4<f32>(0.0);
    }
    let first = EYE_LIGHT_DIM + 3u * depth;
    let light = scene_light(sample_light(stream_uniform(key, first)));
    let b = uniform_triangle(stream_uniform(key, first + 1u), stream_uniform(key, first + 2u));
    let y = light.v0 + light.e1 * b.x + light.e2 * b.y;
    // The shadow ray leaves from the light's side (the far one through rough glass).
    let facing = frame.normal;
    let side = select(-facing, facing, dot(facing, y - position) >= 0.0);
    let origin = position + side * params.ray_epsilon;
    let to_light = y - origin;
    let dist2 = dot(to_light, to_light);
    if dist2 <= 0.0 {
        return vec4<f32>(0.0);
    }
    let dist = sqrt(dist2);
    let wi = to_light / dist;
    let cos_l = -dot(light.normal, wi);
    let lobe = bsdf_glossy_lobe(material, frame, front, wo, wi);
    if cos_l <= 0.0 || all(lobe.xyz == vec3<f32>(0.0)) {
        return vec4<f32>(0.0);
    }
    if occluded(origin, wi, dist - 2.0 * params.ray_epsilon) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let le = scene_material(light.material).emission;
    let pl = light_pdf(light.pdf, light.area, dist2, cos_l);
    return vec4<f32>(lobe.xyz * le * (power_heuristic(pl, lobe.w) / pl), 1.0);
}

// The weight of the emission met at `hit` travelling `dir` after a glossy bounce of density
// `bounce_pdf` (negative: none), against the light sample taken there.
fn emission_weight(hit: Hit, tri: GpuTriangle, dir: vec3<f32>, bounce_pdf: f32) -> f32 {
    let cos_l = -dot(tri.normal, dir);
    if bounce_pdf < 0.0 || tri.light == NO_MATERIAL || cos_l <= 0.0 {
        return 1.0;
    }
    let light = scene_light(tri.light);
    return power_heuristic(bounce_pdf, light_pdf(light.pdf, light.area, hit.t * hit.t, cos_l));
}

// The slot before this iteration's eye path: fresh, or its statistics without a visible point.
fn cleared_slot(slot: u32, pixel: u32) -> HitPoint {
    var hp: HitPoint;
    if (params.flags & EYE_KEEP_STATISTICS) != 0u {
        hp = hit_points[slot];
        hp.position = vec3<f32>(0.0);
        hp.normal = vec3<f32>(0.0);
        hp.throughput = vec3<f32>(0.0);
        hp.flags &= HIT_KEPT;
    } else {
        hp.pixel = pixel;
        hp.r2 = params.r2_initial;
    }
    hp.material = NO_MATERIAL;
    return hp;
}

@compute @workgroup_size(64)
fn eye_pass_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let pixel = slot / params.spp;
    let focus = EYE_KEEP_STATISTICS | EYE_FOCUS;
    if (params.flags & focus) == focus && hit_points[slot].iterations >= params.rest_at {
        // Ahead of the slots a move reset: keep the last visible point and sit this one out.
        hit_points[slot].flags |= HIT_RESTING;
        if (hit_points[slot].flags & HIT_VALID) != 0u {
            atomicAdd(&counters[COUNTER_ITEMS], 1u);
        }
        return;
    }
    let key = StreamKey(params.seed, PASS_EYE, params.iteration, slot);
    var jitter = vec2<f32>(0.5);
    if params.spp != 1u || (params.flags & EYE_JITTER) != 0u {
        // Kept slots continue their own sequence, a re-trace repeats the stratum it last used
        // (backend-cpu's eye_pass.rs).
        var start = params.iteration;
        if (params.flags & EYE_KEEP_STATISTICS) != 0u {
            start = hit_points[slot].iterations;
        } else if (params.flags & EYE_RETRACE) != 0u {
            start = max(hit_points[slot].iterations, 1u) - 1u;
        }
        let sample = start * params.spp + slot % params.spp;
        jitter = stratified_pair(params.seed, PASS_EYE, pixel, 0u, sample);
    }
    let px = f32(pixel % camera.width) + jitter.x;
    let py = f32(pixel / camera.width) + jitter.y;
    var dir = camera_ray(camera, px, py);
    var origin = camera.eye;
    var throughput = vec3<f32>(1.0);
    var out = cleared_slot(slot, pixel);
    var rays = params.max_depth + 1u;
    var shadow_rays = 0u;
    // The box of the path's vertices after the camera (backend-cpu's eye_pass.rs).
    var lo = vec3<f32>(F32_MAX);
    var hi = vec3<f32>(-F32_MAX);
    // What the glossy bounces found (backend-cpu's chain_light.rs): the light samples'
    // radiance, and the last bounce's density within its glossy lobe (negative: none).
    let chained = arrayLength(&chain_light) == arrayLength(&hit_points);
    let sample_lights = chained && (params.flags & EYE_SAMPLE_LIGHTS) != 0u;
    var chain = ChainLight(vec3<f32>(0.0), 1.0);
    var bounce_pdf = -1.0;
    for (var depth = 0u; depth <= params.max_depth; depth++) {
        let hit = closest_hit(origin, dir, T_MISS);
        if hit.triangle == 0xffffffffu {
            rays = depth + 1u;
            break;
        }
        let tri = scene_triangle(hit.triangle);
        out.eye_met |= tri.group;
        let position = origin + dir * hit.t;
        let base = scene_material(tri.material);
        let texture = texture_factor(base, hit.triangle, tri, position);
        var material = base;
        material.albedo *= texture;
        lo = min(lo, position);
        hi = max(hi, position);
        let front = dot(dir, tri.normal) < 0.0;
        let facing = select(-tri.normal, tri.normal, front);
        let u = stream_uniform(key, EYE_GLASS_DIM + depth);
        // Negative where the path continues; always one on a diffuse surface, the only kind
        // without SPECULAR.
        let stop = bsdf_visible_point_weight(material, facing, -dir, u);
        if stop >= 0.0 {
            out.position = position;
            out.normal = facing;
            out.material = tri.material;
            // The texture's factor rides in the throughput (ppm_core::textures), and so does
            // a coat's transmittance towards the eye (ppm_core::bsdf).
            out.throughput = throughput * visible_point_scale(base, material, texture) * stop;
            out.flags |= HIT_VALID | select(0u, HIT_FRONT, front) | (tri.object << HIT_OBJECT_SHIFT);
            chain.emission_weight = emission_weight(hit, tri, dir, bounce_pdf);
            rays = depth + 1u;
            break;
        }
        out.flags |= HIT_EYE_CHAINED;
        let glossy_lobe = sample_lights && bsdf_chain_samples_lights(material);
        let frame = surface_frame(material, hit.triangle, tri, facing);
        if glossy_lobe {
            let light = glossy_vertex_light(material, position, frame, front, -dir, key, depth);
            chain.radiance += throughput * light.xyz;
            shadow_rays += u32(light.w);
        }
        let glossy = EYE_GLOSSY_DIM + 2u * depth;
        let u_dir = vec2<f32>(stream_uniform(key, glossy), stream_uniform(key, glossy + 1u));
        let bounce = bsdf_sample(material, dir, frame, front, u, u_dir, TRANSPORT_RADIANCE);
        if all(bounce.weight == vec3<f32>(0.0)) {
            // A glossy direction below the surface: no visible point.
            rays = depth + 1u;
            break;
        }
        bounce_pdf = -1.0;
        if glossy_lobe {
            bounce_pdf = bsdf_glossy_lobe(material, frame, front, -dir, bounce.dir).w;
        }
        throughput *= bounce.weight;
        dir = bounce.dir;
        let side = select(facing, -facing, bounce.transmitted);
        origin = position + side * params.ray_epsilon;
    }
    hit_points[slot] = out;
    if chained {
        chain_light[slot] = chain;
    }
    if (params.flags & EYE_RECORD_BOUNDS) != 0u {
        // Started over where the slot's statistics start (no direct sample yet).
        var bounds = GpuBounds(vec3<f32>(F32_MAX), 0u, vec3<f32>(-F32_MAX), 0u);
        if out.iterations != 0u {
            bounds = slot_bounds[slot];
        }
        slot_bounds[slot] = GpuBounds(min(bounds.min, lo), 0u, max(bounds.max, hi), 0u);
    }
    atomicAdd(&counters[COUNTER_RAYS], rays + shadow_rays);
    if (out.flags & HIT_VALID) != 0u {
        atomicAdd(&counters[COUNTER_ITEMS], 1u);
    }
}
