//! Paths: moves decided apart from the scene, in time order. Each event moves one or more
//! objects rigidly after some rendering time or iterations. `scenes::file::path` reads them
//! from files; [`MovePath::random`] makes them for tests.

use super::model::{Camera, MaterialKind, Move, Scene};
use crate::rng::{PassKind, StreamKey};
use glam::{Quat, Vec3};

/// How long to render before a step: seconds of rendering or iterations.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum After {
    /// Seconds of rendering since the previous step (or the start).
    Seconds(f64),
    /// Iterations since the previous step (or the start).
    Iterations(u32),
}

impl After {
    /// Whether no time passes: the step goes with the one before it.
    pub fn is_zero(&self) -> bool {
        match *self {
            After::Seconds(s) => s == 0.0,
            After::Iterations(n) => n == 0,
        }
    }
}

/// Where a step puts the camera: its up vector and field of view stay.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CameraStep {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub look_at: Vec3,
}

impl CameraStep {
    /// `camera` put here.
    pub fn place(&self, camera: &Camera) -> Camera {
        Camera {
            eye: self.eye,
            look_at: self.look_at,
            ..camera.clone()
        }
    }
}

/// Moves made at one time: the rigid moves of one or more objects, then perhaps the camera,
/// after `after`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PathEvent {
    /// Rendering before it, since the previous event (or the start).
    pub after: After,
    /// The moves, applied in order to the pose that stands then.
    pub moves: Vec<Move>,
    /// Where the camera goes, after the moves.
    pub camera: Option<CameraStep>,
}

/// Moves nobody declared in the scene, in time order.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct MovePath {
    /// The events, in order.
    pub events: Vec<PathEvent>,
}

impl MovePath {
    /// `count` random rigid moves, one at a time, of random objects that are not lights and
    /// have room to move, each after `first` (the first) or `then` (the others): a rotation
    /// of up to 30 degrees about a random axis, then a translation that keeps the object
    /// inside the scene's bounds, up to a quarter of their extent per axis. Keyed by `seed`.
    pub fn random(scene: &Scene, count: u32, seed: u32, first: After, then: After) -> MovePath {
        let (lo, hi) = scene.bounds();
        let extent = hi - lo;
        let movable: Vec<usize> = (0..scene.objects.len())
            .filter(|&o| {
                let object = &scene.objects[o];
                let light = matches!(
                    scene.materials[object.material].kind,
                    MaterialKind::Light { .. }
                );
                let (a, b) = object.bounds();
                // Room on every axis: a wall spanning the scene cannot move inside it.
                !light && !object.triangles.is_empty() && (b - a).cmplt(extent * 0.9).all()
            })
            .collect();
        let mut posed = scene.clone();
        let mut path = MovePath::default();
        if movable.is_empty() {
            return path;
        }
        for k in 0..count {
            let key = StreamKey {
                seed,
                kind: PassKind::Region,
                pass_index: 0x7a7e_0000,
                path: k,
            };
            let u = |d: u32| key.uniform(d);
            let object = movable[((u(0) * movable.len() as f32) as usize).min(movable.len() - 1)];
            let axis = Vec3::new(u(1) - 0.5, u(2) - 0.5, u(3) - 0.5).normalize_or(Vec3::Y);
            let rotation = Quat::from_axis_angle(axis, (u(4) * 2.0 - 1.0) * 30f32.to_radians());
            let mut turned = posed.clone();
            turned.apply(&Move {
                object,
                translation: Vec3::ZERO,
                rotation,
            });
            let (a, b) = turned.objects[object].bounds();
            // The translation keeps the turned box inside the scene's; a turn that leaves no
            // room (or pushes out) becomes a pure translation.
            let (rotation, a, b) = if a.cmpge(lo).all() && b.cmple(hi).all() {
                (rotation, a, b)
            } else {
                let (a, b) = posed.objects[object].bounds();
                (Quat::IDENTITY, a, b)
            };
            let room_lo = (lo - a).max(-extent * 0.25);
            let room_hi = (hi - b).min(extent * 0.25);
            let t = Vec3::new(u(5), u(6), u(7));
            let translation = room_lo + (room_hi - room_lo) * t;
            let m = Move {
                object,
                translation,
                rotation,
            };
            posed.apply(&m);
            path.events.push(PathEvent {
                after: if k == 0 { first } else { then },
                moves: vec![m],
                camera: None,
            });
        }
        path
    }

    /// The scene's own `[[moves]]` as a path: all of them at once, after `after`.
    pub fn declared(scene: &Scene, after: After) -> MovePath {
        MovePath {
            events: vec![PathEvent {
                after,
                moves: scene.moves.clone(),
                camera: None,
            }],
        }
    }

    /// Rendering before the last event: iterations and seconds summed over the events'
    /// waits (each event waits in one unit).
    pub fn before_last(&self) -> (u32, f64) {
        self.events
            .iter()
            .fold((0, 0.0), |(n, s), e| match e.after {
                After::Iterations(k) => (n.saturating_add(k), s),
                After::Seconds(t) => (n, s + t),
            })
    }

    /// Every move of the path, in order, applied to `scene`: the final pose.
    pub fn final_pose(&self, scene: &Scene) -> Scene {
        let mut posed = scene.clone();
        for event in &self.events {
            for m in &event.moves {
                posed.apply(m);
            }
            if let Some(c) = &event.camera {
                posed.camera = c.place(&posed.camera);
            }
        }
        posed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::quad_triangles;
    use crate::scene::testing::{object, room as room_of};

    fn room() -> Scene {
        let q = |y: f32, s: f32| {
            quad_triangles([
                Vec3::new(-s, y, -s),
                Vec3::new(-s, y, s),
                Vec3::new(s, y, s),
                Vec3::new(s, y, -s),
            ])
            .to_vec()
        };
        room_of(vec![
            object("floor", 0, q(0.0, 4.0)),
            object("tile", 0, q(0.5, 0.5)),
            object("lamp", 1, q(3.0, 0.5)),
        ])
    }

    #[test]
    fn random_paths_move_only_what_may_move_and_stay_inside() {
        let scene = room();
        let (lo, hi) = scene.bounds();
        let path = MovePath::random(&scene, 20, 3, After::Iterations(2), After::Iterations(1));
        assert_eq!(path.events.len(), 20);
        let mut posed = scene.clone();
        for e in &path.events {
            for m in &e.moves {
                assert_eq!(scene.objects[m.object].name, "tile");
                posed.apply(m);
                let (a, b) = posed.objects[m.object].bounds();
                assert!(
                    a.cmpge(lo - 1e-4).all() && b.cmple(hi + 1e-4).all(),
                    "{a} {b}"
                );
            }
        }
        assert_ne!(posed.objects[1].triangles, scene.objects[1].triangles);
        let again = MovePath::random(&scene, 20, 3, After::Iterations(2), After::Iterations(1));
        assert_eq!(path, again);
    }
}
