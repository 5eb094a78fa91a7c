//! Uniform structs of this backend's own kernels (the shared buffer elements live in
//! `ppm_core::layout`). Each is mirrored in the WGSL of its pass; `tests/layout.rs` checks both.

use bytemuck::{Pod, Zeroable};
use ppm_core::layout::{CameraMoveParams, GpuBounds, HitPoint};

/// A bit of [`ppm_core::layout::PhotonPassParams::flags`] this backend sets on its own
/// launches, above the contract's [`ppm_core::layout::photon_flags`]: a pairing pose B whose
/// pose-A deposits are held unfiled in the same buffer marks both deposits of each pair that
/// cancels ([`ppm_core::update::pairing::Partner::cancels`]) by the words beside them
/// (`CANCELLED_PARTNER` in layout.wgsl), and the map that joins them leaves both out
/// ([`GridBuildParams::leave_out`]). Only while they are unfiled: pose A's deposits, filed on
/// their own, would otherwise lose their partners.
pub const PHOTON_MARK_CANCELLED: u32 = 1 << 31;

/// scan.wgsl's parameters. 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ScanParams {
    /// Elements to scan.
    pub count: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

/// photon_grid.wgsl's parameters. 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridBuildParams {
    /// Photons in the batch.
    pub photon_count: u32,
    /// Hash buckets, a power of two.
    pub bucket_count: u32,
    /// Hit-point slots (for the largest radius).
    pub hit_point_count: u32,
    /// The pass's `gather_r2_floor`: the radii the cells are sized to are at least this.
    pub r2_floor: f32,
    /// Deposits of an earlier pass that this one joins (a local correction's pose A, held
    /// for its pose B), first in the buffer: in each bucket they come before the pass's own,
    /// as in the CPU's map, whatever their ranks.
    pub held: u32,
    /// Non-zero: leave out the deposits marked as one of a pair that cancels (a pairing pose
    /// B joining its pose A's, [`PHOTON_MARK_CANCELLED`]), which need four words beside each.
    pub leave_out: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

/// hit_point_update.wgsl's parameters. 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct UpdateParams {
    /// Distance beyond which a hit point counts as moved.
    pub epsilon: f32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

/// scene.wgsl's `SceneIndex`: where each kind of record starts in the scene table (in
/// texels; materials start at 0), and how many lights and mover boxes it holds (a table has
/// no length of its own). 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SceneIndex {
    /// First texel of the triangles.
    pub triangles: u32,
    /// First texel of the BVH nodes.
    pub nodes: u32,
    /// First texel of the lights.
    pub lights: u32,
    /// First texel of the mover boxes.
    pub movers: u32,
    /// Emitting triangles.
    pub light_count: u32,
    /// Boxes of moving objects.
    pub mover_count: u32,
    /// First texel of the triangles' texture coordinates (none without a texture).
    pub uvs: u32,
    /// First texel of the texture headers.
    pub textures: u32,
}

/// screen_cover.wgsl's `CoverParams`: the camera's projection onto the image
/// (`ppm_core::screen_cover::Projection`, its inverse basis computed here as there), and what
/// local_move.wgsl's cover kernel walks. 80 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CoverParams {
    /// The inverse of the camera's basis (forward, right, up as columns), a column per row,
    /// each padded to four floats as WGSL's `mat3x3<f32>` lays them out.
    pub to_camera: [[f32; 4]; 3],
    /// The eye.
    pub eye: [f32; 3],
    /// Triangles of the scene the cover kernel walks.
    pub triangles: u32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Moved objects whose triangles it marks.
    pub objects: u32,
    /// Padding.
    pub _pad0: u32,
}

impl CoverParams {
    /// The projection of `camera`, as `ppm_core::screen_cover::Projection::new` makes it.
    pub fn new(camera: &ppm_core::layout::GpuCamera) -> Self {
        let basis =
            glam::Mat3::from_cols(camera.forward.into(), camera.right.into(), camera.up.into());
        let inverse = basis.inverse();
        let column = |c: glam::Vec3| [c.x, c.y, c.z, 0.0];
        Self {
            to_camera: [
                column(inverse.x_axis),
                column(inverse.y_axis),
                column(inverse.z_axis),
            ],
            eye: camera.eye,
            width: camera.width,
            height: camera.height,
            ..Self::default()
        }
    }
}

/// local_move_vectors.wgsl's input: a case of a local move's per-slot decisions. 320 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MoveDecisionCase {
    /// The box of a slot's paths (also the start box of `segments_may_meet`), the end and
    /// target boxes of `segments_may_meet`, then the move's boxes in
    /// `ppm_core::local_move::LocalMove::boxes` order: `objects` in pose A, as many in pose B,
    /// then `lights`.
    pub boxes: [GpuBounds; 8],
    /// The slot's visible point.
    pub position: [f32; 3],
    /// Whether pose B's outline covers its pixel (0 or 1).
    pub covered: u32,
    /// The camera's position.
    pub eye: [f32; 3],
    /// The groups its eye paths met.
    pub eye_met: u32,
    /// Its flags.
    pub flags: u32,
    /// The moved objects' groups.
    pub groups: u32,
    /// The correction's squared floor radius.
    pub r2_floor: f32,
    /// The widest correction disc, in floor radii.
    pub widest: f32,
    /// Moved objects.
    pub objects: u32,
    /// Light boxes.
    pub lights: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
}

/// local_move_vectors.wgsl's output. 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MoveDecisionOutcome {
    /// `segments_may_meet(boxes[0], boxes[1], boxes[2])` (0 or 1).
    pub meets: u32,
    /// The slot's flags after `prepare_slot`.
    pub flags: u32,
    /// `view_test`'s answer: 0 changes, 1 probe, 2 kept.
    pub view: u32,
    /// `prepare_slot`'s correction disc (`correction_r2`).
    pub correction_r2: f32,
}

/// screen_cover_vectors.wgsl's input: a projection onto an image of at most 256 pixels, and a
/// triangle. 128 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CoverCase {
    /// The projection ([`CoverParams::new`]).
    pub cover: CoverParams,
    /// First vertex.
    pub v0: [f32; 3],
    /// Padding.
    pub _pad0: u32,
    /// Second vertex.
    pub v1: [f32; 3],
    /// Padding.
    pub _pad1: u32,
    /// Third vertex.
    pub v2: [f32; 3],
    /// Padding.
    pub _pad2: u32,
}

/// screen_cover_vectors.wgsl's output: a bit per pixel, row-major. 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CoverOutcome {
    /// The bits.
    pub words: [u32; 8],
}

/// layout.wgsl's `ListParams`: how many slots a kernel over a list walks (those a local move
/// listed in pose A or for its probe, or a focus eye pass's slots behind). 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ListParams {
    /// Slots in the list.
    pub count: u32,
    /// Whether the last move's pairs in its pose B are this move's in pose A, keyed and
    /// traced alike (1), or not (0).
    pub known: u32,
    /// Whether the eye and direct-light passes walk a focus pass's list (1) or every slot (0).
    pub focus: u32,
    /// Padding.
    pub _pad0: u32,
}

/// camera_move_vectors.wgsl's input: a fresh slot of the new view, its box, and the camera
/// move it inherits through (the old view's slots are the call's). 288 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct InheritCase {
    /// The slot, traced fresh in the new view.
    pub slot: HitPoint,
    /// The box of its paths.
    pub bounds: GpuBounds,
    /// The cameras before and after.
    pub request: CameraMoveParams,
}

/// camera_move_vectors.wgsl's output: `inherit_slot`'s slot and box after. 160 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct InheritOutcome {
    /// The slot after.
    pub slot: HitPoint,
    /// Its box after.
    pub bounds: GpuBounds,
    /// Whether it inherited (0 or 1).
    pub inherited: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}
