//! The device: adapter choice, limits, and turning device errors into `BackendError`s.

use ppm_core::passes::BackendError;
use std::sync::{Arc, Mutex};

/// The optional features the passes use where the adapter offers them, each behind a check:
/// timestamp queries, to measure each kernel's device time. Nothing on the required path needs
/// them.
pub const OPTIONAL_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY;

/// A wgpu device and queue, with the adapter's description and error capture. Clones share
/// the device and what it reports (two backends on one device, as the viewer's comparison).
#[derive(Clone)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Which adapter runs the passes (a real GPU, or lavapipe on the CPU).
    pub adapter: wgpu::AdapterInfo,
    /// Why the device was lost, once it is.
    lost: Arc<Mutex<Option<String>>>,
    /// Errors no scope caught (reported with the next pass, never a panic).
    uncaptured: Arc<Mutex<Option<String>>>,
}

impl GpuContext {
    /// Opens the best adapter the environment offers (`WGPU_BACKEND` may narrow the choice).
    ///
    /// Baseline features are requested, and those of [`OPTIONAL_FEATURES`] the adapter offers.
    /// Limits are raised to what the adapter offers, so large images and photon counts fit
    /// where the hardware allows; anything beyond them is refused up front by the buffer code
    /// with the limit named.
    pub fn new() -> Result<Self, BackendError> {
        Self::open(false)
    }

    /// As [`GpuContext::new`], with WebGPU's baseline limits (`wgpu::Limits::default()`)
    /// instead of the adapter's and no optional feature: on it, a render shows that the
    /// passes bind and dispatch no more than any WebGPU device offers.
    pub fn baseline() -> Result<Self, BackendError> {
        Self::open(true)
    }

    fn open(baseline: bool) -> Result<Self, BackendError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| BackendError::Device(format!("no wgpu adapter: {e} (on Linux, install a Vulkan driver such as mesa-vulkan-drivers)")))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("ppm"),
            required_features: if baseline {
                wgpu::Features::empty()
            } else {
                adapter.features() & OPTIONAL_FEATURES
            },
            required_limits: if baseline {
                wgpu::Limits::default()
            } else {
                adapter.limits()
            },
            ..Default::default()
        }))
        .map_err(|e| BackendError::Device(format!("cannot open the device: {e}")))?;
        Ok(Self::adopt(device, queue, adapter.get_info()))
    }

    /// Runs the passes on a device and queue someone else opened (a viewer's, which also
    /// presents to a window). The device must have been requested with at least WebGPU's
    /// baseline limits; this context takes over its lost-device and uncaptured-error
    /// callbacks, so that the passes report what goes wrong.
    pub fn adopt(device: wgpu::Device, queue: wgpu::Queue, adapter: wgpu::AdapterInfo) -> Self {
        let lost = Arc::new(Mutex::new(None));
        let lost_in_callback = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            *lost_in_callback.lock().unwrap_or_else(|p| p.into_inner()) =
                Some(format!("{reason:?}: {message}"));
        });
        let uncaptured = Arc::new(Mutex::new(None));
        let uncaptured_in_handler = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            uncaptured_in_handler
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .get_or_insert(e.to_string());
        }));
        Self {
            device,
            queue,
            adapter,
            lost,
            uncaptured,
        }
    }

    /// Runs `work` inside validation and out-of-memory error scopes and waits for the GPU;
    /// any error the device reports becomes `Err` naming `pass`.
    pub fn scoped<T>(&self, pass: &str, work: impl FnOnce() -> T) -> Result<T, BackendError> {
        let out = self.captured(pass, work);
        self.wait()?;
        let out = out?;
        self.health(pass)?;
        Ok(out)
    }

    /// Runs `work` inside validation and out-of-memory error scopes, which catch what this
    /// thread's calls report (wgpu keeps scopes per thread); an error becomes `Err` naming
    /// `pass`. It neither waits for the GPU nor takes an error other threads' passes left
    /// uncaught, which the passes report themselves: a thread that only compiles pipelines
    /// ahead uses it alone.
    pub fn captured<T>(&self, pass: &str, work: impl FnOnce() -> T) -> Result<T, BackendError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = work();
        let validation = pollster::block_on(validation.pop());
        let oom = pollster::block_on(oom.pop());
        if let Some(e) = oom {
            return Err(BackendError::Limit(format!(
                "{pass} pass: out of device memory: {e}"
            )));
        }
        if let Some(e) = validation {
            return Err(BackendError::Device(format!("{pass} pass: {e}")));
        }
        Ok(out)
    }

    /// Blocks until the queue is idle.
    pub fn wait(&self) -> Result<(), BackendError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| BackendError::Device(format!("waiting for the device: {e}")))
    }

    /// An error if the device was lost or reported an error outside any scope.
    pub fn health(&self, pass: &str) -> Result<(), BackendError> {
        if let Some(reason) = self.lost.lock().unwrap_or_else(|p| p.into_inner()).clone() {
            return Err(BackendError::Device(format!(
                "{pass} pass: device lost: {reason}"
            )));
        }
        if let Some(e) = self
            .uncaptured
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take()
        {
            return Err(BackendError::Device(format!("{pass} pass: {e}")));
        }
        Ok(())
    }

    /// Whether the device was opened with timestamp queries: then the backend measures each
    /// kernel's device time.
    pub fn timestamps(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// The device's limits.
    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// The largest buffer a shader can bind as a whole, in bytes.
    pub fn binding_limit(&self) -> u64 {
        let limits = self.limits();
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
    }
}
