//! What lies under a pixel, and where a drag takes it: the viewer's picking, over the same
//! flattened scene and BVH the passes trace ([`ppm_core::trace`]).

use glam::Vec3;
use ppm_core::compile::{CompiledScene, camera_ray, compile_scene};
use ppm_core::layout::GpuCamera;
use ppm_core::scene::Scene;
use ppm_core::trace::{FlatPose, PoseQueries};

/// An object under a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Picked {
    /// Index into [`Scene::objects`].
    pub object: usize,
    /// The surface point the ray met.
    pub point: Vec3,
}

/// Rays through the pixels of one pose of a scene, seen by its camera at one image size.
pub struct Picker {
    pose: CompiledScene,
}

impl Picker {
    /// Flattens `scene` (its BVH included) for rays at `width` x `height`.
    pub fn new(scene: &Scene, width: u32, height: u32) -> Self {
        Self {
            pose: compile_scene(scene, width, height),
        }
    }

    /// The ray through image point `(px, py)` (pixels, `(0, 0)` the top-left corner): origin
    /// and unit direction.
    pub fn ray(&self, px: f32, py: f32) -> (Vec3, Vec3) {
        ray(&self.pose.camera, px, py)
    }

    /// The object whose surface is nearest along the ray through `(px, py)`, if any.
    pub fn pick(&self, px: f32, py: f32) -> Option<Picked> {
        let (origin, dir) = self.ray(px, py);
        let hit = FlatPose::new(&self.pose).closest_hit(origin, dir, f32::INFINITY)?;
        Some(Picked {
            object: self.pose.triangles[hit.triangle as usize].object as usize,
            point: origin + dir * hit.t,
        })
    }
}

/// The ray of `camera` through image point `(px, py)`: origin and unit direction. A drag
/// needs only this, not the scene.
pub fn ray(camera: &GpuCamera, px: f32, py: f32) -> (Vec3, Vec3) {
    (camera.eye.into(), camera_ray(camera, px, py))
}

/// A plane a drag slides an object in.
#[derive(Clone, Copy, Debug)]
pub struct DragPlane {
    /// A point of the plane (the picked point).
    pub point: Vec3,
    /// Its unit normal.
    pub normal: Vec3,
}

impl DragPlane {
    /// The plane through `point` facing a camera that looks along `forward`.
    pub fn facing(point: Vec3, forward: Vec3) -> Self {
        Self {
            point,
            normal: forward.normalize(),
        }
    }

    /// The horizontal plane (normal +y, the scenes' up) through `point`: a drag along the
    /// floor.
    pub fn level(point: Vec3) -> Self {
        Self {
            point,
            normal: Vec3::Y,
        }
    }

    /// Where the ray meets the plane in front of its origin, if it does (a ray parallel to
    /// the plane, or one that meets it behind, does not).
    pub fn meet(&self, origin: Vec3, dir: Vec3) -> Option<Vec3> {
        let along = dir.dot(self.normal);
        if along.abs() < 1e-6 {
            return None;
        }
        let t = (self.point - origin).dot(self.normal) / along;
        (t > 0.0 && t.is_finite()).then(|| origin + dir * t)
    }

    /// The translation that keeps the dragged point under the cursor as it goes from the ray
    /// `from` to the ray `to` (origin, direction), if both meet the plane.
    pub fn translation(&self, from: (Vec3, Vec3), to: (Vec3, Vec3)) -> Option<Vec3> {
        Some(self.meet(to.0, to.1)? - self.meet(from.0, from.1)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ppm_core::scene::Move;

    /// The pixel where `point` appears, by projecting it with the picker's own camera.
    fn project(picker: &Picker, point: Vec3, width: u32, height: u32) -> (f32, f32) {
        let c = &picker.pose.camera;
        let (eye, f, r, u) = (
            Vec3::from(c.eye),
            Vec3::from(c.forward),
            Vec3::from(c.right),
            Vec3::from(c.up),
        );
        let d = point - eye;
        let depth = d.dot(f);
        let sx = d.dot(r) / (depth * r.length_squared());
        let sy = d.dot(u) / (depth * u.length_squared());
        (
            (sx + 1.0) * 0.5 * width as f32,
            (1.0 - sy) * 0.5 * height as f32,
        )
    }

    #[test]
    fn picking_returns_the_object_under_the_pixel() {
        let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
        let (w, h) = (96, 96);
        let picker = Picker::new(&scene, w, h);
        let tall = scene.object_index("tall-block").unwrap();
        let short = scene.object_index("short-block").unwrap();
        for object in [tall, short] {
            let (lo, hi) = scene.objects[object].bounds();
            // The front face's middle: the centre of the box pulled towards the camera.
            let centre = (lo + hi) * 0.5;
            let (px, py) = project(&picker, centre, w, h);
            let picked = picker.pick(px, py).expect("the block is in view");
            assert_eq!(
                scene.objects[picked.object].name, scene.objects[object].name,
                "pixel ({px}, {py})"
            );
            assert!(picked.point.cmpge(lo - 1e-2).all() && picked.point.cmple(hi + 1e-2).all());
        }
        // The middle of the left edge sees a wall, not a block; moving the short block under
        // another pixel makes that pixel pick it.
        let wall = picker.pick(3.0, h as f32 * 0.5).unwrap();
        assert!(wall.object != tall && wall.object != short);
        let mut moved = scene.clone();
        moved.apply(&Move {
            object: short,
            translation: Vec3::new(120.0, 0.0, 0.0),
            rotation: glam::Quat::IDENTITY,
        });
        let (lo, hi) = moved.objects[short].bounds();
        let (px, py) = project(&picker, (lo + hi) * 0.5, w, h);
        assert_eq!(
            Picker::new(&moved, w, h).pick(px, py).unwrap().object,
            short
        );
    }

    #[test]
    fn a_drag_keeps_the_point_under_the_cursor() {
        let plane = DragPlane::facing(Vec3::new(0.0, 0.0, 10.0), Vec3::Z);
        let eye = Vec3::ZERO;
        let from = (eye, Vec3::Z);
        let to = (eye, Vec3::new(1.0, 0.0, 10.0).normalize());
        let t = plane.translation(from, to).unwrap();
        assert!((t - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-5, "{t}");
        // Along the floor: the height never changes; a ray away from it meets nothing.
        let floor = DragPlane::level(Vec3::new(0.0, -1.0, 5.0));
        let t = floor
            .translation(
                (eye, Vec3::new(0.0, -1.0, 5.0).normalize()),
                (eye, Vec3::new(2.0, -1.0, 5.0).normalize()),
            )
            .unwrap();
        assert!(t.y.abs() < 1e-5 && (t.x - 2.0).abs() < 1e-4, "{t}");
        assert!(floor.meet(eye, Vec3::Y).is_none());
    }
}
