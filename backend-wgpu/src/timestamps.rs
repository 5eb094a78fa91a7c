//! Device time per kernel, where the adapter offers timestamp queries (WebGPU's optional
//! `timestamp-query`, [`wgpu::Features::TIMESTAMP_QUERY`]): each compute pass writes a
//! timestamp where it begins and one where it ends. A submission resolves its own queries
//! into one buffer as it finishes; the host reads that buffer only when asked for the times
//! ([`Timer::take`]) or when the set is nearly full, so no pass waits on it.

use crate::buffers::read_back;
use crate::context::GpuContext;
use ppm_core::device_time::{self, DeviceTime};
use ppm_core::passes::BackendError;
use std::ops::{Deref, DerefMut};

/// Queries in the set: the most one holds; resolved, 32 KiB.
const CAPACITY: u32 = wgpu::QUERY_SET_MAX_QUERIES;
/// A submission's queries start on a 256-byte boundary of the resolve buffer, as
/// `resolve_query_set` requires (32 queries).
const ALIGN: u32 = (wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT / wgpu::QUERY_SIZE as u64) as u32;
/// The set is read back before a submission when fewer queries than this are left: a
/// submission may time 512 dispatches (the largest today, a photon map, has about fifteen).
const ROOM: u32 = 1024;

/// The query set, the buffer it resolves into, and what each pair of queries timed.
pub struct Timer {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    /// Nanoseconds per tick.
    period: f64,
    /// The pass and kernel of each pair of queries written since the last read-back (pair `i`
    /// is queries `2i` and `2i + 1`); `None` for the pairs a submission's alignment skipped.
    pairs: Vec<Option<(&'static str, &'static str)>>,
    /// The pass of the submission being recorded.
    pass: &'static str,
    /// Where the submission being recorded resolves from (a multiple of [`ALIGN`]).
    start: u32,
    /// Dispatches that found the set full, by pass: reported when the times are taken.
    untimed: Option<&'static str>,
    /// What was read back so far and not yet taken.
    total: Vec<DeviceTime>,
}

impl Timer {
    /// A timer on `ctx`'s device if it was opened with timestamp queries, else `None`.
    pub fn new(ctx: &GpuContext) -> Option<Self> {
        if !ctx.timestamps() {
            return None;
        }
        let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: CAPACITY,
        });
        let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resolved timestamps"),
            size: u64::from(CAPACITY) * u64::from(wgpu::QUERY_SIZE),
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Some(Self {
            set,
            resolved,
            period: f64::from(ctx.queue.get_timestamp_period()),
            pairs: Vec::new(),
            pass: "",
            start: 0,
            untimed: None,
            total: Vec::new(),
        })
    }

    /// Starts recording `pass`'s submission, reading the set back first if it is nearly full.
    /// The pairs of a submission that failed before it finished were never resolved: dropped.
    pub fn begin(&mut self, ctx: &GpuContext, pass: &'static str) -> Result<(), BackendError> {
        self.pairs.truncate((self.start / 2) as usize);
        if self.start + ROOM > CAPACITY {
            self.read(ctx)?;
        }
        self.pass = pass;
        Ok(())
    }

    /// The queries a compute pass of `kernel` writes, if the set has room.
    fn pass_writes(
        &mut self,
        kernel: &'static str,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let first = 2 * self.pairs.len() as u32;
        if first + 2 > CAPACITY {
            self.untimed = Some(self.pass);
            return None;
        }
        self.pairs.push(Some((self.pass, kernel)));
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(first),
            end_of_pass_write_index: Some(first + 1),
        })
    }

    /// Resolves the submission's queries at the end of its commands.
    fn finish(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let end = 2 * self.pairs.len() as u32;
        if end > self.start {
            let offset = u64::from(self.start) * u64::from(wgpu::QUERY_SIZE);
            encoder.resolve_query_set(&self.set, self.start..end, &self.resolved, offset);
        }
        self.start = end.next_multiple_of(ALIGN).min(CAPACITY);
        self.pairs.resize((self.start / 2) as usize, None);
    }

    /// Reads the resolved queries back into the running total and empties the set.
    fn read(&mut self, ctx: &GpuContext) -> Result<(), BackendError> {
        let ticks: Vec<u64> = read_back(ctx, &self.resolved, 2 * self.pairs.len())?;
        let measured: Vec<DeviceTime> = self
            .pairs
            .iter()
            .zip(ticks.chunks_exact(2))
            .filter_map(|(pair, t)| {
                let (pass, kernel) = (*pair)?;
                Some(DeviceTime {
                    pass: pass.into(),
                    kernel: kernel.into(),
                    // A clock that steps back between two passes (some drivers' does) counts
                    // the pass as instant rather than wrapping around.
                    seconds: t[1].saturating_sub(t[0]) as f64 * self.period * 1e-9,
                    dispatches: 1,
                })
            })
            .collect();
        device_time::add(&mut self.total, &measured);
        self.pairs.clear();
        self.start = 0;
        Ok(())
    }

    /// Everything measured since the last call, read back now.
    pub fn take(&mut self, ctx: &GpuContext) -> Result<Vec<DeviceTime>, BackendError> {
        self.read(ctx)?;
        if let Some(pass) = self.untimed.take() {
            return Err(BackendError::Limit(format!(
                "device times: a {pass} submission timed more than {} dispatches",
                ROOM / 2
            )));
        }
        Ok(std::mem::take(&mut self.total))
    }
}

/// A command encoder and, on a device with timestamp queries, the timer its compute passes
/// write to. It dereferences to the encoder for copies and clears.
pub struct Encoder<'a> {
    inner: wgpu::CommandEncoder,
    timer: Option<&'a mut Timer>,
}

impl<'a> Encoder<'a> {
    /// An encoder labelled `pass`, timed by `timer` (which [`Timer::begin`] started).
    pub fn new(device: &wgpu::Device, pass: &'static str, timer: Option<&'a mut Timer>) -> Self {
        let inner =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(pass) });
        Self { inner, timer }
    }

    /// Begins a compute pass of `kernel`, timed where the device allows.
    pub fn compute_pass(&mut self, kernel: &'static str) -> wgpu::ComputePass<'_> {
        let timestamp_writes = self
            .timer
            .as_deref_mut()
            .and_then(|t| t.pass_writes(kernel));
        self.inner.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(kernel),
            timestamp_writes,
        })
    }

    /// The commands, with the timer's queries resolved at their end.
    pub fn finish(mut self) -> wgpu::CommandBuffer {
        if let Some(timer) = self.timer {
            timer.finish(&mut self.inner);
        }
        self.inner.finish()
    }
}

impl Deref for Encoder<'_> {
    type Target = wgpu::CommandEncoder;

    fn deref(&self) -> &wgpu::CommandEncoder {
        &self.inner
    }
}

impl DerefMut for Encoder<'_> {
    fn deref_mut(&mut self) -> &mut wgpu::CommandEncoder {
        &mut self.inner
    }
}
