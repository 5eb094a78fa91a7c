//! Scenes: the model, the TOML file format, and validation.

mod error;
mod file;
mod model;

pub use error::SceneError;
pub use file::{degenerate_triangle_count, load_scene_file, parse_scene};
pub use model::{
    Camera, Material, MaterialKind, Move, Object, RenderDefaults, Scene, quad_triangles,
    triangle_area,
};
