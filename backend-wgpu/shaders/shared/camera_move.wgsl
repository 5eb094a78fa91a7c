// A camera move's per-slot work (docs/algorithm.md 3d): the twin of ppm_core::camera_move,
// function for function. A slot of the new view, traced fresh, takes over the light of the
// four earlier slots around where its pixel's centre lands in the old image, where all are
// alike and what its visible point sends towards the eye does not depend on the view.
// Needs, in the importing pass: `scene_material` (materials.wgsl, or a test's own), the
// old view's slots and their boxes as `before_slots` (an array of HitPoint) and
// `before_bounds` (an array of GpuBounds, a box per slot), and the new view's fresh slots as
// `hit_points` (an array of HitPoint, whose visible points `on_an_edge` reads field by
// field: a pass that inherits writes only the fields `inherited_write` sets).

// ppm_core::camera_move's constants.
const NORMAL_COS: f32 = 0.95;
const GRAZING_COS: f32 = 0.1;
// ppm_core::compile::OBJECT_GROUPS.
const OBJECT_GROUPS: u32 = 32u;

// ppm_core::compile::object_group: the bit of object `index`'s group in `eye_met`.
fn object_group(index: u32) -> u32 {
    return 1u << (index % OBJECT_GROUPS);
}

// glam's Vec3::normalize_or_zero: `v` scaled by the reciprocal of its length, or zero where
// that is not a finite positive number.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let len = length(v);
    if is_finite_f32(len) && len > 0.0 {
        let rcp = 1.0 / len;
        if is_finite_f32(rcp) {
            return v * rcp;
        }
    }
    return vec3<f32>(0.0);
}

// ppm_core::camera_move::passes_light_on: a visible point of a diffuse, untextured surface
// that no eye path of the slot reached through a mirror, glass or a glossy surface.
fn passes_light_on(hp: HitPoint) -> bool {
    if !seen_directly(hp.flags) {
        return false;
    }
    let m = scene_material(hp.material);
    return m.kind == MATERIAL_DIFFUSE && m.texture == 0u;
}

// ppm_core::camera_move::seen_directly, from a slot's `flags`: a visible point found with no
// mirror, glass or glossy bounce before it.
fn seen_directly(flags: u32) -> bool {
    return (flags & HIT_VALID) != 0u && (flags & HIT_EYE_CHAINED) == 0u;
}

// ppm_core::camera_move::object: the object a slot's visible point lies on.
fn object(hp: HitPoint) -> u32 {
    return hp.flags >> HIT_OBJECT_SHIFT;
}

// ppm_core::camera_move::pixel_side: the side of `camera`'s pixels at `position`'s depth.
fn pixel_side(camera: GpuCamera, position: vec3<f32>) -> f32 {
    let depth = max(dot(position - camera.eye, camera.forward), 0.0);
    return depth * 2.0 * length(camera.up) / f32(max(camera.height, 1u));
}

// ppm_core::camera_move::footprint: the diagonal (x) and area (y) of the patch of surface a
// pixel of `camera` covers at `position` (normal `normal`).
fn footprint(camera: GpuCamera, position: vec3<f32>, normal: vec3<f32>) -> vec2<f32> {
    let to = position - camera.eye;
    let side = pixel_side(camera, position);
    let cos_seen = max(abs(dot(normal, normalize_or_zero(to))), GRAZING_COS);
    return vec2<f32>(side * sqrt(1.0 + 1.0 / (cos_seen * cos_seen)), side * side / cos_seen);
}

// Where a point lands in an image, in pixels from the top left; `seen` false behind the
// camera (ppm_core's `None`).
struct ImagePoint {
    at: vec2<f32>,
    seen: bool,
}

// ppm_core::camera_move::image_point.
fn image_point(camera: GpuCamera, position: vec3<f32>) -> ImagePoint {
    let to = position - camera.eye;
    let depth = dot(to, camera.forward);
    if depth <= 0.0 || !is_finite_f32(depth) {
        return ImagePoint(vec2<f32>(0.0), false);
    }
    let sx = dot(to, camera.right) / (depth * dot(camera.right, camera.right));
    let sy = dot(to, camera.up) / (depth * dot(camera.up, camera.up));
    let x = (sx + 1.0) * 0.5 * f32(camera.width);
    let y = (1.0 - sy) * 0.5 * f32(camera.height);
    return ImagePoint(vec2<f32>(x, y), true);
}

// ppm_core::camera_move::Inherited: the weighted sums over the earlier slots a slot inherits
// from (`has_bounds` false, `lo` and `hi` unread, for ppm_core's `bounds: None`).
struct Inherited {
    weight: f32,
    r2: f32,
    indirect: vec3<f32>,
    emitted: f32,
    n: f32,
    worth: f32,
    iterations: f32,
    direct: vec3<f32>,
    has_bounds: bool,
    lo: vec3<f32>,
    hi: vec3<f32>,
}

// ppm_core::camera_move::Inherited::add: adds `earlier`, weighing `w`, with its box `bounds`
// where `has_bounds`.
fn inherited_add(sums: ptr<function, Inherited>, w: f32, earlier: HitPoint, has_bounds: bool, bounds: GpuBounds) {
    (*sums).weight += w;
    (*sums).r2 += w * earlier.r2;
    if earlier.emitted > 0.0 && earlier.r2 > 0.0 {
        (*sums).indirect += w * earlier.tau / earlier.r2 / earlier.emitted;
    }
    (*sums).emitted += w * earlier.emitted;
    (*sums).n += w * earlier.n;
    (*sums).worth += w * max(earlier.n - earlier.discounted, 0.0);
    (*sums).iterations += w * f32(earlier.iterations);
    (*sums).direct += w * earlier.direct / f32(max(earlier.iterations, 1u));
    if has_bounds {
        if !(*sums).has_bounds {
            (*sums).lo = vec3<f32>(F32_MAX);
            (*sums).hi = vec3<f32>(-F32_MAX);
        }
        (*sums).has_bounds = true;
        (*sums).lo = min((*sums).lo, bounds.min);
        (*sums).hi = max((*sums).hi, bounds.max);
    }
}

// ppm_core::camera_move::Inherited::write: the weighted means into `hp`, keeping of their
// history the share the weights sum to; false (and `hp` untouched) where that is not one
// whole iteration of direct light.
fn inherited_write(sums: Inherited, hp: ptr<function, HitPoint>, bounds: ptr<function, GpuBounds>) -> bool {
    if sums.weight <= 0.0 {
        return false;
    }
    let keep = min(sums.weight, 1.0);
    let iterations = floor(keep * (sums.iterations / sums.weight));
    if !is_finite_f32(iterations) || iterations < 1.0 {
        return false;
    }
    let r2 = sums.r2 / sums.weight;
    let emitted = keep * (sums.emitted / sums.weight);
    let n = sums.n / sums.weight;
    (*hp).r2 = r2;
    (*hp).emitted = emitted;
    // Multiplied in this order, so that `tau / r2 / emitted` gives the mean back.
    (*hp).tau = sums.indirect / sums.weight * r2 * emitted;
    (*hp).n = n;
    (*hp).discounted = max(n - keep * (sums.worth / sums.weight), 0.0);
    (*hp).iterations = u32(iterations);
    (*hp).direct = sums.direct / sums.weight * iterations;
    (*hp).correction_r2 = 0.0;
    if sums.has_bounds {
        (*bounds) = GpuBounds(min(sums.lo, (*bounds).min), 0u, max(sums.hi, (*bounds).max), 0u);
    }
    return true;
}

// ppm_core::camera_move::pixel_centre_before: where the centre of `hp`'s pixel lands in the
// old image, in its pixels.
fn pixel_centre_before(hp: HitPoint, request: CameraMoveParams) -> ImagePoint {
    let before = image_point(request.before, hp.position);
    let after = image_point(request.after, hp.position);
    if !before.seen || !after.seen {
        return ImagePoint(vec2<f32>(0.0), false);
    }
    let width = max(request.after.width, 1u);
    let centre = vec2<f32>(f32(hp.pixel % width) + 0.5, f32(hp.pixel / width) + 0.5);
    let scale = pixel_side(request.after, hp.position)
        / max(pixel_side(request.before, hp.position), F32_MIN_POSITIVE);
    return ImagePoint(before.at + (centre - after.at) * scale, true);
}

// What `on_an_edge` reads of a slot of the new view: its visible point.
struct Seen {
    position: vec3<f32>,
    normal: vec3<f32>,
    material: u32,
    flags: u32,
}

// The visible point of `hit_points[i]`, read field by field.
fn seen(i: u32) -> Seen {
    return Seen(hit_points[i].position, hit_points[i].normal, hit_points[i].material, hit_points[i].flags);
}

// ppm_core::camera_move::on_an_edge: whether the pixel of slot `slot` of the new view lies
// on an edge of it, where a fresh visible point of another slot of it or of one of the
// eight pixels around is not seen directly, lies on another object or material, faces
// another way, or lies farther than twice the larger footprint diagonal; true at once for
// a slot that passes no light on.
fn on_an_edge(slot: u32, request: CameraMoveParams) -> bool {
    let count = arrayLength(&hit_points);
    if slot >= count {
        return true;
    }
    if !passes_light_on(hit_points[slot]) {
        return true;
    }
    let hp = seen(slot);
    let width = i32(request.after.width);
    let height = i32(request.after.height);
    let spp = i32(max(request.spp, 1u));
    let pixel = i32(hit_points[slot].pixel);
    let x = pixel % max(width, 1);
    let y = pixel / max(width, 1);
    let reach = 2.0 * footprint(request.after, hp.position, hp.normal).x;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let nx = x + dx;
            let ny = y + dy;
            if nx < 0 || nx >= width || ny < 0 || ny >= height {
                continue;
            }
            for (var s = 0; s < spp; s++) {
                let other = u32((ny * width + nx) * spp + s);
                if other == slot {
                    continue;
                }
                if other >= count {
                    return true;
                }
                // On `hp`'s material (so diffuse and untextured as well), near enough.
                let o = seen(other);
                let to = hp.position - o.position;
                let d2 = dot(to, to);
                let same_surface = seen_directly(o.flags)
                    && (o.flags >> HIT_OBJECT_SHIFT) == (hp.flags >> HIT_OBJECT_SHIFT)
                    && o.material == hp.material
                    && dot(o.normal, hp.normal) >= NORMAL_COS;
                if !same_surface {
                    return true;
                }
                if d2 >= reach * reach {
                    let o_reach = 2.0 * footprint(request.after, o.position, o.normal).x;
                    if d2 >= o_reach * o_reach {
                        return true;
                    }
                }
            }
        }
    }
    return false;
}

// ppm_core::camera_move::inherit_slot: `hp`, just traced from scratch, takes over the light
// of the earlier slots in `before_slots` near its visible point, and its box `bounds` grows
// by theirs. Returns whether it inherited; a slot that did not keeps its fresh start.
fn inherit_slot(hp: ptr<function, HitPoint>, bounds: ptr<function, GpuBounds>, request: CameraMoveParams) -> bool {
    let slot = *hp;
    if !passes_light_on(slot) {
        return false;
    }
    let position = slot.position;
    let normal = slot.normal;
    let centre = pixel_centre_before(slot, request);
    if !centre.seen {
        return false;
    }
    let x = centre.at.x;
    let y = centre.at.y;
    let width = f32(request.before.width);
    let height = f32(request.before.height);
    // The four earlier pixels whose centres surround the point, none outside the image.
    let left = floor(x - 0.5);
    let top = floor(y - 0.5);
    if !(left >= -1.0 && left < width && top >= -1.0 && top < height) {
        return false;
    }
    let area = footprint(request.after, position, normal).y;
    var sums: Inherited;
    let before_count = arrayLength(&before_slots);
    let bounds_count = arrayLength(&before_bounds);
    // (0, 0), (1, 0), (0, 1), (1, 1) from the top left one.
    for (var corner = 0u; corner < 4u; corner++) {
        let px = left + f32(corner & 1u);
        let py = top + f32(corner >> 1u);
        let share = (1.0 - abs(x - px - 0.5)) * (1.0 - abs(y - py - 0.5));
        if share <= 0.0 {
            continue;
        }
        if px < 0.0 || px >= width || py < 0.0 || py >= height {
            return false;
        }
        let pixel = u32(py * width + px);
        for (var s = 0u; s < request.spp; s++) {
            let index = pixel * request.spp + s;
            if index >= before_count {
                return false;
            }
            let earlier = before_slots[index];
            // Its history saw this object alone: a slot at an edge averaged two surfaces.
            let alike = object(earlier) == object(slot)
                && earlier.eye_met == object_group(object(earlier))
                && earlier.material == slot.material
                && earlier.iterations > 0u
                && passes_light_on(earlier)
                && dot(earlier.normal, normal) >= NORMAL_COS;
            if !alike {
                return false;
            }
            // The earlier slot saw this surface here: not another part of the object that
            // the earlier view found along the same ray.
            let earlier_footprint = footprint(request.before, earlier.position, earlier.normal);
            let diagonal = earlier_footprint.x;
            // Both points lie somewhere in footprints up to a pixel apart on each axis.
            let reach2 = max(earlier.r2, 4.0 * diagonal * diagonal);
            let to = position - earlier.position;
            let d2 = dot(to, to);
            if !is_finite_f32(d2) || d2 >= reach2 {
                return false;
            }
            let sizes = min(area, earlier_footprint.y) / max(max(area, earlier_footprint.y), F32_MIN_POSITIVE);
            let w = share * sizes / f32(request.spp);
            if w > 0.0 {
                let has_bounds = index < bounds_count;
                inherited_add(&sums, w, earlier, has_bounds, before_bounds[min(index, bounds_count - 1u)]);
            }
        }
    }
    return inherited_write(sums, hp, bounds);
}
