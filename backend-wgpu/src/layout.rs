//! Uniform structs of this backend's own kernels (the shared buffer elements live in
//! `ppm_core::layout`). Each is mirrored in the WGSL of its pass; `tests/layout.rs` checks both.

use bytemuck::{Pod, Zeroable};

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

/// photon_grid.wgsl's parameters. 16 bytes.
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
