//! Mitsuba 3's XML scene format: export of any scene, import of the subset we render.
//!
//! Conventions, checked in Mitsuba 3's source (`Transform::look_at`, `perspective_projection`,
//! the `area` emitter, `Mesh`): `look_at` gives camera +x = `up x dir`, which the sensor puts
//! on the image's left, so its image right is our `forward x up`; pixel (0, 0) is the
//! top-left; `fov_axis = "y"` makes `fov` the full vertical angle as ours; an `area` emitter
//! emits on the side of the shading normal, which for a mesh loaded with `face_normals` is
//! `(v1 - v0) x (v2 - v0)`, as ours. Imported one-sided `diffuse`, `conductor` and `plastic`
//! BSDFs become our two-sided surfaces (they differ only where a back face is seen).

mod read;
mod write;

pub use read::{load_mitsuba_file, parse_mitsuba};
pub use write::export_mitsuba;
