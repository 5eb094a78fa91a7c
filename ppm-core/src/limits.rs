//! Sizes refused before anything is read, allocated or traced, each bound with its argument:
//! an error says what was asked, what fits, and which option to change, instead of the
//! process dying in an allocation or reading `/dev/zero` for ever.

use crate::layout::{HitPoint, Photon};
use crate::params::RenderParams;
use crate::scene::{MaterialKind, Scene, SceneError};
use std::io::Read;
use std::path::Path;

/// Bytes of one hit-point slot: every slot lives for the whole render.
pub const HIT_POINT_BYTES: u64 = size_of::<HitPoint>() as u64;

/// Bytes of one photon deposit: a pass's deposits are all held until its gather.
pub const PHOTON_BYTES: u64 = size_of::<Photon>() as u64;

/// Bytes a pixel of a path-traced reference holds: eight batch sums of three `f64` (192), a
/// round of eight RGB `f32` samples (96), the mean and variance images (24).
pub const REFERENCE_PIXEL_BYTES: u64 = 192 + 96 + 24;

/// Largest scene file (TOML, Mitsuba XML, pbrt): the parsers hold the text and a tree several
/// times its size, and a scene of more than 64 MiB of text keeps its geometry where it
/// belongs, in OBJ or PLY files.
pub const SCENE_FILE_LIMIT: u64 = 64 << 20;

/// Largest mesh file (OBJ, PLY): both readers hold the whole file, then its vertices and
/// triangles, about three times its size; 2 GiB is some 80 million triangles, more than the
/// BVH builder and a render of this tool handle in hours.
pub const MESH_FILE_LIMIT: u64 = 2 << 30;

/// Memory a render may plan to fill, checked before allocation.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryBudget {
    /// Bytes.
    pub bytes: u64,
    /// Where the number comes from, for error messages.
    pub source: String,
}

/// The budget where the machine's memory is unknown (no `/proc/meminfo`).
const FALLBACK_BYTES: u64 = 8 << 30;

impl MemoryBudget {
    /// Three quarters of physical memory, leaving the rest to the system, the scene and its
    /// BVH; a fixed 8 GiB where the machine's memory cannot be read.
    pub fn detect() -> Self {
        let total = std::fs::read_to_string("/proc/meminfo")
            .ok()
            .and_then(|text| mem_total(&text));
        match total {
            Some(total) => Self {
                bytes: total / 4 * 3,
                source: format!("3/4 of this machine's {}", bytes(total)),
            },
            None => Self {
                bytes: FALLBACK_BYTES,
                source: "the budget where the machine's memory is unknown".into(),
            },
        }
    }

    /// Refuses `needed` bytes beyond the budget: `field = value` asked for them, `what` they
    /// hold, `change` says which options lower them.
    fn check(
        &self,
        field: &str,
        value: impl std::fmt::Display,
        needed: u64,
        what: &str,
        change: &str,
    ) -> Result<(), SceneError> {
        if needed <= self.bytes {
            return Ok(());
        }
        Err(SceneError::invalid(
            "command line",
            field,
            value,
            format!(
                "{what} need {}; {} fits ({}): lower {change}",
                bytes(needed),
                bytes(self.bytes),
                self.source
            ),
        ))
    }
}

/// `MemTotal` of `/proc/meminfo`, in bytes.
fn mem_total(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// Bytes for people: decimal units, as the README states sizes.
pub fn bytes(n: u64) -> String {
    let n = n as f64;
    match n {
        n if n >= 1e12 => format!("{:.1} TB", n / 1e12),
        n if n >= 1e9 => format!("{:.1} GB", n / 1e9),
        n if n >= 1e6 => format!("{:.1} MB", n / 1e6),
        n => format!("{n} bytes"),
    }
}

/// Checks that a render's hit-point slots and one pass's deposits fit `budget`.
pub fn check_render_memory(
    params: &RenderParams,
    scene: &Scene,
    budget: &MemoryBudget,
) -> Result<(), SceneError> {
    let slots = u64::from(params.width) * u64::from(params.height) * u64::from(params.spp);
    budget.check(
        "width * height * spp",
        format!(
            "{} * {} * {} = {slots}",
            params.width, params.height, params.spp
        ),
        slots * HIT_POINT_BYTES,
        &format!("hit points of {HIT_POINT_BYTES} bytes"),
        "--width, --height or --spp",
    )?;
    check_deposits(
        params.photons_per_pass,
        "photons_per_pass",
        "--photons-per-pass",
        params,
        scene,
        budget,
    )
}

/// Checks that a pass of `photons` fits `budget`: `field` and `option` name the setting.
///
/// A path deposits at most once per diffuse bounce, and survives each with probability at
/// most the largest albedo `a` (Russian roulette), so it deposits `1 / (1 - a)` times on
/// average at most (no more than its depth limit): the pass's expected deposits.
pub fn check_deposits(
    photons: u32,
    field: &str,
    option: &str,
    params: &RenderParams,
    scene: &Scene,
    budget: &MemoryBudget,
) -> Result<(), SceneError> {
    let albedo = scene
        .materials
        .iter()
        .filter_map(|m| match m.kind {
            MaterialKind::Diffuse { albedo } | MaterialKind::Light { albedo, .. } => {
                Some(albedo.max_element())
            }
            _ => None,
        })
        .fold(0.0f32, f32::max);
    let depth = f64::from(params.max_photon_depth.max(1));
    let per_path = (1.0 / (1.0 - f64::from(albedo).min(1.0))).min(depth);
    let deposits = (f64::from(photons) * per_path).ceil() as u64;
    budget.check(
        field,
        photons,
        deposits * PHOTON_BYTES,
        &format!(
            "{deposits} deposits of {PHOTON_BYTES} bytes ({per_path:.1} per path for albedo \
             {albedo})"
        ),
        option,
    )
}

/// Checks that a path-traced reference of `width` x `height` fits `budget`.
pub fn check_reference_memory(
    width: u32,
    height: u32,
    budget: &MemoryBudget,
) -> Result<(), SceneError> {
    let pixels = u64::from(width) * u64::from(height);
    budget.check(
        "width * height",
        format!("{width} * {height} = {pixels}"),
        pixels * REFERENCE_PIXEL_BYTES,
        &format!("reference pixels of {REFERENCE_PIXEL_BYTES} bytes"),
        "--width or --height",
    )
}

/// Reads a file of at most `limit` bytes, refusing anything that is not a regular file (a
/// device such as `/dev/zero`, a pipe, a folder) before reading a byte. The error says what is
/// wrong, without the path (the caller names the file).
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let mut file = std::fs::File::open(path).map_err(io_reason)?;
    let size = regular_size(&file.metadata().map_err(io_reason)?, limit)?;
    let mut bytes = Vec::with_capacity(size as usize);
    file.by_ref()
        .take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(io_reason)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64, limit));
    }
    Ok(bytes)
}

/// [`read_limited`] as UTF-8 text.
pub fn read_text_limited(path: &Path, limit: u64) -> Result<String, String> {
    String::from_utf8(read_limited(path, limit)?)
        .map_err(|e| format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()))
}

/// Checks, before a reader that opens `path` itself (tobj), that it is a regular file of at
/// most `limit` bytes.
pub fn check_file_size(path: &Path, limit: u64) -> Result<(), String> {
    let meta = std::fs::metadata(path).map_err(io_reason)?;
    regular_size(&meta, limit).map(|_| ())
}

/// What the operating system said, with the commonest case in words.
fn io_reason(e: std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        _ => e.to_string(),
    }
}

fn regular_size(meta: &std::fs::Metadata, limit: u64) -> Result<u64, String> {
    if !meta.is_file() {
        return Err(if meta.is_dir() {
            "is a folder, not a file".into()
        } else {
            "is not a regular file (a device or a pipe never ends)".into()
        });
    }
    if meta.len() > limit {
        return Err(too_large(meta.len(), limit));
    }
    Ok(meta.len())
}

fn too_large(size: u64, limit: u64) -> String {
    format!("is {size} bytes; this kind of file may have at most {limit}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny_budget() -> MemoryBudget {
        MemoryBudget {
            bytes: 1 << 20,
            source: "a test's 1 MiB".into(),
        }
    }

    fn cornell() -> Scene {
        crate::scene::parse_scene(
            include_str!("../../scenes/data/cornell-box.toml"),
            "cornell-box.toml",
            Path::new("."),
        )
        .unwrap()
    }

    #[test]
    fn total_memory_is_read_from_meminfo() {
        let text = "MemTotal:       16318480 kB\nMemFree:         1000 kB\n";
        assert_eq!(mem_total(text), Some(16_318_480 * 1024));
        assert_eq!(mem_total("garbage"), None);
        assert!(MemoryBudget::detect().bytes > 0);
    }

    #[test]
    fn hit_points_beyond_the_budget_are_refused_naming_the_options() {
        let scene = cornell();
        let mut params = RenderParams::for_scene(&scene);
        (params.width, params.height, params.photons_per_pass) = (100, 100, 100);
        assert!(check_render_memory(&params, &scene, &tiny_budget()).is_ok());
        params.width = 200;
        let err = check_render_memory(&params, &scene, &tiny_budget())
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "command line: width * height * spp = 200 * 100 * 1 = 20000: hit points of 96 \
             bytes need 1.9 MB; 1.0 MB fits (a test's 1 MiB): lower --width, --height or --spp"
        );
    }

    /// cornell-box's whitest albedo is 0.725: 3.6 deposits per path at most on average.
    #[test]
    fn deposits_are_bounded_by_the_largest_albedo() {
        let scene = cornell();
        let mut params = RenderParams::for_scene(&scene);
        (params.width, params.height) = (8, 8);
        params.photons_per_pass = 9_000;
        assert!(check_render_memory(&params, &scene, &tiny_budget()).is_ok());
        params.photons_per_pass = 10_000;
        let err = check_render_memory(&params, &scene, &tiny_budget())
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("command line: photons_per_pass = 10000: 36364 deposits of 32 bytes")
                && err.ends_with("lower --photons-per-pass"),
            "{err}"
        );
    }

    #[test]
    fn a_device_or_an_oversized_file_is_refused_before_reading() {
        if cfg!(target_os = "linux") {
            let err = read_limited(Path::new("/dev/zero"), SCENE_FILE_LIMIT).unwrap_err();
            assert_eq!(err, "is not a regular file (a device or a pipe never ends)");
        }
        let dir = std::env::temp_dir();
        assert_eq!(
            check_file_size(&dir, MESH_FILE_LIMIT).unwrap_err(),
            "is a folder, not a file"
        );
        let path = dir.join(format!("ppm-limits-{}.txt", std::process::id()));
        std::fs::write(&path, "0123456789").unwrap();
        let small = read_limited(&path, 10);
        let large = read_limited(&path, 9);
        std::fs::remove_file(&path).ok();
        assert_eq!(small.unwrap().len(), 10);
        assert_eq!(
            large.unwrap_err(),
            "is 10 bytes; this kind of file may have at most 9"
        );
    }
}
