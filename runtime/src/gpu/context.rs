//! The GPU context: one wgpu instance, adapter, device and queue, chosen so that the same code
//! runs on a discrete GPU and, on machines without one, on a software rasteriser (Mesa lavapipe).
//!
//! The adapter choice is explicit rather than left to `request_adapter`: we enumerate every
//! adapter, rank hardware above software, and report which one we took, because a user looking
//! at a slow render must be able to tell at once that it ran on the CPU.

use std::fmt;

use super::GpuError;

/// What kind of adapter the context runs on, as the user should hear it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdapterKind {
    /// A discrete, integrated or virtual GPU.
    Hardware,
    /// A CPU implementation of the graphics API (Mesa lavapipe, SwiftShader, WARP).
    Software,
}

/// The adapter a context was created on: name, backend and device type.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterDescription {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub kind: AdapterKind,
    /// Whether GPU timestamps can be written inside compute passes (kernel timing).
    pub timestamps: bool,
}

impl AdapterDescription {
    /// Describes the adapter `info` reports; `timestamps` says whether kernel timing works.
    fn new(info: &wgpu::AdapterInfo, timestamps: bool) -> Self {
        let kind = if info.device_type == wgpu::DeviceType::Cpu {
            AdapterKind::Software
        } else {
            AdapterKind::Hardware
        };
        Self {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend),
            device_type: format!("{:?}", info.device_type),
            driver: [info.driver.as_str(), info.driver_info.as_str()]
                .iter()
                .filter(|s| !s.is_empty())
                .cloned()
                .collect::<Vec<_>>()
                .join(" "),
            kind,
            timestamps,
        }
    }
}

impl fmt::Display for AdapterDescription {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = match self.kind {
            AdapterKind::Hardware => "hardware",
            AdapterKind::Software => "software rasteriser, no GPU in use",
        };
        write!(
            f,
            "{} ({}, {}, {kind}",
            self.name, self.backend, self.device_type
        )?;
        if !self.driver.is_empty() {
            write!(f, ", driver {}", self.driver)?;
        }
        write!(f, ")")
    }
}

/// Options for [`GpuContext::new`].
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Take a software adapter even when a hardware one exists (reproducible CI images).
    /// Default `false`.
    pub force_software: bool,
}

/// A device and queue with the adapter they came from.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub description: AdapterDescription,
}

impl fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.description)
            .finish_non_exhaustive()
    }
}

/// Ranks adapters: lower is better. Hardware first, software last.
fn rank(device_type: wgpu::DeviceType) -> u32 {
    match device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// The message a user without any adapter needs: what to install.
fn no_adapter_hint() -> &'static str {
    if cfg!(target_os = "linux") {
        "no Vulkan adapter found; install a GPU driver, or Mesa's software Vulkan \
         (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers libvulkan1`)"
    } else {
        "no Vulkan adapter found; install your GPU vendor's Vulkan driver (or MoltenVK on macOS)"
    }
}

impl GpuContext {
    /// Creates a context on the best adapter present. Fails with [`GpuError::NoAdapter`], whose
    /// message says what to install, when there is none.
    pub fn new(options: &ContextOptions) -> Result<Self, GpuError> {
        pollster::block_on(Self::new_async(options))
    }

    /// The asynchronous form of [`GpuContext::new`], for callers that own an executor.
    pub async fn new_async(options: &ContextOptions) -> Result<Self, GpuError> {
        Self::on_instance_async(&Self::instance(), options, None).await
    }

    /// The wgpu instance [`GpuContext::new`] chooses its adapter from: Vulkan, without
    /// validation layers unless the environment asks for them (`WGPU_VALIDATION`). A windowed
    /// viewer creates its surface on this instance and passes both to
    /// [`GpuContext::on_instance`].
    pub fn instance() -> wgpu::Instance {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        // Validation layers are for development; they slow lavapipe down several times.
        desc.flags = wgpu::InstanceFlags::empty().with_env();
        wgpu::Instance::new(desc)
    }

    /// [`GpuContext::new`] on the caller's `instance`, among the adapters that can present to
    /// `compatible_surface` when one is given (a window's).
    pub fn on_instance(
        instance: &wgpu::Instance,
        options: &ContextOptions,
        compatible_surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        pollster::block_on(Self::on_instance_async(
            instance,
            options,
            compatible_surface,
        ))
    }

    /// The asynchronous form of [`GpuContext::on_instance`].
    pub async fn on_instance_async(
        instance: &wgpu::Instance,
        options: &ContextOptions,
        compatible_surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let mut adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
        if options.force_software {
            adapters.retain(|a| a.get_info().device_type == wgpu::DeviceType::Cpu);
        }
        if let Some(surface) = compatible_surface {
            adapters.retain(|a| a.is_surface_supported(surface));
        }
        // Stable sort: among equals, keep the driver's own order.
        adapters.sort_by_key(|a| rank(a.get_info().device_type));
        let adapter = adapters.into_iter().next().ok_or(GpuError::NoAdapter {
            hint: no_adapter_hint(),
        })?;
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut required_features = wgpu::Features::empty();
        if timestamps {
            required_features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        // Lets the renderer multisample its 32-bit float target where the adapter can (WebGPU
        // alone does not promise it).
        required_features |=
            adapter.features() & wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        // Ask for what the adapter offers on buffer sizes: refined meshes are large.
        let adapter_limits = adapter.limits();
        let required_limits = wgpu::Limits {
            max_storage_buffer_binding_size: adapter_limits.max_storage_buffer_binding_size,
            max_buffer_size: adapter_limits.max_buffer_size,
            max_storage_buffers_per_shader_stage: adapter_limits
                .max_storage_buffers_per_shader_stage,
            ..wgpu::Limits::default()
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("hce"),
                required_features,
                required_limits,
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device {
                adapter: info.name.clone(),
                reason: e.to_string(),
            })?;
        let description = AdapterDescription::new(&info, timestamps);
        Ok(Self {
            adapter,
            device,
            queue,
            description,
        })
    }

    /// Wraps a device and queue the caller already owns (a viewer's own renderer), so that
    /// the kernels and [`super::GpuScene`] work on it. The handles are shared, not
    /// copied: work submitted here goes to the caller's queue. Kernel timing is on when the
    /// device was created with `TIMESTAMP_QUERY`.
    pub fn from_existing(
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Self {
        let info = adapter.get_info();
        let description = AdapterDescription::new(
            &info,
            device.features().contains(wgpu::Features::TIMESTAMP_QUERY),
        );
        Self {
            adapter: adapter.clone(),
            device: device.clone(),
            queue: queue.clone(),
            description,
        }
    }

    /// Blocks until all submitted work is done, turning a device loss into an error.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Device {
                adapter: self.description.name.clone(),
                reason: e.to_string(),
            })
    }
}
