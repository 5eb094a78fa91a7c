//! Triangle meshes in files other renderers read: PLY written (binary little-endian, exact
//! `f32` positions), PLY read (ascii and both binary byte orders) and OBJ read (with tobj).
//!
//! PLY is the mesh format Mitsuba 3 (`ply`) and pbrt-v4 (`plymesh`) both load, and a binary
//! file stores each `f32` bit for bit, so an exported mesh comes back identical.

use crate::file::limits::{MESH_FILE_LIMIT, check_file_size, read_limited};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

/// A mesh as read from a file: positions, optional per-vertex normals, and triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, when the file has them (they say which side a face turns to in
    /// renderers that shade with them).
    pub normals: Option<Vec<Vec3>>,
    /// Vertex indices of each triangle (polygons are split into fans).
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex texture coordinates, when the file has them.
    pub uvs: Option<Vec<Vec2>>,
}

impl MeshData {
    /// The triangles as vertex triples.
    pub fn triangle_vertices(&self) -> Vec<[Vec3; 3]> {
        self.triangles
            .iter()
            .map(|t| t.map(|i| self.positions[i as usize]))
            .collect()
    }
}

/// Writes `triangles` as a binary little-endian PLY, with `uvs` (texture coordinates of
/// each triangle's vertices, or empty) as `u` and `v`; vertices shared where their bits are
/// equal, triangles in the given order and winding.
pub fn write_ply(path: &Path, triangles: &[[Vec3; 3]], uvs: &[[Vec2; 3]]) -> std::io::Result<()> {
    let textured = !uvs.is_empty();
    let mut index: HashMap<[u32; 5], u32> = HashMap::new();
    let mut vertices: Vec<[f32; 5]> = Vec::new();
    let mut faces = Vec::with_capacity(triangles.len());
    for (i, t) in triangles.iter().enumerate() {
        faces.push(std::array::from_fn::<u32, 3, _>(|k| {
            let uv = uvs.get(i).map_or(Vec2::ZERO, |uv| uv[k]);
            let vertex = [t[k].x, t[k].y, t[k].z, uv.x, uv.y];
            *index.entry(vertex.map(f32::to_bits)).or_insert_with(|| {
                vertices.push(vertex);
                (vertices.len() - 1) as u32
            })
        }));
    }
    let mut out = Vec::with_capacity(200 + vertices.len() * 20 + faces.len() * 13);
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment written by ppm export\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n{}\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        vertices.len(),
        if textured {
            "property float u\nproperty float v\n"
        } else {
            ""
        },
        faces.len()
    )?;
    let floats = if textured { 5 } else { 3 };
    for v in &vertices {
        for c in &v[..floats] {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for f in &faces {
        out.push(3);
        for i in f {
            out.extend_from_slice(&(*i as i32).to_le_bytes());
        }
    }
    crate::file::output::write_bytes(path, out)
}

/// Reads a PLY file's `vertex` (x, y, z, optional nx, ny, nz) and `face` (`vertex_indices`
/// or `vertex_index`) elements; other elements are skipped. The error says what is wrong.
pub fn read_ply(path: &Path) -> Result<MeshData, String> {
    let bytes = read_limited(path, MESH_FILE_LIMIT)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    parse_ply(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Reads an OBJ file with tobj: every object and group, polygons triangulated.
pub fn read_obj(path: &Path) -> Result<MeshData, String> {
    check_file_size(path, MESH_FILE_LIMIT)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(path, &options)
        .map_err(|e| format!("cannot load OBJ {}: {e}", path.display()))?;
    let mut mesh = MeshData::default();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let mut all_have_normals = true;
    let mut all_have_uvs = true;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if m.normals.len() == m.positions.len() {
            normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        } else {
            all_have_normals = false;
            normals.extend(std::iter::repeat_n(Vec3::ZERO, count));
        }
        if m.texcoords.len() == count * 2 {
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        } else {
            all_have_uvs = false;
            uvs.extend(std::iter::repeat_n(Vec2::ZERO, count));
        }
        mesh.triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if all_have_normals && !mesh.positions.is_empty() {
        mesh.normals = Some(normals);
    }
    if all_have_uvs && !mesh.positions.is_empty() {
        mesh.uvs = Some(uvs);
    }
    let count = mesh.positions.len() as u32;
    if mesh.triangles.iter().flatten().any(|&i| i >= count) {
        return Err(format!(
            "{}: a face refers to a vertex beyond the {count} there are",
            path.display()
        ));
    }
    Ok(mesh)
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Copy)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
}

struct Property {
    name: String,
    /// `Some(count type)` for a list property.
    list: Option<Scalar>,
    value: Scalar,
}

struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// A value read from the body: `f64` holds every PLY scalar exactly, an `f32` included.
struct Body<'a> {
    format: Format,
    bytes: &'a [u8],
    at: usize,
    words: std::str::SplitAsciiWhitespace<'a>,
}

impl Body<'_> {
    fn read(&mut self, ty: Scalar) -> Result<f64, String> {
        if self.format == Format::Ascii {
            let word = self.words.next().ok_or("the data ends early")?;
            return word
                .parse::<f64>()
                .map_err(|_| format!("\"{word}\" is not a number"));
        }
        let n = ty.size();
        let raw = self
            .bytes
            .get(self.at..self.at + n)
            .ok_or("the data ends early")?;
        self.at += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(raw);
        if self.format == Format::Big {
            b[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}

fn parse_ply(bytes: &[u8]) -> Result<MeshData, String> {
    const END: &[u8] = b"end_header";
    let end = bytes
        .windows(END.len())
        .position(|w| w == END)
        .ok_or("no end_header: not a PLY file")?;
    let body_start = bytes[end..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| end + i + 1);
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| "the header is not text")?;
    let mut lines = header.lines().map(str::trim);
    if lines.next() != Some("ply") {
        return Err("does not start with \"ply\"".into());
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in lines {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    other => return Err(format!("unknown format \"{other}\"")),
                })
            }
            ["element", name, count] => elements.push(Element {
                name: (*name).to_owned(),
                count: count
                    .parse()
                    .map_err(|_| format!("element {name}: bad count \"{count}\""))?,
                properties: Vec::new(),
            }),
            ["property", "list", count, value, name] => {
                let element = elements.last_mut().ok_or("a property before any element")?;
                element.properties.push(Property {
                    name: (*name).to_owned(),
                    list: Some(
                        Scalar::parse(count).ok_or_else(|| format!("unknown type \"{count}\""))?,
                    ),
                    value: Scalar::parse(value)
                        .ok_or_else(|| format!("unknown type \"{value}\""))?,
                })
            }
            ["property", ty, name] => {
                let element = elements.last_mut().ok_or("a property before any element")?;
                element.properties.push(Property {
                    name: (*name).to_owned(),
                    list: None,
                    value: Scalar::parse(ty).ok_or_else(|| format!("unknown type \"{ty}\""))?,
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            _ => return Err(format!("header line \"{line}\" is not understood")),
        }
    }
    let format = format.ok_or("the header has no format line")?;
    let body = &bytes[body_start..];
    let text = if format == Format::Ascii {
        std::str::from_utf8(body).map_err(|_| "the ascii data is not text")?
    } else {
        ""
    };
    let mut reader = Body {
        format,
        bytes: body,
        at: 0,
        words: text.split_ascii_whitespace(),
    };
    let mut mesh = MeshData::default();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for element in &elements {
        let find = |name: &str| element.properties.iter().position(|p| p.name == name);
        let xyz = [find("x"), find("y"), find("z")];
        let nxyz = [find("nx"), find("ny"), find("nz")];
        // The spellings of texture coordinates PLY writers use (pbrt-v4 reads the same).
        let uv = [
            ("u", "v"),
            ("s", "t"),
            ("texture_u", "texture_v"),
            ("texture_s", "texture_t"),
        ]
        .into_iter()
        .map(|(u, v)| [find(u), find(v)])
        .find(|uv| !uv.contains(&None))
        .unwrap_or([None, None]);
        let indices = find("vertex_indices").or_else(|| find("vertex_index"));
        let is_vertex = element.name == "vertex";
        if is_vertex && xyz.contains(&None) {
            return Err("the vertex element lacks x, y or z".into());
        }
        let has_normals = is_vertex && !nxyz.contains(&None);
        let has_uvs = is_vertex && !uv.contains(&None);
        // An element without properties has nothing to read, however many it counts.
        let count = if element.properties.is_empty() {
            0
        } else {
            element.count
        };
        for _ in 0..count {
            let mut scalars = [0.0f64; 8];
            for (k, p) in element.properties.iter().enumerate() {
                match p.list {
                    None => {
                        let v = reader.read(p.value)?;
                        if let Some(slot) = xyz
                            .iter()
                            .chain(&nxyz)
                            .chain(&uv)
                            .position(|&i| i == Some(k))
                        {
                            scalars[slot] = v;
                        }
                    }
                    Some(count_type) => {
                        // No capacity from the count: a corrupt one would allocate before
                        // the data runs out.
                        let n = reader.read(count_type)? as usize;
                        let mut polygon = Vec::new();
                        for _ in 0..n {
                            polygon.push(reader.read(p.value)?);
                        }
                        if element.name == "face" && indices == Some(k) {
                            if let Some(bad) = polygon.iter().find(|&&i| {
                                !(i >= 0.0 && i.fract() == 0.0 && i <= f64::from(u32::MAX))
                            }) {
                                return Err(format!("face index {bad} is not a vertex index"));
                            }
                            for i in 1..n.saturating_sub(1) {
                                mesh.triangles.push(
                                    [polygon[0], polygon[i], polygon[i + 1]].map(|x| x as u32),
                                );
                            }
                        }
                    }
                }
            }
            if is_vertex {
                let v = |a: usize| {
                    Vec3::new(
                        scalars[a] as f32,
                        scalars[a + 1] as f32,
                        scalars[a + 2] as f32,
                    )
                };
                mesh.positions.push(v(0));
                if has_normals {
                    normals.push(v(3));
                }
                if has_uvs {
                    uvs.push(Vec2::new(scalars[6] as f32, scalars[7] as f32));
                }
            }
        }
        if element.name == "face" && indices.is_none() {
            return Err("the face element has no vertex_indices list".into());
        }
    }
    if normals.len() == mesh.positions.len() && !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    if uvs.len() == mesh.positions.len() && !uvs.is_empty() {
        mesh.uvs = Some(uvs);
    }
    let count = mesh.positions.len() as u32;
    if let Some(t) = mesh
        .triangles
        .iter()
        .find(|t| t.iter().any(|&i| i >= count))
    {
        return Err(format!(
            "face {t:?} refers to a vertex beyond the {count} there are"
        ));
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_ply_reads_back_bit_for_bit() {
        let tris = vec![
            [
                Vec3::new(0.1, 0.2, 0.3),
                Vec3::new(1e-7, -0.0, 3.5e9),
                Vec3::new(7.0, 8.0, 9.0),
            ],
            [
                Vec3::new(0.1, 0.2, 0.3),
                Vec3::new(7.0, 8.0, 9.0),
                Vec3::new(-1.0, 0.0, 2.0),
            ],
        ];
        let path = std::env::temp_dir().join(format!("ppm-ply-{}.ply", std::process::id()));
        write_ply(&path, &tris, &[]).unwrap();
        let mesh = read_ply(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(mesh.positions.len(), 4, "shared vertices are written once");
        let back = mesh.triangle_vertices();
        let bits = |t: &[[Vec3; 3]]| -> Vec<u32> {
            t.iter()
                .flatten()
                .flat_map(|v| v.to_array().map(f32::to_bits))
                .collect()
        };
        assert_eq!(bits(&back), bits(&tris));
        // With texture coordinates: a vertex shared in position but not in coordinates is
        // written twice, and every coordinate comes back as written.
        let uvs = vec![
            [
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(0.5, 1.0),
            ],
            [
                Vec2::new(0.25, 0.0),
                Vec2::new(0.5, 1.0),
                Vec2::new(-3.0, 2.0),
            ],
        ];
        write_ply(&path, &tris, &uvs).unwrap();
        let mesh = read_ply(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(mesh.positions.len(), 5);
        let read_uvs = mesh.uvs.as_ref().unwrap();
        let back: Vec<[Vec2; 3]> = mesh
            .triangles
            .iter()
            .map(|t| t.map(|i| read_uvs[i as usize]))
            .collect();
        assert_eq!(back, uvs);
    }

    #[test]
    fn ascii_ply_with_normals_and_quads_is_read() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                    property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                    element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3\n";
        let mesh = parse_ply(text.as_bytes()).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.normals.unwrap()[2], Vec3::Z);
    }

    /// Counts in a file are not trusted: a list of 2^31 indices reserves nothing (it ends
    /// where the data ends), a billion billion elements without properties read nothing, and
    /// a negative index is no index.
    #[test]
    fn corrupt_counts_and_indices_are_errors_not_allocations_or_hangs() {
        let huge_list = b"ply\nformat binary_little_endian 1.0\nelement face 1\n\
                          property list int int vertex_indices\nend_header\n\xff\xff\xff\x7f";
        assert_eq!(parse_ply(huge_list).unwrap_err(), "the data ends early");
        let empty = "ply\nformat ascii 1.0\nelement junk 1000000000000000000\nend_header\n";
        assert_eq!(parse_ply(empty.as_bytes()).unwrap(), MeshData::default());
        let negative = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                        property float y\nproperty float z\nelement face 1\n\
                        property list uchar int vertex_indices\nend_header\n\
                        0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n";
        assert_eq!(
            parse_ply(negative.as_bytes()).unwrap_err(),
            "face index -1 is not a vertex index"
        );
    }

    #[test]
    fn truncated_binary_ply_is_an_error() {
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n\
                    property float y\nproperty float z\nend_header\n\0\0\0\0";
        assert_eq!(
            parse_ply(text.as_bytes()).unwrap_err(),
            "the data ends early"
        );
    }
}
