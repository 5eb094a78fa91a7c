//! Scenes: the model, its poses and moves, and its validation. Scene files are read and
//! written by the `scenes` crate (`scenes::file`).

mod error;
mod magnitude;
mod model;
pub mod path;
#[cfg(test)]
pub(crate) mod testing;
mod texture;

pub use error::SceneError;
pub use magnitude::{MAX_COORDINATE, MAX_LIGHT_POWER, MIN_EXTENT, check_magnitudes, number};
pub use model::{
    Camera, Material, MaterialKind, Move, Object, RenderDefaults, Scene, degenerate_triangle_count,
    quad_triangles, triangle_area,
};
pub(crate) use texture::gpu_texture;
pub use texture::{MAX_TEXTURE_SIDE, Texture, TextureFilter, pack_texel, sample, unpack_texel};
