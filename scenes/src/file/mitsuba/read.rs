//! Reads the subset of Mitsuba 3's XML scene format that we can render.
//!
//! roxmltree parses the XML: it keeps every element's position, so an error names its line.

use crate::file::bands;
use crate::file::interop::{
    SceneBuilder, camera_pose, look_at, mesh_triangles, swaps_handedness, unit_cube,
    unit_rectangle, vertical_fov,
};
use crate::file::mesh::{read_obj, read_ply};
use crate::file::scene_file::SceneSource;
use crate::file::texture_image::{Encoding, ImageOptions, read_texture};
use glam::{DMat4, DQuat, DVec3, Vec2, Vec3};
use ppm_core::scene::Scene;
use ppm_core::scene::SceneError;
use ppm_core::scene::{Camera, MaterialKind, Object, Texture, TextureFilter};
use roxmltree::{Document, Node};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Reads a Mitsuba 3 scene file; mesh file names are relative to its folder.
pub fn load_mitsuba_file(path: &Path) -> std::result::Result<Scene, SceneError> {
    let s = SceneSource::read(path)?;
    parse_mitsuba(&s.text, &s.file, &s.base, &s.name)
}

/// Parses Mitsuba 3 XML. `file` names the source in errors, `base` resolves mesh files,
/// `name` names the scene.
pub fn parse_mitsuba(
    text: &str,
    file: &str,
    base: &Path,
    name: &str,
) -> std::result::Result<Scene, SceneError> {
    let doc = Document::parse(text).map_err(|e| SceneError::Syntax {
        file: file.to_owned(),
        reason: format!("not well-formed XML: {e}"),
    })?;
    let mut reader = Reader {
        file,
        base,
        doc: &doc,
        defaults: HashMap::new(),
        builder: SceneBuilder::new(file),
        bsdfs: HashMap::new(),
        default_material: None,
        camera: None,
        sppm: SppmSettings::default(),
    };
    let root = doc.root_element();
    if root.tag_name().name() != "scene" {
        return Err(reader.err(root, "the root element must be <scene>"));
    }
    for node in root.children().filter(Node::is_element) {
        reader.top_level(node)?;
    }
    let Some((camera, mirrored)) = reader.camera.take() else {
        return Err(SceneError::invalid(
            file,
            "sensor",
            "none",
            "the scene has no <sensor type=\"perspective\">",
        ));
    };
    let sppm = reader.sppm;
    let mut scene = reader.builder.finish(name, camera, mirrored)?;
    sppm.apply(&mut scene.render);
    Ok(scene)
}

/// The settings of Mitsuba 0.6's `sppm` integrator (whose files Mitsuba 3 still reads; it
/// ships no photon mapper of its own) that mean what ours mean: the initial radius (0, its
/// default, asks for a heuristic and is not taken), photons per pass, the fraction `alpha`
/// of new photons kept, and the passes (-1: until stopped). Its `maxDepth` counts every
/// bounce of a path, where ours bound eye paths and photon paths apart, and is not taken;
/// neither is `granularity`, a work-splitting setting.
#[derive(Default)]
struct SppmSettings {
    radius: Option<f32>,
    photons: Option<u32>,
    alpha: Option<f32>,
    passes: Option<u32>,
}

impl SppmSettings {
    /// Makes these the scene's render defaults.
    fn apply(&self, render: &mut ppm_core::scene::RenderDefaults) {
        if let Some(r) = self.radius {
            render.initial_radius = r;
        }
        if let Some(n) = self.photons {
            render.photons_per_pass = n;
        }
        if let Some(a) = self.alpha {
            render.alpha = a;
        }
        if let Some(n) = self.passes {
            render.passes = n;
        }
    }
}

struct Reader<'a, 'input> {
    file: &'a str,
    base: &'a Path,
    doc: &'a Document<'input>,
    defaults: HashMap<String, String>,
    builder: SceneBuilder,
    bsdfs: HashMap<String, usize>,
    default_material: Option<usize>,
    camera: Option<(Camera, bool)>,
    sppm: SppmSettings,
}

/// A rough BSDF's microfacet parameters as read so far ([`Reader::microfacet`]).
#[derive(Default)]
struct Microfacet {
    /// `alpha`, which sets both roughnesses where given.
    alpha: Option<f32>,
    /// Whether `distribution="ggx"` was given.
    ggx: bool,
    /// `alpha_u` and `alpha_v`, read where `alpha` is not given.
    alpha_u: Option<f32>,
    alpha_v: Option<f32>,
}

type Result<T> = std::result::Result<T, SceneError>;

const SUBSET: &str = "outside the subset ppm renders";

impl<'input> Reader<'_, 'input> {
    fn err(&self, node: Node, problem: impl Into<String>) -> SceneError {
        SceneError::At {
            file: self.file.to_owned(),
            line: self.doc.text_pos_at(node.range().start).row,
            element: describe(node),
            problem: problem.into(),
        }
    }

    /// An attribute, with `$name` replaced by the value of `<default name="name">`.
    fn attr(&self, node: Node, name: &str) -> Result<Option<String>> {
        let Some(raw) = node.attribute(name) else {
            return Ok(None);
        };
        let Some(key) = raw.strip_prefix('$') else {
            return Ok(Some(raw.to_owned()));
        };
        match self.defaults.get(key) {
            Some(v) => Ok(Some(v.clone())),
            None => Err(self.err(node, format!("${key} has no <default name=\"{key}\">"))),
        }
    }

    fn required(&self, node: Node, name: &str) -> Result<String> {
        self.attr(node, name)?
            .ok_or_else(|| self.err(node, format!("the attribute \"{name}\" is missing")))
    }

    /// Numbers separated by commas or spaces, each parsed as `f32` straight from its text so
    /// that a value written with Rust's `{}` comes back bit for bit.
    fn numbers(&self, node: Node, text: &str) -> Result<Vec<f32>> {
        text.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| {
                s.parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| self.err(node, format!("\"{s}\" is not a finite number")))
            })
            .collect()
    }

    fn number(&self, node: Node, attr: &str) -> Result<f32> {
        let text = self.required(node, attr)?;
        match self.numbers(node, &text)?.as_slice() {
            [v] => Ok(*v),
            _ => Err(self.err(node, format!("\"{text}\" is not one number"))),
        }
    }

    fn vector(&self, node: Node, attr: &str) -> Result<Vec3> {
        let text = self.required(node, attr)?;
        match self.numbers(node, &text)?.as_slice() {
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(self.err(node, format!("{attr} = \"{text}\" is not three numbers"))),
        }
    }

    fn integer(&self, node: Node) -> Result<i64> {
        let text = self.required(node, "value")?;
        text.trim()
            .parse()
            .map_err(|_| self.err(node, format!("\"{text}\" is not an integer")))
    }

    fn boolean(&self, node: Node) -> Result<bool> {
        match self.required(node, "value")?.as_str() {
            "true" => Ok(true),
            "false" => Ok(false),
            other => Err(self.err(node, format!("\"{other}\" is not true or false"))),
        }
    }

    /// The colour a `spectrum` of `wavelength:value` pairs holds, when it is a band
    /// spectrum of `ppm export` (`read`: [`bands::read_reflectance`] or
    /// [`bands::read_illuminant`]).
    fn band_colour(
        &self,
        node: Node,
        text: &str,
        read: fn(&[(f32, f32)]) -> Option<Vec3>,
    ) -> Result<Vec3> {
        let points: Option<Vec<(f32, f32)>> = text
            .split(',')
            .map(|pair| {
                let (l, v) = pair.trim().split_once(':')?;
                Some((l.trim().parse().ok()?, v.trim().parse().ok()?))
            })
            .collect();
        points.as_deref().and_then(read).ok_or_else(|| {
            self.err(
                node,
                format!("a sampled spectrum other than the band spectra ppm export writes is {SUBSET} (RGB only)"),
            )
        })
    }

    /// An emitter's radiance: as [`Self::colour`], or a band spectrum of a light.
    fn radiance(&self, node: Node) -> Result<Vec3> {
        match self.attr(node, "value")? {
            Some(text) if node.tag_name().name() == "spectrum" && text.contains(':') => {
                self.band_colour(node, &text, bands::read_illuminant)
            }
            _ => self.colour(node, None),
        }
    }

    /// A colour parameter (`rgb`, a constant `spectrum`, a band spectrum of `ppm export`,
    /// or a `float`), checked to lie in [0, max] when `max` is given.
    fn colour(&self, node: Node, max: Option<f32>) -> Result<Vec3> {
        let c = match node.tag_name().name() {
            "spectrum" if self.attr(node, "value")?.is_some_and(|t| t.contains(':')) => {
                let text = self.required(node, "value")?;
                self.band_colour(node, &text, bands::read_reflectance)?
            }
            "rgb" | "spectrum" | "float" => {
                let text = self.required(node, "value")?;
                match self.numbers(node, &text)?.as_slice() {
                    [v] => Vec3::splat(*v),
                    [r, g, b] if node.tag_name().name() == "rgb" => Vec3::new(*r, *g, *b),
                    _ => {
                        return Err(
                            self.err(node, format!("\"{text}\" is not one or three numbers"))
                        );
                    }
                }
            }
            "texture" => return Err(self.err(node, format!("a textured parameter is {SUBSET}"))),
            _ => return Err(self.err(node, "expected <rgb>, <spectrum> or <float>")),
        };
        for v in c.to_array() {
            if v < 0.0 {
                return Err(self.err(node, format!("{v} is negative")));
            }
            if let Some(max) = max.filter(|m| v > *m) {
                return Err(self.err(
                    node,
                    format!("{v} is above {max} (a surface cannot reflect more than it receives)"),
                ));
            }
        }
        Ok(c)
    }

    fn top_level(&mut self, node: Node<'_, 'input>) -> Result<()> {
        match node.tag_name().name() {
            "default" => {
                let name = self.required(node, "name")?;
                let value = self.required(node, "value")?;
                self.defaults.insert(name, value);
            }
            "integrator" => self.integrator(node)?,
            "sensor" => self.sensor(node)?,
            "bsdf" => {
                let id = self.attr(node, "id")?;
                let (kind, texture) = self.bsdf(node)?;
                let name = id
                    .clone()
                    .unwrap_or_else(|| format!("bsdf-{}", self.builder.materials.len()));
                let index = self.builder.declare_textured(&name, kind, texture);
                if let Some(id) = id {
                    self.bsdfs.insert(id, index);
                }
            }
            "shape" => self.shape(node)?,
            "emitter" => {
                return Err(self.err(
                    node,
                    format!("{SUBSET}: light comes only from area emitters inside shapes"),
                ));
            }
            "texture" | "medium" | "volume" | "phase" | "include" | "path" | "alias" => {
                return Err(self.err(node, SUBSET));
            }
            _ => return Err(self.err(node, "unknown element")),
        }
        Ok(())
    }

    fn sensor(&mut self, node: Node) -> Result<()> {
        if self.camera.is_some() {
            return Err(self.err(node, "a second sensor: the scene may have one camera"));
        }
        let ty = self.required(node, "type")?;
        if ty != "perspective" {
            return Err(self.err(
                node,
                format!("{SUBSET}: only a perspective (pinhole) camera"),
            ));
        }
        let (mut fov, mut fov_node, mut axis) = (None, node, "x".to_owned());
        let mut to_world = None;
        let (mut width, mut height) = (768u32, 576u32);
        for child in node.children().filter(Node::is_element) {
            match (child.tag_name().name(), child.attribute("name")) {
                ("float", Some("fov")) => {
                    fov = Some(self.number(child, "value")?);
                    fov_node = child;
                }
                ("string", Some("fov_axis")) => {
                    axis = self.required(child, "value")?.to_lowercase()
                }
                ("float", Some("near_clip" | "far_clip")) => {}
                ("transform", Some("to_world")) => to_world = Some(self.transform(child)?),
                ("sampler", _) => {}
                ("film", _) => {
                    for p in child.children().filter(Node::is_element) {
                        let value = |r: &Self| -> Result<u32> {
                            u32::try_from(r.integer(p)?)
                                .ok()
                                .filter(|v| *v > 0)
                                .ok_or_else(|| r.err(p, "must be a positive integer"))
                        };
                        match (p.tag_name().name(), p.attribute("name")) {
                            ("integer", Some("width")) => width = value(self)?,
                            ("integer", Some("height")) => height = value(self)?,
                            ("integer" | "string" | "boolean" | "float", Some(n))
                                if n.starts_with("crop_") =>
                            {
                                return Err(self.err(p, format!("a cropped film is {SUBSET}")));
                            }
                            // Pixel format, file format, filter, banner: how the image is
                            // stored, not what it shows.
                            _ => {}
                        }
                    }
                }
                _ => return Err(self.err(child, "unknown parameter of a perspective sensor")),
            }
        }
        let fov = fov.ok_or_else(|| self.err(node, "the sensor has no <float name=\"fov\">"))?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.err(fov_node, "must lie strictly between 0 and 180 degrees"));
        }
        let aspect = f64::from(width) / f64::from(height);
        let axis = match axis.as_str() {
            "smaller" => {
                if aspect > 1.0 {
                    "y"
                } else {
                    "x"
                }
            }
            "larger" => {
                if aspect > 1.0 {
                    "x"
                } else {
                    "y"
                }
            }
            a => a,
        }
        .to_owned();
        let fov_deg = match axis.as_str() {
            "y" => fov,
            "x" if width == height => fov,
            "x" => vertical_fov(f64::from(fov), width, height),
            "diagonal" => {
                let diagonal = (aspect * aspect + 1.0).sqrt();
                vertical_fov(f64::from(fov), (diagonal * 1e6) as u32, 1_000_000)
            }
            other => {
                return Err(self.err(
                    node,
                    format!("fov_axis \"{other}\" is not x, y, diagonal, smaller or larger"),
                ));
            }
        };
        let (eye, target, up, mirrored) = match to_world {
            Some((_, Some((eye, target, up)))) => (eye, target, up, false),
            Some((m, None)) => camera_pose(m, true)
                .ok_or_else(|| self.err(node, "the camera's to_world is singular"))?,
            None => (Vec3::ZERO, Vec3::Z, Vec3::Y, false),
        };
        if (target - eye)
            .normalize_or_zero()
            .cross(up)
            .length_squared()
            < 1e-12
        {
            return Err(self.err(
                node,
                "the camera's up is zero or parallel to its view direction",
            ));
        }
        let camera = Camera {
            eye,
            look_at: target,
            up,
            fov_deg,
            width,
            height,
        };
        self.camera = Some((camera, mirrored));
        Ok(())
    }

    /// A `to_world` transform: its matrix, and the look-at itself when that is all it holds
    /// (so the camera is read back exactly as written).
    #[allow(clippy::type_complexity)]
    fn transform(&self, node: Node) -> Result<(DMat4, Option<(Vec3, Vec3, Vec3)>)> {
        let mut m = DMat4::IDENTITY;
        let mut exact = None;
        let ops: Vec<Node> = node.children().filter(Node::is_element).collect();
        for op in &ops {
            let op = *op;
            let xyz = |r: &Self, default: f64| -> Result<DVec3> {
                if let Some(v) = r.attr(op, "value")? {
                    let n = r.numbers(op, &v)?;
                    return match n.as_slice() {
                        [s] => Ok(DVec3::splat(f64::from(*s))),
                        [x, y, z] => Ok(DVec3::new(f64::from(*x), f64::from(*y), f64::from(*z))),
                        _ => Err(r.err(op, format!("\"{v}\" is not one or three numbers"))),
                    };
                }
                let mut out = DVec3::splat(default);
                for (k, a) in ["x", "y", "z"].iter().enumerate() {
                    if op.attribute(*a).is_some() {
                        out[k] = f64::from(r.number(op, a)?);
                    }
                }
                Ok(out)
            };
            let step = match op.tag_name().name() {
                "translate" => DMat4::from_translation(xyz(self, 0.0)?),
                "scale" => DMat4::from_scale(xyz(self, 1.0)?),
                "rotate" => {
                    let axis = xyz(self, 0.0)?;
                    let angle = f64::from(self.number(op, "angle")?);
                    let axis = axis
                        .try_normalize()
                        .ok_or_else(|| self.err(op, "the rotation axis is zero"))?;
                    DMat4::from_quat(DQuat::from_axis_angle(axis, angle.to_radians()))
                }
                "matrix" => {
                    let text = self.required(op, "value")?;
                    let v: Vec<f64> = self
                        .numbers(op, &text)?
                        .into_iter()
                        .map(f64::from)
                        .collect();
                    match v.len() {
                        16 => DMat4::from_cols_array(&v.try_into().expect("16")).transpose(),
                        9 => {
                            let r = |i: usize| DVec3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
                            glam::DMat4::from_mat3(
                                glam::DMat3::from_cols(r(0), r(1), r(2)).transpose(),
                            )
                        }
                        n => {
                            return Err(
                                self.err(op, format!("{n} numbers: a matrix has 16 (or 9)"))
                            );
                        }
                    }
                }
                "lookat" => {
                    let eye = self.vector(op, "origin")?;
                    let target = self.vector(op, "target")?;
                    let up = match op.attribute("up") {
                        Some(_) => self.vector(op, "up")?,
                        None => Vec3::Y,
                    };
                    if ops.len() == 1 {
                        exact = Some((eye, target, up));
                    }
                    look_at(eye.as_dvec3(), target.as_dvec3(), up.as_dvec3()).ok_or_else(|| {
                        self.err(op, "origin equals target, or up is parallel to the view")
                    })?
                }
                _ => {
                    return Err(self.err(
                        op,
                        "unknown transform (translate, rotate, scale, matrix, lookat)",
                    ));
                }
            };
            m = step * m;
        }
        Ok((m, exact))
    }

    /// Reads an `sppm` integrator's settings that mean what ours do ([`SppmSettings`], by
    /// Mitsuba 0.6's names or their Mitsuba 3 spelling); another integrator's settings are
    /// another method's, and are ignored.
    fn integrator(&mut self, node: Node) -> Result<()> {
        if self.attr(node, "type")?.as_deref() != Some("sppm") {
            return Ok(());
        }
        for p in node.children().filter(Node::is_element) {
            let name = p.attribute("name").unwrap_or_default();
            match name {
                "initialRadius" | "initial_radius" => {
                    let r = self.number(p, "value")?;
                    if r < 0.0 {
                        return Err(self.err(p, format!("{r}: a radius is not negative")));
                    }
                    self.sppm.radius = (r > 0.0).then_some(r);
                }
                "photonCount" | "photon_count" => {
                    let n = self.integer(p)?;
                    let n = u32::try_from(n).ok().filter(|n| *n > 0).ok_or_else(|| {
                        self.err(p, format!("{n}: must be a positive photon count"))
                    })?;
                    self.sppm.photons = Some(n);
                }
                "alpha" => {
                    let a = self.number(p, "value")?;
                    if !(a > 0.0 && a < 1.0) {
                        return Err(self.err(p, format!("{a}: must be in (0, 1)")));
                    }
                    self.sppm.alpha = Some(a);
                }
                "maxPasses" | "max_passes" => {
                    let n = self.integer(p)?;
                    if n != -1 {
                        let n = u32::try_from(n).ok().filter(|n| *n > 0).ok_or_else(|| {
                            self.err(p, format!("{n}: must be -1 or a positive pass count"))
                        })?;
                        self.sppm.passes = Some(n);
                    }
                }
                // maxDepth, rrDepth, granularity (see SppmSettings).
                _ => {}
            }
        }
        Ok(())
    }

    /// A BSDF, and the texture on its colour: a reflectance given by a `bitmap` (a
    /// `diffuse`'s `reflectance`, a `plastic`'s or `roughplastic`'s `diffuse_reflectance`, a
    /// `conductor`'s or `roughconductor`'s `specular_reflectance`; the colour then 1).
    fn bsdf(&self, node: Node) -> Result<(MaterialKind, Option<Arc<Texture>>)> {
        let ty = self.required(node, "type")?;
        let elements: Vec<Node> = node.children().filter(Node::is_element).collect();
        if let ([inner], "twosided") = (elements.as_slice(), ty.as_str())
            && inner.tag_name().name() == "bsdf"
        {
            return self.bsdf(*inner);
        }
        let reflectance = match ty.as_str() {
            "diffuse" => "reflectance",
            "plastic" | "roughplastic" => "diffuse_reflectance",
            "conductor" | "roughconductor" => "specular_reflectance",
            _ => return Ok((self.bsdf_kind(node, None)?, None)),
        };
        let named = |p: &Node| p.attribute("name") == Some(reflectance);
        let Some(bitmap) = elements
            .iter()
            .copied()
            .find(|p| p.tag_name().name() == "texture" && named(p))
        else {
            return Ok((self.bsdf_kind(node, None)?, None));
        };
        if let Some(other) = elements.iter().find(|p| **p != bitmap && named(p)) {
            return Err(self.err(
                *other,
                format!("a second {reflectance}: the bitmap gives it"),
            ));
        }
        let kind = self.bsdf_kind(node, Some(bitmap))?.white_under_texture();
        Ok((kind, Some(self.bitmap(bitmap)?)))
    }

    /// Mitsuba 3's `bitmap` texture: `filename`, `filter_type`, `wrap_mode` (repeat), `raw`,
    /// and a `to_uv` of scales and translations. Mitsuba's `v = 0` is the image's top row,
    /// ours the bottom: `(s, t) = (u', 1 - v')` of its mapped `(u', v')`.
    fn bitmap(&self, node: Node) -> Result<Arc<Texture>> {
        if self.required(node, "type")? != "bitmap" {
            return Err(self.err(node, format!("{SUBSET}: only bitmap textures")));
        }
        let mut options = ImageOptions::default();
        let (mut file, mut raw, mut to_uv) = (None, false, DMat4::IDENTITY);
        for p in node.children().filter(Node::is_element) {
            match (p.tag_name().name(), p.attribute("name").unwrap_or_default()) {
                ("string", "filename") => file = Some((p, self.required(p, "value")?)),
                ("string", "filter_type") => {
                    options.filter = match self.required(p, "value")?.as_str() {
                        "bilinear" => TextureFilter::Bilinear,
                        "nearest" => TextureFilter::Nearest,
                        other => return Err(self.err(p, format!("filter \"{other}\" is unknown"))),
                    }
                }
                ("string", "wrap_mode") => {
                    let mode = self.required(p, "value")?;
                    if mode != "repeat" {
                        return Err(
                            self.err(p, format!("wrap mode \"{mode}\" is {SUBSET} (repeat)"))
                        );
                    }
                }
                ("boolean", "raw") => raw = self.boolean(p)?,
                ("transform", "to_uv") => to_uv = self.transform(p)?.0,
                _ => return Err(self.err(p, "unknown parameter of a bitmap texture")),
            }
        }
        if raw {
            options.encoding = Encoding::Linear;
        }
        let (a, d) = (to_uv.x_axis.x, to_uv.y_axis.y);
        let (tx, ty) = (to_uv.w_axis.x, to_uv.w_axis.y);
        if to_uv.x_axis.y != 0.0 || to_uv.y_axis.x != 0.0 {
            return Err(self.err(node, format!("a rotated or sheared to_uv is {SUBSET}")));
        }
        let (p, name) = file.ok_or_else(|| self.err(node, "the bitmap has no filename"))?;
        let mut texture =
            read_texture(&self.base.join(&name), options).map_err(|e| self.err(p, e))?;
        texture.scale = Vec2::new(a as f32, -d as f32);
        texture.offset = Vec2::new(tx as f32, (1.0 - ty) as f32);
        Ok(Arc::new(texture))
    }

    /// A BSDF's kind from its parameters, leaving out `texture` (a bitmap [`Self::bsdf`]
    /// reads).
    fn bsdf_kind(&self, node: Node, texture: Option<Node>) -> Result<MaterialKind> {
        let ty = self.required(node, "type")?;
        let params: Vec<Node> = node
            .children()
            .filter(|n| n.is_element() && Some(*n) != texture)
            .collect();
        let named = |n: &Node, name: &str| n.attribute("name") == Some(name);
        match ty.as_str() {
            "twosided" => {
                let inner: Vec<Node> = params
                    .iter()
                    .copied()
                    .filter(|n| n.tag_name().name() == "bsdf")
                    .collect();
                if params.len() != inner.len() || inner.is_empty() {
                    return Err(self.err(node, "a twosided BSDF holds one <bsdf>"));
                }
                if inner.len() > 1 {
                    return Err(self.err(
                        node,
                        format!("different BSDFs on the two sides are {SUBSET}"),
                    ));
                }
                self.bsdf_kind(inner[0], None)
            }
            "diffuse" => {
                let mut albedo = Vec3::splat(0.5);
                for p in &params {
                    if named(p, "reflectance") {
                        albedo = self.colour(*p, Some(1.0))?;
                    } else {
                        return Err(self.err(*p, "unknown parameter of a diffuse BSDF"));
                    }
                }
                Ok(MaterialKind::Diffuse { albedo })
            }
            "conductor" | "roughconductor" => {
                let rough = ty == "roughconductor";
                let mut reflectance = Vec3::ONE;
                let (mut eta, mut k) = (None, None);
                let mut microfacet = Microfacet::default();
                for p in &params {
                    if named(p, "specular_reflectance") {
                        reflectance = self.colour(*p, Some(1.0))?;
                    } else if named(p, "material") {
                        let m = self.required(*p, "value")?;
                        if m != "none" {
                            return Err(self.err(*p, format!(
                                "a named conductor preset is {SUBSET}: give material=\"none\" (a perfect mirror) or rgb eta and k"
                            )));
                        }
                    } else if named(p, "eta") {
                        eta = Some(self.colour(*p, None)?);
                    } else if named(p, "k") {
                        k = Some(self.colour(*p, None)?);
                    } else if !(rough && self.microfacet(*p, &mut microfacet)?) {
                        return Err(self.err(*p, format!("unknown parameter of a {ty}")));
                    }
                }
                let (alpha, alpha_v) = self.ggx_alphas(rough, node, &ty, &microfacet)?;
                match (eta, k) {
                    (None, None) if !rough => Ok(MaterialKind::Mirror { reflectance }),
                    // Mitsuba's material "none": a lossless metal, Fresnel factor one.
                    (None, None) => Ok(MaterialKind::Conductor {
                        eta: Vec3::ZERO,
                        k: Vec3::ONE,
                        reflectance,
                        alpha,
                        alpha_v,
                    }),
                    (Some(eta), Some(k)) => Ok(MaterialKind::Conductor {
                        eta,
                        k,
                        reflectance,
                        alpha,
                        alpha_v,
                    }),
                    _ => Err(self.err(node, "a conductor needs both eta and k, or neither")),
                }
            }
            // Mitsuba 3's plastic: a diffuse base under a smooth (or GGX-rough) dielectric
            // coat of index int_ior / ext_ior, polypropylene in air by default.
            "plastic" | "roughplastic" => {
                let rough = ty == "roughplastic";
                let mut albedo = Vec3::splat(0.5);
                let (mut int_ior, mut ext_ior) = (1.49f32, 1.000277f32);
                let mut nonlinear = false;
                let mut microfacet = Microfacet::default();
                for p in &params {
                    if named(p, "diffuse_reflectance") {
                        albedo = self.colour(*p, Some(1.0))?;
                    } else if named(p, "specular_reflectance") {
                        if self.colour(*p, None)? != Vec3::ONE {
                            return Err(self.err(
                                *p,
                                format!("a specular_reflectance other than 1 (a tinted coat) is {SUBSET}"),
                            ));
                        }
                    } else if named(p, "int_ior") || named(p, "ext_ior") {
                        let v = self.ior(*p)?;
                        if named(p, "int_ior") {
                            int_ior = v
                        } else {
                            ext_ior = v
                        }
                    } else if named(p, "nonlinear") {
                        nonlinear = self.boolean(*p)?;
                    } else if !(rough && self.microfacet(*p, &mut microfacet)?) {
                        return Err(self.err(*p, format!("unknown parameter of a {ty}")));
                    }
                }
                let (alpha, alpha_v) = self.ggx_alphas(rough, node, &ty, &microfacet)?;
                if alpha != alpha_v {
                    return Err(self.err(
                        node,
                        format!("anisotropic roughness (alpha_u {alpha}, alpha_v {alpha_v}) on a {ty} is {SUBSET}: ours is isotropic"),
                    ));
                }
                let ior = ior_ratio(int_ior, ext_ior);
                if ior <= 1.0 || !ior.is_finite() {
                    return Err(self.err(
                        node,
                        format!(
                            "int_ior / ext_ior = {int_ior} / {ext_ior} = {ior}: a coat's index must exceed the outside's"
                        ),
                    ));
                }
                Ok(MaterialKind::Coated {
                    albedo,
                    ior,
                    alpha,
                    nonlinear,
                })
            }
            // Mitsuba 3's dielectric: smooth (or GGX-rough) glass of index int_ior / ext_ior,
            // BK7 in air by default.
            "dielectric" | "roughdielectric" => {
                let rough = ty == "roughdielectric";
                let (mut int_ior, mut ext_ior) = (1.5046f32, 1.000277f32);
                let mut microfacet = Microfacet::default();
                for p in &params {
                    if named(p, "int_ior") || named(p, "ext_ior") {
                        let v = self.ior(*p)?;
                        if named(p, "int_ior") {
                            int_ior = v
                        } else {
                            ext_ior = v
                        }
                    } else if named(p, "specular_reflectance") || named(p, "specular_transmittance")
                    {
                        if self.colour(*p, None)? != Vec3::ONE {
                            let name = p.attribute("name").unwrap_or_default();
                            return Err(self.err(
                                *p,
                                format!("a {name} other than 1 (a tinted {ty}) is {SUBSET}"),
                            ));
                        }
                    } else if !(rough && self.microfacet(*p, &mut microfacet)?) {
                        return Err(self.err(*p, format!("unknown parameter of a {ty}")));
                    }
                }
                let (alpha, alpha_v) = self.ggx_alphas(rough, node, &ty, &microfacet)?;
                let ior = ior_ratio(int_ior, ext_ior);
                Ok(MaterialKind::Glass {
                    ior,
                    alpha,
                    alpha_v,
                })
            }
            _ => Err(self.err(
                node,
                format!(
                    "{SUBSET} (diffuse, conductor, roughconductor, plastic, roughplastic, dielectric, roughdielectric, twosided)"
                ),
            )),
        }
    }

    /// Reads `p` into `m` if it is a microfacet parameter of a rough BSDF (`distribution`,
    /// `alpha`, `alpha_u`, `alpha_v`, `sample_visible`); false if it is none of them.
    fn microfacet(&self, p: Node, m: &mut Microfacet) -> Result<bool> {
        let named = |name: &str| p.attribute("name") == Some(name);
        if named("distribution") {
            let d = self.required(p, "value")?;
            if d != "ggx" {
                return Err(self.err(
                    p,
                    format!("the {d} distribution is {SUBSET}: give distribution=\"ggx\""),
                ));
            }
            m.ggx = true;
        } else if named("alpha") || named("alpha_u") || named("alpha_v") {
            let a = self.number(p, "value")?;
            if !(0.0..=1.0).contains(&a) {
                return Err(self.err(p, format!("{a}: must be in [0, 1] (GGX roughness)")));
            }
            let slot = match p.attribute("name") {
                Some("alpha_u") => &mut m.alpha_u,
                Some("alpha_v") => &mut m.alpha_v,
                _ => &mut m.alpha,
            };
            *slot = Some(a);
        } else if !named("sample_visible") {
            // sample_visible is a sampling strategy: the image is the same either way.
            return Ok(false);
        }
        Ok(true)
    }

    /// The GGX roughness of the BSDF `node` (of type `ty`) along and across the surface's
    /// tangent: 0 unless it is `rough`; else from the microfacet parameters read into `m`,
    /// `alpha` for both where given, else `alpha_u` and `alpha_v`, each Mitsuba's default
    /// 0.1 where not given. Without `distribution="ggx"` the distribution is Beckmann's
    /// (Mitsuba's default), refused.
    fn ggx_alphas(&self, rough: bool, node: Node, ty: &str, m: &Microfacet) -> Result<(f32, f32)> {
        if !rough {
            return Ok((0.0, 0.0));
        }
        if !m.ggx {
            return Err(self.err(
                node,
                format!(
                    "a {ty} without distribution=\"ggx\" is Beckmann's (Mitsuba's default), {SUBSET}"
                ),
            ));
        }
        Ok(match m.alpha {
            Some(alpha) => (alpha, alpha),
            None => (m.alpha_u.unwrap_or(0.1), m.alpha_v.unwrap_or(0.1)),
        })
    }

    /// An index of refraction, a number or one of Mitsuba's named materials.
    fn ior(&self, node: Node) -> Result<f32> {
        let text = self.required(node, "value")?;
        if node.tag_name().name() == "float" {
            let v = self.number(node, "value")?;
            if v > 0.0 {
                return Ok(v);
            }
            return Err(self.err(node, "must be a positive number"));
        }
        const NAMED: &[(&str, f32)] = &[
            ("vacuum", 1.0),
            ("air", 1.000277),
            ("water", 1.333),
            ("water ice", 1.31),
            ("fused quartz", 1.458),
            ("pyrex", 1.47),
            ("acrylic glass", 1.49),
            ("polypropylene", 1.49),
            ("bk7", 1.5046),
            ("sodium chloride", 1.544),
            ("amber", 1.55),
            ("pet", 1.575),
            ("diamond", 2.419),
        ];
        NAMED
            .iter()
            .find(|(n, _)| *n == text.to_lowercase())
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                self.err(
                    node,
                    format!("\"{text}\" is not a number or a known material"),
                )
            })
    }

    fn shape(&mut self, node: Node) -> Result<()> {
        let ty = self.required(node, "type")?;
        if !matches!(ty.as_str(), "obj" | "ply" | "rectangle" | "cube") {
            return Err(self.err(node, format!("{SUBSET} (obj, ply, rectangle, cube)")));
        }
        let mut filename = None;
        let (mut face_normals, mut flip) = (false, false);
        let mut to_world = None;
        let mut surface = None;
        let mut emission = None;
        for p in node.children().filter(Node::is_element) {
            match (p.tag_name().name(), p.attribute("name")) {
                ("string", Some("filename")) if ty == "obj" || ty == "ply" => {
                    filename = Some((p, self.required(p, "value")?));
                }
                ("boolean", Some("face_normals")) => face_normals = self.boolean(p)?,
                ("boolean", Some("flip_normals")) => flip = self.boolean(p)?,
                ("transform", Some("to_world")) => to_world = Some(self.transform(p)?.0),
                ("ref", _) => {
                    let id = self.required(p, "id")?;
                    let index = *self.bsdfs.get(&id).ok_or_else(|| {
                        self.err(p, format!("no <bsdf id=\"{id}\"> before this shape"))
                    })?;
                    surface = Some(index);
                }
                ("bsdf", _) => {
                    let (kind, texture) = self.bsdf(p)?;
                    let name = format!("{}-bsdf", node.attribute("id").unwrap_or("shape"));
                    surface = Some(self.builder.declare_textured(&name, kind, texture));
                }
                ("emitter", _) => {
                    if self.required(p, "type")? != "area" {
                        return Err(self.err(p, format!("{SUBSET}: only area emitters")));
                    }
                    let mut radiance = None;
                    for q in p.children().filter(Node::is_element) {
                        if q.attribute("name") == Some("radiance") {
                            radiance = Some(self.radiance(q)?);
                        } else {
                            return Err(self.err(q, "unknown parameter of an area emitter"));
                        }
                    }
                    emission = Some(
                        radiance.ok_or_else(|| self.err(p, "the area emitter has no radiance"))?,
                    );
                }
                _ => return Err(self.err(p, format!("unknown parameter of a {ty} shape"))),
            }
        }
        let mut mesh = match ty.as_str() {
            "rectangle" => unit_rectangle(),
            "cube" => unit_cube(),
            _ => {
                let (p, name) =
                    filename.ok_or_else(|| self.err(node, "the shape has no filename"))?;
                let path = self.base.join(&name);
                let read = if ty == "obj" {
                    read_obj(&path)
                } else {
                    read_ply(&path)
                };
                read.map_err(|e| self.err(p, e))?
            }
        };
        if face_normals {
            mesh.normals = None;
        }
        // Mitsuba's rectangle and cube keep their authored normals through a mirroring
        // transform (they are transformed as normals); our winding follows suit.
        let analytic = ty == "rectangle" || ty == "cube";
        let plain_flip = flip ^ (analytic && swaps_handedness(to_world));
        let to_world = to_world.filter(|m| *m != DMat4::IDENTITY);
        let (triangles, uvs) = mesh_triangles(&mesh, to_world, plain_flip, flip);
        if triangles.iter().flatten().any(|v| !v.is_finite()) {
            return Err(self.err(node, "a vertex is not finite"));
        }
        let surface = match surface {
            Some(s) => s,
            None => *self.default_material.get_or_insert_with(|| {
                self.builder.declare(
                    "default",
                    MaterialKind::Diffuse {
                        albedo: Vec3::splat(0.5),
                    },
                )
            }),
        };
        if self.builder.materials[surface].texture.is_some() && uvs.is_empty() {
            return Err(self.err(
                node,
                format!("a textured shape without texture coordinates is {SUBSET}"),
            ));
        }
        let material = self
            .builder
            .material_for(surface, emission)
            .map_err(|problem| self.err(node, problem))?;
        let name = node.attribute("id").map_or_else(
            || format!("shape-{}", self.builder.objects.len()),
            str::to_owned,
        );
        self.builder.objects.push(Object {
            name,
            material,
            triangles,
            uvs,
        });
        Ok(())
    }
}

/// An element as a reader finds it in the file: its tag and identifying attributes.
fn describe(node: Node) -> String {
    let mut s = format!("<{}", node.tag_name().name());
    for a in ["type", "id", "name", "value"] {
        if let Some(v) = node.attribute(a) {
            s.push_str(&format!(" {a}=\"{v}\""));
        }
    }
    s.push('>');
    s
}

/// The index Mitsuba's `int_ior` and `ext_ior` make, `int / ext`; `int` itself in air of
/// index one, so that it keeps its bits.
fn ior_ratio(int_ior: f32, ext_ior: f32) -> f32 {
    if ext_ior == 1.0 {
        int_ior
    } else {
        int_ior / ext_ior
    }
}
