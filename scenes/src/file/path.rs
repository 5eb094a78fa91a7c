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

use crate::file::scene_file::{SceneSource, euler_degrees};
use glam::Vec3;
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
}
