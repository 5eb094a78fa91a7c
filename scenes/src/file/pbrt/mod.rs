//! pbrt-v4's scene format: export of any scene, import of the subset we render.
//!
//! Conventions, checked in pbrt-v4's source (`LookAt`, `BasicSceneBuilder::WorldBegin`,
//! `Triangle`, `DiffuseAreaLight`): `LookAt` gives camera +x = `up x dir`, and pbrt's raster
//! x grows with camera x, so a plain `LookAt` shows our world mirrored; `Scale -1 1 1` before
//! it gives our image. `WorldBegin` resets the transform. A triangle's normal is
//! `(v1 - v0) x (v2 - v0)`, negated under `ReverseOrientation` or a transform that swaps
//! handedness, and turned to the vertex normals when the mesh has them; a diffuse area light
//! emits on that side only unless `twosided`. An imported scene whose camera has no mirroring
//! transform is mirrored in x as a whole, so our image is pbrt's.

mod lexer;
mod read;
mod write;

pub use read::{load_pbrt_file, parse_pbrt};
pub use write::{PBRT_MAX_DEPTH, export_pbrt};
