//! The per-pass photon map on the GPU (photon_grid.wgsl): bounds, grid parameters, bucket
//! counts, scan, scatter, and the per-bucket sort that makes the order deterministic.

use crate::buffers::{storage_zeroed, uniform};
use crate::context::GpuContext;
use crate::kernel::{Kernel, Slot, WORKGROUP, shader_module};
use crate::layout::GridBuildParams;
use crate::scan::Scan;
use crate::shaders;
use ppm_core::grid::{RADIUS_BINS, bucket_count};
use ppm_core::layout::{GridParams, GridPhoton, Photon};
use ppm_core::passes::BackendError;

/// One pass's photons and the grid that indexes them.
pub struct PhotonMap {
    /// Deposits, in path order.
    pub photons: wgpu::Buffer,
    /// Number of deposits.
    pub count: u32,
    /// The grid's [`GridParams`], computed on the GPU.
    pub grid: wgpu::Buffer,
    /// Bucket starts: `bucket_count + 1` entries, the last being `count`.
    pub bucket_start: wgpu::Buffer,
    /// Index in `photons` of each photon of `sorted`.
    pub order: wgpu::Buffer,
    /// The photons in bucket order (ascending index within a bucket), with their cell keys.
    pub sorted: wgpu::Buffer,
    /// Path weight of each deposit.
    pub weights: wgpu::Buffer,
}

/// The grid kernels.
pub struct PhotonGridKernels {
    histogram: Kernel,
    params: Kernel,
    count: Kernel,
    scatter: Kernel,
    sort: Kernel,
    copy: Kernel,
}

impl PhotonGridKernels {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        use Slot::{Read, ReadWrite, Uniform};
        let module = shader_module(&ctx.device, "photon_grid", shaders::PHOTON_GRID);
        let slots = [
            Uniform, Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
            ReadWrite,
        ];
        let kernel = |entry, workgroup| Kernel::new(&ctx.device, &module, entry, &slots, workgroup);
        Self {
            histogram: kernel("grid_histogram_main", WORKGROUP),
            params: kernel("grid_params_main", 1),
            count: kernel("grid_count_main", WORKGROUP),
            scatter: kernel("grid_scatter_main", WORKGROUP),
            sort: kernel("grid_sort_main", WORKGROUP),
            copy: kernel("grid_copy_main", WORKGROUP),
        }
    }

    /// Records the grid build over `photons` (`count` deposits), its cells sized to the
    /// radii of the hit points' visible points; returns the map whose buffers the commands
    /// fill.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scan: &Scan,
        (photons, weights, count): (wgpu::Buffer, wgpu::Buffer, u32),
        (hit_points, slots): (&wgpu::Buffer, u32),
    ) -> Result<PhotonMap, BackendError> {
        let bucket_count = bucket_count(count);
        let histogram = storage_zeroed(ctx, "radius histogram", u64::from(RADIUS_BINS) * 4)?;
        let grid = storage_zeroed(ctx, "grid", size_of::<GridParams>() as u64)?;
        let bucket_bytes = (u64::from(bucket_count) + 1) * 4;
        let bucket_start = storage_zeroed(ctx, "bucket_start", bucket_bytes)?;
        let bucket_cursor = storage_zeroed(ctx, "bucket_cursor", bucket_bytes)?;
        let order = storage_zeroed(ctx, "order", u64::from(count) * 4)?;
        let keys = storage_zeroed(ctx, "cell keys", u64::from(count) * 4)?;
        let sorted = storage_zeroed(
            ctx,
            "sorted photons",
            u64::from(count.max(1)) * size_of::<GridPhoton>() as u64,
        )?;
        let params = uniform(
            ctx,
            "grid params",
            &GridBuildParams {
                photon_count: count,
                bucket_count,
                hit_point_count: slots,
                _pad0: 0,
            },
        );
        let buffers = [
            &params,
            &photons,
            hit_points,
            &histogram,
            &grid,
            &bucket_start,
            &bucket_cursor,
            &order,
            &keys,
            &sorted,
        ];
        let group = self.histogram.bind(&ctx.device, &buffers);
        self.histogram.dispatch(encoder, &group, slots);
        self.params.dispatch(encoder, &group, 1);
        self.count.dispatch(encoder, &group, count);
        scan.record(ctx, encoder, &bucket_start, bucket_count + 1)?;
        encoder.copy_buffer_to_buffer(&bucket_start, 0, &bucket_cursor, 0, bucket_bytes);
        self.scatter.dispatch(encoder, &group, count);
        self.sort.dispatch(encoder, &group, bucket_count);
        self.copy.dispatch(encoder, &group, count);
        Ok(PhotonMap {
            photons,
            weights,
            count,
            grid,
            bucket_start,
            order,
            sorted,
        })
    }
}

/// Bytes of a buffer for `count` photon records (at least one: a binding must hold a whole
/// element even when a pass deposits nothing).
pub fn photon_bytes(count: u32) -> u64 {
    u64::from(count.max(1)) * size_of::<Photon>() as u64
}
