//! A focus eye pass on the device ([`eye_flags::FOCUS`] with [`eye_flags::KEEP_STATISTICS`]):
//! after a move, the slots at `rest_at` iterations or more rest and only those behind trace,
//! typically a few percent scattered over the image. Walking every slot, each SIMD group would
//! pay for its one active lane and the pass would cost nearly a full one; so focus.wgsl rests
//! the slots ahead and lists the others, and the eye path and the direct light after it walk
//! the list alone ([`FocusList`]), in the pipelines that walk every slot otherwise. Each listed
//! slot does what it did over every slot, keyed by its own index: the image is the same bit
//! for bit.
//!
//! [`eye_flags::FOCUS`]: ppm_core::layout::eye_flags::FOCUS
//! [`eye_flags::KEEP_STATISTICS`]: ppm_core::layout::eye_flags::KEEP_STATISTICS

use crate::buffers::{SceneBuffers, storage_init, storage_zeroed, uniform};
use crate::context::GpuContext;
use crate::kernel::{Kernel, Slot, WORKGROUP, shader_module};
use crate::layout::ListParams;
use crate::passes::{EyeOutputs, Slots};
use crate::timestamps::Encoder;
use crate::{COUNTER_ITEMS, COUNTER_LISTED, COUNTERS_RESET, Specialisation, WgpuBackend};
use ppm_core::layout::EyePassParams;
use ppm_core::passes::BackendError;
use std::sync::OnceLock;

/// The slots the eye and direct-light passes walk: those a focus eye pass listed (the ones
/// that do not rest, while the list is current), or every slot.
pub struct FocusList {
    /// A word per slot, the first `count` of them listed (`listed` in focus.wgsl); one
    /// placeholder word where the passes walk every slot.
    pub listed: wgpu::Buffer,
    /// The [`ListParams`] that says which (`list`).
    pub list: wgpu::Buffer,
    /// Slots listed; none where the passes walk every slot.
    count: Option<u32>,
    /// The focus pass's `rest_at`: a next focus pass at the same `rest_at` walks this list
    /// again.
    rest_at: u32,
    /// Slots with a visible point that focus.wgsl rested (left off the list).
    rested: u32,
}

impl FocusList {
    /// The list that walks every slot.
    pub fn every_slot(ctx: &GpuContext) -> Self {
        Self {
            listed: storage_init(ctx, "no focus list", &[0u32]),
            list: uniform(ctx, "no focus list", &ListParams::default()),
            count: None,
            rest_at: 0,
            rested: 0,
        }
    }

    /// The work items of a pass over `slots` slots that walks this list.
    pub fn items(&self, slots: u32) -> u32 {
        self.count.unwrap_or(slots)
    }
}

/// focus.wgsl, its pipeline compiled at the first focus pass.
pub struct FocusKernel {
    module: wgpu::ShaderModule,
    kernel: OnceLock<Kernel>,
}

impl FocusKernel {
    /// Parses the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            module: shader_module(&ctx.device, "focus", crate::shaders::FOCUS),
            kernel: OnceLock::new(),
        }
    }

    /// Records the rest test of every slot, those behind listed into `listed`.
    fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        params: &EyePassParams,
        slots: &Slots,
        listed: &wgpu::Buffer,
    ) {
        use Slot::{ReadWrite, Uniform};
        let kernel = self.kernel.get_or_init(|| {
            let slots = [Uniform, ReadWrite, ReadWrite, ReadWrite];
            Kernel::new(&ctx.device, &self.module, "focus_main", &slots, WORKGROUP)
        });
        let params = uniform(ctx, "focus params", params);
        let group = kernel.bind(
            &ctx.device,
            &[&params, slots.hit_points, slots.counters, listed],
        );
        kernel.dispatch(encoder, &group, slots.count);
    }
}

impl WgpuBackend {
    /// A focus eye pass over `slots`: rests the slots ahead and lists those behind, then, once
    /// the count is read back, traces the listed ones (and checks every slot). Returns the
    /// counters a pass over every slot would have (the rays, the slots with a visible point,
    /// resting or traced) and the list; where no slot is behind, nothing is traced.
    ///
    /// `last`, the list of the focus pass just before, is walked again where that pass rested
    /// at the same count (the catch-up's passes of one iteration): a slot only gains direct
    /// samples between them, so the slots it left off are still ahead, and eye_pass.wgsl rests
    /// the listed ones that have caught up, as focus.wgsl would. Otherwise its store takes the
    /// new list where it holds every slot.
    pub(crate) fn focus_eye_pass(
        &self,
        params: &EyePassParams,
        scene: &SceneBuffers,
        (slots, outputs): (&Slots, &EyeOutputs),
        (spec, last): (Specialisation, Option<FocusList>),
    ) -> Result<([u32; 4], FocusList), BackendError> {
        let focus = match last {
            Some(last) if last.count.is_some() && last.rest_at == params.rest_at => last,
            last => self.focus_list(params, slots, last)?,
        };
        let mut counters = COUNTERS_RESET;
        if focus.count.is_some_and(|count| count > 0) {
            counters = self.run("eye", |encoder| {
                let walk = (spec, &focus);
                self.kernels
                    .eye
                    .record(&self.ctx, encoder, params, scene, slots, outputs, walk);
                self.kernels.check.record(&self.ctx, encoder, slots);
                Ok(())
            })?;
        }
        counters[COUNTER_ITEMS] += focus.rested;
        Ok((counters, focus))
    }

    /// focus.wgsl over `slots`: rests those at `params.rest_at` direct samples or more, and
    /// lists the others into `last`'s store where it holds every slot.
    fn focus_list(
        &self,
        params: &EyePassParams,
        slots: &Slots,
        last: Option<FocusList>,
    ) -> Result<FocusList, BackendError> {
        let bytes = u64::from(slots.count) * 4;
        let listed = match last {
            Some(last) if last.listed.size() >= bytes => last.listed,
            _ => storage_zeroed(&self.ctx, "focus list", bytes)?,
        };
        let rested = self.run("eye focus", |encoder| {
            self.kernels
                .focus
                .record(&self.ctx, encoder, params, slots, &listed);
            Ok(())
        })?;
        let count = rested[COUNTER_LISTED];
        let list = ListParams {
            count,
            focus: 1,
            ..ListParams::default()
        };
        Ok(FocusList {
            listed,
            list: uniform(&self.ctx, "focus list", &list),
            count: Some(count),
            rest_at: params.rest_at,
            rested: rested[COUNTER_ITEMS],
        })
    }
}
