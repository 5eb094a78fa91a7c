//! The contract of progressive photon mapping with compensation photons: what every backend
//! shares and nothing that executes.
//!
//! - [`passes`]: one trait per pass, implemented by each backend.
//! - [`layout`]: the `#[repr(C)]` buffer elements, byte-for-byte what the GPU binds.
//! - [`update`]: the progressive update formulas in their stable forms.
//! - [`rng`], [`sampling`], [`geometry`]: math that exists once here and once in WGSL.
//! - [`scene`], [`compile`]: the scene model, its file format, path files of moves nobody
//!   declared ([`scene::path`]), and the flattening into buffers.
//! - [`grid`]: the photon hash grid's cell and bucket mapping; [`screen_cover`]: the pixels a
//!   mesh may cover, and [`reach`]: where a slot's paths and light may pass, for local mode's
//!   resets and corrections.
//! - [`params`], [`image`], [`metrics`]: render settings, images and their EXR/PNG files, and
//!   the distances error reports measure; [`output`]: every file written whole or not at all;
//!   [`limits`]: the sizes and magnitudes refused before anything is allocated or traced.

#![warn(missing_docs)]

pub mod check;
pub mod compile;
pub mod emission;
pub mod geometry;
pub mod grid;
pub mod image;
pub mod layout;
pub mod limits;
pub mod metrics;
pub mod output;
pub mod params;
pub mod passes;
pub mod qmc;
pub mod reach;
pub mod region;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod screen_cover;
pub mod update;
