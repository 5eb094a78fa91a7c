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

// ppm_core::update::pairing::partner: the partner of a pose-B deposit of normal
// `normal_oct`, the `nth` its path stored, among pose A's deposits of the path: (position,
// luminance), or zero for none.
fn pairing_partner(pose_a: PathDeposits, nth: u32, normal_oct: u32) -> vec4<f32> {
    if nth < PAIRED_DEPOSITS {
        let a = pose_a.deposits[nth];
        if a.w != 0.0 && pose_a.normal_oct[nth] == normal_oct {
            return a;
        }
    }
    return vec4<f32>(0.0);
}

// ppm_core::update::pairing::Partner::cancels: whether a deposit at `position` of luminance
// `own` is its partner `partner` (a real one, luminance not zero) with the power negated.
fn partner_cancels(partner: vec4<f32>, position: vec3<f32>, own: f32) -> bool {
    return partner.w != 0.0 && all(partner.xyz == position) && partner.w == -own;
}

// ppm_core::update::pairing::variance_term: what a deposit of luminance `own` adds to a
// disc's correction variance, its partner of luminance `partner` in the disc or not; the
// cross term floored as ppm_core::update::pairing::cross_term floors it, and a pair that
// `cancels` (ppm_core::update::pairing::Partner::cancels) counting nothing.
fn variance_term(own: f32, partner: f32, both: bool, cancels: bool) -> f32 {
    let squares = partner * partner + own * own;
    let cross = select(max(2.0 * partner * own, -(1.0 - PAIR_FLOOR) * squares), -squares, cancels);
    return own * own + select(0.0, cross, both);
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

// The gather rule: the twin of ppm_core::update::gather, kind for kind (both reproduce
// ppm_core::update::gather::test_cases, backend-wgpu's tests/gather_rule.rs).

struct SlotState {
    tau: vec3<f32>,
    n: f32,
    pending: vec4<f32>,
    r2: f32,
    emitted: f32,
    flags: u32,
    discounted: f32,
}

struct Found {
    flux: vec3<f32>,
    count: f32,
    weight: f32,
    power_sq: f32,
    _pad: vec2<f32>,
}

fn serves(flags: u32, kind: u32) -> bool {
    let updated = (flags & HIT_UPDATED) != 0u;
    switch kind & GATHER_KIND_MASK {
        case GATHER_REGION_NEGATIVE, GATHER_REGION_POSITIVE: {
            return !updated;
        }
        case GATHER_GUIDED: {
            return updated;
        }
        default: {
            return true;
        }
    }
}

fn gathers(flags: u32, kind: u32) -> bool {
    return (flags & HIT_VALID) != 0u && serves(flags, kind);
}

// The squared radius of the disc a slot searches a map within: ppm_core's search_r2.
fn search_r2(hp: HitPoint, r2_floor: f32) -> f32 {
    if r2_floor > 0.0 {
        return max(max(hp.r2, r2_floor), hp.correction_r2);
    }
    return hp.r2;
}

// What photons found within a disc of squared radius `searched` stand for in the slot's own
// disc of `r2`: ppm_core's disc_shrink.
fn disc_shrink(r2: f32, searched: f32) -> f32 {
    return select(1.0, r2 / searched, searched > r2);
}

fn uses_pending(kind: u32) -> bool {
    return (kind & GATHER_DEFERRED) != 0u || (kind & GATHER_KIND_MASK) == GATHER_REGION_APPLY;
}

fn gather_rule(p: GatherParams, r2_initial: f32, reflectance: vec3<f32>, slot: SlotState, found: Found) -> SlotState {
    let kind = p.kind & GATHER_KIND_MASK;
    if kind == GATHER_REGION_APPLY {
        return apply_pending(p, r2_initial, slot);
    }
    var s = slot;
    if !gathers(s.flags, p.kind) {
        if serves(s.flags, p.kind) {
            s.emitted += p.emitted_increment;
        }
        return s;
    }
    let region = kind == GATHER_REGION_NEGATIVE || kind == GATHER_REGION_POSITIVE;
    let scale = select(1.0, s.emitted / p.region_photons, region);
    var m = found.count;
    if region && (p.kind & GATHER_RAW_COUNT) == 0u {
        m = found.weight * scale;
    }
    let factor = reflectance * scale;
    let dtau = found.flux * factor;
    if (p.kind & GATHER_DEFERRED) != 0u {
        let sign = select(1.0, -1.0, kind == GATHER_REGION_NEGATIVE);
        let lum = luminance(factor);
        let count = select(sign * m, found.power_sq * lum * lum, (p.kind & GATHER_ADD_FLUX) != 0u);
        s.pending += vec4<f32>(dtau, count);
        return s;
    }
    let before = Statistics(s.n, s.r2, s.tau);
    var after: Statistics;
    if kind == GATHER_REGION_NEGATIVE {
        after = compensation_update(before, m, dtau, p.alpha, r2_initial);
    } else {
        after = ppm_update(before, m, dtau, p.alpha);
    }
    s.n = after.n;
    s.r2 = after.r2;
    s.tau = after.tau;
    s.discounted = min(s.discounted, s.n);
    s.emitted += p.emitted_increment;
    if kind == GATHER_REGION_NEGATIVE && m > 0.0 && after.n == 0.0 {
        s.emitted = 0.0;
    }
    return s;
}

fn apply_pending(p: GatherParams, r2_initial: f32, slot: SlotState) -> SlotState {
    var s = slot;
    let q = s.pending;
    s.pending = vec4<f32>(0.0);
    if (s.flags & HIT_VALID) == 0u || all(q == vec4<f32>(0.0)) {
        return s;
    }
    if (p.kind & GATHER_ADD_FLUX) != 0u {
        let tau = max(s.tau + q.xyz, vec3<f32>(0.0));
        let worth = max(s.n - s.discounted, 0.0);
        let kept = history_kept(worth, tau, q.w);
        s.tau = tau * kept;
        s.emitted *= kept;
        s.discounted = s.n - worth * kept;
        return s;
    }
    let before = Statistics(s.n, s.r2, s.tau);
    var after: Statistics;
    if q.w >= 0.0 {
        after = ppm_update(before, q.w, q.xyz, p.alpha);
        after.tau = max(after.tau, vec3<f32>(0.0));
    } else {
        after = compensation_update(before, -q.w, q.xyz, p.alpha, r2_initial);
        if after.n == 0.0 {
            s.emitted = 0.0;
        }
    }
    s.n = after.n;
    s.r2 = after.r2;
    s.tau = after.tau;
    s.discounted = min(s.discounted, s.n);
    return s;
}
