//! What the Mitsuba 3 and pbrt-v4 formats share: writing an export (scene file, PLY meshes,
//! the list of what the other renderer does differently), and building a [`Scene`] from an
//! imported file (materials that become lights, camera poses, mirrored worlds).
//!
//! Conventions both renderers were checked against (their sources, see each format's module):
//! a triangle `(v0, v1, v2)` faces `(v1 - v0) x (v2 - v0)` in both, as here; both images have
//! pixel (0, 0) at the top-left. Our camera's image right is `forward x up`, which is
//! Mitsuba's `look_at` as written and pbrt's `LookAt` after `Scale -1 1 1`.

use crate::file::bands::Colours;
use crate::file::image::ImageFiles;
use crate::file::mesh::{MeshData, write_ply};
use glam::{DMat3, DMat4, DVec3, Vec2, Vec3};
use ppm_core::image::Image;
use ppm_core::scene::{
    Camera, Material, MaterialKind, Object, RenderDefaults, Scene, SceneError, check_magnitudes,
};
use ppm_core::scene::{Texture, unpack_texel};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use thiserror::Error;

/// Settings of an export that are not part of the scene.
#[derive(Clone, Debug)]
pub struct ExportOptions {
    /// Samples per pixel the other renderer takes.
    pub samples_per_pixel: u32,
    /// Which frame of the scene the exported scene is (only named in the file's comment).
    pub frame: u32,
    /// How colours are written; `None` takes the format's own choice: band spectra for
    /// pbrt-v4, which renders spectrally, RGB for Mitsuba 3, whose `scalar_rgb` is exact.
    pub colours: Option<Colours>,
}

impl Default for ExportOptions {
    fn default() -> Self {
        Self {
            samples_per_pixel: 1024,
            frame: 0,
            colours: None,
        }
    }
}

/// A scene written for another renderer: the scene file's text, the meshes beside it, and
/// what that renderer will do differently from us (also listed in the text as a comment).
#[derive(Clone, Debug)]
pub struct Export {
    /// File name of the scene file, e.g. `cornell-box.xml`.
    pub scene_file: String,
    /// Its contents.
    pub text: String,
    /// Mesh files beside it.
    pub meshes: Vec<MeshFile>,
    /// Texture image file names beside it, with their linear texels.
    pub textures: Vec<(String, Image)>,
    /// What cannot be expressed exactly, one sentence each.
    pub notes: Vec<String>,
}

/// One object's mesh as an export writes it.
#[derive(Clone, Debug)]
pub struct MeshFile {
    /// File name.
    pub name: String,
    /// Triangles in world space.
    pub triangles: Vec<[Vec3; 3]>,
    /// Their vertices' texture coordinates (empty for an object whose material has neither
    /// a texture nor an anisotropic lobe, which they orient).
    pub uvs: Vec<[Vec2; 3]>,
}

/// Why an export could not be written.
#[derive(Debug, Error)]
#[error("{path}: cannot write: {source}")]
pub struct ExportError {
    /// File or folder.
    pub path: String,
    /// What the operating system said.
    pub source: std::io::Error,
}

impl Export {
    /// The export of `scene` as `text` in a scene file named after it with `extension`, its
    /// objects' meshes under `mesh_names` (one per object, in order).
    pub(crate) fn of(
        scene: &Scene,
        format: Format,
        text: String,
        mesh_names: Vec<String>,
        notes: Vec<String>,
    ) -> Self {
        let extension = match format {
            Format::Mitsuba => "xml",
            Format::Pbrt => "pbrt",
        };
        let textures = texture_files(scene, format)
            .into_iter()
            .zip(&scene.materials)
            .filter_map(|(file, m)| Some((file?, texture_image(m, format)?)))
            .collect();
        Export {
            scene_file: format!("{}.{extension}", scene_stem(scene)),
            text,
            meshes: mesh_names
                .into_iter()
                .zip(&scene.objects)
                .map(|(name, o)| {
                    let material = &scene.materials[o.material];
                    let uvs = texture_written(material, format) || material.kind.is_anisotropic();
                    MeshFile {
                        name,
                        triangles: o.triangles.clone(),
                        uvs: if uvs { object_uvs(o) } else { Vec::new() },
                    }
                })
                .collect(),
            textures,
            notes,
        }
    }

    /// Writes the scene file and its meshes into `dir` (created if missing); returns the
    /// scene file's path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, ExportError> {
        let fail = |path: &Path| {
            let path = path.display().to_string();
            move |source| ExportError { path, source }
        };
        std::fs::create_dir_all(dir).map_err(fail(dir))?;
        for mesh in &self.meshes {
            let path = dir.join(&mesh.name);
            write_ply(&path, &mesh.triangles, &mesh.uvs).map_err(fail(&path))?;
        }
        for (name, image) in &self.textures {
            let path = dir.join(name);
            image.write_exr(&path).map_err(|e| ExportError {
                path: path.display().to_string(),
                source: std::io::Error::other(e.to_string()),
            })?;
        }
        let path = dir.join(&self.scene_file);
        crate::file::output::write_bytes(&path, &self.text).map_err(fail(&path))?;
        Ok(path)
    }
}

/// One PLY file name per object (`floor.ply`), made safe for file systems and unique.
pub(crate) fn mesh_names(scene: &Scene) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for object in &scene.objects {
        let stem = safe_stem(&object.name, "object");
        let mut name = format!("{stem}.ply");
        let mut k = 2;
        while names.contains(&name) {
            name = format!("{stem}-{k}.ply");
            k += 1;
        }
        names.push(name);
    }
    names
}

/// The format an export writes, which decides the colours it can take from an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Format {
    /// Mitsuba 3's XML.
    Mitsuba,
    /// pbrt-v4's scene description.
    Pbrt,
}

/// Whether an export writes `m`'s texture ([`textured_colour`]); a texture on another colour
/// is left out (the notes say so).
fn texture_written(m: &Material, format: Format) -> bool {
    m.texture.is_some() && textured_colour(&m.kind, format).is_some()
}

/// The colour a texture on `kind` scales, for the kinds whose texture `format` takes: both
/// take an image as a diffuse reflectance (a diffuse surface's, or a coated one's base);
/// Mitsuba also as a mirror's or conductor's `specular_reflectance`, a factor as ours.
/// pbrt-v4 turns a conductor's textured reflectance into an index per point, not a factor.
fn textured_colour(kind: &MaterialKind, format: Format) -> Option<Vec3> {
    match (kind, format) {
        (MaterialKind::Diffuse { albedo } | MaterialKind::Coated { albedo, .. }, _) => {
            Some(*albedo)
        }
        (
            MaterialKind::Mirror { reflectance } | MaterialKind::Conductor { reflectance, .. },
            Format::Mitsuba,
        ) => Some(*reflectance),
        _ => None,
    }
}

/// Per material, the file its texture is written to (`wood-texture.exr`), unique and safe
/// for file systems; `None` for a material whose texture is not written or that has none.
pub(crate) fn texture_files(scene: &Scene, format: Format) -> Vec<Option<String>> {
    let mut names: Vec<Option<String>> = Vec::new();
    for m in &scene.materials {
        if !texture_written(m, format) {
            names.push(None);
            continue;
        }
        let stem = safe_stem(&m.name, "material");
        let mut name = format!("{stem}-texture.exr");
        let mut k = 2;
        while names.iter().flatten().any(|n| *n == name) {
            name = format!("{stem}-texture-{k}.exr");
            k += 1;
        }
        names.push(Some(name));
    }
    names
}

/// A textured material's image as written: its texels times the material's colour (both
/// formats then read the colour from the image alone), linear.
fn texture_image(m: &Material, format: Format) -> Option<Image> {
    let (Some(t), Some(colour)) = (&m.texture, textured_colour(&m.kind, format)) else {
        return None;
    };
    let mut image = Image::new(t.width, t.height);
    for (p, texel) in image.pixels.iter_mut().zip(&t.texels) {
        *p = (unpack_texel(*texel) * colour).to_array();
    }
    Some(image)
}

/// An object's texture coordinates as the file says them: pbrt's default where it has none.
fn object_uvs(o: &Object) -> Vec<[Vec2; 3]> {
    if o.uvs.len() == o.triangles.len() {
        o.uvs.clone()
    } else {
        vec![[Vec2::ZERO, Vec2::X, Vec2::ONE]; o.triangles.len()]
    }
}

/// File stem of the scene file: the scene's name made safe for file systems.
pub(crate) fn scene_stem(scene: &Scene) -> String {
    safe_stem(&scene.name, "scene")
}

/// `name` with every character but ASCII letters, digits, `-` and `_` replaced by `_`, so it
/// can never become a path; `empty` when nothing is left.
fn safe_stem(name: &str, empty: &str) -> String {
    if name.is_empty() {
        return empty.into();
    }
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// What neither format can hold, whatever the renderer: our photon-mapping settings, the
/// moves, and lights that no object uses (their radiance lives on shapes there).
pub(crate) fn common_notes(scene: &Scene, options: &ExportOptions, format: Format) -> Vec<String> {
    let r = &scene.render;
    let mut notes = vec![format!(
        "photon mapping settings have no equivalent (initial radius {}, alpha {}, {} photons \
         per pass, {} passes); the path tracer converges to the same image instead",
        r.initial_radius, r.alpha, r.photons_per_pass, r.passes
    )];
    if !scene.moves.is_empty() {
        notes.push(format!(
            "the scene's moves are not written: this file is frame {} (frame 1 is the scene \
             with its moves applied)",
            options.frame
        ));
    }
    for (i, m) in scene.materials.iter().enumerate() {
        if let Some(t) = &m.texture {
            notes.push(if texture_written(m, format) {
                format!(
                    "material '{}' is textured ({}, {}x{}): its image is written as a linear \
                     EXR with the colour baked in; ours is read bilinear (or nearest) at its one \
                     resolution, the other renderer may filter by the ray's footprint",
                    m.name, t.name, t.width, t.height
                )
            } else {
                format!(
                    "material '{}' is textured ({}): this format takes a texture only on a \
                     diffuse reflectance{}, the other renderer sees this colour without it",
                    m.name,
                    t.name,
                    match format {
                        Format::Mitsuba => " or a specular one",
                        Format::Pbrt => " (pbrt-v4 reads a conductor's as an index per point)",
                    }
                )
            });
        }
        let used = scene.objects.iter().any(|o| o.material == i);
        if !used && matches!(m.kind, MaterialKind::Light { .. }) {
            notes.push(format!(
                "material '{}' is a light no object uses: only its surface is written, an \
                 emitter needs a shape",
                m.name
            ));
        }
    }
    notes
}

/// Near and far clip distances that keep every vertex in view: the other renderers clip,
/// we do not.
pub(crate) fn clip_range(scene: &Scene) -> (f32, f32) {
    let eye = scene.camera.eye;
    let far = scene
        .objects
        .iter()
        .flat_map(|o| o.triangles.iter().flatten())
        .map(|v| v.distance(eye))
        .fold(0.0f32, f32::max);
    let far = (far * 2.0).max(1e-3);
    (far * 1e-7, far)
}

/// `a, b, c` with Rust's shortest round-tripping float formatting.
pub(crate) fn list3(v: Vec3, separator: &str) -> String {
    format!("{}{separator}{}{separator}{}", v.x, v.y, v.z)
}

// ---------------------------------------------------------------------------------------------
// Import.

/// How a declared surface material has been used so far by shapes.
#[derive(Clone, Copy, PartialEq)]
enum Usage {
    Unused,
    Surface,
    Emitter(Vec3),
}

/// Collects an imported scene. A file's material becomes a light where a shape that emits
/// uses it; one used both ways (or with two radiances) is split into several of ours.
pub(crate) struct SceneBuilder {
    pub file: String,
    pub materials: Vec<Material>,
    usage: Vec<Usage>,
    /// Index of the surface material each material came from (itself for declared ones).
    origin: Vec<usize>,
    /// Each material as declared: the first shape to use one may turn it into a light.
    declared: Vec<Material>,
    pub objects: Vec<Object>,
}

impl SceneBuilder {
    pub fn new(file: &str) -> Self {
        Self {
            file: file.to_owned(),
            materials: Vec::new(),
            usage: Vec::new(),
            origin: Vec::new(),
            declared: Vec::new(),
            objects: Vec::new(),
        }
    }

    /// Declares a surface material (diffuse, mirror or glass); returns its index.
    pub fn declare(&mut self, name: &str, kind: MaterialKind) -> usize {
        self.declare_textured(name, kind, None)
    }

    /// Declares a surface material whose colour `texture` may scale; returns its index.
    pub fn declare_textured(
        &mut self,
        name: &str,
        kind: MaterialKind,
        texture: Option<Arc<Texture>>,
    ) -> usize {
        self.materials.push(Material {
            name: name.to_owned(),
            kind,
            texture,
        });
        self.declared
            .push(self.materials[self.materials.len() - 1].clone());
        self.usage.push(Usage::Unused);
        self.origin.push(self.materials.len() - 1);
        self.materials.len() - 1
    }

    /// The material of a shape with surface `surface` that emits `emission` (if any).
    /// `Err` holds the problem when an emitting surface is not diffuse.
    pub fn material_for(
        &mut self,
        surface: usize,
        emission: Option<Vec3>,
    ) -> Result<usize, String> {
        let wanted = emission.map_or(Usage::Surface, Usage::Emitter);
        if let Some(i) = (0..self.materials.len())
            .find(|&i| self.origin[i] == surface && self.usage[i] == wanted)
        {
            return Ok(i);
        }
        let base = self.declared[surface].clone();
        let kind = match (emission, &base.kind) {
            (None, kind) => kind.clone(),
            (Some(_), _) if base.texture.is_some() => {
                return Err(format!(
                    "material '{}' emits and is textured: a textured light is outside the \
                     subset ppm renders",
                    base.name
                ));
            }
            (Some(radiance), MaterialKind::Diffuse { albedo }) => MaterialKind::Light {
                radiance,
                albedo: *albedo,
            },
            (Some(_), _) => {
                return Err(format!(
                    "material '{}' emits but is not diffuse: our area lights are diffuse \
                     surfaces",
                    base.name
                ));
            }
        };
        let i = if self.usage[surface] == Usage::Unused {
            surface
        } else {
            let suffix = if emission.is_some() {
                "emitter"
            } else {
                "surface"
            };
            self.materials.push(Material {
                name: format!("{}-{suffix}-{}", base.name, self.materials.len()),
                kind: kind.clone(),
                texture: base.texture.clone(),
            });
            self.usage.push(Usage::Unused);
            self.origin.push(surface);
            self.declared.push(base.clone());
            self.materials.len() - 1
        };
        self.materials[i].kind = kind;
        self.usage[i] = wanted;
        Ok(i)
    }

    /// The scene, checked as a TOML scene is: triangles, a light, a camera. A camera that
    /// mirrors the image (see [`camera_pose`]) mirrors the whole world instead, so the image
    /// is the other renderer's.
    pub fn finish(self, name: &str, camera: Camera, mirrored: bool) -> Result<Scene, SceneError> {
        let err = |field: &str, value: usize, problem: &str| {
            SceneError::invalid(&self.file, field, value, problem)
        };
        let triangles: usize = self.objects.iter().map(|o| o.triangles.len()).sum();
        if triangles == 0 {
            return Err(err(
                "shapes",
                self.objects.len(),
                "the scene has no triangles to render",
            ));
        }
        let lit = self
            .objects
            .iter()
            .any(|o| matches!(self.materials[o.material].kind, MaterialKind::Light { .. }));
        if !lit {
            return Err(err(
                "shapes",
                self.objects.len(),
                "no shape has an area emitter: the scene has no light",
            ));
        }
        let mut scene = Scene {
            name: name.to_owned(),
            camera,
            materials: self.materials,
            objects: self.objects,
            render: RenderDefaults::default(),
            moves: Vec::new(),
        };
        if mirrored {
            mirror_x(&mut scene);
        }
        scene.render.initial_radius = default_radius(&scene);
        check_magnitudes(&scene, &self.file)?;
        Ok(scene)
    }
}

/// A gather radius for a scene that suggests none: a hundredth of its bounding-box diagonal.
fn default_radius(scene: &Scene) -> f32 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for v in scene
        .objects
        .iter()
        .flat_map(|o| o.triangles.iter().flatten())
    {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    let r = (hi - lo).length() / 100.0;
    if r.is_finite() && r > 0.0 { r } else { 1.0 }
}

/// Mirrors the world in x (vertices and camera), reversing each triangle's winding so that
/// every surface keeps facing the same way in the mirrored world.
pub(crate) fn mirror_x(scene: &mut Scene) {
    let m = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
    let c = &mut scene.camera;
    (c.eye, c.look_at, c.up) = (m(c.eye), m(c.look_at), m(c.up));
    for t in scene
        .objects
        .iter_mut()
        .flat_map(|o| o.triangles.iter_mut())
    {
        *t = [m(t[0]), m(t[2]), m(t[1])];
    }
}

/// The world-from-camera matrix of a look-at: columns `up x dir`, the orthogonal up, `dir`,
/// and the eye. This is Mitsuba's `look_at` and the inverse of pbrt's `LookAt`.
pub(crate) fn look_at(eye: DVec3, target: DVec3, up: DVec3) -> Option<DMat4> {
    let dir = (target - eye).try_normalize()?;
    let side = up.try_normalize()?.cross(dir).try_normalize()?;
    let new_up = dir.cross(side);
    Some(DMat4::from_cols(
        side.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    ))
}

/// Our camera's eye, look-at point and up from a world-from-camera matrix whose camera
/// looks along +z with +y up. `ours_if_positive`: whether a positive determinant of its 3x3
/// part is our handedness (Mitsuba) or the mirror of it (pbrt). Returns the pose and whether
/// the image is mirrored relative to ours; `None` when the matrix is singular.
pub(crate) fn camera_pose(m: DMat4, ours_if_positive: bool) -> Option<(Vec3, Vec3, Vec3, bool)> {
    let eye = m.transform_point3(DVec3::ZERO);
    let forward = m.transform_vector3(DVec3::Z).try_normalize()?;
    let up = m.transform_vector3(DVec3::Y).try_normalize()?;
    let det = DMat3::from_mat4(m).determinant();
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let mirrored = (det > 0.0) != ours_if_positive;
    Some((
        eye.as_vec3(),
        (eye + forward).as_vec3(),
        up.as_vec3(),
        mirrored,
    ))
}

/// Our vertical field of view from a horizontal one, for a `width` x `height` image.
pub(crate) fn vertical_fov(horizontal_deg: f64, width: u32, height: u32) -> f32 {
    let aspect = f64::from(width) / f64::from(height);
    (2.0 * ((horizontal_deg.to_radians() * 0.5).tan() / aspect).atan()).to_degrees() as f32
}

/// The triangles of `mesh` in world space. Without vertex normals the winding is reversed
/// where `flip` says so; with them each triangle turns to the side its (transformed) normals
/// point to, reversed where `flip_normals` says so: both renderers orient a face by its
/// shading normals when a mesh has them, and their flags act on the normals then. With the
/// triangles come their vertices' texture coordinates, in the same order (none when the mesh
/// has none).
pub(crate) fn mesh_triangles(
    mesh: &MeshData,
    to_world: Option<DMat4>,
    flip: bool,
    flip_normals: bool,
) -> (Vec<[Vec3; 3]>, Vec<[Vec2; 3]>) {
    let point = |p: Vec3| match to_world {
        Some(m) => m.transform_point3(p.as_dvec3()).as_vec3(),
        None => p,
    };
    let normal_matrix = to_world.map(|m| DMat3::from_mat4(m).inverse().transpose());
    let mut uvs = Vec::new();
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| {
            let v = t.map(|i| point(mesh.positions[i as usize]));
            let mut reverse = flip;
            if let Some(normals) = &mesh.normals {
                let n: Vec3 = t.iter().map(|&i| normals[i as usize]).sum();
                let n = match normal_matrix {
                    Some(nm) => (nm * n.as_dvec3()).as_vec3(),
                    None => n,
                };
                let face = (v[1] - v[0]).cross(v[2] - v[0]);
                reverse = (face.dot(n) < 0.0) != flip_normals;
            }
            let order = if reverse { [0, 2, 1] } else { [0, 1, 2] };
            if let Some(uv) = &mesh.uvs {
                uvs.push(order.map(|k| uv[t[k] as usize]));
            }
            order.map(|k| v[k])
        })
        .collect();
    (triangles, uvs)
}

/// Whether a transform turns right-handed frames into left-handed ones.
pub(crate) fn swaps_handedness(m: Option<DMat4>) -> bool {
    m.is_some_and(|m| DMat3::from_mat4(m).determinant() < 0.0)
}

/// Mitsuba's `cube` (and a unit cube for pbrt users): `[-1, 1]^3`, faces outwards, two
/// triangles per face in Mitsuba's own order.
pub(crate) fn unit_cube() -> MeshData {
    let corner = |c: u32| {
        Vec3::new(
            if c & 1 != 0 { 1.0 } else { -1.0 },
            if c & 2 != 0 { 1.0 } else { -1.0 },
            if c & 4 != 0 { 1.0 } else { -1.0 },
        )
    };
    const FACES: [[u32; 4]; 6] = [
        [1, 5, 4, 0],
        [3, 2, 6, 7],
        [1, 3, 7, 5],
        [5, 7, 6, 4],
        [4, 6, 2, 0],
        [3, 1, 0, 2],
    ];
    let mut mesh = MeshData::default();
    for f in FACES {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(f.map(corner));
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base + 3, base, base + 2]);
    }
    mesh
}

/// Mitsuba's `rectangle`: `[-1, 1]^2` at z = 0, facing +z.
pub(crate) fn unit_rectangle() -> MeshData {
    MeshData {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ],
        uvs: None,
        normals: None,
        triangles: vec![[1, 2, 0], [1, 3, 2]],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn faces_out(mesh: &MeshData) -> bool {
        mesh.triangle_vertices().iter().all(|t| {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            n.dot((t[0] + t[1] + t[2]) / 3.0) > 0.0
        })
    }

    #[test]
    fn unit_cube_faces_outwards_and_rectangle_faces_plus_z() {
        assert!(faces_out(&unit_cube()));
        for t in unit_rectangle().triangle_vertices() {
            assert!((t[1] - t[0]).cross(t[2] - t[0]).z > 0.0);
        }
    }

    /// Our camera's right is `forward x up`; Mitsuba's look-at puts `up x dir` on the image's
    /// left, so the pose read back is ours and not mirrored.
    #[test]
    fn look_at_pose_round_trips_and_keeps_handedness() {
        let m = look_at(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(1.0, 2.0, 10.0),
            DVec3::Y,
        )
        .unwrap();
        let (eye, target, up, mirrored) = camera_pose(m, true).unwrap();
        assert_eq!(
            (eye, up, mirrored),
            (Vec3::new(1.0, 2.0, 3.0), Vec3::Y, false)
        );
        assert_eq!(target, Vec3::new(1.0, 2.0, 4.0));
        assert!(camera_pose(m, false).unwrap().3);
    }
}

/// Longitude steps of a tessellated sphere (half as many in latitude): its flat facets lie
/// within 0.12% of the radius of the true sphere and its area is 0.2% smaller
/// (docs/other-renderers.md).
pub(crate) const SPHERE_SEGMENTS: u32 = 64;

/// A sphere of `radius` about the origin as triangles facing outwards: rings of
/// [`SPHERE_SEGMENTS`] quads between the poles, with pbrt's `(phi / 2 pi, theta / pi)`
/// texture coordinates.
pub(crate) fn sphere_mesh(radius: f32) -> MeshData {
    let (n, m) = (SPHERE_SEGMENTS, SPHERE_SEGMENTS / 2);
    let mut mesh = MeshData::default();
    let mut uvs = Vec::new();
    for j in 0..=m {
        let theta = std::f32::consts::PI * j as f32 / m as f32;
        for i in 0..=n {
            let phi = std::f32::consts::TAU * i as f32 / n as f32;
            let (st, ct) = theta.sin_cos();
            mesh.positions
                .push(radius * Vec3::new(st * phi.cos(), st * phi.sin(), -ct));
            uvs.push(Vec2::new(i as f32 / n as f32, j as f32 / m as f32));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..m {
        for i in 0..n {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // The first ring and the last meet at a pole: one triangle each there.
            if j > 0 {
                mesh.triangles.push([a, b, c]);
            }
            if j + 1 < m {
                mesh.triangles.push([a, c, d]);
            }
        }
    }
    mesh.uvs = Some(uvs);
    mesh
}

#[cfg(test)]
mod sphere_tests {
    use super::*;

    #[test]
    fn the_tessellated_sphere_is_closed_faces_out_and_near_the_true_one() {
        let mesh = sphere_mesh(2.0);
        let triangles = mesh.triangle_vertices();
        let mut area = 0.0;
        for t in &triangles {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            assert!(n.length() > 0.0, "no degenerate facet");
            let centre = (t[0] + t[1] + t[2]) / 3.0;
            assert!(n.dot(centre) > 0.0, "facet faces inwards at {centre}");
            area += 0.5 * n.length();
        }
        let true_area = 4.0 * std::f32::consts::PI * 4.0;
        assert!(
            (1.0 - area / true_area - 0.002).abs() < 2e-4,
            "area {area} against {true_area}"
        );
        for v in &mesh.positions {
            assert!((v.length() - 2.0).abs() < 1e-5);
        }
    }
}
