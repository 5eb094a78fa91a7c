//! A camera move's per-slot work (docs/algorithm.md 3d), one home for every backend's
//! [`inherit_light`](crate::passes::LocalMoves::inherit_light) pass: which earlier slots a
//! slot of the new view takes its light over from, and what it keeps of theirs.
//!
//! A camera move changes none of the light in the scene, only which points the pixels see.
//! So a slot of the new view whose visible point lies where earlier slots gathered, on the
//! same object and facing the same way, may take over their statistics, wherever what the
//! point sends towards the eye does not depend on the direction it is seen from: a diffuse,
//! untextured surface seen directly ([`passes_light_on`]). Everything else starts over.
//!
//! The earlier slots a new one inherits from are found through the image of the camera
//! before: the new visible point lands at a point of it, and the four earlier pixels whose
//! centres surround that point share it as bilinear interpolation would (a point a quarter
//! of a pixel from one centre takes mostly that pixel's). The slot inherits only where every
//! one of them is alike: the same object and material, normals within [`NORMAL_COS`], light
//! passed on, a history that saw that object alone, and a visible point within its gather
//! radius of the new one, or within twice the diagonal of its pixel's footprint where that
//! is larger (its visible points wandered over that footprint as its jitter drew them, and
//! the new one over its own, up to a pixel away on each axis). A pixel
//! near an edge, in the old view or the new ([`on_an_edge`]: an edge the move brought
//! crosses pixels whose earlier slots all saw one surface), starts over: its one fresh eye
//! path fell on one side of the edge, and inheriting that side's light would weigh one
//! sample as a history.
//! Each counts with its share times `a`, the ratio of the smaller footprint's area to the
//! larger's (after a dolly a pixel covers more or less of the surface than those it
//! inherits from). The slot takes the weighted mean of their estimates and keeps of their
//! history the share the weights sum to: all of it for a camera that did not move, less
//! after a dolly. What it keeps weighs less with every iteration of its own, so the render
//! still converges to the truth of the new view ([`inherit_slot`]).

use crate::compile::object_group;
use crate::layout::{
    CameraMoveParams, GpuCamera, GpuMaterial, HitPoint, SlotBounds, hit_flags, material_kind,
};
use glam::Vec3;

/// The least cosine between the normals of a slot and of an earlier slot it inherits from:
/// about 18 degrees, so that the light of a corner or of another side of a curved surface
/// is never taken for this one's.
pub const NORMAL_COS: f32 = 0.95;

/// The least cosine of the angle a footprint is seen at, so that a grazing view does not
/// stretch it without bound.
pub const GRAZING_COS: f32 = 0.1;

/// A camera move as its passes see it: the cameras before and after.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraMove {
    /// The camera the slots were traced from so far.
    pub before: GpuCamera,
    /// The camera from now on.
    pub after: GpuCamera,
    /// Eye samples per pixel.
    pub spp: u32,
}

impl CameraMove {
    /// The move as a GPU backend uploads it.
    pub fn params(&self) -> CameraMoveParams {
        CameraMoveParams {
            before: self.before,
            after: self.after,
            spp: self.spp,
            ..CameraMoveParams::default()
        }
    }
}

/// What the slots of a camera move did, for the driver to report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CameraMoveStats {
    /// Slots that took over earlier slots' light.
    pub inherited: u64,
    /// Slots that started over.
    pub reset: u64,
}

/// Whether what `hp`'s visible point sends towards the eye is the same from every direction
/// it may be seen from, so that another view may keep it: a visible point of a diffuse,
/// untextured surface that no eye path of the slot reached through a mirror, glass or a
/// glossy surface (whose light depends on where the eye is). A coated surface's light
/// passes its coat at the angle it is seen at, and a texture changes within the footprint
/// a slot averages over: both start over.
pub fn passes_light_on(hp: &HitPoint, materials: &[GpuMaterial]) -> bool {
    seen_directly(hp)
        && materials
            .get(hp.material as usize)
            .is_some_and(|m| m.kind == material_kind::DIFFUSE && m.texture == 0)
}

/// Whether `hp`'s eye paths found a visible point with no mirror, glass or glossy bounce
/// before it.
fn seen_directly(hp: &HitPoint) -> bool {
    hp.flags & hit_flags::VALID != 0 && hp.flags & hit_flags::EYE_CHAINED == 0
}

/// The object a slot's visible point lies on.
fn object(hp: &HitPoint) -> u32 {
    hp.flags >> hit_flags::OBJECT_SHIFT
}

/// The side of `camera`'s pixels at `position`'s depth, facing the camera.
fn pixel_side(camera: &GpuCamera, position: Vec3) -> f32 {
    let depth = (position - Vec3::from(camera.eye))
        .dot(Vec3::from(camera.forward))
        .max(0.0);
    depth * 2.0 * Vec3::from(camera.up).length() / camera.height.max(1) as f32
}

/// A pixel's footprint at `position` (normal `normal`) seen from `camera`: the diagonal of
/// the patch of surface it covers, and that patch's area.
pub fn footprint(camera: &GpuCamera, position: Vec3, normal: Vec3) -> (f32, f32) {
    let to = position - Vec3::from(camera.eye);
    let side = pixel_side(camera, position);
    let cos = (normal.dot(to.normalize_or_zero()).abs()).max(GRAZING_COS);
    (side * (1.0 + 1.0 / (cos * cos)).sqrt(), side * side / cos)
}

/// Where `position` lands in `camera`'s image, in pixels from the top left; `None` behind
/// the camera.
pub fn image_point(camera: &GpuCamera, position: Vec3) -> Option<(f32, f32)> {
    let to = position - Vec3::from(camera.eye);
    let depth = to.dot(Vec3::from(camera.forward));
    if depth <= 0.0 || !depth.is_finite() {
        return None;
    }
    let (right, up) = (Vec3::from(camera.right), Vec3::from(camera.up));
    let sx = to.dot(right) / (depth * right.length_squared());
    let sy = to.dot(up) / (depth * up.length_squared());
    Some((
        (sx + 1.0) * 0.5 * camera.width as f32,
        (1.0 - sy) * 0.5 * camera.height as f32,
    ))
}

/// The weighted sums over the earlier slots a slot inherits from.
#[derive(Default)]
struct Inherited {
    weight: f32,
    r2: f32,
    /// `tau / r2 / emitted`, per channel: the indirect estimate without its `pi`.
    indirect: Vec3,
    emitted: f32,
    n: f32,
    worth: f32,
    iterations: f32,
    direct: Vec3,
    bounds: Option<(Vec3, Vec3)>,
}

impl Inherited {
    fn add(&mut self, w: f32, from: &HitPoint, bounds: Option<&SlotBounds>) {
        self.weight += w;
        self.r2 += w * from.r2;
        if from.emitted > 0.0 && from.r2 > 0.0 {
            self.indirect += w * Vec3::from(from.tau) / from.r2 / from.emitted;
        }
        self.emitted += w * from.emitted;
        self.n += w * from.n;
        self.worth += w * (from.n - from.discounted).max(0.0);
        self.iterations += w * from.iterations as f32;
        self.direct += w * Vec3::from(from.direct) / from.iterations.max(1) as f32;
        if let Some(b) = bounds {
            let (lo, hi) = self.bounds.unwrap_or((Vec3::MAX, Vec3::MIN));
            self.bounds = Some((lo.min(b.min.into()), hi.max(b.max.into())));
        }
    }

    /// Writes the weighted means into `hp`, keeping of their history the share the weights
    /// sum to; `false` (and `hp` untouched) where that is not one whole iteration of direct
    /// light.
    fn write(self, hp: &mut HitPoint, bounds: Option<&mut SlotBounds>) -> bool {
        if self.weight <= 0.0 {
            return false;
        }
        let keep = self.weight.min(1.0);
        let mean = |x: f32| x / self.weight;
        let iterations = (keep * mean(self.iterations)).floor();
        if iterations < 1.0 || !iterations.is_finite() {
            return false;
        }
        let (r2, emitted, n) = (mean(self.r2), keep * mean(self.emitted), mean(self.n));
        hp.r2 = r2;
        hp.emitted = emitted;
        // Multiplied in this order, so that `tau / r2 / emitted` gives the mean back.
        hp.tau = (self.indirect / self.weight * r2 * emitted).into();
        hp.n = n;
        hp.discounted = (n - keep * mean(self.worth)).max(0.0);
        hp.iterations = iterations as u32;
        hp.direct = (self.direct / self.weight * iterations).into();
        hp.correction_r2 = 0.0;
        if let (Some(slot), Some((lo, hi))) = (bounds, self.bounds) {
            *slot = SlotBounds::new(lo.min(slot.min.into()), hi.max(slot.max.into()));
        }
        true
    }
}

/// Where the centre of `hp`'s pixel lands in the image of the camera before, in its pixels:
/// where its visible point lands, shifted by the point's offset from the centre in the new
/// image, scaled from new pixels to old ones. A slot that inherits looks there, so that a
/// camera that did not move gives each slot its own earlier statistics, whatever point of
/// the pixel its fresh eye path went through.
fn pixel_centre_before(hp: &HitPoint, request: &CameraMove) -> Option<(f32, f32)> {
    let position = Vec3::from(hp.position);
    let (x, y) = image_point(&request.before, position)?;
    let (xa, ya) = image_point(&request.after, position)?;
    let width = request.after.width.max(1);
    let centre = (
        (hp.pixel % width) as f32 + 0.5,
        (hp.pixel / width) as f32 + 0.5,
    );
    let scale = pixel_side(&request.after, position)
        / pixel_side(&request.before, position).max(f32::MIN_POSITIVE);
    Some((x + (centre.0 - xa) * scale, y + (centre.1 - ya) * scale))
}

/// Whether `hp`, right after a camera move's passes (its fresh eye path, the inheritance and
/// the move's direct-light sample), started over: a slot that inherited holds at least one
/// earlier iteration besides that sample ([`inherit_slot`] keeps none where it would be 0).
pub fn started_over(hp: &HitPoint) -> bool {
    hp.iterations <= 1
}

/// Whether the pixel of slot `slot` of the new view `after` (its slots just traced fresh)
/// lies on an edge of that view: the fresh visible point of another slot of it or of one of
/// the eight pixels around it is not seen directly (the void, a mirror, glass), lies on
/// another object or material, faces another way ([`NORMAL_COS`]), or lies farther than
/// twice the larger of the two footprint diagonals from its own (an edge of the same object
/// in front of itself). Such a pixel averages two surfaces, and an edge the move brought
/// (one object now in front of another) is no edge of the old view: its one fresh eye path
/// fell on one side, and inheriting that side's light would keep the other side out of the
/// pixel for as long as the history weighs. It starts over. A slot that passes no light on
/// ([`passes_light_on`]) starts over anyway, and counts as on an edge without a look around.
pub fn on_an_edge(
    after: &[HitPoint],
    slot: usize,
    request: &CameraMove,
    materials: &[GpuMaterial],
) -> bool {
    let Some(hp) = after.get(slot).filter(|hp| passes_light_on(hp, materials)) else {
        return true;
    };
    let (width, height) = (request.after.width as i64, request.after.height as i64);
    let spp = request.spp.max(1) as i64;
    let (x, y) = (
        hp.pixel as i64 % width.max(1),
        hp.pixel as i64 / width.max(1),
    );
    let (position, normal) = (Vec3::from(hp.position), Vec3::from(hp.normal));
    let reach = 2.0 * footprint(&request.after, position, normal).0;
    // `o` on `hp`'s material (so diffuse and untextured as well), near enough.
    let alike = |o: &HitPoint| {
        let (o_position, o_normal) = (Vec3::from(o.position), Vec3::from(o.normal));
        let d2 = position.distance_squared(o_position);
        seen_directly(o)
            && object(o) == object(hp)
            && o.material == hp.material
            && o_normal.dot(normal) >= NORMAL_COS
            && (d2 < reach * reach || {
                let o_reach = 2.0 * footprint(&request.after, o_position, o_normal).0;
                d2 < o_reach * o_reach
            })
    };
    for (nx, ny) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy))) {
        if nx < 0 || nx >= width || ny < 0 || ny >= height {
            continue;
        }
        for s in 0..spp {
            let other = ((ny * width + nx) * spp + s) as usize;
            if other != slot && !after.get(other).is_some_and(alike) {
                return true;
            }
        }
    }
    false
}

/// A slot of the new view, just traced from scratch (no statistics yet), takes over the
/// light of the earlier slots `before` (with their bounds `before_bounds`, empty where the
/// backend keeps none) near its visible point, as the module says. Its box grows by theirs
/// (their paths met its object alone, as its own did), so that a later object move finds
/// every path its light came from. Returns whether it inherited; a slot that did
/// not keeps its fresh start.
pub fn inherit_slot(
    hp: &mut HitPoint,
    bounds: Option<&mut SlotBounds>,
    request: &CameraMove,
    materials: &[GpuMaterial],
    (before, before_bounds): (&[HitPoint], &[SlotBounds]),
) -> bool {
    if !passes_light_on(hp, materials) {
        return false;
    }
    let (position, normal) = (Vec3::from(hp.position), Vec3::from(hp.normal));
    let Some((x, y)) = pixel_centre_before(hp, request) else {
        return false;
    };
    let (width, height) = (request.before.width as f32, request.before.height as f32);
    // The four earlier pixels whose centres surround the point, none outside the image.
    let (left, top) = ((x - 0.5).floor(), (y - 0.5).floor());
    if !(left >= -1.0 && left < width && top >= -1.0 && top < height) {
        return false;
    }
    let (_, area) = footprint(&request.after, position, normal);
    let mut sums = Inherited::default();
    for (px, py) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let (px, py) = (left + px, top + py);
        let share = (1.0 - (x - px - 0.5).abs()) * (1.0 - (y - py - 0.5).abs());
        if share <= 0.0 {
            continue;
        }
        if px < 0.0 || px >= width || py < 0.0 || py >= height {
            return false;
        }
        let pixel = (py * width + px) as usize;
        for s in 0..request.spp as usize {
            let slot = pixel * request.spp as usize + s;
            let Some(from) = before.get(slot) else {
                return false;
            };
            // Its history saw this object alone: a slot at an edge averaged two surfaces.
            let alike = object(from) == object(hp)
                && from.eye_met == object_group(object(from) as usize)
                && from.material == hp.material
                && from.iterations > 0
                && passes_light_on(from, materials)
                && Vec3::from(from.normal).dot(normal) >= NORMAL_COS;
            if !alike {
                return false;
            }
            // The earlier slot saw this surface here: not another part of the object that
            // the earlier view found along the same ray.
            let from_position = Vec3::from(from.position);
            let (diagonal, from_area) =
                footprint(&request.before, from_position, Vec3::from(from.normal));
            // Both points lie somewhere in footprints up to a pixel apart on each axis.
            let reach2 = from.r2.max(4.0 * diagonal * diagonal);
            let d2 = position.distance_squared(from_position);
            if d2 >= reach2 || d2.is_nan() {
                return false;
            }
            let sizes = area.min(from_area) / area.max(from_area).max(f32::MIN_POSITIVE);
            let w = share * sizes / request.spp as f32;
            if w > 0.0 {
                sums.add(w, from, before_bounds.get(slot));
            }
        }
    }
    sums.write(hp, bounds)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::gpu_camera;
    use crate::scene::Camera;

    fn camera(eye: Vec3) -> GpuCamera {
        let c = Camera {
            eye,
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_deg: 40.0,
            width: 64,
            height: 64,
        };
        gpu_camera(&c, 64, 64)
    }

    fn white() -> Vec<GpuMaterial> {
        vec![GpuMaterial {
            albedo: [0.5; 3],
            kind: material_kind::DIFFUSE,
            ..GpuMaterial::default()
        }]
    }

    /// A slot of `camera`'s pixel that sees the plane z = 0 at the pixel's centre, with
    /// statistics worth `iterations` iterations.
    fn converged(camera: &GpuCamera, pixel: u32, iterations: u32) -> HitPoint {
        let (eye, dir) = crate::eye_path::camera_segment(camera, pixel, (0.5, 0.5));
        let t = -eye.z / dir.z;
        HitPoint {
            position: (eye + dir * t).into(),
            normal: [0.0, 0.0, 1.0],
            material: 0,
            throughput: [1.0; 3],
            r2: 1e-4,
            tau: [3e-3, 2e-3, 1e-3],
            n: 400.0,
            direct: [0.5 * iterations as f32, 0.25 * iterations as f32, 0.0],
            emitted: 1e6,
            iterations,
            flags: hit_flags::VALID | hit_flags::FRONT | (7 << hit_flags::OBJECT_SHIFT),
            eye_met: 1 << 7,
            ..HitPoint::empty(pixel)
        }
    }

    fn image(camera: &GpuCamera, iterations: u32) -> Vec<HitPoint> {
        (0..camera.width * camera.height)
            .map(|p| converged(camera, p, iterations))
            .collect()
    }

    /// A fresh slot of the new view at `pixel`.
    fn fresh(camera: &GpuCamera, pixel: u32) -> HitPoint {
        let mut hp = converged(camera, pixel, 0);
        (hp.tau, hp.n, hp.direct, hp.emitted, hp.r2, hp.eye_met) =
            ([0.0; 3], 0.0, [0.0; 3], 0.0, 4e-4, 1 << 7);
        hp
    }

    fn pixel_value(hp: &HitPoint) -> Vec3 {
        let indirect = Vec3::from(hp.tau) / hp.emitted / (std::f32::consts::PI * hp.r2);
        Vec3::from(hp.direct) / hp.iterations as f32 + indirect
    }

    #[test]
    fn an_unmoved_camera_keeps_each_slots_estimate_and_history() {
        let cam = camera(Vec3::new(0.0, 0.0, 5.0));
        let before = image(&cam, 200);
        let request = CameraMove {
            before: cam,
            after: cam,
            spp: 1,
        };
        let pixel = 32 * 64 + 20;
        let mut hp = fresh(&cam, pixel);
        assert!(inherit_slot(
            &mut hp,
            None,
            &request,
            &white(),
            (&before, &[])
        ));
        let want = pixel_value(&before[pixel as usize]);
        approx::assert_relative_eq!(
            pixel_value(&hp).to_array()[..],
            want.to_array()[..],
            max_relative = 1e-5
        );
        assert_eq!(hp.iterations, 200);
        approx::assert_relative_eq!(hp.emitted, 1e6, max_relative = 1e-6);
        approx::assert_relative_eq!(hp.n, 400.0);
        assert!(hp.discounted < 1e-3, "{}", hp.discounted);
    }

    #[test]
    fn a_dolly_keeps_less_the_more_the_footprint_changes() {
        let near = camera(Vec3::new(0.0, 0.0, 5.0));
        let before = image(&near, 200);
        let kept = |distance: f32| {
            let after = camera(Vec3::new(0.0, 0.0, distance));
            let request = CameraMove {
                before: near,
                after,
                spp: 1,
            };
            let mut hp = fresh(&after, 32 * 64 + 32);
            inherit_slot(&mut hp, None, &request, &white(), (&before, &[]));
            hp.iterations
        };
        let (same, farther, much_farther) = (kept(5.0), kept(5.5), kept(10.0));
        assert!(
            same > farther && farther > much_farther,
            "{same} {farther} {much_farther}"
        );
        // Twice as far, footprints four times the area keep a quarter at most.
        assert!(much_farther <= 200 / 4, "{much_farther}");
    }

    #[test]
    fn what_depends_on_the_view_starts_over() {
        let cam = camera(Vec3::new(0.0, 0.0, 5.0));
        let before = image(&cam, 200);
        let request = CameraMove {
            before: cam,
            after: cam,
            spp: 1,
        };
        let pixel = 32 * 64 + 32;
        let inherits = |materials: &[GpuMaterial], edit: &dyn Fn(&mut HitPoint)| {
            let mut hp = fresh(&cam, pixel);
            edit(&mut hp);
            let start = hp;
            let took = inherit_slot(&mut hp, None, &request, materials, (&before, &[]));
            if !took {
                assert_eq!(
                    hp, start,
                    "a slot that does not inherit keeps its fresh start"
                );
            }
            took
        };
        let mut textured = white();
        textured[0].texture = 1;
        let mut coated = white();
        coated[0].kind = material_kind::COATED;
        assert!(inherits(&white(), &|_| {}));
        assert!(!inherits(&textured, &|_| {}));
        assert!(!inherits(&coated, &|_| {}));
        assert!(!inherits(&white(), &|hp| hp.flags |= hit_flags::EYE_CHAINED));
        assert!(!inherits(&white(), &|hp| hp.flags &= !hit_flags::VALID));
        // Another object, and a surface facing elsewhere, at the same point.
        assert!(!inherits(&white(), &|hp| hp.flags ^= 1 << hit_flags::OBJECT_SHIFT));
        assert!(!inherits(&white(), &|hp| hp.normal = [0.0, 0.6, 0.8]));
        // Far from every earlier visible point.
        assert!(!inherits(&white(), &|hp| hp.position[2] = 0.5));
    }

    #[test]
    fn the_box_grows_by_the_inherited_ones_and_edges_pass_nothing_on() {
        let cam = camera(Vec3::new(0.0, 0.0, 5.0));
        let mut before = image(&cam, 50);
        let before_bounds = vec![SlotBounds::new(Vec3::splat(-2.0), Vec3::splat(2.0)); 64 * 64];
        let request = CameraMove {
            before: cam,
            after: cam,
            spp: 1,
        };
        let pixel = 32 * 64 + 32;
        let mut hp = fresh(&cam, pixel);
        let mut own = SlotBounds::new(Vec3::ZERO, Vec3::ONE);
        let inputs = (before.as_slice(), before_bounds.as_slice());
        assert!(inherit_slot(
            &mut hp,
            Some(&mut own),
            &request,
            &white(),
            inputs
        ));
        assert_eq!(own, SlotBounds::new(Vec3::splat(-2.0), Vec3::splat(2.0)));
        // A slot whose paths met another object too averaged two surfaces: an edge.
        before[pixel as usize].eye_met |= 1 << 3;
        let mut hp = fresh(&cam, pixel);
        let inputs = (before.as_slice(), before_bounds.as_slice());
        assert!(!inherit_slot(&mut hp, None, &request, &white(), inputs));
    }

    #[test]
    fn a_pixel_next_to_another_surface_is_on_an_edge_and_a_plane_has_none() {
        let cam = camera(Vec3::new(0.0, 0.0, 5.0));
        let request = CameraMove {
            before: cam,
            after: cam,
            spp: 1,
        };
        let mut view = image(&cam, 0);
        let edges = |view: &[HitPoint]| -> Vec<u32> {
            (0..view.len())
                .filter(|&slot| on_an_edge(view, slot, &request, &white()))
                .map(|slot| slot as u32)
                .collect()
        };
        assert_eq!(edges(&view), Vec::<u32>::new(), "a plane has no edge");
        // Another object at pixel (20, 10): it and the eight around it.
        view[10 * 64 + 20].flags ^= 1 << hit_flags::OBJECT_SHIFT;
        let ring: Vec<u32> = (9..=11)
            .flat_map(|y| (19..=21).map(move |x| y * 64 + x))
            .collect();
        assert_eq!(edges(&view), ring);
        // The same object half a unit nearer the camera at (40, 30): a step, not a plane.
        let mut view = image(&cam, 0);
        view[30 * 64 + 40].position[2] += 0.5;
        assert_eq!(edges(&view).len(), 9);
        // A crease is an edge, and so is the void or a reflection.
        for edit in [
            (|hp: &mut HitPoint| hp.normal = [0.0, 0.6, 0.8]) as fn(&mut HitPoint),
            |hp| hp.flags &= !hit_flags::VALID,
            |hp| hp.flags |= hit_flags::EYE_CHAINED,
        ] {
            let mut view = image(&cam, 0);
            edit(&mut view[5 * 64 + 5]);
            assert_eq!(edges(&view).len(), 9);
        }
    }

    #[test]
    fn points_behind_or_beside_the_earlier_camera_inherit_nothing() {
        let cam = camera(Vec3::new(0.0, 0.0, 5.0));
        assert_eq!(image_point(&cam, Vec3::new(0.0, 0.0, 6.0)), None);
        let (x, y) = image_point(&cam, Vec3::ZERO).unwrap();
        approx::assert_relative_eq!(x, 32.0, epsilon = 1e-4);
        approx::assert_relative_eq!(y, 32.0, epsilon = 1e-4);
        // The pixel centre's ray lands back in its pixel.
        let hp = converged(&cam, 5 * 64 + 9, 1);
        let (x, y) = image_point(&cam, Vec3::from(hp.position)).unwrap();
        approx::assert_relative_eq!(x, 9.5, epsilon = 1e-3);
        approx::assert_relative_eq!(y, 5.5, epsilon = 1e-3);
    }
}
