//! The contract of progressive photon mapping with compensation photons: what every backend
//! shares and nothing that executes.
//!
//! - [`passes`]: one trait per pass, implemented by each backend.
//! - [`layout`]: the `#[repr(C)]` buffer elements, byte-for-byte what the GPU binds.
//! - [`update`]: the progressive update formulas in their stable forms.
//! - [`rng`], [`sampling`], [`geometry`], [`bsdf`]: math that exists once here and once in
//!   WGSL; [`bsdf`] is what every material does with light.
//! - [`trace`], [`eye_path`], [`direct_light`], [`photon_path`], [`local_move`]: the per-item
//!   functions of the passes (ray queries over the flattened tree, an eye path, a slot's
//!   direct light, a photon's path, a local move's decisions and corrections), one home in Rust, each the twin of a WGSL function;
//!   [`camera_move`]: what a slot of a new view takes over from the slots of the old one;
//!   backends run them over their slots.
//! - [`scene`], [`compile`]: the scene model, its poses and paths of moves nobody declared
//!   ([`scene::path`]), and the flattening into buffers; [`textures`]: the colour a
//!   texture gives a surface point. Files are the `scenes` crate's.
//! - [`grid`]: the photon hash grid's cell and bucket mapping; [`screen_cover`]: the pixels a
//!   mesh may cover, and [`reach`]: where a slot's paths and light may pass, for local mode's
//!   resets and corrections.
//! - [`params`], [`image`], [`metrics`], [`stats`]: render settings, images, the distances
//!   error reports measure and the statistics of the tests of agreement; [`limits`]: the
//!   sizes refused before anything is allocated or traced; [`device_time`]: the time a
//!   device measured in each kernel of each pass.

#![warn(missing_docs)]

pub mod bsdf;
pub mod camera_move;
pub mod check;
pub mod compile;
pub mod device_time;
pub mod direct_light;
pub mod emission;
pub mod eye_path;
pub mod geometry;
pub mod grid;
pub mod image;
pub mod layout;
pub mod limits;
pub mod local_move;
pub mod metrics;
pub mod params;
pub mod passes;
pub mod photon_path;
pub mod qmc;
pub mod reach;
pub mod refit;
pub mod region;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod scene_tree;
pub mod screen_cover;
pub mod stats;
pub mod textures;
pub mod trace;
pub mod update;
