// An eye path (docs/algorithm.md 1.1): the twin of ppm_core::eye_path::trace_eye_path, for
// every caller: the eye pass, and a local move's probes and paired direct-light samples.
// From the eye through a point of a pixel, through mirrors, glass and glossy bounces, to its
// visible point; at each glossy bounce it may take a light sample, weighed by the power
// heuristic against the bounce, which weighs the emission met next (docs/algorithm.md 1.2).
// Needs the bindings `camera`, `scene_table`, `scene` and `scene_texels` in the importing
// pass (and layout, rng, sampling, geometry, bsdf, bvh, lights, tables, scene, materials and
// textures imported).

// ppm_core::eye_path::EyePathSettings.
struct EyePathSettings {
    max_depth: u32,
    ray_epsilon: f32,
    sample_lights: bool,
}

// ppm_core::eye_path::EyePath, its visible point inline (`visible` says whether it has one).
// The WGSL twin watches groups only: no pass on the device asks whether a path crossed a box.
struct EyePath {
    visible: bool,
    position: vec3<f32>,
    // The surface's normal on the path's side.
    normal: vec3<f32>,
    material: u32,
    object: u32,
    // The throughput at the visible point, the texture's factor and a coat's transmittance
    // towards the eye included.
    throughput: vec3<f32>,
    front: bool,
    // What its glossy bounces found.
    chain: ChainLight,
    // The object groups of every surface it met.
    met: u32,
    // It stopped on a surface of a watched group.
    watched: bool,
    // It met a surface that continues paths on its way, or ended on one.
    chained: bool,
    // How far its first segment went; T_MISS where it left the scene.
    first_t: f32,
    // The box of its vertices after the eye (lo > hi where it met nothing).
    lo: vec3<f32>,
    hi: vec3<f32>,
    // Rays traced: its segments and its light samples' shadow rays.
    rays: u32,
}

// The light sample at a glossy bounce at `depth` (ppm_core::eye_path's glossy_vertex_light):
// f cos Le / p_light weighed against the bounce's density in xyz, before the path's
// throughput; w one when a shadow ray was traced.
fn glossy_vertex_light(material: GpuMaterial, position: vec3<f32>, frame: Frame, front: bool, wo: vec3<f32>, key: StreamKey, depth: u32, ray_epsilon: f32) -> vec4<f32> {
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
    let origin = position + side * ray_epsilon;
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
    if occluded(origin, wi, dist - 2.0 * ray_epsilon) {
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

// Traces the eye path through point `jitter` of `pixel`, its lobes and glossy bounces drawn
// from `key`, to its visible point; it stops instead at the first surface of one of the
// groups `watch` (bits of ppm_core::compile::object_group; zero watches none).
fn trace_eye_path(pixel: u32, jitter: vec2<f32>, key: StreamKey, settings: EyePathSettings, watch: u32) -> EyePath {
    var path: EyePath;
    path.chain = ChainLight(vec3<f32>(0.0), 1.0);
    path.first_t = T_MISS;
    path.lo = vec3<f32>(F32_MAX);
    path.hi = vec3<f32>(-F32_MAX);
    let px = f32(pixel % camera.width) + jitter.x;
    let py = f32(pixel / camera.width) + jitter.y;
    var dir = camera_ray(camera, px, py);
    var origin = camera.eye;
    var throughput = vec3<f32>(1.0);
    var segments = settings.max_depth + 1u;
    var shadow_rays = 0u;
    // The density of the last glossy bounce within its lobe (negative: none).
    var bounce_pdf = -1.0;
    for (var depth = 0u; depth <= settings.max_depth; depth++) {
        let hit = closest_hit(origin, dir, T_MISS);
        if hit.triangle == 0xffffffffu {
            segments = depth + 1u;
            break;
        }
        if depth == 0u {
            path.first_t = hit.t;
        }
        let tri = scene_triangle(hit.triangle);
        path.met |= tri.group;
        if (tri.group & watch) != 0u {
            path.watched = true;
            segments = depth + 1u;
            break;
        }
        let position = origin + dir * hit.t;
        let base = scene_material(tri.material);
        let texture = texture_factor(base, hit.triangle, tri, position);
        var material = base;
        material.albedo *= texture;
        path.lo = min(path.lo, position);
        path.hi = max(path.hi, position);
        let front = dot(dir, tri.normal) < 0.0;
        let facing = select(-tri.normal, tri.normal, front);
        let u = stream_uniform(key, EYE_GLASS_DIM + depth);
        // Negative where the path continues; always one on a diffuse surface.
        let stop = bsdf_visible_point_weight(material, facing, -dir, u);
        if stop >= 0.0 {
            path.visible = true;
            path.position = position;
            path.normal = facing;
            path.material = tri.material;
            path.object = tri.object;
            // The texture's factor rides in the throughput (ppm_core::textures), and so does
            // a coat's transmittance towards the eye (ppm_core::bsdf).
            path.throughput = throughput * visible_point_scale(base, material, texture) * stop;
            path.front = front;
            path.chain.emission_weight = emission_weight(hit, tri, dir, bounce_pdf);
            segments = depth + 1u;
            break;
        }
        path.chained = true;
        let glossy_lobe = settings.sample_lights && bsdf_chain_samples_lights(material);
        let frame = surface_frame(material, hit.triangle, tri, facing);
        if glossy_lobe {
            let light = glossy_vertex_light(material, position, frame, front, -dir, key, depth, settings.ray_epsilon);
            path.chain.radiance += throughput * light.xyz;
            shadow_rays += u32(light.w);
        }
        let glossy = EYE_GLOSSY_DIM + 2u * depth;
        let u_dir = vec2<f32>(stream_uniform(key, glossy), stream_uniform(key, glossy + 1u));
        let bounce = bsdf_sample(material, dir, frame, front, u, u_dir, TRANSPORT_RADIANCE);
        if all(bounce.weight == vec3<f32>(0.0)) {
            // A glossy direction below the surface: no visible point.
            segments = depth + 1u;
            break;
        }
        bounce_pdf = -1.0;
        if glossy_lobe {
            bounce_pdf = bsdf_glossy_lobe(material, frame, front, -dir, bounce.dir).w;
        }
        throughput *= bounce.weight;
        dir = bounce.dir;
        let side = select(facing, -facing, bounce.transmitted);
        origin = position + side * settings.ray_epsilon;
    }
    path.rays = segments + shadow_rays;
    return path;
}

// The visible point's slot flags (ppm_core::eye_path::Visible::flags): VALID, FRONT where
// it is, and its object; none without a visible point.
fn eye_path_flags(path: EyePath) -> u32 {
    if !path.visible {
        return 0u;
    }
    return HIT_VALID | select(0u, HIT_FRONT, path.front) | (path.object << HIT_OBJECT_SHIFT);
}
