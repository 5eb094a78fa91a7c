//! The per-pass photon map on the GPU (photon_grid.wgsl): bounds, grid parameters, bucket
//! counts, scan, scatter, and the per-bucket sort that makes the order deterministic.

use crate::buffers::{storage_zeroed, uniform};
use crate::context::GpuContext;
use crate::kernel::{Kernel, Slot, WORKGROUP, shader_module};
use crate::layout::GridBuildParams;
use crate::scan::Scan;
use crate::shaders;
use ppm_core::layout::{GridParams, Photon};
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
    /// Photon indices grouped by bucket, ascending within each.
    pub order: wgpu::Buffer,
    /// Path weight of each deposit.
    pub weights: wgpu::Buffer,
}

/// Initial bounds keys: minima start at the largest key, maxima and r2 at the smallest.
const BOUNDS_INIT: [u32; 8] = [u32::MAX, u32::MAX, u32::MAX, 0, 0, 0, 0, 0];

/// The grid kernels.
pub struct PhotonGridKernels {
    bounds: Kernel,
    params: Kernel,
    count: Kernel,
    scatter: Kernel,
    sort: Kernel,
}

impl PhotonGridKernels {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        use Slot::{Read, ReadWrite, Uniform};
        let module = shader_module(&ctx.device, "photon_grid", shaders::PHOTON_GRID);
        let slots = [
            Uniform, Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
        ];
        let kernel = |entry, workgroup| Kernel::new(&ctx.device, &module, entry, &slots, workgroup);
        Self {
            bounds: kernel("grid_bounds_main", WORKGROUP),
            params: kernel("grid_params_main", 1),
            count: kernel("grid_count_main", WORKGROUP),
            scatter: kernel("grid_scatter_main", WORKGROUP),
            sort: kernel("grid_sort_main", WORKGROUP),
        }
    }

    /// Records the grid build over `photons` (`count` deposits), sized for the largest radius
    /// among the hit points; returns the map whose buffers the commands fill.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scan: &Scan,
        (photons, weights, count): (wgpu::Buffer, wgpu::Buffer, u32),
        (hit_points, slots): (&wgpu::Buffer, u32),
    ) -> Result<PhotonMap, BackendError> {
        // The same bucket count as ppm_core::grid::grid_params.
        let bucket_count = count.max(1).next_power_of_two().min(1 << 26);
        let bounds = storage_zeroed(ctx, "grid bounds", 32)?;
        ctx.queue
            .write_buffer(&bounds, 0, bytemuck::cast_slice(&BOUNDS_INIT));
        let grid = storage_zeroed(ctx, "grid", size_of::<GridParams>() as u64)?;
        let bucket_bytes = (u64::from(bucket_count) + 1) * 4;
        let bucket_start = storage_zeroed(ctx, "bucket_start", bucket_bytes)?;
        let bucket_cursor = storage_zeroed(ctx, "bucket_cursor", bucket_bytes)?;
        let order = storage_zeroed(ctx, "order", u64::from(count) * 4)?;
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
            &bounds,
            &grid,
            &bucket_start,
            &bucket_cursor,
            &order,
        ];
        let group = self.bounds.bind(&ctx.device, &buffers);
        self.bounds.dispatch(encoder, &group, count.max(slots));
        self.params.dispatch(encoder, &group, 1);
        self.count.dispatch(encoder, &group, count);
        scan.record(ctx, encoder, &bucket_start, bucket_count + 1)?;
        encoder.copy_buffer_to_buffer(&bucket_start, 0, &bucket_cursor, 0, bucket_bytes);
        self.scatter.dispatch(encoder, &group, count);
        self.sort.dispatch(encoder, &group, bucket_count);
        Ok(PhotonMap {
            photons,
            weights,
            count,
            grid,
            bucket_start,
            order,
        })
    }
}

/// Bytes of a buffer for `count` photon records (at least one: a binding must hold a whole
/// element even when a pass deposits nothing).
pub fn photon_bytes(count: u32) -> u64 {
    u64::from(count.max(1)) * size_of::<Photon>() as u64
}
