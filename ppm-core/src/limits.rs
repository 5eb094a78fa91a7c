//! Sizes refused before anything is allocated or traced, each bound with its argument: an
//! error says what was asked, what fits, and which option to change, instead of the process
//! dying in an allocation. (The files a scene may be read from are bounded in
//! `scenes::file::limits`.)

use crate::layout::{HitPoint, Photon};
use crate::params::RenderParams;
use crate::scene::{MaterialKind, Scene, SceneError};

/// Bytes of one hit-point slot: every slot lives for the whole render.
pub const HIT_POINT_BYTES: u64 = size_of::<HitPoint>() as u64;

/// Bytes of one photon deposit: a pass's deposits are all held until its gather.
pub const PHOTON_BYTES: u64 = size_of::<Photon>() as u64;

/// Bytes a pixel of a path-traced reference holds: eight batch sums of three `f64` (192), a
/// round of eight RGB `f32` samples (96), the mean and variance images (24).
pub const REFERENCE_PIXEL_BYTES: u64 = 192 + 96 + 24;

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
/// average at most (no more than its depth limit): the pass's expected deposits. A coated
/// surface counts as albedo one: a photon that takes its coat's reflection plays no
/// roulette, so only the depth limit bounds its deposits.
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
            MaterialKind::Coated { .. } => Some(1.0),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn total_memory_is_read_from_meminfo() {
        let text = "MemTotal:       16318480 kB\nMemFree:         1000 kB\n";
        assert_eq!(mem_total(text), Some(16_318_480 * 1024));
        assert_eq!(mem_total("garbage"), None);
        assert!(MemoryBudget::detect().bytes > 0);
    }
}
