// Local mode's per-slot decisions and its direct-light change (docs/algorithm.md 3b, 3c):
// the twin of ppm_core::local_move, function for function, over a move's boxes in
// `move_boxes` (in the order of ppm_core::local_move::LocalMove::boxes). Needs `move_boxes`
// (an array of GpuBounds: the move's storage buffer, or a test's private copy) in the
// importing pass, and reach.wgsl and update.wgsl imported. The paths a move traces (the
// probe, the pairs) are local_move.wgsl's, the pass.

// ppm_core::local_move's constants.
const CORRECTION_SPREAD: f32 = 0.3;
const PROBE_PATHS: u32 = 32u;
const PROBE_SEED: u32 = 0x9b0be5edu;
const MOST_SAMPLES: u32 = 16u;
const CHANGE_SEED: u32 = 0x5eedc0deu;

// ppm_core::local_move::View.
const VIEW_CHANGES: u32 = 0u;
const VIEW_PROBE: u32 = 1u;
const VIEW_KEPT: u32 = 2u;

// Where a move's boxes lie in `move_boxes`: from `first`, its `objects` boxes in pose A, as
// many in pose B, then its `lights`.
struct MoveBoxes {
    first: u32,
    objects: u32,
    lights: u32,
}

fn move_box(i: u32) -> Aabb {
    return aabb_of(move_boxes[i]);
}

// The distance from `p` to the nearest of the `count` boxes from `first` (F32_MAX for none,
// where ppm_core folds from infinity: both clamp and compare alike).
fn nearest_box(p: vec3<f32>, first: u32, count: u32) -> f32 {
    var nearest = F32_MAX;
    for (var i = first; i < first + count; i++) {
        nearest = min(nearest, aabb_distance_from(move_box(i), p));
    }
    return nearest;
}

// ppm_core::local_move::LocalMove::nearest_after: from `p` to the nearest moved box in pose B.
fn nearest_after(boxes: MoveBoxes, p: vec3<f32>) -> f32 {
    return nearest_box(p, boxes.first + boxes.objects, boxes.objects);
}

// ppm_core::local_move::correction_r2: the floor's squared radius, widened to
// CORRECTION_SPREAD times the distance to the nearest moved box (both poses), at most
// `widest` floors.
fn correction_r2(position: vec3<f32>, boxes: MoveBoxes, r2_floor: f32, widest: f32) -> f32 {
    let floor = sqrt(r2_floor);
    let nearest = nearest_box(position, boxes.first, 2u * boxes.objects);
    let r = clamp(CORRECTION_SPREAD * nearest, floor, widest * floor);
    return r * r;
}

// ppm_core::local_move::direct_may_change: whether a ray from a point of `start` to a light
// may cross a moved box.
fn direct_may_change(start: Aabb, boxes: MoveBoxes) -> bool {
    let lights = boxes.first + 2u * boxes.objects;
    for (var l = lights; l < lights + boxes.lights; l++) {
        for (var m = boxes.first; m < lights; m++) {
            if segments_may_meet(start, move_box(l), move_box(m)) {
                return true;
            }
        }
    }
    return false;
}

// ppm_core::local_move::prepare_slot: the slot's correction disc, DIRECT_MAY_CHANGE where its
// direct light may change, the flags of the last move and of resting cleared; `bounds` is
// the box of its paths' vertices.
fn prepare_slot(hp: HitPoint, bounds: Aabb, m: LocalMoveParams, boxes: MoveBoxes) -> HitPoint {
    var out = hp;
    out.flags &= ~(HIT_UPDATED | HIT_RESTING | HIT_DIRECT_MAY_CHANGE);
    out.correction_r2 = correction_r2(hp.position, boxes, m.r2_floor, m.widest);
    if direct_may_change(bounds, boxes) {
        out.flags |= HIT_DIRECT_MAY_CHANGE;
    }
    return out;
}

// ppm_core::local_move::view_test: what the move may do to what slot `hp` sees (a VIEW_*),
// from the groups its paths met, whether they bounced, and `bounds`, the box of their
// vertices; `covered`: pose B's outline covers its pixel; `eye`, `nearest`: the camera and
// its distance to the nearest moved box in pose B.
fn view_test(hp: HitPoint, bounds: Aabb, covered: bool, eye: vec3<f32>, nearest: f32, groups: u32, boxes: MoveBoxes) -> u32 {
    if (hp.eye_met & groups) != 0u
        || (covered && (aabb_is_empty(bounds) || nearest < aabb_farthest_from(bounds, eye))) {
        return VIEW_CHANGES;
    }
    if (hp.flags & HIT_EYE_CHAINED) != 0u {
        let after = boxes.first + boxes.objects;
        for (var i = after; i < after + boxes.objects; i++) {
            if aabb_overlaps(move_box(i), bounds) {
                return VIEW_PROBE;
            }
        }
    }
    return VIEW_KEPT;
}

// ppm_core::local_move::reset_slot: no visible point, no statistics, `r2` its initial value,
// flagged UPDATED.
fn reset_slot(pixel: u32, r2_initial: f32) -> HitPoint {
    var hp: HitPoint;
    hp.pixel = pixel;
    hp.material = NO_MATERIAL;
    hp.r2 = r2_initial;
    hp.flags = HIT_UPDATED;
    return hp;
}

// ppm_core::local_move::DirectChange.
struct DirectChange {
    mean: vec3<f32>,
    variance: f32,
}

// The mean of `k` paired differences whose sum is `sum` (ppm_core::local_move::change_of).
fn change_mean(sum: vec3<f32>, k: u32) -> vec3<f32> {
    return sum / f32(k);
}

// ppm_core::local_move::change_of: the change of mean `mean` over `k` pairs whose
// luminances spread by `spread` (their squared deviations from the mean's, summed), known to
// the sample variance of the mean, at least lum(mean)^2 / k.
fn change_of(mean: vec3<f32>, spread: f32, k: u32) -> DirectChange {
    let n = f32(k);
    let sample_variance = spread / max(n * (n - 1.0), 1.0);
    let lum = luminance(mean);
    return DirectChange(mean, max(sample_variance, lum * lum / n));
}

// Rust's f32::round for x >= 0: halves away from zero (WGSL's round takes them to even).
fn round_half_up(x: f32) -> f32 {
    let whole = floor(x);
    return select(whole, whole + 1.0, x - whole >= 0.5);
}

// ppm_core::local_move::apply_direct_change: the slot's direct sum corrected by `change`,
// weighed against its history; a change of nothing keeps the sum bit for bit.
fn apply_direct_change(hp: HitPoint, change: DirectChange) -> HitPoint {
    var out = hp;
    if all(change.mean == vec3<f32>(0.0)) || hp.iterations == 0u {
        return out;
    }
    let n = f32(hp.iterations);
    let mean = max(hp.direct / n + change.mean, vec3<f32>(0.0));
    let kept = history_kept(n, mean, change.variance);
    let count = clamp(u32(round_half_up(n * kept)), 1u, hp.iterations);
    out.direct = mean * f32(count);
    out.iterations = count;
    return out;
}
