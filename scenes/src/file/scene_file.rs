//! The TOML scene format: parsing, and conversion to the [`Scene`] model with validation.
//!
//! The format is documented in the repository's docs/scene-format.md. Every value is checked
//! before anything is rendered, and a bad one is reported with the file, the dotted field path
//! and the value.

use crate::file::limits::{MESH_FILE_LIMIT, SCENE_FILE_LIMIT, check_file_size, read_text_limited};
use crate::file::texture_image::{ImageOptions, read_texture};
use glam::{DVec3, EulerRot, Quat, Vec2, Vec3};
use ppm_core::params::Estimator;
use ppm_core::scene::{
    Camera, MAX_COORDINATE, Material, MaterialKind, Move, Object, RenderDefaults, Scene,
    SceneError, Texture, check_magnitudes, number, quad_triangles,
};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: String,
    camera: CameraFile,
    #[serde(default)]
    render: Option<RenderFile>,
    materials: BTreeMap<String, MaterialFile>,
    #[serde(default)]
    objects: Vec<ObjectFile>,
    #[serde(default)]
    moves: Vec<MoveFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    eye: [f32; 3],
    look_at: [f32; 3],
    #[serde(default = "default_up")]
    up: [f32; 3],
    fov: f32,
    width: u32,
    height: u32,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderFile {
    initial_radius: Option<f32>,
    alpha: Option<f32>,
    photons_per_pass: Option<u32>,
    passes: Option<u32>,
    estimator: Option<Estimator>,
}

/// A conductor's default reflectance factor.
fn white() -> [f32; 3] {
    [1.0; 3]
}

/// A coat's default index of refraction (pbrt-v4's `coateddiffuse` default).
fn coat_ior() -> f32 {
    1.5
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum MaterialFile {
    Diffuse {
        /// Required unless `texture` is given (then 1 by default, a factor on it).
        albedo: Option<[f32; 3]>,
        /// An image file, relative to the scene file, whose colour scales the albedo.
        texture: Option<String>,
    },
    Mirror {
        /// Required unless `texture` is given (then 1 by default, a factor on it).
        reflectance: Option<[f32; 3]>,
        /// An image file, relative to the scene file, whose colour scales the reflectance.
        texture: Option<String>,
    },
    Glass {
        ior: f32,
        #[serde(default)]
        alpha: f32,
        /// Roughness across the tangent; `alpha` when not given (isotropic).
        alpha_v: Option<f32>,
    },
    Conductor {
        eta: [f32; 3],
        k: [f32; 3],
        #[serde(default = "white")]
        reflectance: [f32; 3],
        /// An image file, relative to the scene file, whose colour scales the reflectance.
        texture: Option<String>,
        #[serde(default)]
        alpha: f32,
        /// Roughness across the tangent; `alpha` when not given (isotropic).
        alpha_v: Option<f32>,
    },
    Coated {
        /// Required unless `texture` is given (then 1 by default, a factor on it), as for
        /// diffuse.
        albedo: Option<[f32; 3]>,
        /// An image file, relative to the scene file, whose colour scales the albedo.
        texture: Option<String>,
        #[serde(default = "coat_ior")]
        ior: f32,
        #[serde(default)]
        alpha: f32,
        #[serde(default)]
        nonlinear: bool,
    },
    Light {
        radiance: [f32; 3],
        #[serde(default)]
        albedo: [f32; 3],
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectFile {
    name: String,
    material: String,
    #[serde(default)]
    quads: Vec<[[f32; 3]; 4]>,
    #[serde(default)]
    triangles: Vec<[[f32; 3]; 3]>,
    obj: Option<String>,
    #[serde(default = "one")]
    scale: f32,
    #[serde(default)]
    rotate: [f32; 3],
    #[serde(default)]
    translate: [f32; 3],
}

/// Triangles and their vertices' texture coordinates.
type TexturedTriangles = (Vec<[Vec3; 3]>, Vec<[Vec2; 3]>);

fn one() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MoveFile {
    object: String,
    #[serde(default)]
    translate: [f32; 3],
    #[serde(default)]
    rotate: [f32; 3],
}

/// A scene file read whole (within [`SCENE_FILE_LIMIT`]), with what every format's parser
/// needs beside its text.
pub(crate) struct SceneSource {
    /// The file's contents.
    pub text: String,
    /// The path as errors name it.
    pub file: String,
    /// The folder mesh file names are relative to.
    pub base: PathBuf,
    /// The file stem, the scene's name where the format has none.
    pub name: String,
}

impl SceneSource {
    /// Reads `path`, refusing what is not a regular file or is too large.
    pub(crate) fn read(path: &Path) -> Result<Self, SceneError> {
        let file = path.display().to_string();
        let text =
            read_text_limited(path, SCENE_FILE_LIMIT).map_err(|reason| SceneError::Read {
                file: file.clone(),
                reason,
            })?;
        Ok(Self {
            text,
            file,
            base: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            name: path
                .file_stem()
                .map_or("scene".into(), |s| s.to_string_lossy().into_owned()),
        })
    }
}

/// Reads and validates a scene file; OBJ paths are relative to the file's folder.
pub fn load_scene_file(path: &Path) -> Result<Scene, SceneError> {
    let source = SceneSource::read(path)?;
    parse_scene(&source.text, &source.file, &source.base)
}

/// Parses and validates scene text. `file` names the source in errors; `base` resolves OBJ paths.
pub fn parse_scene(text: &str, file: &str, base: &Path) -> Result<Scene, SceneError> {
    let raw: SceneFile = toml::from_str(text).map_err(|e| SceneError::Syntax {
        file: file.to_owned(),
        reason: e.to_string().trim_end().replace('\n', "\n  "),
    })?;
    Converter { file, base }.scene(raw)
}

struct Converter<'a> {
    file: &'a str,
    base: &'a Path,
}

impl Converter<'_> {
    fn err(
        &self,
        field: impl Into<String>,
        value: impl std::fmt::Display,
        problem: &str,
    ) -> SceneError {
        SceneError::invalid(self.file, field, value, problem)
    }

    fn scene(&self, raw: SceneFile) -> Result<Scene, SceneError> {
        let camera = self.camera(&raw.camera)?;
        let render = self.render(raw.render.as_ref())?;
        let mut materials = Vec::new();
        for (name, m) in &raw.materials {
            materials.push(self.material(name, m)?);
        }
        let mut objects = Vec::new();
        for (i, o) in raw.objects.iter().enumerate() {
            objects.push(self.object(i, o, &materials)?);
        }
        if objects.iter().all(|o| o.triangles.is_empty()) {
            return Err(self.err(
                "objects",
                objects.len(),
                "the scene has no triangles to render",
            ));
        }
        let lit = objects
            .iter()
            .any(|o| matches!(materials[o.material].kind, MaterialKind::Light { .. }));
        if !lit {
            return Err(self.err(
                "objects",
                objects.len(),
                "no object uses a material of type \"light\": the scene has no light",
            ));
        }
        for (i, o) in objects.iter().enumerate() {
            if let Some(first) = objects[..i].iter().position(|p| p.name == o.name) {
                return Err(self.err(
                    format!("objects[{i}].name"),
                    format!("\"{}\"", o.name),
                    &format!("also the name of objects[{first}]: a move names one object"),
                ));
            }
        }
        let mut moves = Vec::new();
        for (i, m) in raw.moves.iter().enumerate() {
            moves.push(self.movement(i, m, &objects)?);
        }
        let scene = Scene {
            name: raw.name,
            camera,
            materials,
            objects,
            render,
            moves,
        };
        check_magnitudes(&scene, self.file)?;
        Ok(scene)
    }

    fn vec3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        for (i, c) in v.iter().enumerate() {
            if !c.is_finite() {
                return Err(self.err(format!("{field}[{i}]"), c, "not a finite number"));
            }
        }
        Ok(Vec3::from(v))
    }

    /// A GGX roughness: finite, in [0, 1].
    fn roughness(&self, field: &str, alpha: f32) -> Result<f32, SceneError> {
        if !(0.0..=1.0).contains(&alpha) {
            return Err(self.err(
                field,
                alpha,
                "must be in [0, 1] (GGX roughness; 0 is smooth)",
            ));
        }
        Ok(alpha)
    }

    /// A colour whose channels lie in [0, max].
    fn colour(&self, field: &str, v: [f32; 3], max: Option<f32>) -> Result<Vec3, SceneError> {
        let c = self.vec3(field, v)?;
        for (i, x) in v.iter().enumerate() {
            if *x < 0.0 {
                return Err(self.err(format!("{field}[{i}]"), x, "negative"));
            }
            if let Some(max) = max.filter(|m| x > m) {
                return Err(self.err(
                    format!("{field}[{i}]"),
                    x,
                    &format!("above {max} (a surface cannot reflect more than it receives)"),
                ));
            }
        }
        Ok(c)
    }

    /// A reflecting colour (a diffuse or coated base's `albedo`, a mirror's or conductor's
    /// `reflectance`, the field `colour_field`) in [0, 1], and the image `texture` names,
    /// read relative to the scene file, that scales it (the colour is then 1 unless given).
    /// One of the two is needed.
    fn textured_colour(
        &self,
        (name, what): (&str, &str),
        colour_field: &str,
        colour: Option<[f32; 3]>,
        texture: &Option<String>,
    ) -> Result<(Vec3, Option<Arc<Texture>>), SceneError> {
        let field = |f: &str| format!("materials.{name}.{f}");
        let colour = match (colour, texture) {
            (Some(c), _) => self.colour(&field(colour_field), c, Some(1.0))?,
            (None, Some(_)) => Vec3::ONE,
            (None, None) => {
                return Err(self.err(
                    field(colour_field),
                    "missing",
                    &format!("a {what} material needs its {colour_field} or a texture"),
                ));
            }
        };
        let Some(file) = texture else {
            return Ok((colour, None));
        };
        let path = self.base.join(file);
        let texture = read_texture(&path, ImageOptions::default())
            .map_err(|e| self.err(field("texture"), format!("\"{file}\""), &e))?;
        Ok((colour, Some(Arc::new(texture))))
    }

    /// The camera, its directions judged in `f64` (in `f32`, lengths at 1e20 square to
    /// infinity and at 1e-30 to zero); `up` is stored normalised, so that the `f32` camera
    /// basis is well defined at any scale.
    fn camera(&self, c: &CameraFile) -> Result<Camera, SceneError> {
        let eye = self.vec3("camera.eye", c.eye)?;
        let look_at = self.vec3("camera.look_at", c.look_at)?;
        let up = self.vec3("camera.up", c.up)?;
        let forward = look_at.as_dvec3() - eye.as_dvec3();
        if forward == DVec3::ZERO {
            return Err(self.err(
                "camera.look_at",
                list(look_at),
                "equals camera.eye: the camera has no view direction",
            ));
        }
        let up64 = up.as_dvec3();
        if up64 == DVec3::ZERO
            || forward.normalize().cross(up64.normalize()).length_squared() < 1e-12
        {
            return Err(self.err(
                "camera.up",
                list(up),
                "is zero or parallel to the view direction",
            ));
        }
        let up = up64.normalize().as_vec3();
        if !(c.fov.is_finite() && c.fov > 0.0 && c.fov < 180.0) {
            return Err(self.err(
                "camera.fov",
                c.fov,
                "must lie strictly between 0 and 180 degrees",
            ));
        }
        if c.width == 0 {
            return Err(self.err("camera.width", c.width, "must be at least 1"));
        }
        if c.height == 0 {
            return Err(self.err("camera.height", c.height, "must be at least 1"));
        }
        Ok(Camera {
            eye,
            look_at,
            up,
            fov_deg: c.fov,
            width: c.width,
            height: c.height,
        })
    }

    fn render(&self, r: Option<&RenderFile>) -> Result<RenderDefaults, SceneError> {
        let mut d = RenderDefaults::default();
        let Some(r) = r else { return Ok(d) };
        if let Some(radius) = r.initial_radius {
            if !(radius.is_finite() && radius > 0.0) {
                return Err(self.err("render.initial_radius", radius, "must be a positive number"));
            }
            if radius > MAX_COORDINATE {
                return Err(self.err(
                    "render.initial_radius",
                    number(radius),
                    &format!("above {MAX_COORDINATE:e}: its square overflows f32"),
                ));
            }
            d.initial_radius = radius;
        }
        if let Some(alpha) = r.alpha {
            if !(alpha > 0.0 && alpha < 1.0) {
                return Err(self.err("render.alpha", alpha, "must lie strictly between 0 and 1"));
            }
            d.alpha = alpha;
        }
        if let Some(p) = r.photons_per_pass {
            if p == 0 {
                return Err(self.err("render.photons_per_pass", p, "must be at least 1"));
            }
            d.photons_per_pass = p;
        }
        if let Some(p) = r.passes {
            if p == 0 {
                return Err(self.err("render.passes", p, "must be at least 1"));
            }
            d.passes = p;
        }
        if let Some(e) = r.estimator {
            d.estimator = e;
        }
        Ok(d)
    }

    fn material(&self, name: &str, m: &MaterialFile) -> Result<Material, SceneError> {
        let field = |f: &str| format!("materials.{name}.{f}");
        let kind = match m {
            MaterialFile::Diffuse { albedo, texture } => {
                let (albedo, texture) =
                    self.textured_colour((name, "diffuse"), "albedo", *albedo, texture)?;
                return Ok(Material {
                    texture,
                    ..Material::new(name, MaterialKind::Diffuse { albedo })
                });
            }
            MaterialFile::Mirror {
                reflectance,
                texture,
            } => {
                let (reflectance, texture) =
                    self.textured_colour((name, "mirror"), "reflectance", *reflectance, texture)?;
                return Ok(Material {
                    texture,
                    ..Material::new(name, MaterialKind::Mirror { reflectance })
                });
            }
            MaterialFile::Glass {
                ior,
                alpha,
                alpha_v,
            } => {
                if !(ior.is_finite() && *ior > 0.0) {
                    return Err(self.err(field("ior"), ior, "must be a positive number"));
                }
                let alpha = self.roughness(&field("alpha"), *alpha)?;
                MaterialKind::Glass {
                    ior: *ior,
                    alpha,
                    alpha_v: self.roughness(&field("alpha_v"), alpha_v.unwrap_or(alpha))?,
                }
            }
            MaterialFile::Conductor {
                eta,
                k,
                reflectance,
                texture,
                alpha,
                alpha_v,
            } => {
                let alpha = self.roughness(&field("alpha"), *alpha)?;
                let (reflectance, texture) = self.textured_colour(
                    (name, "conductor"),
                    "reflectance",
                    Some(*reflectance),
                    texture,
                )?;
                let kind = MaterialKind::Conductor {
                    eta: self.colour(&field("eta"), *eta, None)?,
                    k: self.colour(&field("k"), *k, None)?,
                    reflectance,
                    alpha,
                    alpha_v: self.roughness(&field("alpha_v"), alpha_v.unwrap_or(alpha))?,
                };
                return Ok(Material {
                    texture,
                    ..Material::new(name, kind)
                });
            }
            MaterialFile::Coated {
                albedo,
                texture,
                ior,
                alpha,
                nonlinear,
            } => {
                let (albedo, texture) =
                    self.textured_colour((name, "coated"), "albedo", *albedo, texture)?;
                if !(ior.is_finite() && *ior > 1.0) {
                    return Err(self.err(
                        field("ior"),
                        ior,
                        "must be a number above 1 (the coat's index over the outside's)",
                    ));
                }
                let kind = MaterialKind::Coated {
                    albedo,
                    ior: *ior,
                    alpha: self.roughness(&field("alpha"), *alpha)?,
                    nonlinear: *nonlinear,
                };
                return Ok(Material {
                    texture,
                    ..Material::new(name, kind)
                });
            }
            MaterialFile::Light { radiance, albedo } => MaterialKind::Light {
                radiance: self.colour(&field("radiance"), *radiance, None)?,
                albedo: self.colour(&field("albedo"), *albedo, Some(1.0))?,
            },
        };
        Ok(Material {
            name: name.to_owned(),
            kind,
            texture: None,
        })
    }

    fn object(
        &self,
        i: usize,
        o: &ObjectFile,
        materials: &[Material],
    ) -> Result<Object, SceneError> {
        let at = format!("objects[{i}] ({})", o.name);
        let material = materials
            .iter()
            .position(|m| m.name == o.material)
            .ok_or_else(|| {
                let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                self.err(
                    format!("{at}.material"),
                    format!("\"{}\"", o.material),
                    &format!("no such material (defined: {})", known.join(", ")),
                )
            })?;
        if !(o.scale.is_finite() && o.scale > 0.0) {
            return Err(self.err(format!("{at}.scale"), o.scale, "must be a positive number"));
        }
        let rotate = self.vec3(&format!("{at}.rotate"), o.rotate)?;
        let translate = self.vec3(&format!("{at}.translate"), o.translate)?;
        let mut triangles = Vec::new();
        // A quad spans the unit square from its first corner; a triangle given alone reads
        // pbrt's default coordinates, as one from an OBJ without them.
        let mut uvs = Vec::new();
        let quad_uvs = [
            [Vec2::ZERO, Vec2::X, Vec2::ONE],
            [Vec2::ZERO, Vec2::ONE, Vec2::Y],
        ];
        for (q, quad) in o.quads.iter().enumerate() {
            let mut v = [Vec3::ZERO; 4];
            for (k, p) in quad.iter().enumerate() {
                v[k] = self.vec3(&format!("{at}.quads[{q}][{k}]"), *p)?;
            }
            triangles.extend(quad_triangles(v));
            uvs.extend(quad_uvs);
        }
        for (t, tri) in o.triangles.iter().enumerate() {
            let mut v = [Vec3::ZERO; 3];
            for (k, p) in tri.iter().enumerate() {
                v[k] = self.vec3(&format!("{at}.triangles[{t}][{k}]"), *p)?;
            }
            triangles.push(v);
            uvs.push([Vec2::ZERO, Vec2::X, Vec2::ONE]);
        }
        if let Some(obj) = &o.obj {
            let (t, uv) = self.load_obj(&format!("{at}.obj"), obj)?;
            triangles.extend(t);
            uvs.extend(uv);
        }
        let rotation = euler_degrees(rotate);
        for v in triangles.iter_mut().flatten() {
            *v = rotation * (*v * o.scale) + translate;
        }
        Ok(Object {
            name: o.name.clone(),
            material,
            triangles,
            uvs,
        })
    }

    /// The triangles of an OBJ file and their texture coordinates (pbrt's default where the
    /// file has none).
    fn load_obj(&self, field: &str, name: &str) -> Result<TexturedTriangles, SceneError> {
        let path: PathBuf = self.base.join(name);
        check_file_size(&path, MESH_FILE_LIMIT).map_err(|e| {
            self.err(
                field,
                format!("\"{name}\""),
                &format!("{e}: {}", path.display()),
            )
        })?;
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj(&path, &options).map_err(|e| {
            self.err(
                field,
                format!("\"{name}\""),
                &format!("cannot load OBJ {}: {e}", path.display()),
            )
        })?;
        let mut triangles = Vec::new();
        let mut uvs = Vec::new();
        for model in &models {
            let p = &model.mesh.positions;
            let tc = &model.mesh.texcoords;
            let uv = |i: u32| -> Vec2 {
                let i = i as usize * 2;
                match tc.get(i..i + 2) {
                    Some(&[u, v]) if u.is_finite() && v.is_finite() => Vec2::new(u, v),
                    _ => Vec2::ZERO,
                }
            };
            let vertex = |i: u32| -> Result<Vec3, SceneError> {
                let i = i as usize * 3;
                let Some(&[x, y, z]) = p.get(i..i + 3) else {
                    return Err(self.err(
                        field,
                        format!("\"{name}\""),
                        "has a face that refers to a vertex that does not exist",
                    ));
                };
                let v = Vec3::new(x, y, z);
                if !v.is_finite() {
                    return Err(self.err(
                        field,
                        format!("\"{name}\""),
                        "has a vertex that is not finite",
                    ));
                }
                if v.abs().max_element() > MAX_COORDINATE {
                    return Err(self.err(
                        field,
                        format!("\"{name}\""),
                        &format!(
                            "has a vertex beyond +-{MAX_COORDINATE:e}, where squared distances \
                             overflow f32: [{}, {}, {}]",
                            number(x),
                            number(y),
                            number(z)
                        ),
                    ));
                }
                Ok(v)
            };
            for t in model.mesh.indices.chunks_exact(3) {
                triangles.push([vertex(t[0])?, vertex(t[1])?, vertex(t[2])?]);
                uvs.push(if tc.is_empty() {
                    [Vec2::ZERO, Vec2::X, Vec2::ONE]
                } else {
                    [uv(t[0]), uv(t[1]), uv(t[2])]
                });
            }
        }
        if triangles.is_empty() {
            return Err(self.err(field, format!("\"{name}\""), "holds no triangles"));
        }
        Ok((triangles, uvs))
    }

    fn movement(&self, i: usize, m: &MoveFile, objects: &[Object]) -> Result<Move, SceneError> {
        let object = objects
            .iter()
            .position(|o| o.name == m.object)
            .ok_or_else(|| {
                self.err(
                    format!("moves[{i}].object"),
                    format!("\"{}\"", m.object),
                    "no object has this name",
                )
            })?;
        Ok(Move {
            object,
            translation: self.vec3(&format!("moves[{i}].translate"), m.translate)?,
            rotation: euler_degrees(self.vec3(&format!("moves[{i}].rotate"), m.rotate)?),
        })
    }
}

/// A vector as written in the scene file.
fn list(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// Rotation from Euler angles in degrees, applied about x, then y, then z.
pub(crate) fn euler_degrees(deg: Vec3) -> Quat {
    Quat::from_euler(
        EulerRot::ZYX,
        deg.z.to_radians(),
        deg.y.to_radians(),
        deg.x.to_radians(),
    )
}
