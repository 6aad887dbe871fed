//! The GPU context: created headless from the environment (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`, ...) or handed
//! over by the app (eframe's device). Timestamp features are requested whenever the adapter has them.

pub mod bind;
pub mod buffer;
pub mod kernels;
pub mod pipeline;
pub mod readback;

use crate::error::GpuError;

/// A device and queue plus what the renderer needs to know about them.
#[derive(Clone)]
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_info: wgpu::AdapterInfo,
    /// True when `TIMESTAMP_QUERY` is enabled on the device: per-pass GPU times come from timestamps.
    pub timestamps: bool,
    /// Why the device was lost, once wgpu says it was (its device-lost callback, on any thread).
    lost: std::sync::Arc<std::sync::Mutex<Option<String>>>,
}

/// The timer features ShadowLab uses when an adapter offers them.
pub const TIMER_FEATURES: wgpu::Features = wgpu_profiler::GpuProfiler::ALL_WGPU_TIMER_FEATURES;
/// Every optional feature ShadowLab requests when an adapter offers it: the timers, and blending into an f32
/// HDR target (`SharedLayouts::hdr_format`).
pub const OPTIONAL_FEATURES: wgpu::Features = TIMER_FEATURES.union(wgpu::Features::FLOAT32_BLENDABLE);

/// Whether `adapter` runs compute shaders, which every technique needs (GL before 4.3, GLES before 3.1 and
/// WebGL2 do not).
pub fn has_compute(adapter: &wgpu::Adapter) -> bool {
    adapter.get_downlevel_capabilities().flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
}

/// "llvmpipe (LLVM 15.0.6, 256 bits) (Gl)": an adapter as errors name it.
fn adapter_label(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?})", info.name, info.backend)
}

/// What ShadowLab asks of a device on `adapter`, headless or in the app's window (one request, so the app and
/// the CLI run the same shaders under the same limits): the optional features the adapter has, the downlevel
/// defaults (compute shaders included) with the adapter's texture sizes, storage buffer sizes and array layers,
/// and eight storage buffers per stage.
pub fn device_descriptor(adapter: &wgpu::Adapter) -> wgpu::DeviceDescriptor<'static> {
    let a = adapter.limits();
    let limits = wgpu::Limits::downlevel_defaults().using_resolution(a.clone());
    let limits = wgpu::Limits {
        max_texture_array_layers: a.max_texture_array_layers,
        max_storage_buffer_binding_size: a.max_storage_buffer_binding_size,
        max_buffer_size: a.max_buffer_size,
        // WebGPU's default, which every desktop adapter meets: the ray-traced shading binds lights, tile
        // lists, the BVH and the work counters in one stage.
        max_storage_buffers_per_shader_stage: a.max_storage_buffers_per_shader_stage.min(8),
        ..limits
    };
    wgpu::DeviceDescriptor {
        label: Some("shadowlab"),
        required_features: adapter.features() & OPTIONAL_FEATURES,
        required_limits: limits,
        ..Default::default()
    }
}

impl GpuContext {
    /// Create a device without a window. Honours `WGPU_BACKEND` (e.g. `vulkan`, `gl`), `WGPU_ADAPTER_NAME` and
    /// the debug/validation variables. Works on Mesa lavapipe and GL llvmpipe.
    pub fn headless() -> Result<GpuContext, GpuError> {
        Self::headless_with(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
    }

    /// A headless device on the given backends only (e.g. `wgpu::Backends::GL`), for tests of one backend.
    pub fn headless_on(backends: wgpu::Backends) -> Result<GpuContext, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        desc.backends = backends;
        Self::headless_with(desc)
    }

    fn headless_with(desc: wgpu::InstanceDescriptor) -> Result<GpuContext, GpuError> {
        let instance = wgpu::Instance::new(desc);
        // `initialize_adapter_from_env_or_default` panics when WGPU_ADAPTER_NAME matches nothing; check first so a
        // typo gives an error, not a panic.
        if let Ok(wanted) = std::env::var("WGPU_ADAPTER_NAME") {
            let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
            let wanted_lc = wanted.to_lowercase();
            if !adapters.iter().any(|a| a.get_info().name.to_lowercase().contains(&wanted_lc)) {
                return Err(GpuError::NoAdapter);
            }
        }
        let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(&instance, None))
            .map_err(|_| GpuError::NoAdapter)?;
        if !has_compute(&adapter) {
            return Err(GpuError::NoCompute(adapter_label(&adapter.get_info())));
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&device_descriptor(&adapter)))
            .map_err(|e| GpuError::RequestDevice(e.to_string()))?;
        Ok(GpuContext::from_device(device, queue, adapter.get_info()))
    }

    /// Whether the adapter a window would get (the environment's choice, else the default) is a software
    /// rasterizer such as lavapipe; `None` without any adapter. Creates no device (a few milliseconds).
    pub fn default_adapter_is_software() -> Option<bool> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(&instance, None)).ok()?;
        Some(adapter.get_info().device_type == wgpu::DeviceType::Cpu)
    }

    /// Use a device created elsewhere (the app passes eframe's).
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue, adapter_info: wgpu::AdapterInfo) -> GpuContext {
        // Which clock a run reports (timestamps or wall-clock steps) is `timing::PassTimer`'s choice.
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        // After a loss every call on the device is void and wgpu's buffer helpers panic: `guarded` refuses work
        // from then on. wgpu calls this at once for a real loss, and at the next poll after `destroy`.
        let lost = std::sync::Arc::new(std::sync::Mutex::new(None));
        let flag = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            let text = if message.is_empty() { format!("{reason:?}") } else { format!("{reason:?}: {message}") };
            if let Ok(mut l) = flag.lock() {
                *l = Some(text);
            }
        });
        GpuContext { device, queue, adapter_info, timestamps, lost }
    }

    /// Why the device was lost, or None while it works.
    pub fn lost(&self) -> Option<String> {
        self.lost.lock().ok().and_then(|l| l.clone())
    }

    /// `Err(DeviceLost)` once the device is lost (readbacks check it: mapping a buffer of a lost device is an
    /// uncaptured error, which wgpu's default handler turns into a panic).
    pub fn check_lost(&self) -> Result<(), GpuError> {
        match self.lost() {
            Some(reason) => Err(GpuError::DeviceLost(reason)),
            None => Ok(()),
        }
    }

    /// "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)".
    pub fn adapter_description(&self) -> String {
        format!("{} ({:?}, {:?})", self.adapter_info.name, self.adapter_info.backend, self.adapter_info.device_type)
    }

    /// Run `f` inside out-of-memory and validation error scopes: a wgpu error it causes becomes a
    /// [`GpuError`] (the last good state is the caller's to keep) instead of the default handler's panic.
    /// Scopes are per thread; `f` must not leave work for another thread.
    pub fn guarded<T>(&self, f: impl FnOnce() -> Result<T, GpuError>) -> Result<T, GpuError> {
        if let Some(reason) = self.lost() {
            return Err(GpuError::DeviceLost(reason));
        }
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = f();
        let validation = pollster::block_on(validation.pop());
        let oom = pollster::block_on(oom.pop());
        if let Some(e) = oom {
            return Err(GpuError::OutOfMemory(e.to_string()));
        }
        if let Some(reason) = self.lost() {
            return Err(GpuError::DeviceLost(reason));
        }
        if let Some(e) = validation {
            return Err(GpuError::Validation(e.to_string()));
        }
        result
    }

    /// Block until all submitted work is done.
    pub fn wait_idle(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Validation(format!("device poll failed: {e}")))
    }
}
