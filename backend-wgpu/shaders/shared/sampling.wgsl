// Warps from uniform numbers to sampled distributions: the twin of ppm_core::sampling.

const PI: f32 = 3.14159265358979;

fn cosine_hemisphere(u1: f32, u2: f32) -> vec3<f32> {
    let r = sqrt(u1);
    let phi = 2.0 * PI * u2;
    return vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u1, 0.0)));
}

fn uniform_triangle(u1: f32, u2: f32) -> vec2<f32> {
    let s = sqrt(u1);
    return vec2<f32>(s * (1.0 - u2), s * u2);
}

fn uniform_cone(u1: f32, u2: f32, cos_max: f32) -> vec3<f32> {
    let cos_t = 1.0 - u1 * (1.0 - cos_max);
    let sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    let phi = 2.0 * PI * u2;
    return vec3<f32>(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Solid-angle density of a point on a light (selection probability `pdf`, uniform on `area`)
// seen at squared distance `dist2` under cosine `cos_l`.
fn light_pdf(pdf: f32, area: f32, dist2: f32, cos_l: f32) -> f32 {
    return pdf / area * dist2 / cos_l;
}

// Power-heuristic weight of a strategy with density `a` against one with density `b`.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    if a2 + b2 > 0.0 {
        return a2 / (a2 + b2);
    }
    return 0.0;
}
