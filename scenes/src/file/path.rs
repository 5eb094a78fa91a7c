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
//!
//! A step may move the camera instead of an object: `camera = { eye = [...], look_at = [...] }`
//! (its up vector and field of view stay). The viewer's scripts (`ppm view --script`) are
//! path files whose steps may also only ask for a screenshot (`screenshot = true`, allowed on
//! any step: taken after what the step does).

use crate::file::scene_file::{SceneSource, euler_degrees};
use glam::Vec3;
pub use ppm_core::scene::path::CameraStep;
use ppm_core::scene::path::{After, MovePath, PathEvent};
use ppm_core::scene::{MAX_COORDINATE, Move, Scene, SceneError};
use serde::Deserialize;
use std::path::Path;

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
    object: Option<String>,
    #[serde(default)]
    translate: [f32; 3],
    #[serde(default)]
    rotate: [f32; 3],
    camera: Option<CameraFile>,
    #[serde(default)]
    screenshot: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    eye: [f32; 3],
    look_at: [f32; 3],
}

/// What a viewer script does at one time.
#[derive(Clone, Debug, PartialEq)]
pub struct ScriptEvent {
    /// Rendering before it, since the previous event (or the start).
    pub after: After,
    /// Rigid moves, applied in order, all in one move of the render.
    pub moves: Vec<Move>,
    /// A new camera, after the moves.
    pub camera: Option<CameraStep>,
    /// Write the presented frame once the rest is done.
    pub screenshot: bool,
}

/// A viewer script: a path file whose steps may also move the camera or ask for screenshots.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    /// The events, in order.
    pub events: Vec<ScriptEvent>,
}

/// Reads and checks a path file against `scene` (frame 0, the pose a render starts in).
pub fn load_path_file(path: &Path, scene: &Scene) -> Result<MovePath, SceneError> {
    let source = SceneSource::read(path)?;
    parse_path(&source.text, &source.file, scene)
}

/// Reads and checks a viewer script against `scene`.
pub fn load_script_file(path: &Path, scene: &Scene) -> Result<Script, SceneError> {
    let source = SceneSource::read(path)?;
    parse_script(&source.text, &source.file, scene)
}

/// Parses and checks path text against `scene`; `file` names the source in errors. Camera
/// and screenshot steps are the viewer's and refused here.
pub fn parse_path(text: &str, file: &str, scene: &Scene) -> Result<MovePath, SceneError> {
    let (script, steps) = parse_steps(text, file, scene)?;
    if let Some((i, field)) = steps.iter().enumerate().find_map(|(i, s)| {
        let field = match (s.object.is_none() && s.camera.is_none(), s.screenshot) {
            (_, true) => "screenshot",
            (true, _) => "object",
            _ => return None,
        };
        Some((i, field))
    }) {
        return Err(SceneError::invalid(
            file,
            format!("step[{i}].{field}"),
            if field == "object" {
                "missing"
            } else {
                "given"
            },
            "a path moves objects or the camera: every step names an object or a camera; \
             screenshot steps are for `ppm view --script`",
        ));
    }
    Ok(MovePath {
        events: script
            .events
            .into_iter()
            .map(|e| PathEvent {
                after: e.after,
                moves: e.moves,
                camera: e.camera,
            })
            .collect(),
    })
}

/// Parses and checks a viewer script against `scene`; `file` names the source in errors.
pub fn parse_script(text: &str, file: &str, scene: &Scene) -> Result<Script, SceneError> {
    parse_steps(text, file, scene).map(|(script, _)| script)
}

fn parse_steps(
    text: &str,
    file: &str,
    scene: &Scene,
) -> Result<(Script, Vec<StepFile>), SceneError> {
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
    let mut script = Script::default();
    let (bounds, mut posed) = (scene.bounds(), scene.clone());
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
        let finite = |field: &str, v: [f32; 3]| match v.iter().position(|c| !c.is_finite()) {
            Some(k) => Err(err(
                &format!("{field}[{k}]"),
                v[k].to_string(),
                "not a finite number",
            )),
            None => Ok(Vec3::from(v)),
        };
        let moved = match (&step.object, &step.camera) {
            (Some(_), Some(_)) => {
                return Err(err(
                    "camera",
                    "given".to_owned(),
                    "a step moves an object or the camera, not both",
                ));
            }
            (Some(name), None) => {
                let object = scene.object_index(name).ok_or_else(|| {
                    err("object", format!("\"{name}\""), "no object has this name")
                })?;
                Some(Move {
                    object,
                    translation: finite("translate", step.translate)?,
                    rotation: euler_degrees(finite("rotate", step.rotate)?),
                })
            }
            (None, camera) => {
                if step.translate != [0.0; 3] || step.rotate != [0.0; 3] {
                    return Err(err(
                        "object",
                        "missing".to_owned(),
                        "translate and rotate need the object they move",
                    ));
                }
                if camera.is_none() && !step.screenshot {
                    return Err(err(
                        "object",
                        "missing".to_owned(),
                        "a step names an object to move (or, in a viewer script, a camera \
                         or screenshot = true)",
                    ));
                }
                None
            }
        };
        let camera = match &step.camera {
            Some(c) => {
                let eye = finite("camera.eye", c.eye)?;
                let look_at = finite("camera.look_at", c.look_at)?;
                if (look_at - eye).length() <= f32::EPSILON * eye.abs().max_element().max(1.0) {
                    return Err(err(
                        "camera.look_at",
                        format!("{look_at}"),
                        "the camera looks at its own eye",
                    ));
                }
                Some(CameraStep { eye, look_at })
            }
            None => None,
        };
        let event = match script.events.last_mut() {
            Some(event) if after.is_zero() => event,
            _ => {
                script.events.push(ScriptEvent {
                    after,
                    moves: Vec::new(),
                    camera: None,
                    screenshot: false,
                });
                script.events.last_mut().expect("pushed above")
            }
        };
        if let Some(m) = &moved {
            check_inside(&mut posed, m, bounds, format!("step[{i}]"), file)?;
        }
        event.moves.extend(moved);
        event.camera = camera.or(event.camera);
        event.screenshot |= step.screenshot;
    }
    Ok((script, raw.step))
}

/// Every moved object stays inside the box of the whole scene as loaded, `bounds` (a path
/// that takes an object elsewhere is more likely a typo than a wish); `posed` is the pose
/// before `m`, and after it on return.
fn check_inside(
    posed: &mut Scene,
    m: &Move,
    (lo, hi): (Vec3, Vec3),
    field: String,
    file: &str,
) -> Result<(), SceneError> {
    let slack = (hi - lo) * 1e-4;
    posed.apply(m);
    let (a, b) = posed.objects[m.object].bounds();
    let far = a.abs().max(b.abs()).max_element() > MAX_COORDINATE;
    if far || a.cmplt(lo - slack).any() || b.cmpgt(hi + slack).any() {
        return Err(SceneError::invalid(
            file,
            field,
            format!("\"{}\"", posed.objects[m.object].name),
            format!("moves the object to [{a}, {b}], outside the scene's bounds [{lo}, {hi}]"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell() -> Scene {
        crate::cornell_box_file().unwrap()
    }

    #[test]
    fn steps_at_the_same_time_form_one_event() {
        let text = r#"
            [[step]]
            after_iterations = 4
            object = "short-block"
            translate = [10.0, 0.0, 0.0]
            [[step]]
            object = "tall-block"
            translate = [0.0, 0.0, -5.0]
            [[step]]
            after_seconds = 0.5
            object = "short-block"
            rotate = [0.0, 90.0, 0.0]
        "#;
        let scene = cornell();
        let path = parse_path(text, "p.toml", &scene).unwrap();
        assert_eq!(path.events.len(), 2);
        assert_eq!(path.events[0].after, After::Iterations(4));
        assert_eq!(path.events[0].moves.len(), 2);
        assert_eq!(path.events[1].after, After::Seconds(0.5));
        let block = scene.object_index("short-block").unwrap();
        let end = path.final_pose(&scene);
        let moved = end.objects[block].bounds_centre() - scene.objects[block].bounds_centre();
        assert!(
            (moved - Vec3::new(10.0, 0.0, 0.0)).length() < 1e-3,
            "{moved}"
        );
    }

    #[test]
    fn bad_steps_name_the_file_step_field_and_value() {
        let scene = cornell();
        let bad = |text: &str| parse_path(text, "p.toml", &scene).unwrap_err().to_string();
        let unknown = bad("[[step]]\nafter_iterations = 1\nobject = \"chair\"");
        assert_eq!(
            unknown,
            "p.toml: step[0].object = \"chair\": no object has this name"
        );
        let nan = bad("[[step]]\nobject = \"short-block\"\ntranslate = [0.0, nan, 0.0]");
        assert_eq!(
            nan,
            "p.toml: step[0].translate[1] = NaN: not a finite number"
        );
        let outside = bad("[[step]]\nobject = \"short-block\"\ntranslate = [0.0, 900.0, 0.0]");
        assert!(
            outside.starts_with("p.toml: step[0] = \"short-block\": moves the object to"),
            "{outside}"
        );
        let both =
            bad("[[step]]\nobject = \"short-block\"\nafter_seconds = 1.0\nafter_iterations = 2");
        assert!(both.contains("not both"), "{both}");
        let negative = bad("[[step]]\nobject = \"short-block\"\nafter_seconds = -1.0");
        assert!(
            negative.contains("step[0].after_seconds = -1"),
            "{negative}"
        );
        let typo = bad("[[step]]\nobject = \"short-block\"\ntranslation = [0.0, 1.0, 0.0]");
        assert!(typo.contains("unknown field"), "{typo}");
        assert!(bad("").contains("at least one"));
    }

    #[test]
    fn scripts_take_cameras_and_screenshots_and_paths_refuse_screenshots() {
        let text = r#"
            [[step]]
            after_iterations = 3
            screenshot = true
            [[step]]
            after_iterations = 2
            object = "short-block"
            translate = [10.0, 0.0, 0.0]
            [[step]]
            screenshot = true
            [[step]]
            after_seconds = 0.5
            camera = { eye = [278.0, 273.0, -700.0], look_at = [278.0, 273.0, 0.0] }
        "#;
        let scene = cornell();
        let script = parse_script(text, "s.toml", &scene).unwrap();
        assert_eq!(script.events.len(), 3);
        assert!(script.events[0].screenshot && script.events[0].moves.is_empty());
        assert_eq!(script.events[1].moves.len(), 1);
        assert!(
            script.events[1].screenshot,
            "a zero-time step joins the one before"
        );
        let camera = script.events[2].camera.unwrap();
        assert_eq!(camera.eye, Vec3::new(278.0, 273.0, -700.0));
        let refused = parse_path(text, "s.toml", &scene).unwrap_err().to_string();
        assert!(
            refused.starts_with("s.toml: step[0].screenshot"),
            "{refused}"
        );
        let camera_path = "[[step]]\nafter_iterations = 4\ncamera = { eye = [278.0, 273.0, -700.0], look_at = [278.0, 273.0, 0.0] }";
        let path = parse_path(camera_path, "c.toml", &scene).unwrap();
        assert_eq!(path.events[0].camera, Some(camera));
        assert_eq!(path.final_pose(&scene).camera.eye, camera.eye);
        let bad = |text: &str| {
            parse_script(text, "s.toml", &scene)
                .unwrap_err()
                .to_string()
        };
        let both = bad(
            "[[step]]\nobject = \"short-block\"\ncamera = { eye = [0.0, 0.0, 0.0], look_at = [0.0, 0.0, 1.0] }",
        );
        assert!(
            both.contains("step[0].camera") && both.contains("not both"),
            "{both}"
        );
        let blind = bad("[[step]]\ncamera = { eye = [1.0, 2.0, 3.0], look_at = [1.0, 2.0, 3.0] }");
        assert!(blind.contains("step[0].camera.look_at"), "{blind}");
        let nothing = bad("[[step]]\nafter_iterations = 2");
        assert!(nothing.contains("step[0].object = missing"), "{nothing}");
    }
}
