//! Everything that reads or writes files, kept out of `ppm-core` so that a backend depends on
//! nothing that parses them: our TOML scene format ([`scene_file`]), path files of moves
//! ([`path`]), Mitsuba 3 and pbrt-v4 scenes ([`mitsuba`], [`pbrt`], exported through
//! [`interop`]), OBJ and PLY meshes ([`mesh`]), EXR and PNG images ([`image`]), texture images
//! ([`texture_image`]), files written
//! whole or not at all ([`output`]) and the sizes refused before reading ([`limits`]).

pub mod bands;
pub mod image;
pub mod interop;
pub mod limits;
pub mod mesh;
pub mod mitsuba;
pub mod output;
pub mod path;
pub mod pbrt;
pub mod scene_file;
pub mod texture_image;

pub use interop::{Export, ExportError, ExportOptions, MeshFile};
pub use scene_file::{load_scene_file, parse_scene};
