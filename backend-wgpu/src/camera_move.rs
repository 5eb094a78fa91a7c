//! A camera move's passes on the device (docs/algorithm.md 3d): the twin of backend-cpu's
//! camera_move.rs, camera_move.wgsl running ppm_core::camera_move::inherit_slot (its WGSL
//! twin) over the slots where they lie. No slot crosses to the host: the move's start copies
//! the old view's slots and boxes on the device, into buffers allocated at the first camera
//! move and kept for the next (at 768x768, 66 MB and 19 MB beside the slots'), and what
//! crosses are the request (a uniform) and the pass counters.

use crate::buffers::{self, read_back, storage_zeroed};
use crate::kernel::{Kernel, Slot, WORKGROUP, shader_module};
use crate::layout::{InheritCase, InheritOutcome};
use crate::passes::Slots;
use crate::timestamps::Encoder;
use crate::{COUNTER_ITEMS, GpuContext, WgpuBackend, shaders};
use ppm_core::camera_move::{CameraMove, CameraMoveStats};
use ppm_core::layout::{GpuMaterial, HitPoint, SlotBounds};
use ppm_core::passes::BackendError;

use Slot::{Read, ReadWrite, Table, Uniform};

/// camera_move.wgsl's pipeline, compiled at a backend's first camera move or ahead of it
/// ([`crate::move_kernels`]).
pub struct CameraMoveKernel(Kernel);

impl CameraMoveKernel {
    /// Compiles the shader.
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(&ctx.device, "camera_move", shaders::CAMERA_MOVE);
        let slots = [Uniform, Table, Read, Read, ReadWrite, ReadWrite, ReadWrite];
        Self(Kernel::new(
            &ctx.device,
            &module,
            "camera_move_main",
            &slots,
            WORKGROUP,
        ))
    }

    /// Records the inheritance of every slot from `copies`.
    fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut Encoder<'_>,
        (moving, scene, copies): (&CameraInProgress, &crate::buffers::SceneBuffers, &Copies),
        (slots, slot_bounds): (&Slots, &wgpu::Buffer),
    ) {
        let group = self.0.bind(
            &ctx.device,
            &[
                &moving.params,
                &scene.table,
                &copies.hit_points,
                &copies.bounds,
                slots.hit_points,
                slot_bounds,
                slots.counters,
            ],
        );
        self.0.dispatch(encoder, &group, slots.count);
    }
}

/// The old view's slots and boxes (`before_slots`, `before_bounds` in camera_move.wgsl),
/// copied on the device when a camera move begins; kept from move to move.
pub struct Copies {
    /// Slots they hold.
    slots: u32,
    hit_points: wgpu::Buffer,
    bounds: wgpu::Buffer,
}

impl Copies {
    /// The bytes of copies of `slots` slots and their boxes.
    pub fn bytes(slots: u32) -> u64 {
        u64::from(slots) * (size_of::<HitPoint>() + size_of::<SlotBounds>()) as u64
    }
}

/// A camera move between its passes.
pub struct CameraInProgress {
    /// The cameras before and after.
    request: CameraMove,
    /// Its [`ppm_core::layout::CameraMoveParams`] (`params` in camera_move.wgsl).
    params: wgpu::Buffer,
    /// An eye pass has started every slot fresh since the move began.
    pub traced: bool,
}

impl WgpuBackend {
    /// [`ppm_core::passes::LocalMoves::begin_camera_move`]: the slots and their boxes copied
    /// on the device, what local moves kept of this view forgotten, a local move in progress
    /// ended.
    pub(crate) fn begin_camera(&mut self, request: &CameraMove) -> Result<(), BackendError> {
        const PASS: &str = "camera move";
        self.scene(PASS)?;
        let &(_, slots) = self.hit_points(PASS)?;
        if self.slot_bounds.is_none() {
            return Err(BackendError::OutOfOrder {
                pass: PASS,
                needs: "an eye pass",
            });
        }
        if let Some(preparing) = self.preparing.take() {
            preparing.finish()?;
        }
        self.ctx.scoped("shader compilation", || {
            self.kernels.moves.camera(&self.ctx);
        })?;
        let hit_point_bytes = u64::from(slots) * size_of::<HitPoint>() as u64;
        let bounds_bytes = u64::from(slots) * size_of::<SlotBounds>() as u64;
        if self.camera_copies.as_ref().is_none_or(|c| c.slots != slots) {
            self.camera_copies = Some(Copies {
                slots,
                hit_points: storage_zeroed(&self.ctx, "slots before", hit_point_bytes)?,
                bounds: storage_zeroed(&self.ctx, "bounds before", bounds_bytes)?,
            });
        }
        let copies = self.camera_copies.as_ref().expect("allocated above");
        let (hit_points, _) = self.hit_points(PASS)?;
        let bounds = self.slot_bounds.as_ref().expect("checked above");
        self.run(PASS, |encoder| {
            encoder.copy_buffer_to_buffer(hit_points, 0, &copies.hit_points, 0, hit_point_bytes);
            encoder.copy_buffer_to_buffer(bounds, 0, &copies.bounds, 0, bounds_bytes);
            Ok(())
        })?;
        // Pairs were traced through the old view's pixels; a move in progress ends here.
        if let Some(held) = self.move_buffers.as_mut() {
            held.forget_pairs();
        }
        self.moving = None;
        self.camera_moving = Some(CameraInProgress {
            request: *request,
            params: buffers::uniform(&self.ctx, "camera move", &request.params()),
            traced: false,
        });
        Ok(())
    }

    /// [`ppm_core::passes::LocalMoves::inherit_light`]: `inherit_slot` at every slot, counted
    /// on the device.
    pub(crate) fn inherit(&mut self) -> Result<CameraMoveStats, BackendError> {
        const PASS: &str = "inherit light";
        let camera = self.scene(PASS)?.camera_value;
        let moving = match self.camera_moving.take() {
            Some(m) if m.traced && camera == m.request.after => m,
            Some(m) if m.traced => {
                self.camera_moving = Some(m);
                return Err(BackendError::OutOfOrder {
                    pass: PASS,
                    needs: "the scene update to the new camera",
                });
            }
            other => {
                self.camera_moving = other;
                return Err(BackendError::OutOfOrder {
                    pass: PASS,
                    needs: "begin_camera_move, then an eye pass that starts the slots fresh",
                });
            }
        };
        let scene = self.scene(PASS)?;
        let &(ref hit_points, count) = self.hit_points(PASS)?;
        let slot_bounds = self.slot_bounds.as_ref().ok_or(BackendError::OutOfOrder {
            pass: PASS,
            needs: "an eye pass",
        })?;
        let kernel = self.kernels.moves.camera(&self.ctx);
        let copies = self
            .camera_copies
            .as_ref()
            .expect("allocated at the move's start");
        let slots = Slots {
            hit_points,
            counters: &self.counters,
            count,
        };
        let counters = self.run(PASS, |encoder| {
            kernel.record(
                &self.ctx,
                encoder,
                (&moving, scene, copies),
                (&slots, slot_bounds),
            );
            self.kernels.check.record(&self.ctx, encoder, &slots);
            Ok(())
        })?;
        self.check(PASS, &counters)?;
        let inherited = u64::from(counters[COUNTER_ITEMS]);
        Ok(CameraMoveStats {
            inherited,
            reset: u64::from(count) - inherited,
        })
    }

    /// Runs camera_move_vectors.wgsl on `cases` over the old view `before` (its slots and
    /// their boxes) with `materials`, and its edge test at every slot of the new view
    /// `after` of `request`: a test compares the outcomes and the edges (1 on an edge) with
    /// [`ppm_core::camera_move::inherit_slot`] and [`ppm_core::camera_move::on_an_edge`]
    /// (tests/camera_move.rs). Compiles its kernel on every call.
    pub fn camera_move_vectors(
        &self,
        (before, before_bounds): (&[HitPoint], &[SlotBounds]),
        materials: &[GpuMaterial],
        cases: &[InheritCase],
        (after, request): (&[HitPoint], &CameraMove),
    ) -> Result<(Vec<InheritOutcome>, Vec<u32>), BackendError> {
        const NAME: &str = "camera_move_vectors";
        let module = shader_module(&self.ctx.device, NAME, shaders::CAMERA_MOVE_VECTORS);
        let slots = [Read, Read, Read, Read, ReadWrite, Read, Uniform, ReadWrite];
        let kernel = Kernel::new(
            &self.ctx.device,
            &module,
            "camera_move_vectors_main",
            &slots,
            WORKGROUP,
        );
        let inputs = [
            buffers::storage_init(&self.ctx, "inherit cases", cases),
            buffers::storage_init(&self.ctx, "slots before", before),
            buffers::storage_init(&self.ctx, "bounds before", before_bounds),
            buffers::storage_init(&self.ctx, "case materials", materials),
            buffers::storage_init(&self.ctx, "slots after", after),
            buffers::uniform(&self.ctx, "edge request", &request.params()),
        ];
        let size = (cases.len() * size_of::<InheritOutcome>()) as u64;
        let outcomes = storage_zeroed(&self.ctx, NAME, size)?;
        let edges = storage_zeroed(&self.ctx, "edges", (after.len() * 4) as u64)?;
        self.run(NAME, |encoder| {
            let group = kernel.bind(
                &self.ctx.device,
                &[
                    &inputs[0], &inputs[1], &inputs[2], &inputs[3], &outcomes, &inputs[4],
                    &inputs[5], &edges,
                ],
            );
            kernel.dispatch(encoder, &group, cases.len().max(after.len()) as u32);
            Ok(())
        })?;
        Ok((
            read_back(&self.ctx, &outcomes, cases.len())?,
            read_back(&self.ctx, &edges, after.len())?,
        ))
    }

    /// What [`crate::Backend::not_created`] says of camera moves: their pipeline and the
    /// copies of the slots until the first.
    pub(crate) fn camera_moves_not_created(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !self.kernels.moves.camera_compiled() {
            out.push("camera-move pipeline: not compiled (no camera move)".to_owned());
        }
        if let (None, Some((_, slots))) = (&self.camera_copies, &self.hit_points) {
            out.push(format!(
                "camera-move copies of the slots: {} bytes not allocated (no camera move)",
                Copies::bytes(*slots)
            ));
        }
        out
    }
}
