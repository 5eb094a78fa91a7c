// #import layout rng qmc sampling geometry bsdf bvh lights tables scene materials textures update reach screen_cover eye_path direct_light local_move
// A local move's passes (docs/algorithm.md 3b, 3c): the twin of backend-cpu's local_move.rs,
// over ppm_core::local_move's per-slot functions (their twins in the shared local_move.wgsl).
// No slot leaves the device; what the host reads back are the counters in `move_counters`.
//   pose A: `local_begin_main` per slot (prepare_slot; lists the slots whose direct light
//           may change and that hold a direct sum), `local_pairs_copy_main` per listed slot
//           (its pairs' light taken from the last move's pose B where that is this pose and
//           it evaluated them, the other pairs listed), then `local_pairs_before_main` per
//           listed pair (pose A's half);
//   pose B: `local_cover_main` per triangle (pose B's outline of the moved objects, a bit per
//           pixel), `local_resets_main` per slot (reset_if_seen, listing the slots only a
//           probe can tell about), `local_probes_main` per such slot (the probe), then
//           `local_pairs_after_main` per listed slot (pose B's half, the change, its
//           application).

@group(0) @binding(0) var<uniform> params: LocalMoveParams;
@group(0) @binding(1) var<uniform> camera: GpuCamera;
@group(0) @binding(2) var scene_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(3) var<uniform> scene: SceneIndex;
@group(0) @binding(4) var<storage, read> scene_texels: array<vec2<u32>>;
// The move's boxes: its objects' in pose A, in pose B, then the lights'
// (ppm_core::local_move::LocalMove::boxes).
@group(0) @binding(5) var<storage, read> move_boxes: array<GpuBounds>;
// The moved objects' indices (their triangles' `object`).
@group(0) @binding(6) var<storage, read> moved_objects: array<u32>;
@group(0) @binding(7) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(8) var<storage, read> slot_bounds: array<GpuBounds>;
// A bit per pixel, row-major, set where pose B's outline may cover it; the word after the
// last pixel's is set where a moved triangle reaches behind the eye (every pixel covered).
@group(0) @binding(9) var<storage, read_write> covered: array<atomic<u32>>;
// The slots listed in pose A, in no particular order (`list.count` of them after the
// count): their pairs' records have the same index.
@group(0) @binding(10) var<storage, read_write> listed: array<u32>;
// Per listed slot, 3 direct_samples words: each pair's direct light in pose A (RGB), or
// NO_CHANGE in its first word for a pair that cannot change.
@group(0) @binding(11) var<storage, read_write> pair_store: array<f32>;
// MOVE_* below.
@group(0) @binding(12) var<storage, read_write> move_counters: array<atomic<u32>, 8>;
@group(0) @binding(13) var<uniform> cover: CoverParams;
@group(0) @binding(14) var<uniform> list: ListParams;
// The slots whose view only a probe can tell about, listed by the resets (`MOVE_PROBED` of
// them).
@group(0) @binding(15) var<storage, read_write> probes: array<u32>;
// Per slot: one more than the index of its record in `known_store` where the last move
// corrected it, zero where it did not.
@group(0) @binding(16) var<storage, read_write> known: array<u32>;
// The last move's records in its pose B, as `pair_store` holds this move's in pose A (pose B
// writes this move's here, once pose A has read them).
@group(0) @binding(17) var<storage, read_write> known_store: array<f32>;
// Pose A's pairs to trace, `i * direct_samples + j` for pair `j` of listed slot `i`
// (`MOVE_PAIRS` of them): those the last move did not evaluate in this pose.
@group(0) @binding(18) var<storage, read_write> pair_list: array<u32>;

// A pair's first word in `pair_store` where it cannot change: its eye path goes straight to
// its visible point (or out of the scene) past every moved box, and no ray from there to a
// light may cross one (ppm_core::local_move::Pair::difference). Light is never negative.
const NO_CHANGE: f32 = -1.0;

// Slots of `move_counters` (backend-wgpu's local_move.rs).
const MOVE_RESET: u32 = 0u;
const MOVE_CORRECTED: u32 = 1u;
const MOVE_PROBED: u32 = 2u;
const MOVE_LISTED: u32 = 3u;
const MOVE_RAYS: u32 = 4u;
const MOVE_PAIRS: u32 = 5u;

// Rays this invocation traced, added to MOVE_RAYS once at its end (count_rays).
var<private> rays: u32;

fn count_rays() {
    if rays > 0u {
        atomicAdd(&move_counters[MOVE_RAYS], rays);
    }
}

fn boxes() -> MoveBoxes {
    return MoveBoxes(0u, params.objects, params.lights);
}

// ppm_core::local_move::probe_meets: whether one of PROBE_PATHS eye paths through stratified
// points of `pixel`, traced in this pose (pose B), meets one of the moved objects' groups at
// a surface up to its visible point. Counts its rays.
fn probe_meets(pixel: u32) -> bool {
    let seed = params.seed ^ PROBE_SEED;
    let settings = EyePathSettings(params.max_depth, params.ray_epsilon, false);
    var meets = false;
    for (var path = 0u; path < PROBE_PATHS; path++) {
        let key = StreamKey(seed, PASS_EYE, path, pixel);
        let jitter = stratified_pair(seed, PASS_EYE, pixel, 0u, path);
        let traced = trace_eye_path(pixel, jitter, key, settings, params.groups);
        rays += traced.rays;
        if traced.watched {
            meets = true;
            break;
        }
    }
    return meets;
}

// ppm_core::local_move::Pair: sample `k` of slot `slot` (pixel `pixel`) in this pose: its
// eye path (Pair::trace).
fn pair_path(slot: u32, pixel: u32, k: u32) -> EyePath {
    let seed = params.seed ^ CHANGE_SEED;
    let key = StreamKey(seed, PASS_EYE, k, slot);
    let jitter = stratified_pair(seed, PASS_EYE, slot, 0u, k);
    // The pairs' eye paths take the light samples the eye pass takes at glossy bounces.
    let settings = EyePathSettings(params.max_depth, params.ray_epsilon, true);
    let path = trace_eye_path(pixel, jitter, key, settings, 0u);
    rays += path.rays;
    return path;
}

// Whether pair `k` of slot `slot` (pixel `pixel`), whose eye path in pose A is `path`, may
// bring another light in pose B (ppm_core::local_move::Pair::difference): its path may be
// another one there (it bounced, or its one segment meets a moved box in either pose), or a
// ray from its visible point to a light may cross a moved box. Where it cannot, its path is
// the same in both poses, and so is its light, bit for bit.
fn pair_may_change(path: EyePath, slot: u32, pixel: u32, k: u32) -> bool {
    if path.chained {
        return true;
    }
    let jitter = stratified_pair(params.seed ^ CHANGE_SEED, PASS_EYE, slot, 0u, k);
    let px = f32(pixel % camera.width) + jitter.x;
    let py = f32(pixel / camera.width) + jitter.y;
    let dir = camera_ray(camera, px, py);
    let moved = boxes();
    for (var m = 0u; m < 2u * moved.objects; m++) {
        let b = move_boxes[m];
        if segment_meets_box(camera.eye, dir, path.first_t, b.min, b.max) {
            return true;
        }
    }
    if !path.visible {
        return false;
    }
    // The box of the visible point and of its rays' origin, offset along the normal.
    let offset = path.position + path.normal * params.ray_epsilon;
    return direct_may_change(Aabb(min(path.position, offset), max(path.position, offset)), moved);
}

// The direct light that pair `k`'s eye path `path` brings to the eye in this pose
// (ppm_core::local_move::Pair::direct). Counts its rays.
fn pair_light(path: EyePath, slot: u32, pixel: u32, k: u32) -> vec3<f32> {
    var visible: HitPoint;
    visible.pixel = pixel;
    visible.material = NO_MATERIAL;
    if path.visible {
        visible.position = path.position;
        visible.normal = path.normal;
        visible.material = path.material;
        visible.throughput = path.throughput;
        visible.flags = eye_path_flags(path);
    }
    let seed = params.seed ^ CHANGE_SEED;
    let light = DirectLightParams(seed, 1u, k, params.ray_epsilon, DIRECT_REPLACE, 0u, 0u, 0u);
    let direct = slot_direct(light, visible, path.chain, slot);
    rays += direct.rays;
    return direct.radiance;
}

// Pose A, per slot: prepare_slot, and the slot listed where its direct light may change
// and it holds a direct sum (what local_direct_change corrects, unless the resets start it
// over).
@compute @workgroup_size(64)
fn local_begin_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = prepare_slot(hit_points[slot], aabb_of(slot_bounds[slot]), params, boxes());
    // Only the fields prepare_slot changes are written back.
    hit_points[slot].flags = hp.flags;
    hit_points[slot].correction_r2 = hp.correction_r2;
    // A slot whose eye paths met a moved object starts over in pose B whatever else the
    // view test finds: its pairs would be traced for nothing.
    let kept = (hp.eye_met & params.groups) == 0u;
    if (hp.flags & HIT_DIRECT_MAY_CHANGE) != 0u && hp.iterations > 0u && kept {
        listed[atomicAdd(&move_counters[MOVE_LISTED], 1u)] = slot;
    }
}

// The first of listed slot `i`'s words in `pair_store` (and of the last move's listed slot
// `i` in `known_store`).
fn pair_record(i: u32) -> u32 {
    return i * 3u * params.direct_samples;
}

fn store_light(at: u32) -> vec3<f32> {
    return vec3<f32>(pair_store[at], pair_store[at + 1u], pair_store[at + 2u]);
}

fn known_light(at: u32) -> vec3<f32> {
    return vec3<f32>(known_store[at], known_store[at + 1u], known_store[at + 2u]);
}

// Appends pair `j` of listed slot `i` to `pair_list`, for a kernel that traces those pairs
// only (see local_pairs_copy_main).
fn list_pair(i: u32, j: u32) {
    pair_list[atomicAdd(&move_counters[MOVE_PAIRS], 1u)] = i * params.direct_samples + j;
}

// The listed slot and pair of the `p`-th entry of `pair_list`.
fn listed_pair(p: u32) -> vec2<u32> {
    let e = pair_list[p];
    return vec2<u32>(e / params.direct_samples, e % params.direct_samples);
}

// Pose A, per listed slot: the pairs the last move evaluated in its pose B, this pose, with the
// same keys are the same pairs here (ppm_core::local_move::Pair: every move draws a slot's
// pairs from the same numbers): their light is copied. The others are listed for
// local_pairs_before_main. A copied pair counts as one that may change, which costs nothing
// where it cannot: there its path and light are the same in both poses, bit for bit, so its
// difference is exactly zero. Along a drag the boxes barely move from step to step, so the
// pairs that changed last step are those that may change in this one.
@compute @workgroup_size(64)
fn local_pairs_copy_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= list.count {
        return;
    }
    var was = 0u;
    if list.known != 0u {
        was = known[listed[i]];
    }
    let record = pair_record(i);
    for (var j = 0u; j < params.direct_samples; j++) {
        var copied = false;
        if was != 0u {
            let kept = pair_record(was - 1u) + 3u * j;
            copied = known_store[kept] != NO_CHANGE;
            if copied {
                let at = record + 3u * j;
                pair_store[at] = known_store[kept];
                pair_store[at + 1u] = known_store[kept + 1u];
                pair_store[at + 2u] = known_store[kept + 2u];
            }
        }
        if !copied {
            list_pair(i, j);
        }
    }
}

// Pose A, per pair local_pairs_copy_main listed (`list.count` of them): its path, and its
// light where it may change in pose B (NO_CHANGE where it cannot).
@compute @workgroup_size(64)
fn local_pairs_before_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let p = item_index(gid, groups);
    if p >= list.count {
        return;
    }
    let pair = listed_pair(p);
    let slot = listed[pair.x];
    let pixel = hit_points[slot].pixel;
    var light = vec3<f32>(NO_CHANGE, 0.0, 0.0);
    let path = pair_path(slot, pixel, pair.y);
    if pair_may_change(path, slot, pixel, pair.y) {
        light = pair_light(path, slot, pixel, pair.y);
    }
    let at = pair_record(pair.x) + 3u * pair.y;
    pair_store[at] = light.x;
    pair_store[at + 1u] = light.y;
    pair_store[at + 2u] = light.z;
    count_rays();
}

// Marks pixels first.x..=last.x of row `y` that triangle `t` may cover, a word at a time.
fn cover_row(t: CoverTriangle, y: u32) {
    var word = 0xffffffffu;
    var bits = 0u;
    for (var x = t.first.x; x <= t.last.x; x++) {
        if !cover_pixel(t, x, y) {
            continue;
        }
        let pixel = y * cover.width + x;
        if pixel / 32u != word {
            if bits != 0u {
                atomicOr(&covered[word], bits);
            }
            word = pixel / 32u;
            bits = 0u;
        }
        bits |= 1u << (pixel % 32u);
    }
    if bits != 0u {
        atomicOr(&covered[word], bits);
    }
}

// Pose B, per triangle of the scene: where it belongs to a moved object, the pixels it may
// cover (ppm_core::local_move::moved_cover).
@compute @workgroup_size(64)
fn local_cover_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= cover.triangles {
        return;
    }
    let tri = scene_triangle(i);
    var moved = false;
    for (var o = 0u; o < cover.objects; o++) {
        moved = moved || moved_objects[o] == tri.object;
    }
    if !moved {
        return;
    }
    let t = cover_triangle(cover, tri.v0, tri.v0 + tri.e1, tri.v0 + tri.e2);
    if t.everything {
        atomicOr(&covered[(cover.width * cover.height + 31u) / 32u], 1u);
        return;
    }
    if t.nothing {
        return;
    }
    for (var y = t.first.y; y <= t.last.y; y++) {
        cover_row(t, y);
    }
}

// Whether pose B's outline may cover `pixel`.
fn pixel_covered(pixel: u32) -> bool {
    let everything = atomicLoad(&covered[(camera.width * camera.height + 31u) / 32u]) != 0u;
    return everything || (atomicLoad(&covered[pixel / 32u]) & (1u << (pixel % 32u))) != 0u;
}

// Starts slot `slot` (pixel `pixel`) over where the move changes what it sees; else counts
// it corrected where its direct light may change.
fn reset_or_keep(slot: u32, pixel: u32, flags: u32, changes: bool) {
    if changes {
        hit_points[slot] = reset_slot(pixel, params.r2_initial);
        atomicAdd(&move_counters[MOVE_RESET], 1u);
    } else if (flags & HIT_DIRECT_MAY_CHANGE) != 0u {
        atomicAdd(&move_counters[MOVE_CORRECTED], 1u);
    }
}

// Pose B, per slot: ppm_core::local_move::reset_if_seen where the view test decides; the
// slots only a probe can tell about are listed for local_probes_main (the probe's paths in a
// kernel of their own, which the slots without one neither wait for nor carry).
@compute @workgroup_size(64)
fn local_resets_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = item_index(gid, groups);
    if slot >= arrayLength(&hit_points) {
        return;
    }
    let hp = hit_points[slot];
    let bounds = aabb_of(slot_bounds[slot]);
    let nearest = nearest_after(boxes(), camera.eye);
    let view = view_test(hp, bounds, pixel_covered(hp.pixel), camera.eye, nearest, params.groups, boxes());
    if view == VIEW_PROBE {
        probes[atomicAdd(&move_counters[MOVE_PROBED], 1u)] = slot;
        return;
    }
    reset_or_keep(slot, hp.pixel, hp.flags, view == VIEW_CHANGES);
}

// Pose B, per slot the resets listed: the probe of its pixel decides (reset_if_seen).
@compute @workgroup_size(64)
fn local_probes_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= list.count {
        return;
    }
    let slot = probes[i];
    let hp = hit_points[slot];
    reset_or_keep(slot, hp.pixel, hp.flags, probe_meets(hp.pixel));
    count_rays();
}

// Pose B, per listed slot still kept with a direct sum: pose B's half of the pairs that may
// change (the others change by nothing), the change (ppm_core::local_move::change_of: the
// mean of the pairs' differences, the spread of their luminances) and its application
// weighed against the history (apply_direct_change). Pose B's lights go to `known_store`, for
// the next move, whose pose A this is.
@compute @workgroup_size(64)
fn local_pairs_after_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= list.count {
        return;
    }
    let slot = listed[i];
    let hp = hit_points[slot];
    if (hp.flags & HIT_DIRECT_MAY_CHANGE) == 0u || hp.iterations == 0u {
        // Started over by the resets.
        return;
    }
    atomicAdd(&move_counters[MOVE_CORRECTED], 1u);
    let record = pair_record(i);
    let k = params.direct_samples;
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < k; j++) {
        let at = record + 3u * j;
        var light = vec3<f32>(NO_CHANGE, 0.0, 0.0);
        if pair_store[at] != NO_CHANGE {
            light = pair_light(pair_path(slot, hp.pixel, j), slot, hp.pixel, j);
            sum += light - store_light(at);
        }
        known_store[at] = light.x;
        known_store[at + 1u] = light.y;
        known_store[at + 2u] = light.z;
    }
    known[slot] = i + 1u;
    let mean = change_mean(sum, k);
    let lum = luminance(mean);
    var spread = 0.0;
    for (var j = 0u; j < k; j++) {
        let at = record + 3u * j;
        var change = 0.0;
        if pair_store[at] != NO_CHANGE {
            change = luminance(known_light(at) - store_light(at));
        }
        let deviation = change - lum;
        spread += deviation * deviation;
    }
    let corrected = apply_direct_change(hp, change_of(mean, spread, k));
    hit_points[slot].direct = corrected.direct;
    hit_points[slot].iterations = corrected.iterations;
    count_rays();
}
