//! Path files: moves decided apart from the scene, read at run time. A path is a list of
//! steps, each a rigid move of one named object after some rendering time or iterations;
//! steps at the same time move their objects together.
//!
//! ```toml
//! [[step]]
//! after_seconds = 2.0          # or after_iterations = 40; counted from the previous step
//! object = "short-block"
//! translate = [-40.0, 0.0, -40.0]
//! rotate = [0.0, 15.0, 0.0]    # degrees about x, then y, then z, about the object's
//!                              # bounding-box centre in its current pose
//! ```
//!
//! A step without `after_seconds` or `after_iterations` (or with zero) moves together with the
//! step before it. Errors name the file, the step, the field and the value.

use super::error::SceneError;
use super::file::{SceneSource, euler_degrees};
use super::magnitude::MAX_COORDINATE;
use super::model::{MaterialKind, Move, Scene};
use crate::rng::{PassKind, StreamKey};
use glam::{Quat, Vec3};
use serde::Deserialize;
use std::path::Path;

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
    fn is_zero(&self) -> bool {
        match *self {
            After::Seconds(s) => s == 0.0,
            After::Iterations(n) => n == 0,
        }
    }
}

/// Moves made at one time: the rigid moves of one or more objects, after `after`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PathEvent {
    /// Rendering before it, since the previous event (or the start).
    pub after: After,
    /// The moves, applied in order to the pose that stands then.
    pub moves: Vec<Move>,
}

/// Moves nobody declared in the scene, in time order.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct MovePath {
    /// The events, in order.
    pub events: Vec<PathEvent>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PathFile {
    #[serde(default)]
    step: Vec<StepFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StepFile {
    after_seconds: Option<f64>,
    after_iterations: Option<u32>,
    object: String,
    #[serde(default)]
    translate: [f32; 3],
    #[serde(default)]
    rotate: [f32; 3],
}

/// Reads and checks a path file against `scene` (frame 0, the pose a render starts in).
pub fn load_path_file(path: &Path, scene: &Scene) -> Result<MovePath, SceneError> {
    let source = SceneSource::read(path)?;
    parse_path(&source.text, &source.file, scene)
}

/// Parses and checks path text against `scene`; `file` names the source in errors.
pub fn parse_path(text: &str, file: &str, scene: &Scene) -> Result<MovePath, SceneError> {
    let raw: PathFile = toml::from_str(text).map_err(|e| SceneError::Syntax {
        file: file.to_owned(),
        reason: e.to_string().trim_end().replace('\n', "\n  "),
    })?;
    if raw.step.is_empty() {
        return Err(SceneError::invalid(
            file,
            "step",
            "[]",
            "a path needs at least one [[step]]",
        ));
    }
    let mut path = MovePath::default();
    for (i, step) in raw.step.iter().enumerate() {
        let err = |field: &str, value: String, problem: &str| {
            SceneError::invalid(file, format!("step[{i}].{field}"), value, problem)
        };
        let after = match (step.after_seconds, step.after_iterations) {
            (Some(_), Some(_)) => {
                return Err(err(
                    "after_seconds",
                    format!("{:?}", step.after_seconds.unwrap_or_default()),
                    "give after_seconds or after_iterations, not both",
                ));
            }
            (Some(s), None) if !(s.is_finite() && s >= 0.0) => {
                return Err(err(
                    "after_seconds",
                    s.to_string(),
                    "not a finite, non-negative number",
                ));
            }
            (Some(s), None) => After::Seconds(s),
            (None, Some(n)) => After::Iterations(n),
            (None, None) => After::Iterations(0),
        };
        let object = scene.object_index(&step.object).ok_or_else(|| {
            err(
                "object",
                format!("\"{}\"", step.object),
                "no object has this name",
            )
        })?;
        let finite = |field: &str, v: [f32; 3]| match v.iter().position(|c| !c.is_finite()) {
            Some(k) => Err(err(
                &format!("{field}[{k}]"),
                v[k].to_string(),
                "not a finite number",
            )),
            None => Ok(Vec3::from(v)),
        };
        let m = Move {
            object,
            translation: finite("translate", step.translate)?,
            rotation: euler_degrees(finite("rotate", step.rotate)?),
        };
        match path.events.last_mut() {
            Some(event) if after.is_zero() => event.moves.push(m),
            _ => path.events.push(PathEvent {
                after,
                moves: vec![m],
            }),
        }
    }
    check_inside(&path, scene, file)?;
    Ok(path)
}

/// Every moved object stays inside the box of the whole scene as loaded (a path that takes
/// an object elsewhere is more likely a typo than a wish).
fn check_inside(path: &MovePath, scene: &Scene, file: &str) -> Result<(), SceneError> {
    let (lo, hi) = scene.bounds();
    let slack = (hi - lo) * 1e-4;
    let mut posed = scene.clone();
    let mut step = 0;
    for event in &path.events {
        for m in &event.moves {
            posed.apply(m);
            let (a, b) = posed.objects[m.object].bounds();
            let far = a.abs().max(b.abs()).max_element() > MAX_COORDINATE;
            if far || a.cmplt(lo - slack).any() || b.cmpgt(hi + slack).any() {
                return Err(SceneError::invalid(
                    file,
                    format!("step[{step}]"),
                    format!("\"{}\"", posed.objects[m.object].name),
                    format!(
                        "moves the object to [{a}, {b}], outside the scene's bounds [{lo}, {hi}]"
                    ),
                ));
            }
            step += 1;
        }
    }
    Ok(())
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
        for m in self.events.iter().flat_map(|e| &e.moves) {
            posed.apply(m);
        }
        posed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Material, Object, RenderDefaults, quad_triangles};

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
        Scene {
            name: "room".into(),
            camera: Camera {
                eye: Vec3::new(0.0, 1.0, -5.0),
                look_at: Vec3::ZERO,
                up: Vec3::Y,
                fov_deg: 40.0,
                width: 8,
                height: 8,
            },
            materials: vec![
                Material {
                    name: "white".into(),
                    kind: MaterialKind::Diffuse {
                        albedo: Vec3::splat(0.5),
                    },
                },
                Material {
                    name: "lamp".into(),
                    kind: MaterialKind::Light {
                        radiance: Vec3::ONE,
                        albedo: Vec3::ZERO,
                    },
                },
            ],
            objects: vec![
                Object {
                    name: "floor".into(),
                    material: 0,
                    triangles: q(0.0, 4.0),
                },
                Object {
                    name: "tile".into(),
                    material: 0,
                    triangles: q(0.5, 0.5),
                },
                Object {
                    name: "lamp".into(),
                    material: 1,
                    triangles: q(3.0, 0.5),
                },
            ],
            render: RenderDefaults::default(),
            moves: Vec::new(),
        }
    }

    #[test]
    fn steps_at_the_same_time_form_one_event() {
        let text = r#"
            [[step]]
            after_iterations = 4
            object = "tile"
            translate = [1.0, 0.0, 0.0]
            [[step]]
            object = "lamp"
            translate = [0.0, -1.0, 0.0]
            [[step]]
            after_seconds = 0.5
            object = "tile"
            rotate = [0.0, 90.0, 0.0]
        "#;
        let path = parse_path(text, "p.toml", &room()).unwrap();
        assert_eq!(path.events.len(), 2);
        assert_eq!(path.events[0].after, After::Iterations(4));
        assert_eq!(path.events[0].moves.len(), 2);
        assert_eq!(path.events[1].after, After::Seconds(0.5));
        let end = path.final_pose(&room());
        assert_eq!(end.objects[1].bounds_centre(), Vec3::new(1.0, 0.5, 0.0));
    }

    #[test]
    fn bad_steps_name_the_file_step_field_and_value() {
        let bad = |text: &str| parse_path(text, "p.toml", &room()).unwrap_err().to_string();
        let unknown = bad("[[step]]\nafter_iterations = 1\nobject = \"chair\"");
        assert_eq!(
            unknown,
            "p.toml: step[0].object = \"chair\": no object has this name"
        );
        let nan = bad("[[step]]\nobject = \"tile\"\ntranslate = [0.0, nan, 0.0]");
        assert_eq!(
            nan,
            "p.toml: step[0].translate[1] = NaN: not a finite number"
        );
        let outside = bad("[[step]]\nobject = \"tile\"\ntranslate = [0.0, 9.0, 0.0]");
        assert!(
            outside.starts_with("p.toml: step[0] = \"tile\": moves the object to"),
            "{outside}"
        );
        let both = bad("[[step]]\nobject = \"tile\"\nafter_seconds = 1.0\nafter_iterations = 2");
        assert!(both.contains("not both"), "{both}");
        let negative = bad("[[step]]\nobject = \"tile\"\nafter_seconds = -1.0");
        assert!(
            negative.contains("step[0].after_seconds = -1"),
            "{negative}"
        );
        let typo = bad("[[step]]\nobject = \"tile\"\ntranslation = [0.0, 1.0, 0.0]");
        assert!(typo.contains("unknown field"), "{typo}");
        assert!(bad("").contains("at least one"));
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
