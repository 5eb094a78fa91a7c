// Where a slot's light may come from: the twin of ppm_core::reach, its boxes and the
// conservative test of segments between two boxes meeting a third.

// ppm_core::reach::Aabb: a box by its corners (lo > hi on some axis: the box of nothing).
struct Aabb {
    lo: vec3<f32>,
    hi: vec3<f32>,
}

fn aabb_of(b: GpuBounds) -> Aabb {
    return Aabb(b.min, b.max);
}

fn aabb_is_empty(b: Aabb) -> bool {
    return any(b.lo > b.hi);
}

// Whether the two boxes share a point (closed boxes).
fn aabb_overlaps(a: Aabb, b: Aabb) -> bool {
    return !aabb_is_empty(a) && !aabb_is_empty(b) && all(a.lo <= b.hi) && all(b.lo <= a.hi);
}

// glam's length, term by term: (x x + y y) + z z, then the root.
fn reach_length(v: vec3<f32>) -> f32 {
    return sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
}

// Distance from `p` to the nearest point of the box (0 inside it).
fn aabb_distance_from(b: Aabb, p: vec3<f32>) -> f32 {
    return reach_length(max(max(b.lo - p, p - b.hi), vec3<f32>(0.0)));
}

// Distance from `p` to the farthest point of the box.
fn aabb_farthest_from(b: Aabb, p: vec3<f32>) -> f32 {
    return reach_length(max(abs(b.lo - p), abs(b.hi - p)));
}

// ppm_core::reach::WIDEN: each bound of the obstacle widened, relative to the largest
// coordinate in play.
const REACH_WIDEN: f32 = 1e-5;

// The interval of s in [0, 1] where (1 - s) at0 + s at1 <= bound, widened by REACH_WIDEN
// (empty: x > y); infinite inputs answer all of [0, 1] (ppm_core::reach's at_most).
fn reach_at_most(at0: f32, at1: f32, bound_in: f32) -> vec2<f32> {
    let bound = bound_in + REACH_WIDEN * max(max(abs(bound_in), abs(at0)), abs(at1));
    let slope = at1 - at0;
    if !(is_finite_f32(slope) && is_finite_f32(bound)) {
        return vec2<f32>(0.0, 1.0);
    }
    if slope == 0.0 {
        return select(vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0), at0 <= bound);
    }
    let s = (bound - at0) / slope;
    return select(vec2<f32>(s, 1.0), vec2<f32>(0.0, s), slope > 0.0);
}

// Whether `obstacle` comes near the box around `start` and `end`, within a margin far wider
// than the sweep's rounding (ppm_core::reach::near_both).
fn reach_near_both(start: Aabb, end: Aabb, obstacle: Aabb) -> bool {
    let lo = min(start.lo, end.lo);
    let hi = max(start.hi, end.hi);
    let scale = max(max(abs(lo), abs(hi)), max(abs(obstacle.lo), abs(obstacle.hi)));
    let margin = scale * (16.0 * REACH_WIDEN);
    return !(any(lo - margin > obstacle.hi) || any(hi + margin < obstacle.lo));
}

// Whether some segment from a point of `start` to a point of `end` may meet `obstacle`
// (ppm_core::reach::segments_may_meet: the box swept from one to the other overlaps the
// obstacle on a shared interval of s per axis; an obstacle well apart from the box around
// both is answered no first).
fn segments_may_meet(start: Aabb, end: Aabb, obstacle: Aabb) -> bool {
    if aabb_is_empty(start) || aabb_is_empty(end) || aabb_is_empty(obstacle) {
        return false;
    }
    if !reach_near_both(start, end, obstacle) {
        return false;
    }
    var first = 0.0;
    var last = 1.0;
    for (var k = 0u; k < 3u; k++) {
        let ab = reach_at_most(start.lo[k], end.lo[k], obstacle.hi[k]);
        let cd = reach_at_most(-start.hi[k], -end.hi[k], -obstacle.lo[k]);
        first = max(max(first, ab.x), cd.x);
        last = min(min(last, ab.y), cd.y);
    }
    return first <= last;
}
