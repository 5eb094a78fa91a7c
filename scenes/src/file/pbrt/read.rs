//! Reads the subset of pbrt-v4's scene format that we can render.

use super::lexer::{Param, Token, tokenize};
use crate::file::bands;
use crate::file::interop::{
    SceneBuilder, camera_pose, look_at, mesh_triangles, sphere_mesh, swaps_handedness,
};
use crate::file::mesh::{MeshData, read_ply};
use crate::file::scene_file::SceneSource;
use crate::file::texture_image::{Encoding, ImageOptions, read_texture};
use glam::{DMat4, DQuat, DVec3, Vec2, Vec3};
use ppm_core::scene::{Camera, MaterialKind, Object};
use ppm_core::scene::{MAX_COORDINATE, RenderDefaults, Scene};
use ppm_core::scene::{SceneError, Texture, TextureFilter};
use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::sync::Arc;

/// Reads a pbrt-v4 scene file; PLY file names are relative to its folder.
pub fn load_pbrt_file(path: &Path) -> std::result::Result<Scene, SceneError> {
    let s = SceneSource::read(path)?;
    parse_pbrt(&s.text, &s.file, &s.base, &s.name)
}

/// Parses pbrt-v4 scene text. `file` names the source in errors, `base` resolves PLY files,
/// `name` names the scene.
pub fn parse_pbrt(
    text: &str,
    file: &str,
    base: &Path,
    name: &str,
) -> std::result::Result<Scene, SceneError> {
    let tokens = tokenize(text).map_err(|(line, problem)| SceneError::At {
        file: file.to_owned(),
        line,
        element: "string".into(),
        problem,
    })?;
    let mut reader = Reader {
        file,
        base,
        builder: SceneBuilder::new(file),
        state: State::default(),
        stack: Vec::new(),
        named: HashMap::new(),
        coordinate_systems: HashMap::new(),
        default_material: None,
        camera: None,
        resolution: (1280, 720),
        sppm: SppmSettings::default(),
        textures: HashMap::new(),
        float_textures: HashSet::new(),
    };
    let mut i = 0;
    while i < tokens.len() {
        let (token, line) = &tokens[i];
        let Token::Word(directive) = token else {
            return Err(reader.at(*line, &format!("{token:?}"), "expected a directive here"));
        };
        let mut end = i + 1;
        while end < tokens.len()
            && !matches!(&tokens[end].0, Token::Word(w) if w != "true" && w != "false")
        {
            end += 1;
        }
        let args = &tokens[i + 1..end];
        reader.directive(directive, *line, args)?;
        i = end;
    }
    if let Some((line, _)) = reader.stack.last() {
        return Err(reader.at(*line, "AttributeBegin", "has no AttributeEnd"));
    }
    let Some(camera) = reader.camera.take() else {
        return Err(SceneError::invalid(
            file,
            "Camera",
            "none",
            "the scene has no Camera \"perspective\"",
        ));
    };
    let (camera, mirrored) = reader.camera_model(camera)?;
    let (sppm, resolution) = (reader.sppm, reader.resolution);
    let mut scene = reader.builder.finish(name, camera, mirrored)?;
    sppm.apply(&mut scene.render, resolution);
    Ok(scene)
}

/// The settings of an `Integrator "sppm"` that mean what ours mean: its initial search
/// radius, photons per iteration and iterations (pbrt-v4's `SPPMIntegrator`). Its `maxdepth`
/// counts every bounce of a path, where ours bound eye paths through mirrors and glass and
/// photon paths apart, and is not taken.
#[derive(Default)]
struct SppmSettings {
    radius: Option<f32>,
    photons_per_iteration: Option<PhotonsPerIteration>,
    iterations: Option<u32>,
}

/// pbrt's `photonsperiteration`: a count, or -1 (its default) for one per pixel.
#[derive(Clone, Copy)]
enum PhotonsPerIteration {
    Count(u32),
    PerPixel,
}

impl SppmSettings {
    /// Makes these the scene's render defaults; `resolution` is the film's, for one photon
    /// per pixel.
    fn apply(&self, render: &mut RenderDefaults, resolution: (u32, u32)) {
        if let Some(r) = self.radius {
            render.initial_radius = r;
        }
        match self.photons_per_iteration {
            Some(PhotonsPerIteration::Count(n)) => render.photons_per_pass = n,
            Some(PhotonsPerIteration::PerPixel) => {
                render.photons_per_pass = resolution.0.saturating_mul(resolution.1).max(1);
            }
            None => {}
        }
        if let Some(n) = self.iterations {
            render.passes = n;
        }
    }
}

/// How the current transform was built: pbrt's usual camera set-up (`Scale -1 1 1` and
/// `LookAt`) is kept as written so the camera is read back exactly.
#[derive(Clone, Copy, Default, PartialEq)]
enum Built {
    #[default]
    Identity,
    Flip,
    LookAt {
        flip: bool,
        eye: Vec3,
        target: Vec3,
        up: Vec3,
    },
    Other,
}

#[derive(Clone, Default)]
struct State {
    ctm: DMat4,
    built: Built,
    material: Option<usize>,
    emission: Option<Vec3>,
    reverse: bool,
}

struct CameraDirective {
    line: u32,
    ctm: DMat4,
    built: Built,
    fov: f32,
    window: Option<[f32; 4]>,
}

struct Reader<'a> {
    file: &'a str,
    base: &'a Path,
    builder: SceneBuilder,
    state: State,
    /// Saved states with the line of their `AttributeBegin`.
    stack: Vec<(u32, State)>,
    named: HashMap<String, usize>,
    coordinate_systems: HashMap<String, DMat4>,
    default_material: Option<usize>,
    camera: Option<CameraDirective>,
    resolution: (u32, u32),
    sppm: SppmSettings,
    /// `Texture "name" "spectrum"` by name, read when declared.
    textures: HashMap<String, Arc<Texture>>,
    /// `Texture "name" "float"`: declared, refused where a material uses one.
    float_textures: HashSet<String>,
}

type Result<T> = std::result::Result<T, SceneError>;

const SUBSET: &str = "outside the subset ppm renders";

fn word(t: &Token) -> String {
    match t {
        Token::Word(s) | Token::Number(s) => s.clone(),
        Token::Str(s) => format!("\"{s}\""),
        Token::Open => "[".into(),
        Token::Close => "]".into(),
    }
}

impl Reader<'_> {
    fn at(&self, line: u32, element: &str, problem: impl Into<String>) -> SceneError {
        SceneError::At {
            file: self.file.to_owned(),
            line,
            element: element.to_owned(),
            problem: problem.into(),
        }
    }

    fn directive(&mut self, name: &str, line: u32, args: &[(Token, u32)]) -> Result<()> {
        let first_string = args.iter().find_map(|(t, _)| match t {
            Token::Str(s) => Some(s.clone()),
            _ => None,
        });
        let element = match &first_string {
            Some(s) => format!("{name} \"{s}\""),
            None => name.to_owned(),
        };
        let d = Directive {
            reader: self.file,
            name: element,
            line,
            args,
        };
        match name {
            "Identity" => self.set(DMat4::IDENTITY, Built::Identity),
            "Translate" => {
                let v = d.numbers(3)?;
                self.apply(DMat4::from_translation(dvec(&v)), Built::Other);
            }
            "Scale" => {
                let v = d.numbers(3)?;
                let built = if v == [-1.0, 1.0, 1.0] && self.state.built == Built::Identity {
                    Built::Flip
                } else {
                    Built::Other
                };
                self.apply(DMat4::from_scale(dvec(&v)), built);
            }
            "Rotate" => {
                let v = d.numbers(4)?;
                let axis = dvec(&v[1..])
                    .try_normalize()
                    .ok_or_else(|| d.err("the rotation axis is zero"))?;
                let r = DQuat::from_axis_angle(axis, f64::from(v[0]).to_radians());
                self.apply(DMat4::from_quat(r), Built::Other);
            }
            "LookAt" => {
                let v = d.numbers(9)?;
                let (eye, target, up) = (vec(&v[0..3]), vec(&v[3..6]), vec(&v[6..9]));
                let world_from_camera = look_at(eye.as_dvec3(), target.as_dvec3(), up.as_dvec3())
                    .ok_or_else(|| {
                    d.err("the eye equals the look-at point, or up is parallel to the view")
                })?;
                let built = match self.state.built {
                    Built::Identity => Built::LookAt {
                        flip: false,
                        eye,
                        target,
                        up,
                    },
                    Built::Flip => Built::LookAt {
                        flip: true,
                        eye,
                        target,
                        up,
                    },
                    _ => Built::Other,
                };
                self.apply(world_from_camera.inverse(), built);
            }
            "Transform" | "ConcatTransform" => {
                let v = d.numbers(16)?;
                let m: [f64; 16] = std::array::from_fn(|k| f64::from(v[k]));
                let m = DMat4::from_cols_array(&m);
                if name == "Transform" {
                    self.set(m, Built::Other);
                } else {
                    self.apply(m, Built::Other);
                }
            }
            "CoordinateSystem" => {
                let n = d.string(0)?;
                self.coordinate_systems.insert(n, self.state.ctm);
            }
            "CoordSysTransform" => {
                let n = d.string(0)?;
                let m = *self
                    .coordinate_systems
                    .get(&n)
                    .ok_or_else(|| d.err(format!("no coordinate system \"{n}\"")))?;
                self.set(m, Built::Other);
            }
            "ReverseOrientation" => self.state.reverse = !self.state.reverse,
            "AttributeBegin" | "TransformBegin" => self.stack.push((line, self.state.clone())),
            "AttributeEnd" | "TransformEnd" => {
                let (_, saved) = self
                    .stack
                    .pop()
                    .ok_or_else(|| d.err("has no AttributeBegin"))?;
                if name == "AttributeEnd" {
                    self.state = saved;
                } else {
                    (self.state.ctm, self.state.built) = (saved.ctm, saved.built);
                }
            }
            "Camera" => self.camera_directive(&d)?,
            "Film" => {
                for p in d.params(1)? {
                    match p.name.as_str() {
                        "xresolution" => self.resolution.0 = d.positive(&p)?,
                        "yresolution" => self.resolution.1 = d.positive(&p)?,
                        "cropwindow" | "pixelbounds" => {
                            return Err(d.param_err(&p, format!("a cropped film is {SUBSET}")));
                        }
                        // File name, sensor, white balance: how the image is stored.
                        _ => {}
                    }
                }
            }
            "Integrator" => self.integrator(&d)?,
            "Sampler" | "PixelFilter" | "Accelerator" | "ColorSpace" | "Option" => {}
            "WorldBegin" => self.set(DMat4::IDENTITY, Built::Identity),
            "WorldEnd" => {}
            "Material" => {
                let ty = d.string(0)?;
                let (kind, texture) = self.material(&d, &ty, &d.params(1)?)?;
                let index =
                    self.builder
                        .declare_textured(&format!("material-{line}"), kind, texture);
                self.state.material = Some(index);
            }
            "MakeNamedMaterial" => {
                let n = d.string(0)?;
                let params = d.params(1)?;
                let ty = params
                    .iter()
                    .find(|p| p.name == "type" && p.ty == "string")
                    .ok_or_else(|| d.err("has no \"string type\""))?;
                let ty = d.one_string(ty)?;
                let rest: Vec<Param> = params.into_iter().filter(|p| p.name != "type").collect();
                let (kind, texture) = self.material(&d, &ty, &rest)?;
                let index = self.builder.declare_textured(&n, kind, texture);
                self.named.insert(n, index);
            }
            "NamedMaterial" => {
                let n = d.string(0)?;
                let index = *self
                    .named
                    .get(&n)
                    .ok_or_else(|| d.err(format!("no MakeNamedMaterial \"{n}\" before it")))?;
                self.state.material = Some(index);
            }
            "AreaLightSource" => self.area_light(&d)?,
            "Shape" => self.shape(&d)?,
            "LightSource" => {
                return Err(d.err(format!(
                    "{SUBSET}: light comes only from AreaLightSource \"diffuse\" on shapes"
                )));
            }
            "Texture" => self.texture(&d)?,
            "MakeNamedMedium" | "MediumInterface" | "ObjectBegin" | "ObjectEnd"
            | "ObjectInstance" | "Include" | "Import" | "Attribute" | "ActiveTransform"
            | "TransformTimes" => return Err(d.err(SUBSET)),
            _ => return Err(d.err("unknown directive")),
        }
        Ok(())
    }

    fn set(&mut self, m: DMat4, built: Built) {
        self.state.ctm = m;
        self.state.built = built;
    }

    /// pbrt post-multiplies: a directive acts on the object before those written above it.
    fn apply(&mut self, m: DMat4, built: Built) {
        self.state.ctm *= m;
        self.state.built = built;
    }

    /// Reads an `Integrator "sppm"`'s settings that mean what ours do ([`SppmSettings`]);
    /// another integrator's settings are another method's, and are ignored.
    fn integrator(&mut self, d: &Directive) -> Result<()> {
        if d.string(0)? != "sppm" {
            return Ok(());
        }
        for p in d.params(1)? {
            match p.name.as_str() {
                "radius" => {
                    let r = d.float(&p)?;
                    if !(r.is_finite() && r > 0.0 && r <= MAX_COORDINATE) {
                        return Err(d.param_err(
                            &p,
                            format!("{r} is not a radius in (0, {MAX_COORDINATE:e}]"),
                        ));
                    }
                    self.sppm.radius = Some(r);
                }
                "photonsperiteration" => {
                    let count = match d.float(&p)? {
                        -1.0 => PhotonsPerIteration::PerPixel,
                        _ => PhotonsPerIteration::Count(d.positive(&p)?),
                    };
                    self.sppm.photons_per_iteration = Some(count);
                }
                "iterations" | "numiterations" => self.sppm.iterations = Some(d.positive(&p)?),
                // maxdepth (see SppmSettings), seed, imagewritefrequency.
                _ => {}
            }
        }
        Ok(())
    }

    fn camera_directive(&mut self, d: &Directive) -> Result<()> {
        let ty = d.string(0)?;
        if ty != "perspective" {
            return Err(d.err(format!("{SUBSET}: only a perspective (pinhole) camera")));
        }
        let mut fov = 90.0;
        let mut window = None;
        for p in d.params(1)? {
            match p.name.as_str() {
                "fov" => fov = d.float(&p)?,
                "screenwindow" => {
                    let v = d.floats(&p)?;
                    window = Some(
                        <[f32; 4]>::try_from(v.as_slice())
                            .map_err(|_| d.param_err(&p, "must have 4 numbers"))?,
                    );
                }
                "lensradius" if d.float(&p)? == 0.0 => {}
                "focaldistance" | "shutteropen" | "shutterclose" | "frameaspectratio" => {}
                _ => return Err(d.param_err(&p, "unknown parameter of a perspective camera, or one outside the subset ppm renders")),
            }
        }
        if !(fov > 0.0 && fov < 180.0) {
            return Err(d.err(format!(
                "fov = {fov}: must lie strictly between 0 and 180 degrees"
            )));
        }
        self.coordinate_systems
            .insert("camera".into(), self.state.ctm.inverse());
        self.camera = Some(CameraDirective {
            line: d.line,
            ctm: self.state.ctm,
            built: self.state.built,
            fov,
            window,
        });
        Ok(())
    }

    /// Our camera from pbrt's: pbrt's `fov` spans the shorter image side (or the screen
    /// window's unit extent); its camera space is left-handed, so a camera without a
    /// mirroring transform sees the world mirrored relative to ours.
    fn camera_model(&self, c: CameraDirective) -> Result<(Camera, bool)> {
        let (width, height) = self.resolution;
        let here = |p: &str| self.at(c.line, "Camera \"perspective\"", p.to_owned());
        let aspect = width as f32 / height as f32;
        let y1 = match c.window {
            Some([x0, x1, y0, y1]) => {
                if x0 != -x1 || y0 != -y1 || x1 <= 0.0 || y1 <= 0.0 {
                    return Err(here(
                        "an off-centre or empty screenwindow is outside the subset ppm renders",
                    ));
                }
                if ((x1 / y1) / aspect - 1.0).abs() > 1e-4 {
                    return Err(here(
                        "a screenwindow whose shape is not the image's stretches the image: outside the subset ppm renders",
                    ));
                }
                y1
            }
            None if aspect >= 1.0 => 1.0,
            None => 1.0 / aspect,
        };
        let fov_deg = if y1 == 1.0 {
            c.fov
        } else {
            let half = (f64::from(c.fov).to_radians() * 0.5).tan() * f64::from(y1);
            (2.0 * half.atan()).to_degrees() as f32
        };
        let (eye, target, up, mirrored) = match c.built {
            Built::LookAt {
                flip,
                eye,
                target,
                up,
            } => (eye, target, up, !flip),
            _ => camera_pose(c.ctm.inverse(), false)
                .ok_or_else(|| here("the camera transform is singular"))?,
        };
        Ok((
            Camera {
                eye,
                look_at: target,
                up,
                fov_deg,
                width,
                height,
            },
            mirrored,
        ))
    }

    /// A `Texture` directive: a spectrum `imagemap` (read now) or 2D `checkerboard` with
    /// `uv` mapping; a float texture is noted, and refused where a material uses it.
    fn texture(&mut self, d: &Directive) -> Result<()> {
        let name = d.string(0)?;
        let ty = d.string(1)?;
        let class = d.string(2)?;
        match ty.as_str() {
            "float" => {
                self.float_textures.insert(name);
                return Ok(());
            }
            "spectrum" | "color" => {}
            _ => return Err(d.err(format!("texture type \"{ty}\" is unknown"))),
        }
        let mut options = ImageOptions::default();
        let (mut scale, mut offset) = (Vec2::ONE, Vec2::ZERO);
        let (mut filename, mut even, mut odd) = (None, Vec3::ONE, Vec3::ZERO);
        for p in d.params(3)? {
            match (class.as_str(), p.name.as_str()) {
                (_, "uscale") => scale.x = d.float(&p)?,
                (_, "vscale") => scale.y = d.float(&p)?,
                (_, "udelta") => offset.x = d.float(&p)?,
                (_, "vdelta") => offset.y = d.float(&p)?,
                (_, "mapping") => {
                    let m = d.one_string(&p)?;
                    if m != "uv" {
                        return Err(d.param_err(&p, format!("mapping \"{m}\" is {SUBSET} (uv)")));
                    }
                }
                ("imagemap", "filename") => filename = Some(d.one_string(&p)?),
                ("imagemap", "filter") => {
                    // Without MIP maps, trilinear and EWA lookups are bilinear ones.
                    options.filter = match d.one_string(&p)?.as_str() {
                        "point" => TextureFilter::Nearest,
                        "bilinear" | "trilinear" | "ewa" | "EWA" => TextureFilter::Bilinear,
                        other => {
                            return Err(d.param_err(&p, format!("filter \"{other}\" is unknown (point, bilinear, trilinear, ewa)")));
                        }
                    }
                }
                ("imagemap", "encoding") => {
                    let e = d.one_string(&p)?;
                    options.encoding = match e.as_str() {
                        "sRGB" => Encoding::Srgb,
                        "linear" => Encoding::Linear,
                        g => match g.strip_prefix("gamma ").map(str::parse::<f32>) {
                            Some(Ok(gamma)) if gamma > 0.0 => Encoding::Gamma(gamma),
                            _ => {
                                return Err(d.param_err(
                                    &p,
                                    format!("encoding \"{e}\" is unknown (sRGB, linear, gamma G)"),
                                ));
                            }
                        },
                    }
                }
                ("imagemap", "scale") => options.scale = d.float(&p)?,
                ("imagemap", "invert") => options.invert = d.boolean(&p)?,
                ("imagemap", "wrap") => {
                    let w = d.one_string(&p)?;
                    if w != "repeat" {
                        return Err(d.param_err(&p, format!("wrap \"{w}\" is {SUBSET} (repeat)")));
                    }
                }
                ("imagemap", "maxanisotropy") => {}
                ("checkerboard", "tex1") => even = d.colour(&p, Some(1.0))?,
                ("checkerboard", "tex2") => odd = d.colour(&p, Some(1.0))?,
                ("checkerboard", "dimension") => {
                    if d.float(&p)? != 2.0 {
                        return Err(d.param_err(&p, format!("a 3D checkerboard is {SUBSET}")));
                    }
                }
                _ => {
                    return Err(d.param_err(&p, format!("unknown parameter of a {class} texture, or one outside the subset ppm renders")));
                }
            }
        }
        if !(scale.is_finite() && offset.is_finite()) || options.scale < 0.0 {
            return Err(
                d.err("uscale, vscale, udelta, vdelta must be finite and scale non-negative")
            );
        }
        let mut texture = match class.as_str() {
            "imagemap" => {
                let file = filename.ok_or_else(|| d.err("has no \"string filename\""))?;
                read_texture(&self.base.join(&file), options).map_err(|e| d.err(e))?
            }
            "checkerboard" => Texture::checkerboard(even, odd, Vec2::ONE).map_err(|e| d.err(e))?,
            _ => {
                return Err(d.err(format!(
                    "a {class} texture is {SUBSET} (imagemap, checkerboard)"
                )));
            }
        };
        texture.offset = offset * texture.scale;
        texture.scale *= scale;
        self.textures.insert(name, Arc::new(texture));
        Ok(())
    }

    /// The texture a material's `"texture NAME"` parameter names.
    fn texture_param(&self, d: &Directive, p: &Param) -> Result<Arc<Texture>> {
        let name = d.one_string(p)?;
        if let Some(t) = self.textures.get(&name) {
            return Ok(t.clone());
        }
        Err(d.param_err(
            p,
            if self.float_textures.contains(&name) {
                format!(
                    "\"{name}\" is a float texture: a textured {} is {SUBSET}",
                    p.name
                )
            } else {
                format!("no Texture \"{name}\" before it")
            },
        ))
    }

    /// A material, and the texture on its colour: a diffuse's or a coated diffuse's
    /// `"texture reflectance"` (its albedo then 1, the texture's values taken whole).
    fn material(
        &mut self,
        d: &Directive,
        ty: &str,
        params: &[Param],
    ) -> Result<(MaterialKind, Option<Arc<Texture>>)> {
        let textured = |p: &&Param| p.name == "reflectance" && p.ty == "texture";
        if let (Some(p), "conductor") = (params.iter().find(textured), ty) {
            return Err(d.param_err(
                p,
                format!("a textured conductor reflectance is {SUBSET}: pbrt-v4 turns it into an index per point (eta 1, k from the texel), which ours has no form for; Mitsuba 3's specular_reflectance bitmap, a factor as ours, is read"),
            ));
        }
        if let (Some(p), "diffuse" | "coateddiffuse") = (params.iter().find(textured), ty) {
            let texture = self.texture_param(d, p)?;
            let rest: Vec<Param> = params.iter().filter(|p| !textured(p)).cloned().collect();
            return Ok((
                self.material_kind(d, ty, &rest)?.white_under_texture(),
                Some(texture),
            ));
        }
        Ok((self.material_kind(d, ty, params)?, None))
    }

    /// A material's kind from its parameters. A `coateddiffuse` is our coated material of
    /// index `eta` (a float above 1) and pbrt's roughness, with `nonlinear` set: pbrt's random
    /// walk in the layer meets the base's colour at every return. pbrt also attenuates light
    /// crossing the layer by `exp(-thickness / |cos|)`, which we do not model: `thickness` is
    /// taken and ignored, as are `g`, `maxdepth` and `nsamples`, which tune pbrt's stochastic
    /// evaluation (`g` that of a medium in the layer, whose nonzero `albedo` we refuse).
    fn material_kind(&mut self, d: &Directive, ty: &str, params: &[Param]) -> Result<MaterialKind> {
        let unknown = |p: &Param| {
            d.param_err(
                p,
                format!(
                    "unknown parameter of a {ty} material, or one outside the subset ppm renders"
                ),
            )
        };
        match ty {
            "diffuse" => {
                let mut albedo = Vec3::splat(0.5);
                for p in params {
                    match p.name.as_str() {
                        "reflectance" => albedo = d.colour(p, Some(1.0))?,
                        _ => return Err(unknown(p)),
                    }
                }
                Ok(MaterialKind::Diffuse { albedo })
            }
            "conductor" => {
                let mut reflectance = None;
                let (mut eta, mut k) = (None, None);
                let mut roughness = Roughness::default();
                for p in params {
                    match p.name.as_str() {
                        "reflectance" => reflectance = Some(d.colour(p, Some(1.0))?),
                        "eta" | "k" => {
                            let v = match (p.ty.as_str(), named_metal(&p.values)) {
                                ("spectrum", Some(v)) => v,
                                ("spectrum", None)
                                    if d.band_colour(p, bands::read_reflectance).is_none() =>
                                {
                                    return Err(d.param_err(p, format!("a conductor given by a sampled spectrum (other than the band spectra ppm export writes), or a named one other than pbrt-v4's metal-{{Ag,Al,Au,Cu,CuZn}}-{{eta,k}}, is {SUBSET}: give \"rgb eta\" and \"rgb k\", or \"rgb reflectance\"")));
                                }
                                _ => d.colour(p, None)?,
                            };
                            if p.name == "eta" {
                                eta = Some(v);
                            } else {
                                k = Some(v);
                            }
                        }
                        _ if roughness.read(d, p)? => {}
                        _ => return Err(unknown(p)),
                    }
                }
                let (alpha, alpha_v) = roughness.alphas();
                match (eta, k, reflectance) {
                    // As our export writes a mirror.
                    (None, None, Some(reflectance)) if alpha.max(alpha_v) == 0.0 => {
                        Ok(MaterialKind::Mirror { reflectance })
                    }
                    // pbrt-v4's ConductorMaterial: the index whose normal-incidence
                    // reflectance is `r`.
                    (None, None, Some(r)) => {
                        let r = r.clamp(Vec3::ZERO, Vec3::splat(0.9999));
                        Ok(MaterialKind::Conductor {
                            eta: Vec3::ONE,
                            k: 2.0 * r.powf(0.5) / (Vec3::ONE - r).powf(0.5),
                            reflectance: Vec3::ONE,
                            alpha,
                            alpha_v,
                        })
                    }
                    (Some(eta), Some(k), None) => Ok(MaterialKind::Conductor {
                        eta,
                        k,
                        reflectance: Vec3::ONE,
                        alpha,
                        alpha_v,
                    }),
                    (None, None, None) => Err(d.err(format!("a conductor without \"rgb reflectance\" or \"rgb eta\" and \"rgb k\" (pbrt's default is copper's named spectra) is {SUBSET}"))),
                    _ => Err(d.err("a conductor takes \"rgb eta\" and \"rgb k\" together, or \"rgb reflectance\" alone")),
                }
            }
            // pbrt-v4's DielectricMaterial: eta 1.5 and roughness 0 by default, the roughness
            // read as a conductor's.
            "dielectric" => {
                let mut ior = 1.5;
                let mut roughness = Roughness::default();
                for p in params {
                    match p.name.as_str() {
                        "eta" if p.ty == "float" => {
                            ior = d.float(p)?;
                            if ior <= 0.0 {
                                return Err(d.param_err(p, "must be a positive number"));
                            }
                        }
                        "eta" => {
                            return Err(
                                d.param_err(p, format!("a dispersive (spectral) eta is {SUBSET}"))
                            );
                        }
                        _ if roughness.read(d, p)? => {}
                        _ => return Err(unknown(p)),
                    }
                }
                let (alpha, alpha_v) = roughness.alphas();
                Ok(MaterialKind::Glass {
                    ior,
                    alpha,
                    alpha_v,
                })
            }
            // pbrt-v4's CoatedDiffuseMaterial, its defaults (reflectance 0.5, roughness 0,
            // eta 1.5) and the rules above.
            "coateddiffuse" => {
                let mut albedo = Vec3::splat(0.5);
                let mut ior = 1.5;
                let mut roughness = Roughness::default();
                for p in params {
                    match p.name.as_str() {
                        "reflectance" => albedo = d.colour(p, Some(1.0))?,
                        "eta" if p.ty == "float" => {
                            ior = d.float(p)?;
                            if ior <= 1.0 {
                                return Err(d.param_err(
                                    p,
                                    format!("{ior}: must be above 1 (the coat's index over the outside's)"),
                                ));
                            }
                        }
                        "eta" => {
                            return Err(
                                d.param_err(p, format!("a dispersive (spectral) eta is {SUBSET}"))
                            );
                        }
                        "albedo" => {
                            if p.ty == "texture" || d.colour(p, None)? != Vec3::ZERO {
                                return Err(d.param_err(
                                    p,
                                    format!("a scattering medium in the coat's layer is {SUBSET} (albedo 0 only)"),
                                ));
                            }
                        }
                        "thickness" | "g" | "maxdepth" | "nsamples" => {}
                        _ if roughness.read(d, p)? => {}
                        _ => return Err(unknown(p)),
                    }
                }
                Ok(MaterialKind::Coated {
                    albedo,
                    ior,
                    alpha: roughness.isotropic_alpha(d)?,
                    nonlinear: true,
                })
            }
            _ => Err(d.err(format!(
                "material \"{ty}\" is {SUBSET} (diffuse, coateddiffuse, conductor, dielectric)"
            ))),
        }
    }

    fn area_light(&mut self, d: &Directive) -> Result<()> {
        let ty = d.string(0)?;
        if ty != "diffuse" {
            return Err(d.err(format!("{SUBSET}: only \"diffuse\" area lights")));
        }
        let (mut radiance, mut scale) = (Vec3::ONE, 1.0f32);
        // pbrt divides a light's spectrum by its luminance (an RGB light's by its
        // illuminant's, which keeps the colour's own).
        let mut per_luminance = false;
        for p in d.params(1)? {
            match p.name.as_str() {
                "L" if p.ty == "spectrum" => {
                    radiance = d.band_colour(&p, bands::read_illuminant).ok_or_else(|| {
                        d.param_err(&p, format!("a light given by a spectrum other than the band spectra ppm export writes is {SUBSET}: give \"rgb L\""))
                    })?;
                    per_luminance = true;
                }
                "L" => radiance = d.colour(&p, None)?,
                "scale" => scale = d.float(&p)?,
                "twosided" => {
                    if d.boolean(&p)? {
                        return Err(d.param_err(&p, format!("a two-sided light is {SUBSET}: ours emit on one side")));
                    }
                }
                _ => return Err(d.param_err(&p, "unknown parameter of a diffuse area light, or one outside the subset ppm renders")),
            }
        }
        if scale < 0.0 {
            return Err(d.err(format!("scale = {scale}: must not be negative")));
        }
        if per_luminance {
            let luminance = bands::luminance(radiance);
            if luminance <= 0.0 {
                return Err(d.err("a light spectrum of luminance 0: pbrt-v4 divides by it"));
            }
            scale /= luminance;
        }
        self.state.emission = Some(if scale == 1.0 {
            radiance
        } else {
            radiance * scale
        });
        Ok(())
    }

    fn shape(&mut self, d: &Directive) -> Result<()> {
        let ty = d.string(0)?;
        let params = d.params(1)?;
        let mesh = match ty.as_str() {
            "trianglemesh" => {
                let mut mesh = MeshData::default();
                let mut indices = None;
                for p in &params {
                    match p.name.as_str() {
                        "P" => mesh.positions = d.points(p)?,
                        "N" => mesh.normals = Some(d.points(p)?),
                        "indices" => indices = Some(d.integers(p)?),
                        "uv" | "st" => {
                            let v = d.floats(p)?;
                            if v.len() % 2 != 0 || v.iter().any(|x| !x.is_finite()) {
                                return Err(d.param_err(p, "texture coordinates come in finite pairs"));
                            }
                            mesh.uvs = Some(v.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect());
                        }
                        "S" | "faceIndices" => {}
                        _ => return Err(d.param_err(p, "unknown parameter of a triangle mesh, or one outside the subset ppm renders")),
                    }
                }
                let indices = match indices {
                    Some(i) => i,
                    None if mesh.positions.len() == 3 => vec![0, 1, 2],
                    None => return Err(d.err("has no \"integer indices\"")),
                };
                if indices.len() % 3 != 0 {
                    return Err(d.err(format!("{} indices: not a multiple of 3", indices.len())));
                }
                let count = mesh.positions.len() as u32;
                if let Some(i) = indices.iter().find(|&&i| i >= count) {
                    return Err(d.err(format!("index {i} is beyond the {count} points")));
                }
                if mesh
                    .normals
                    .as_ref()
                    .is_some_and(|n| n.len() != mesh.positions.len())
                {
                    return Err(d.err("\"N\" does not have one normal per point"));
                }
                if mesh
                    .uvs
                    .as_ref()
                    .is_some_and(|uv| uv.len() != mesh.positions.len())
                {
                    return Err(d.err("\"uv\" does not have one pair per point"));
                }
                mesh.triangles = indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect();
                mesh
            }
            "plymesh" => {
                let mut filename = None;
                for p in &params {
                    match p.name.as_str() {
                        "filename" => filename = Some((d.one_string(p)?, p.line)),
                        "edgelength" => {}
                        _ => return Err(d.param_err(
                            p,
                            "unknown parameter of a plymesh, or one outside the subset ppm renders",
                        )),
                    }
                }
                let (name, _) = filename.ok_or_else(|| d.err("has no \"string filename\""))?;
                read_ply(&self.base.join(&name)).map_err(|e| d.err(e))?
            }
            "sphere" => {
                let mut radius = 1.0;
                for p in &params {
                    match p.name.as_str() {
                        "radius" => {
                            radius = d.float(p)?;
                            if !(radius > 0.0 && radius.is_finite()) {
                                return Err(d.param_err(p, "must be a positive number"));
                            }
                        }
                        "zmin" | "zmax" | "phimax" => {
                            return Err(d.param_err(p, format!("a partial sphere is {SUBSET}")));
                        }
                        _ => return Err(d.param_err(
                            p,
                            "unknown parameter of a sphere, or one outside the subset ppm renders",
                        )),
                    }
                }
                sphere_mesh(radius)
            }
            _ => {
                return Err(d.err(format!("{SUBSET} (trianglemesh, plymesh, sphere)")));
            }
        };
        let to_world = Some(self.state.ctm).filter(|m| *m != DMat4::IDENTITY);
        // pbrt turns a sphere's normal outwards through any transform (a normal transform)
        // before ReverseOrientation and a mirroring transform flip it; a triangle's comes
        // from its transformed edges, which a mirroring transform already turned.
        let analytic = ty == "sphere";
        let flip = self.state.reverse ^ (swaps_handedness(to_world) && !analytic);
        // pbrt negates the normals under ReverseOrientation (not for a mirroring transform).
        let (triangles, uvs) = mesh_triangles(&mesh, to_world, flip, self.state.reverse);
        if triangles.iter().flatten().any(|v| !v.is_finite()) {
            return Err(d.err("a vertex is not finite"));
        }
        let surface = match self.state.material {
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
        let material = self
            .builder
            .material_for(surface, self.state.emission)
            .map_err(|problem| d.err(problem))?;
        let name = params
            .iter()
            .find(|p| p.name == "filename")
            .and_then(|p| d.one_string(p).ok())
            .and_then(|f| {
                Path::new(&f)
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
            })
            .unwrap_or_else(|| format!("shape-{}", d.line));
        self.builder.objects.push(Object {
            name,
            material,
            triangles,
            uvs,
        });
        Ok(())
    }
}

fn dvec(v: &[f32]) -> DVec3 {
    DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))
}

fn vec(v: &[f32]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// pbrt-v4's named metal spectra (`"spectrum eta" [ "metal-Ag-eta" ]`, `"metal-Ag-k"`) as
/// our RGB values: the measured index or absorption at 650, 550 and 450 nm, interpolated
/// linearly in pbrt-v4's own tables (the wavelengths of `scenes::material_scenes::GOLD`).
/// `None` for any other value.
fn named_metal(values: &[Token]) -> Option<Vec3> {
    let [Token::Str(name)] = values else {
        return None;
    };
    let (metal, part) = name.strip_prefix("metal-")?.rsplit_once('-')?;
    let (eta, k) = match metal {
        "Ag" => ([0.1394, 0.1248, 0.1517], [4.1288, 3.3396, 2.4704]),
        "Al" => ([1.4748, 0.9586, 0.6180], [7.7941, 6.6870, 5.4694]),
        "Au" => ([0.1678, 0.3504, 1.5085], [3.1378, 2.7141, 1.8788]),
        "Cu" => ([0.2166, 0.9582, 1.1658], [3.6377, 2.5771, 2.3939]),
        "CuZn" => ([0.4440, 0.5270, 1.0940], [3.6950, 2.7650, 1.8290]),
        _ => return None,
    };
    match part {
        "eta" => Some(Vec3::from(eta)),
        "k" => Some(Vec3::from(k)),
        _ => None,
    }
}

/// A microfacet material's roughness as pbrt-v4 reads it: `uroughness` and `vroughness`,
/// each `roughness` where not given, in [0, 1], and `remaproughness`.
struct Roughness {
    roughness: f32,
    remap: bool,
    u: Option<f32>,
    v: Option<f32>,
}

impl Default for Roughness {
    fn default() -> Self {
        Self {
            roughness: 0.0,
            remap: true,
            u: None,
            v: None,
        }
    }
}

impl Roughness {
    /// Reads `p` if it is one of the roughness parameters; false if it is not.
    fn read(&mut self, d: &Directive, p: &Param) -> Result<bool> {
        match p.name.as_str() {
            "roughness" | "uroughness" | "vroughness" => {
                let r = d.float(p)?;
                if !(0.0..=1.0).contains(&r) {
                    return Err(d.param_err(p, "must be in [0, 1]"));
                }
                match p.name.as_str() {
                    "uroughness" => self.u = Some(r),
                    "vroughness" => self.v = Some(r),
                    _ => self.roughness = r,
                }
            }
            "remaproughness" => self.remap = d.boolean(p)?,
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// The GGX alphas along and across the tangent: pbrt-v4's
    /// TrowbridgeReitzDistribution::RoughnessToAlpha (the square root) unless
    /// `remaproughness` is false.
    fn alphas(&self) -> (f32, f32) {
        let alpha = |r: f32| if self.remap { r.sqrt() } else { r };
        (
            alpha(self.u.unwrap_or(self.roughness)),
            alpha(self.v.unwrap_or(self.roughness)),
        )
    }

    /// The one GGX alpha of a lobe that must be isotropic (a coat's); `d` is refused where
    /// the two differ.
    fn isotropic_alpha(&self, d: &Directive) -> Result<f32> {
        match self.alphas() {
            (u, v) if u == v => Ok(u),
            (u, v) => Err(d.err(format!(
                "anisotropic roughness (alpha {u} along u, {v} along v) on a coat is {SUBSET}: ours is isotropic"
            ))),
        }
    }
}

/// A directive and its arguments, with the helpers that read them and name it in errors.
struct Directive<'a> {
    reader: &'a str,
    name: String,
    line: u32,
    args: &'a [(Token, u32)],
}

impl Directive<'_> {
    fn err(&self, problem: impl Into<String>) -> SceneError {
        SceneError::At {
            file: self.reader.to_owned(),
            line: self.line,
            element: self.name.clone(),
            problem: problem.into(),
        }
    }

    fn param_err(&self, p: &Param, problem: impl Into<String>) -> SceneError {
        SceneError::At {
            file: self.reader.to_owned(),
            line: p.line,
            element: format!("{} \"{} {}\"", self.name, p.ty, p.name),
            problem: problem.into(),
        }
    }

    fn parse_number(&self, line: u32, t: &Token) -> Result<f32> {
        match t {
            Token::Number(s) => s
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| SceneError::At {
                    file: self.reader.to_owned(),
                    line,
                    element: self.name.clone(),
                    problem: format!("\"{s}\" is not a finite number"),
                }),
            other => Err(SceneError::At {
                file: self.reader.to_owned(),
                line,
                element: self.name.clone(),
                problem: format!("{} is not a number", word(other)),
            }),
        }
    }

    /// Exactly `n` numbers, bare or in one bracket.
    fn numbers(&self, n: usize) -> Result<Vec<f32>> {
        let values: Vec<&(Token, u32)> = self
            .args
            .iter()
            .filter(|(t, _)| !matches!(t, Token::Open | Token::Close))
            .collect();
        if values.len() != n {
            return Err(self.err(format!("takes {n} numbers, has {}", values.len())));
        }
        values
            .iter()
            .map(|(t, l)| self.parse_number(*l, t))
            .collect()
    }

    /// The `k`-th positional string.
    fn string(&self, k: usize) -> Result<String> {
        match self.args.get(k) {
            Some((Token::Str(s), _)) => Ok(s.clone()),
            _ => Err(self.err("a quoted name is missing")),
        }
    }

    /// The parameter list after `skip` positional strings.
    fn params(&self, skip: usize) -> Result<Vec<Param>> {
        let mut out = Vec::new();
        let mut i = skip;
        while i < self.args.len() {
            let (t, line) = &self.args[i];
            let Token::Str(decl) = t else {
                return Err(SceneError::At {
                    file: self.reader.to_owned(),
                    line: *line,
                    element: self.name.clone(),
                    problem: format!("expected a \"type name\" parameter, found {}", word(t)),
                });
            };
            let mut parts = decl.split_whitespace();
            let (Some(ty), Some(name), None) = (parts.next(), parts.next(), parts.next()) else {
                return Err(SceneError::At {
                    file: self.reader.to_owned(),
                    line: *line,
                    element: self.name.clone(),
                    problem: format!("\"{decl}\" is not a \"type name\" parameter"),
                });
            };
            i += 1;
            let mut values = Vec::new();
            match self.args.get(i) {
                Some((Token::Open, _)) => {
                    i += 1;
                    while let Some((t, _)) = self.args.get(i) {
                        i += 1;
                        if *t == Token::Close {
                            break;
                        }
                        values.push(t.clone());
                    }
                }
                Some((t, _)) => {
                    values.push(t.clone());
                    i += 1;
                }
                None => {}
            }
            out.push(Param {
                ty: ty.to_owned(),
                name: name.to_owned(),
                values,
                line: *line,
            });
        }
        Ok(out)
    }

    fn floats(&self, p: &Param) -> Result<Vec<f32>> {
        p.values
            .iter()
            .map(|t| {
                self.parse_number(p.line, t).map_err(|e| match e {
                    SceneError::At { problem, .. } => self.param_err(p, problem),
                    other => other,
                })
            })
            .collect()
    }

    fn float(&self, p: &Param) -> Result<f32> {
        match self.floats(p)?.as_slice() {
            [v] => Ok(*v),
            v => Err(self.param_err(p, format!("{} values: expected one number", v.len()))),
        }
    }

    fn positive(&self, p: &Param) -> Result<u32> {
        let v = self.float(p)?;
        if v >= 1.0 && v.fract() == 0.0 && v <= u32::MAX as f32 {
            Ok(v as u32)
        } else {
            Err(self.param_err(p, format!("{v} is not a positive integer")))
        }
    }

    fn integers(&self, p: &Param) -> Result<Vec<u32>> {
        p.values
            .iter()
            .map(|t| match t {
                Token::Number(s) => s
                    .parse::<u32>()
                    .map_err(|_| self.param_err(p, format!("\"{s}\" is not an index"))),
                other => Err(self.param_err(p, format!("{} is not an index", word(other)))),
            })
            .collect()
    }

    fn points(&self, p: &Param) -> Result<Vec<Vec3>> {
        let v = self.floats(p)?;
        if v.len() % 3 != 0 {
            return Err(self.param_err(p, format!("{} numbers: not a multiple of 3", v.len())));
        }
        Ok(v.chunks_exact(3).map(vec).collect())
    }

    fn one_string(&self, p: &Param) -> Result<String> {
        match p.values.as_slice() {
            [Token::Str(s)] => Ok(s.clone()),
            _ => Err(self.param_err(p, "expected one quoted string")),
        }
    }

    fn boolean(&self, p: &Param) -> Result<bool> {
        match p.values.as_slice() {
            [Token::Word(w) | Token::Str(w)] if w == "true" => Ok(true),
            [Token::Word(w) | Token::Str(w)] if w == "false" => Ok(false),
            _ => Err(self.param_err(p, "expected true or false")),
        }
    }

    /// The colour a `spectrum` of (wavelength, value) pairs holds, when it is a band
    /// spectrum of `ppm export` (`read`: [`bands::read_reflectance`] or
    /// [`bands::read_illuminant`]); `None` for any other spectrum.
    fn band_colour(&self, p: &Param, read: fn(&[(f32, f32)]) -> Option<Vec3>) -> Option<Vec3> {
        let values = self.floats(p).ok()?;
        if values.len() % 2 != 0 {
            return None;
        }
        let points: Vec<(f32, f32)> = values.chunks(2).map(|c| (c[0], c[1])).collect();
        read(&points)
    }

    /// An `rgb` colour (or a `float` grey, or a band spectrum of `ppm export`), in [0, max]
    /// when `max` is given.
    fn colour(&self, p: &Param, max: Option<f32>) -> Result<Vec3> {
        let c = match p.ty.as_str() {
            "rgb" | "color" => match self.floats(p)?.as_slice() {
                [r, g, b] => Vec3::new(*r, *g, *b),
                v => return Err(self.param_err(p, format!("{} values: an rgb has 3", v.len()))),
            },
            "float" => Vec3::splat(self.float(p)?),
            "spectrum" => self.band_colour(p, bands::read_reflectance).ok_or_else(|| {
                self.param_err(p, format!("a spectrum other than the band spectra ppm export writes is {SUBSET} (rgb only)"))
            })?,
            "texture" => return Err(self.param_err(p, format!("a textured parameter is {SUBSET}"))),
            _ => return Err(self.param_err(p, format!("a {} value is {SUBSET} (rgb only)", p.ty))),
        };
        for v in c.to_array() {
            if v < 0.0 {
                return Err(self.param_err(p, format!("{v} is negative")));
            }
            if let Some(max) = max.filter(|m| v > *m) {
                return Err(self.param_err(
                    p,
                    format!("{v} is above {max} (a surface cannot reflect more than it receives)"),
                ));
            }
        }
        Ok(c)
    }
}
