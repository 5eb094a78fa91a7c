// Where photons leave the lights: the twin of ppm_core::emission. Needs the bindings
// `scene_table`, `scene`, `emitter` and `recorded` in the importing pass.

struct Emission {
    origin: vec3<f32>,
    direction: vec3<f32>,
    power: vec3<f32>,
    light: u32,
    normal: vec3<f32>,
    weight: f32,
}

fn light_power(light: GpuLight) -> vec3<f32> {
    return scene_material(light.material).emission * (PI * light.area / light.pdf);
}

fn point_on(light: GpuLight, u1: f32, u2: f32) -> vec3<f32> {
    let b = uniform_triangle(u1, u2);
    return light.v0 + light.e1 * b.x + light.e2 * b.y;
}

fn ordinary_emission(key: StreamKey) -> Emission {
    let index = sample_light(stream_uniform(key, 0u));
    let light = scene_light(index);
    return Emission(
        point_on(light, stream_uniform(key, 1u), stream_uniform(key, 2u)),
        to_world(cosine_hemisphere(stream_uniform(key, 3u), stream_uniform(key, 4u)), light.normal),
        light_power(light),
        index,
        light.normal,
        1.0,
    );
}

fn region_emission(key: StreamKey) -> Emission {
    let region = emitter.region;
    let index = sample_light(stream_uniform(key, 0u));
    let light = scene_light(index);
    var origin = region.light_point;
    if region.mode != REGION_POINT {
        origin = point_on(light, stream_uniform(key, 1u), stream_uniform(key, 2u));
    }
    let target_point = region.origin + region.edge_u * stream_uniform(key, 3u) + region.edge_v * stream_uniform(key, 4u);
    let to = target_point - origin;
    let d2 = dot(to, to);
    var direction = light.normal;
    if d2 > 0.0 {
        direction = to / sqrt(d2);
    }
    let cos_l = dot(light.normal, direction);
    let rect_normal = cross(region.edge_u, region.edge_v);
    var cos_r = 0.0;
    if dot(rect_normal, rect_normal) > 0.0 {
        cos_r = abs(dot(normalize(rect_normal), direction));
    }
    var weight = 0.0;
    if d2 > 0.0 && cos_l > 0.0 && region.area > 0.0 {
        weight = region.area * cos_l * cos_r / (PI * d2);
    }
    return Emission(origin, direction, light_power(light) * weight, index, light.normal, weight);
}

fn guided_emission(key: StreamKey) -> Emission {
    let guide = emitter.guide;
    let count = guide.paths;
    if count == 0u {
        return ordinary_emission(key);
    }
    let use_ordinary = guide.weighted == 1u && stream_uniform(key, 7u) < guide.beta;
    if use_ordinary && guide.weighted == 0u {
        return ordinary_emission(key);
    }
    let k = min(u32(stream_uniform(key, 5u) * f32(count)), count - 1u);
    let recorded_path = recorded[k];
    let cone = uniform_cone(stream_uniform(key, 3u), stream_uniform(key, 4u), guide.cos_cone);
    if guide.weighted == 0u {
        let light = scene_light(recorded_path.light);
        return Emission(
            recorded_path.origin,
            to_world(cone, recorded_path.direction),
            light_power(light),
            recorded_path.light,
            light.normal,
            1.0,
        );
    }
    var e = ordinary_emission(key);
    if !use_ordinary {
        e.direction = to_world(cone, recorded_path.direction);
    }
    let cos_d = dot(e.normal, e.direction);
    let omega = 2.0 * PI * (1.0 - guide.cos_cone);
    var in_cones = 0.0;
    for (var i = 0u; i < count; i++) {
        if dot(recorded[i].direction, e.direction) >= guide.cos_cone {
            in_cones += 1.0;
        }
    }
    let mixture = guide.beta * cos_d / PI + (1.0 - guide.beta) * in_cones / (f32(count) * omega);
    e.weight = 0.0;
    if cos_d > 0.0 && mixture > 0.0 {
        e.weight = (cos_d / PI) / mixture;
    }
    e.power *= e.weight;
    return e;
}
