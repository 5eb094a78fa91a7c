//! Drives any backend through the passes of ppm-core: the one driver and its report, the
//! ground truth and the error reports measured against it, the diff harness that compares two
//! backends, the conformance suite, the stress family, and scene lookup by name or file. The
//! `ppm` command is built on it.

#![warn(missing_docs)]

pub mod chart;
pub mod cli;
pub mod clock;
pub mod conformance;
pub mod convergence;
pub mod diff;
pub mod driver;
pub mod error_report;
pub mod merge;
pub mod pick;
pub mod reference;
pub mod registry;
pub mod report;
pub mod shard;
pub mod stress;

use ppm_core::scene::{Scene, SceneError};
use scenes::file::load_scene_file;
use std::path::Path;

/// A built-in scene by name, or else a scene file by path: Mitsuba 3 (`.xml`), pbrt-v4
/// (`.pbrt`), or our TOML format (any other extension).
pub fn load_scene(name_or_path: &str) -> Result<Scene, SceneError> {
    if let Some(builtin) = scenes::builtin(name_or_path) {
        return builtin.load();
    }
    let path = Path::new(name_or_path);
    if !path.exists() {
        let names: Vec<&str> = scenes::BUILTIN.iter().map(|s| s.name).collect();
        return Err(SceneError::Read {
            file: name_or_path.to_owned(),
            reason: format!(
                "no such file, and no built-in scene has this name (built-in: {})",
                names.join(", ")
            ),
        });
    }
    match path.extension().and_then(|e| e.to_str()) {
        Some("xml") => scenes::file::mitsuba::load_mitsuba_file(path),
        Some("pbrt") => scenes::file::pbrt::load_pbrt_file(path),
        _ => load_scene_file(path),
    }
}
