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
    /// Padding.
    pub _pad0: u32,
}
