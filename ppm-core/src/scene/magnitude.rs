//! The magnitudes a scene may hold, argued from keeping every `f32` the passes compute finite
//! and normal, and checked in `f64`, so that a scene far outside them is judged by its true
//! values (in `f32`, a length at 1e20 squares to infinity and one at 1e-30 to zero, and both
//! used to be misread as a camera looking at itself or along its up vector).

use super::error::SceneError;
use super::model::{MaterialKind, Scene};
use glam::{DVec3, Vec3};

/// Largest magnitude of any coordinate (vertices in both frames, the camera). The passes take
/// differences, squared lengths and cross products of positions in `f32`: with every
/// coordinate within 1e18 a difference is within 2e18, a squared length within
/// `3 * 4e36 = 1.2e37` and a cross product's component within `8e36`, all a factor 28 or more
/// below `f32::MAX` (3.4e38). The gather radius obeys the same bound, its square being `r2`.
pub const MAX_COORDINATE: f32 = 1e18;

/// Smallest extent of the scene, and distance from the camera to what it looks at. A
/// squared distance at this scale (1e-30) stays a normal `f32` (above 1.2e-38) with room to
/// spare for radii a hundredth of it that shrink further as passes go; below it, squared
/// lengths flush to zero and directions to NaN.
pub const MIN_EXTENT: f64 = 1e-15;

/// Largest power `pi * A * Le` of all lights together, per channel. A photon leaves with the
/// lights' whole power, and a hit point's flux `tau` sums, in `f32`, the powers of the
/// photons it gathers over every pass: 1e32 leaves a factor of a million below `f32::MAX`
/// for those sums (the stress family's `power-1e30` case, photon power 1e32, sits at it).
pub const MAX_LIGHT_POWER: f64 = 1e32;

/// Checks `scene` (as loaded from `file`) against the bounds above; errors name the field
/// and the value.
pub fn check_magnitudes(scene: &Scene, file: &str) -> Result<(), SceneError> {
    let err = |field: String, value: String, problem: String| {
        SceneError::invalid(file, field, value, problem)
    };
    let beyond = |v: Vec3| v.abs().max_element() > MAX_COORDINATE || !v.is_finite();
    let c = &scene.camera;
    for (field, v) in [("camera.eye", c.eye), ("camera.look_at", c.look_at)] {
        if beyond(v) {
            return Err(err(field.into(), list(v), beyond_problem(v)));
        }
    }
    let view = (c.look_at.as_dvec3() - c.eye.as_dvec3()).length();
    if view > 0.0 && view < MIN_EXTENT {
        return Err(err(
            "camera.look_at".into(),
            list(c.look_at),
            format!(
                "{view:.2e} from camera.eye, below {MIN_EXTENT:e}: the view direction's squared \
                 length underflows f32"
            ),
        ));
    }
    for (frame, posed) in [(0, scene.clone()), (1, scene.at_frame(1))] {
        for (i, o) in posed.objects.iter().enumerate() {
            if let Some(v) = o.triangles.iter().flatten().find(|v| beyond(**v)) {
                let field = match scene.moves.iter().position(|m| m.object == i) {
                    Some(m) if frame == 1 => format!("moves[{m}] (object {})", o.name),
                    _ => format!("objects[{i}] ({}) vertex", o.name),
                };
                return Err(err(field, list(*v), beyond_problem(*v)));
            }
        }
    }
    let (lo, hi) = bounds(scene);
    let extent = (hi - lo).length();
    if extent < MIN_EXTENT {
        return Err(err(
            "objects".into(),
            format!("{} triangles", scene.triangle_count()),
            format!(
                "span {extent:.2e} (bounding-box diagonal), below {MIN_EXTENT:e}: squared \
                 distances at this scale underflow f32; scale the scene up"
            ),
        ));
    }
    check_lights(scene, file)?;
    check_textures(scene, file)
}

/// Textures scale a reflecting colour: a light or glass takes none (a light's emission
/// would be scaled with it where an eye path stops, ppm_core::textures), and texture
/// coordinates are finite, one triple per triangle.
fn check_textures(scene: &Scene, file: &str) -> Result<(), SceneError> {
    for (i, m) in scene.materials.iter().enumerate() {
        let bare = matches!(
            m.kind,
            MaterialKind::Light { .. } | MaterialKind::Glass { .. }
        );
        if let (Some(t), true) = (&m.texture, bare) {
            return Err(SceneError::invalid(
                file,
                format!("materials[{i}] ({}).texture", m.name),
                &t.name,
                "a light or glass takes no texture",
            ));
        }
    }
    for (i, o) in scene.objects.iter().enumerate() {
        let field = format!("objects[{i}] ({}).uvs", o.name);
        if !o.uvs.is_empty() && o.uvs.len() != o.triangles.len() {
            return Err(SceneError::invalid(
                file,
                field,
                format!("{} triples", o.uvs.len()),
                format!("one per triangle ({}) or none", o.triangles.len()),
            ));
        }
        if let Some(uv) = o.uvs.iter().flatten().find(|uv| !uv.is_finite()) {
            return Err(SceneError::invalid(
                file,
                field,
                uv,
                "texture coordinates must be finite",
            ));
        }
    }
    Ok(())
}

/// Every light has an area that `f32` holds, and all together a power within
/// [`MAX_LIGHT_POWER`].
fn check_lights(scene: &Scene, file: &str) -> Result<(), SceneError> {
    let mut power = DVec3::ZERO;
    for (i, o) in scene.objects.iter().enumerate() {
        let MaterialKind::Light { radiance, .. } = scene.materials[o.material].kind else {
            continue;
        };
        let area: f64 = o.triangles.iter().map(area_f64).sum();
        let field = format!("objects[{i}] ({}).area", o.name);
        if !(area > 0.0 && area.is_finite()) {
            return Err(SceneError::invalid(
                file,
                field,
                area,
                "a light must have a positive, finite area",
            ));
        }
        let area_f32 = area as f32;
        if !(area_f32 > 0.0 && area_f32.is_finite()) {
            return Err(SceneError::invalid(
                file,
                field,
                format!("{area:e}"),
                "does not fit an f32: scale the light",
            ));
        }
        power += std::f64::consts::PI * area * radiance.as_dvec3();
        if power.max_element() > MAX_LIGHT_POWER {
            let name = &scene.materials[o.material].name;
            return Err(SceneError::invalid(
                file,
                format!("materials.{name}.radiance"),
                list(radiance),
                format!(
                    "the lights' power pi * A * Le reaches {:.2e}, above {MAX_LIGHT_POWER:e}: \
                     the flux photons carry would overflow f32",
                    power.max_element()
                ),
            ));
        }
    }
    Ok(())
}

fn beyond_problem(v: Vec3) -> String {
    if v.is_finite() {
        format!("beyond +-{MAX_COORDINATE:e}, where squared distances overflow f32")
    } else {
        "not a finite number".into()
    }
}

fn area_f64(t: &[Vec3; 3]) -> f64 {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    0.5 * (b - a).cross(c - a).length()
}

fn bounds(scene: &Scene) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for v in scene
        .objects
        .iter()
        .flat_map(|o| o.triangles.iter().flatten())
    {
        lo = lo.min(v.as_dvec3());
        hi = hi.max(v.as_dvec3());
    }
    (lo, hi)
}

/// A vector as a scene file writes it.
fn list(v: Vec3) -> String {
    format!("[{}, {}, {}]", number(v.x), number(v.y), number(v.z))
}

/// A number as written, very large or small ones with an exponent (`1e20`, not twenty-one
/// digits).
pub fn number(x: f32) -> String {
    if x != 0.0 && !(1e-4..1e7).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::testing::{object, room};
    use crate::scene::{Texture, TextureFilter};
    use std::sync::Arc;

    #[test]
    fn a_textured_light_and_bad_coordinates_are_refused_by_name() {
        let quad = vec![
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::X, Vec3::ONE, Vec3::Y],
        ];
        let mut scene = room(vec![
            object("wall", 0, quad.clone()),
            object("lamp", 1, quad),
        ]);
        assert!(check_magnitudes(&scene, "s.toml").is_ok());
        let grey = Texture::from_linear(
            "grey.png",
            1,
            1,
            &[Vec3::splat(0.5)],
            TextureFilter::Nearest,
        );
        scene.materials[1].texture = Some(Arc::new(grey.unwrap()));
        let err = check_magnitudes(&scene, "s.toml").unwrap_err().to_string();
        assert!(
            err.contains("materials[1] (lamp).texture") && err.contains("grey.png"),
            "{err}"
        );
        scene.materials[1].texture = None;
        scene.objects[0].uvs = vec![[glam::Vec2::ZERO; 3]];
        let err = check_magnitudes(&scene, "s.toml").unwrap_err().to_string();
        assert!(err.contains("objects[0] (wall).uvs"), "{err}");
        scene.objects[0].uvs = vec![[glam::Vec2::new(f32::NAN, 0.0); 3]; 2];
        let err = check_magnitudes(&scene, "s.toml").unwrap_err().to_string();
        assert!(err.contains("must be finite"), "{err}");
    }
}
