//! Exclusive prefix sum of a u32 buffer in place (scan.wgsl), recursing over block totals.

use crate::buffers::{storage_zeroed, uniform};
use crate::context::GpuContext;
use crate::kernel::{Kernel, Slot, shader_module};
use crate::layout::ScanParams;
use crate::timestamps::Encoder;
use ppm_core::passes::BackendError;

/// Elements one workgroup scans (`BLOCK` in scan.wgsl).
const BLOCK: u32 = 2048;

/// Invocations of a scan workgroup.
const WORKGROUP: u32 = 256;

/// The two scan kernels.
pub struct Scan {
    blocks: Kernel,
    add: Kernel,
}

impl Scan {
    /// Compiles the scan shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "scan", crate::shaders::SCAN);
        let slots = [Slot::Uniform, Slot::ReadWrite, Slot::ReadWrite];
        Self {
            blocks: Kernel::new(&ctx.device, &module, "scan_blocks_main", &slots, WORKGROUP),
            add: Kernel::new(&ctx.device, &module, "scan_add_main", &slots, WORKGROUP),
        }
    }

    /// Records the scan of the first `count` elements of `data`.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        data: &wgpu::Buffer,
        count: u32,
    ) -> Result<(), BackendError> {
        if count == 0 {
            return Ok(());
        }
        let blocks = count.div_ceil(BLOCK);
        let sums = storage_zeroed(ctx, "scan block sums", u64::from(blocks) * 4)?;
        let params = uniform(
            ctx,
            "scan params",
            &ScanParams {
                count,
                _pad0: 0,
                _pad1: 0,
                _pad2: 0,
            },
        );
        let group = self.blocks.bind(&ctx.device, &[&params, data, &sums]);
        self.blocks.dispatch(encoder, &group, blocks * WORKGROUP);
        if blocks > 1 {
            self.record(ctx, encoder, &sums, blocks)?;
            let group = self.add.bind(&ctx.device, &[&params, data, &sums]);
            self.add.dispatch(encoder, &group, count);
        }
        Ok(())
    }
}
