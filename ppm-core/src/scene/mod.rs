//! Scenes: the model, the TOML file format, and validation; Mitsuba 3 and pbrt-v4 scene
//! files written for other renderers and read back.

mod error;
mod file;
pub mod interop;
mod magnitude;
pub mod mesh_file;
pub mod mitsuba;
mod model;
pub mod path;
pub mod pbrt;

pub use error::SceneError;
pub use file::{degenerate_triangle_count, load_scene_file, parse_scene};
pub use interop::{Export, ExportError, ExportOptions};
pub use magnitude::{MAX_COORDINATE, MAX_LIGHT_POWER, MIN_EXTENT, check_magnitudes, number};
pub use model::{
    Camera, Material, MaterialKind, Move, Object, RenderDefaults, Scene, quad_triangles,
    triangle_area,
};
