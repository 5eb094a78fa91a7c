// The progressive statistics update: the twin of ppm_core::update, in the same stable forms.

struct Statistics {
    n: f32,
    r2: f32,
    tau: vec3<f32>,
}

fn shrink_ratio(n: f32, m: f32, alpha: f32) -> f32 {
    return 1.0 - (1.0 - alpha) * (m / (n + m));
}

fn ppm_update(s: Statistics, m: f32, dtau: vec3<f32>, alpha: f32) -> Statistics {
    if s.n + m <= 0.0 {
        return s;
    }
    let ratio = shrink_ratio(s.n, m, alpha);
    return Statistics(s.n + alpha * m, s.r2 * ratio, (s.tau + dtau) * ratio);
}

fn radiance(tau: vec3<f32>, r2: f32, emitted: f32) -> vec3<f32> {
    if emitted <= 0.0 || r2 <= 0.0 {
        return vec3<f32>(0.0);
    }
    let area = PI * r2;
    return min((tau / emitted) / area, vec3<f32>(3.4028235e38));
}

fn compensation_update(s: Statistics, m: f32, dtau: vec3<f32>, alpha: f32, r2_initial: f32) -> Statistics {
    if m <= 0.0 {
        return s;
    }
    if m >= s.n {
        return Statistics(0.0, r2_initial, vec3<f32>(0.0));
    }
    let ratio = 1.0 + (1.0 - alpha) * (m / (s.n - m));
    // The flux grows with the disc, capped alike (ppm_core::update::compensation_update).
    let r2 = min(s.r2 * ratio, r2_initial);
    let grown = select(ratio, r2 / s.r2, s.r2 > 0.0);
    return Statistics(s.n - alpha * m, r2, max((s.tau + dtau) * grown, vec3<f32>(0.0)));
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// ppm_core::update::history_kept: the share of a slot's history worth keeping after a
// correction of `variance` (squared luminance) was added to its flux `tau`.
fn history_kept(n: f32, tau: vec3<f32>, variance: f32) -> f32 {
    if !(variance > 0.0) {
        return 1.0;
    }
    let lum = luminance(tau);
    let relative = variance / (lum * lum);
    if !is_finite_f32(relative) {
        return 0.0;
    }
    return clamp(1.0 / (1.0 + n * relative), 0.0, 1.0);
}
