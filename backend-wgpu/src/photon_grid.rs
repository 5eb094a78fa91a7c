//! The per-pass photon map on the GPU (photon_grid.wgsl): radius histogram, grid parameters,
//! bucket counts, scan, scatter, and the per-bucket sort that makes the order deterministic.

use crate::buffers::{storage_zeroed, uniform};
use crate::context::GpuContext;
use crate::kernel::{Bindable, Kernel, Slot, WORKGROUP, shader_module};
use crate::layout::GridBuildParams;
use crate::scan::Scan;
use crate::shaders;
use crate::table::{Table, Texel};
use crate::timestamps::Encoder;
use ppm_core::grid::{RADIUS_BINS, bucket_count};
use ppm_core::layout::{GridParams, GridPhoton, Photon};
use ppm_core::passes::BackendError;

/// One pass's photons and the grid that indexes them.
pub struct PhotonMap {
    /// Deposits, in path order.
    pub photons: wgpu::Buffer,
    /// Number of deposits, those the grid leaves out included.
    pub count: u32,
    /// The grid's [`GridParams`], computed on the GPU; its `photon_count` is the deposits
    /// filed, `count` less those left out.
    pub grid: wgpu::Buffer,
    /// Bucket starts: `bucket_count + 1` entries, the last being the deposits filed.
    pub bucket_start: wgpu::Buffer,
    /// Index in `photons` of each photon of `sorted`.
    pub order: wgpu::Buffer,
    /// The photons in bucket order (ascending rank within a bucket), with their cell keys.
    pub sorted: wgpu::Buffer,
    /// `sorted` as a table (two texels a photon), for the gather.
    pub sorted_table: Table,
    /// `bucket_start` as a table, for the gather.
    pub bucket_table: Table,
    /// Each deposit's rank in path order.
    pub ranks: wgpu::Buffer,
    /// The words beside each deposit (a path weight, or a pose-A partner's four) in bucket
    /// order, as `sorted_table` holds the photons; what it holds where the pass wrote none
    /// is never read.
    pub words_table: Table,
}

/// Texels of one [`GridPhoton`] in a table.
const PHOTON_TEXELS: u32 = (size_of::<GridPhoton>() / 16) as u32;

/// Workgroups of the radius histogram (`HISTOGRAM_GROUPS` in photon_grid.wgsl).
const HISTOGRAM_GROUPS: u32 = 64;

/// The grid kernels.
pub struct PhotonGridKernels {
    histogram: Kernel,
    params: Kernel,
    count: Kernel,
    scatter: Kernel,
    sort: Kernel,
    copy: Kernel,
    /// The copy of the deposits' words, one word (path weights) or four (partners) each.
    copy_words: [Kernel; 2],
}

impl PhotonGridKernels {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        use Slot::{Read, ReadWrite, Uniform};
        let module = shader_module(&ctx.device, "photon_grid", shaders::PHOTON_GRID);
        // The shader's bindings: params, photons, hit_points, histogram, grid, bucket_counts,
        // bucket_cursor, order, keys, sorted, ranks, words, sorted_words. Each step binds
        // those it reads (all at once would pass baseline WebGPU's eight storage buffers per
        // stage).
        let slots = [
            Uniform, Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
            ReadWrite, Read, Read, ReadWrite,
        ];
        let layout = |used: &[usize]| {
            let mut own = slots.map(|_| Slot::Unused);
            for &i in used {
                own[i] = slots[i];
            }
            own
        };
        let kernel = |entry, workgroup, used: &[usize]| {
            Kernel::new(&ctx.device, &module, entry, &layout(used), workgroup)
        };
        let copy_words = [1, 4].map(|words: u32| {
            Kernel::specialised(
                &ctx.device,
                &module,
                "grid_copy_words_main",
                &layout(&[0, 4, 7, 11, 12]),
                WORKGROUP,
                &[("WORDS", f64::from(words))],
            )
        });
        Self {
            histogram: kernel("grid_histogram_main", WORKGROUP, &[0, 2, 3]),
            params: kernel("grid_params_main", 1, &[0, 3, 4]),
            count: kernel("grid_count_main", WORKGROUP, &[0, 1, 4, 5, 8, 11]),
            scatter: kernel("grid_scatter_main", WORKGROUP, &[0, 6, 7, 8, 11]),
            sort: kernel("grid_sort_main", WORKGROUP, &[0, 4, 5, 6, 7, 8, 10]),
            copy: kernel("grid_copy_main", WORKGROUP, &[0, 1, 4, 7, 8, 9]),
            copy_words,
        }
    }

    /// Records the grid build over `photons` (`count` deposits, ranked in path order by
    /// `ranks`, the first `held` an earlier pass's, with `words` beside each in `weights`: 0,
    /// 1 or 4) into `buffers`, its cells sized to the gather radii of the hit points' visible
    /// points (at least `sqrt(r2_floor)`), leaving out the deposits marked as pairs that
    /// cancel where `leave_out` (and four words each); returns the map whose buffers the
    /// commands fill.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        scan: &Scan,
        buffers: &GridBuffers,
        (photons, (weights, words), ranks, count): (
            wgpu::Buffer,
            (wgpu::Buffer, u32),
            &wgpu::Buffer,
            u32,
        ),
        (hit_points, slots): (&wgpu::Buffer, u32),
        (r2_floor, held, leave_out): (f32, u32, bool),
    ) -> Result<PhotonMap, BackendError> {
        let bucket_count = bucket_count(count);
        let bucket_bytes = (u64::from(bucket_count) + 1) * 4;
        encoder.clear_buffer(&buffers.histogram, 0, None);
        encoder.clear_buffer(&buffers.bucket_start, 0, Some(bucket_bytes));
        let params = uniform(
            ctx,
            "grid params",
            &GridBuildParams {
                photon_count: count,
                bucket_count,
                hit_point_count: slots,
                r2_floor,
                held,
                leave_out: u32::from(leave_out && words == 4),
                ..GridBuildParams::default()
            },
        );
        let bindings: [&dyn Bindable; 13] = [
            &params,
            &photons,
            hit_points,
            &buffers.histogram,
            &buffers.grid,
            &buffers.bucket_start,
            &buffers.bucket_cursor,
            &buffers.order,
            &buffers.keys,
            &buffers.sorted,
            ranks,
            &weights,
            &buffers.sorted_words,
        ];
        let step = |kernel: &Kernel, encoder: &mut Encoder<'_>, items: u32| {
            kernel.dispatch(encoder, &kernel.bind(&ctx.device, &bindings), items);
        };
        // A fixed number of workgroups, each striding over the hit points (HISTOGRAM_GROUPS).
        step(&self.histogram, encoder, HISTOGRAM_GROUPS * WORKGROUP);
        step(&self.params, encoder, 1);
        step(&self.count, encoder, count);
        scan.record(ctx, encoder, &buffers.bucket_start, bucket_count + 1)?;
        encoder.copy_buffer_to_buffer(
            &buffers.bucket_start,
            0,
            &buffers.bucket_cursor,
            0,
            bucket_bytes,
        );
        step(&self.scatter, encoder, count);
        step(&self.sort, encoder, count);
        // The sort wrote the bucket order into the cursors (photon_grid.wgsl).
        encoder.copy_buffer_to_buffer(
            &buffers.bucket_cursor,
            0,
            &buffers.order,
            0,
            u64::from(count) * 4,
        );
        step(&self.copy, encoder, count);
        if words == 1 || words == 4 {
            step(&self.copy_words[usize::from(words == 4)], encoder, count);
            let texels = (count * words).div_ceil(4);
            buffers
                .words_table
                .record_copy(encoder, &buffers.sorted_words, texels);
        }
        buffers
            .sorted_table
            .record_copy(encoder, &buffers.sorted, count * PHOTON_TEXELS);
        buffers
            .bucket_table
            .record_copy(encoder, &buffers.bucket_start, bucket_count + 1);
        Ok(PhotonMap {
            photons,
            words_table: buffers.words_table.clone(),
            count,
            grid: buffers.grid.clone(),
            bucket_start: buffers.bucket_start.clone(),
            order: buffers.order.clone(),
            sorted: buffers.sorted.clone(),
            sorted_table: buffers.sorted_table.clone(),
            bucket_table: buffers.bucket_table.clone(),
            ranks: ranks.clone(),
        })
    }
}

/// The grid's working buffers, kept from pass to pass and grown when a pass needs more, so a
/// pass allocates and zeroes nothing it did not need.
pub struct GridBuffers {
    histogram: wgpu::Buffer,
    grid: wgpu::Buffer,
    bucket_start: wgpu::Buffer,
    bucket_cursor: wgpu::Buffer,
    order: wgpu::Buffer,
    keys: wgpu::Buffer,
    sorted: wgpu::Buffer,
    /// The deposits' words in bucket order, four a photon at most, and as a table.
    sorted_words: wgpu::Buffer,
    words_table: Table,
    sorted_table: Table,
    bucket_table: Table,
    /// Photons they hold at most.
    capacity: u32,
}

impl GridBuffers {
    /// Buffers for `count` photons: `kept` if it holds enough, else new ones.
    pub fn fit(
        ctx: &GpuContext,
        kept: Option<GridBuffers>,
        count: u32,
    ) -> Result<GridBuffers, BackendError> {
        if let Some(b) = kept.filter(|b| b.capacity >= count) {
            return Ok(b);
        }
        let bucket_bytes = (u64::from(bucket_count(count)) + 1) * 4;
        let per_photon = u64::from(count.max(1));
        Ok(GridBuffers {
            histogram: storage_zeroed(ctx, "radius histogram", u64::from(RADIUS_BINS) * 4)?,
            grid: storage_zeroed(ctx, "grid", size_of::<GridParams>() as u64)?,
            bucket_start: storage_zeroed(ctx, "bucket_start", bucket_bytes)?,
            bucket_cursor: storage_zeroed(ctx, "bucket_cursor", bucket_bytes)?,
            order: storage_zeroed(ctx, "order", per_photon * 4)?,
            keys: storage_zeroed(ctx, "cell keys", per_photon * 4)?,
            sorted: storage_zeroed(
                ctx,
                "sorted photons",
                per_photon * size_of::<GridPhoton>() as u64,
            )?,
            sorted_words: storage_zeroed(ctx, "sorted words", per_photon * 16)?,
            words_table: Table::new(ctx, "sorted words table", Texel::Words4, count.max(1))?,
            sorted_table: Table::new(
                ctx,
                "sorted photon table",
                Texel::Words4,
                count.max(1) * PHOTON_TEXELS,
            )?,
            bucket_table: Table::new(
                ctx,
                "bucket start table",
                Texel::Word,
                bucket_count(count) + 1,
            )?,
            capacity: count.max(1),
        })
    }
}

/// Bytes of a buffer for `count` photon records (at least one: a binding must hold a whole
/// element even when a pass deposits nothing).
pub fn photon_bytes(count: u32) -> u64 {
    u64::from(count.max(1)) * size_of::<Photon>() as u64
}
