//! The headless wgpu context: adapter choice, optional features, and the facts every CSV row
//! records about the device.

use std::sync::{Arc, Mutex};

use crate::{CoreError, Result};

/// Optional features the methods can use, with the names the CSV records; requested only
/// where the adapter has them.
pub const FEATURE_NAMES: &[(wgpu::Features, &str)] = &[
    (wgpu::Features::TIMESTAMP_QUERY, "TIMESTAMP_QUERY"),
    (
        wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
        "TIMESTAMP_QUERY_INSIDE_ENCODERS",
    ),
    (
        wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES,
        "TIMESTAMP_QUERY_INSIDE_PASSES",
    ),
    (wgpu::Features::FLOAT32_BLENDABLE, "FLOAT32_BLENDABLE"),
    (wgpu::Features::SHADER_INT64, "SHADER_INT64"),
    (
        wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
        "SHADER_INT64_ATOMIC_MIN_MAX",
    ),
    (
        wgpu::Features::PIPELINE_STATISTICS_QUERY,
        "PIPELINE_STATISTICS_QUERY",
    ),
    (
        wgpu::Features::INDIRECT_FIRST_INSTANCE,
        "INDIRECT_FIRST_INSTANCE",
    ),
    (
        wgpu::Features::MULTI_DRAW_INDIRECT_COUNT,
        "MULTI_DRAW_INDIRECT_COUNT",
    ),
    (wgpu::Features::SHADER_F16, "SHADER_F16"),
    (
        wgpu::Features::RG11B10UFLOAT_RENDERABLE,
        "RG11B10UFLOAT_RENDERABLE",
    ),
    (
        wgpu::Features::VERTEX_WRITABLE_STORAGE,
        "VERTEX_WRITABLE_STORAGE",
    ),
    (wgpu::Features::PRIMITIVE_INDEX, "PRIMITIVE_INDEX"),
    // MSAA with 2 or 8 samples (WebGPU guarantees only 1 and 4): the adapter's own format
    // capabilities apply where this is granted.
    (
        wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
        "TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES",
    ),
];

/// The union of [`FEATURE_NAMES`].
pub fn wanted_features() -> wgpu::Features {
    FEATURE_NAMES
        .iter()
        .fold(wgpu::Features::empty(), |a, (f, _)| a | *f)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendChoice {
    Vulkan,
    /// wgpu's own GL set-up: desktop GL 3.3 where EGL offers OpenGL (no compute), else GLES.
    Gl,
    /// A GLES 3.x context of our own through EGL ([`crate::gles`]): compute where the driver
    /// offers GLES 3.1+, on drivers where wgpu itself would pick desktop GL 3.3.
    Gles,
    Any,
}

impl std::str::FromStr for BackendChoice {
    type Err = crate::UnknownWord;
    fn from_str(s: &str) -> std::result::Result<Self, crate::UnknownWord> {
        match s.to_ascii_lowercase().as_str() {
            "vulkan" | "vk" => Ok(BackendChoice::Vulkan),
            "gl" | "opengl" => Ok(BackendChoice::Gl),
            "gles" => Ok(BackendChoice::Gles),
            "any" => Ok(BackendChoice::Any),
            other => Err(crate::UnknownWord {
                what: "backend",
                text: other.to_string(),
                known: "vulkan, gl, gles, any".into(),
            }),
        }
    }
}

impl BackendChoice {
    pub fn backends(self) -> wgpu::Backends {
        match self {
            BackendChoice::Vulkan => wgpu::Backends::VULKAN,
            BackendChoice::Gl => wgpu::Backends::GL,
            // Our own EGL context: wgpu opens none of its own (it would take desktop GL).
            BackendChoice::Gles => wgpu::Backends::empty(),
            BackendChoice::Any => wgpu::Backends::VULKAN | wgpu::Backends::GL,
        }
    }
}

/// How to pick the adapter.
#[derive(Clone, Debug)]
pub struct GpuOptions {
    pub backend: BackendChoice,
    /// Case-insensitive substring of the adapter name.
    pub adapter: Option<String>,
    /// Index into `mfx list adapters` (after the backend filter).
    pub adapter_index: Option<usize>,
    /// Where render targets' memory comes from (None: wgpu's pool, the default; see
    /// [`crate::texture_memory`] for what was measured).
    pub texture_memory: Option<crate::texture_memory::TextureMemory>,
    /// The limits the device is requested with (`--limits`, [`crate::limits`]).
    pub limits: crate::limits::Profile,
}

impl Default for GpuOptions {
    fn default() -> Self {
        GpuOptions {
            backend: BackendChoice::Vulkan,
            adapter: None,
            adapter_index: None,
            texture_memory: None,
            limits: Default::default(),
        }
    }
}

/// What the CSV records about the device.
#[derive(Clone, Debug, serde::Serialize)]
pub struct AdapterFacts {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    /// Optional features granted (names, `|`-separated).
    pub features: String,
    pub is_software: bool,
}

/// `features` by the names `mfx list adapters` prints, `|`-joined (wgpu's Debug text of its
/// two bit sets where a feature is not one mfx names).
pub fn feature_names(features: wgpu::Features) -> String {
    let names: Vec<&str> = FEATURE_NAMES
        .iter()
        .filter(|(f, _)| features.contains(*f))
        .map(|(_, n)| *n)
        .collect();
    if (features - wanted_features()).is_empty() {
        names.join("|")
    } else {
        format!("{features:?}")
    }
}

impl AdapterFacts {
    pub fn of(info: &wgpu::AdapterInfo, features: wgpu::Features) -> Self {
        AdapterFacts {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend).to_lowercase(),
            device_type: format!("{:?}", info.device_type).to_lowercase(),
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
            features: feature_names(features),
            is_software: info.device_type == wgpu::DeviceType::Cpu,
        }
    }
}

/// A device and queue plus what was granted. Cheap to share by reference.
pub struct Gpu {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub features: wgpu::Features,
    pub limits: wgpu::Limits,
    pub facts: AdapterFacts,
    pub downlevel: wgpu::DownlevelCapabilities,
    /// The limits profile `limits` and `features` were requested under (column `limits`).
    pub profile: crate::limits::Profile,
    /// Set by the device-lost callback; a lost device fails every later point with this reason.
    pub lost: Arc<Mutex<Option<String>>>,
    /// NVML for this adapter's clocks, temperature, power and throttle reasons, or why not
    /// (no NVIDIA driver, not an NVIDIA adapter): every point's `clock_source` says which.
    pub monitor: std::result::Result<crate::clocks::GpuMonitor, crate::clocks::MonitorError>,
    /// Where the processes holding the GPU are read after every timed frame (flag
    /// `gpu_shared`): `None` reads NVML's lists through `monitor`; a test sets its own.
    pub process_list: Option<Box<dyn crate::clocks::ProcessList>>,
    /// The busy kernel that lifts a lowered SM clock (`measure`), built on first use.
    spin: std::sync::OnceLock<Kernel>,
    /// The fixed kernel timed after each sample (`measure`'s canary rule), built on first use,
    /// with the fastest time it has taken in this process.
    canary: std::sync::OnceLock<Mutex<Canary>>,
    /// The memory roofs (`roofs`), measured on first use ([`Gpu::roofs`]).
    roofs: std::sync::OnceLock<Option<crate::roofs::Roofs>>,
    /// `--timing cold=true`: the buffer cleared before each sample to flush the L2.
    l2_flush: std::sync::OnceLock<wgpu::Buffer>,
    /// The first bind group layout made since the last [`Gpu::take_stage_violation`] that is
    /// over the profile's per-stage storage limits (`limits::check_stage_storage`), which wgpu
    /// does not check: a point that made one is skipped naming the limit.
    stage_violation: Mutex<Option<String>>,
    /// Where render targets' memory comes from (`texture_memory` column); see
    /// [`crate::texture_memory`]. Set before any method prepares.
    pub texture_memory: crate::texture_memory::TextureMemory,
    /// Textures made in dedicated allocations so far (tests check the path was taken).
    pub dedicated_textures: std::sync::atomic::AtomicUsize,
    /// `--backend gles`: the EGL context the device renders with (current on this thread).
    /// Declared last: it outlives the device and adapter above it.
    gles: Option<crate::gles::GlesContext>,
}

/// Lists adapters for a backend choice, in enumeration order (the `--adapter-index` order).
/// Why `gles` has none is logged (see [`candidates`]).
pub fn list_adapters(backend: BackendChoice) -> Vec<wgpu::Adapter> {
    match candidates(backend) {
        Ok(c) => c.into_iter().map(|(a, _)| a).collect(),
        Err(why) => {
            log::warn!("{why}");
            Vec::new()
        }
    }
}

/// The adapters of a backend choice, each with its GLES context where it has one; or why
/// `gles` has none (no libEGL, no display, no GLES 3 context).
fn candidates(
    backend: BackendChoice,
) -> std::result::Result<
    Vec<(wgpu::Adapter, Option<crate::gles::GlesContext>)>,
    crate::gles::GlesError,
> {
    let instance = make_instance(backend);
    if backend == BackendChoice::Gles {
        return Ok(crate::gles::adapters(&instance)?
            .into_iter()
            .map(|(a, c)| (a, Some(c)))
            .collect());
    }
    Ok(
        pollster::block_on(instance.enumerate_adapters(backend.backends()))
            .into_iter()
            .map(|a| (a, None))
            .collect(),
    )
}

fn make_instance(backend: BackendChoice) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    // `gles`: no backend of wgpu's own; the adapters come from `crate::gles`.
    desc.backends = backend.backends();
    wgpu::Instance::new(desc)
}

fn type_rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

impl Gpu {
    /// Opens the chosen adapter: a hardware GPU if one exists, else a software one (lavapipe).
    pub fn new(opts: &GpuOptions) -> Result<Gpu> {
        let adapters = candidates(opts.backend).map_err(|e| CoreError::NoAdapter(e.to_string()))?;
        if adapters.is_empty() {
            return Err(CoreError::NoAdapter(format!(
                "no {:?} adapter found (on a machine without a GPU install Mesa's lavapipe: scripts/setup.sh)",
                opts.backend
            )));
        }
        let adapter = if let Some(i) = opts.adapter_index {
            let n = adapters.len();
            adapters.into_iter().nth(i).ok_or_else(|| {
                CoreError::NoAdapter(format!(
                    "--adapter-index {i} out of range: {n} adapter(s) (see `mfx list adapters`)"
                ))
            })?
        } else {
            let mut cands: Vec<_> = adapters
                .into_iter()
                .filter(|(a, _)| match &opts.adapter {
                    Some(s) => a.get_info().name.to_lowercase().contains(&s.to_lowercase()),
                    None => true,
                })
                .collect();
            if cands.is_empty() {
                return Err(CoreError::NoAdapter(format!(
                    "no adapter name contains '{}' (see `mfx list adapters`)",
                    opts.adapter.clone().unwrap_or_default()
                )));
            }
            cands.sort_by_key(|(a, _)| type_rank(a.get_info().device_type));
            cands.remove(0)
        };
        let (adapter, gles) = adapter;
        let mut gpu = match gles {
            Some(ctx) => {
                ctx.make_current()
                    .map_err(|e| CoreError::NoAdapter(e.to_string()))?;
                let mut gpu = Self::open_with(adapter, opts.limits)?;
                gpu.facts.backend = "gles".into();
                gpu.gles = Some(ctx);
                gpu
            }
            None => Self::open_with(adapter, opts.limits)?,
        };
        if let Some(m) = opts.texture_memory {
            gpu.set_texture_memory(m);
        }
        Ok(gpu)
    }

    pub fn open(adapter: wgpu::Adapter) -> Result<Gpu> {
        Self::open_with(adapter, Default::default())
    }

    /// Opens `adapter` held to `profile`'s limits and features.
    pub fn open_with(adapter: wgpu::Adapter, profile: crate::limits::Profile) -> Result<Gpu> {
        let info = adapter.get_info();
        let features = profile.features(adapter.features() & wanted_features());
        let limits = profile.limits(&adapter.limits());
        let desc = wgpu::DeviceDescriptor {
            label: Some("mfx"),
            required_features: features,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc)).map_err(|e| {
            CoreError::NoAdapter(format!("request_device on '{}' failed: {e}", info.name))
        })?;
        let lost = Arc::new(Mutex::new(None));
        let lost2 = lost.clone();
        device.set_device_lost_callback(move |reason, msg| {
            *lost2.lock().unwrap() = Some(format!("device lost ({reason:?}): {msg}"));
        });
        // Uncaptured errors are logged; the runner wraps each point in error scopes to attribute them.
        device.on_uncaptured_error(Arc::new(|e: wgpu::Error| {
            log::error!("uncaptured wgpu error: {e}")
        }));
        let downlevel = profile.downlevel(adapter.get_downlevel_capabilities());
        // 0x10DE: NVIDIA's PCI vendor id (NVML knows no other vendor's GPUs).
        let monitor = if info.vendor == 0x10DE {
            crate::clocks::GpuMonitor::open(
                Some(info.device_pci_bus_id.as_str()).filter(|s| !s.is_empty()),
            )
        } else {
            Err(crate::clocks::MonitorError::NotNvidia {
                name: info.name.clone(),
                vendor: info.vendor,
            })
        };
        Ok(Gpu {
            facts: AdapterFacts::of(&info, features),
            adapter,
            device,
            queue,
            features,
            limits,
            downlevel,
            profile,
            lost,
            monitor,
            process_list: None,
            spin: std::sync::OnceLock::new(),
            canary: std::sync::OnceLock::new(),
            roofs: std::sync::OnceLock::new(),
            l2_flush: std::sync::OnceLock::new(),
            stage_violation: Mutex::new(None),
            texture_memory: crate::texture_memory::TextureMemory::Pooled,
            dedicated_textures: Default::default(),
            gles: None,
        })
    }

    /// How many processes other than this one hold the GPU now (`process_list`, else NVML's
    /// lists); `None` without a list or when it cannot be read.
    pub fn other_processes(&self) -> Option<u32> {
        let pids = match &self.process_list {
            Some(l) => l.pids(),
            None => match &self.monitor {
                Ok(m) => crate::clocks::ProcessList::pids(m),
                Err(_) => return None,
            },
        };
        match pids {
            Ok(p) => Some(crate::clocks::other_processes(
                &p,
                &crate::clocks::own_pids(),
            )),
            Err(e) => {
                log::warn!("GPU process list: {e}");
                None
            }
        }
    }

    /// A texture, its memory placed as `texture_memory` says (every method's textures go
    /// through here, so a run's render targets all come from one kind of memory).
    pub fn create_texture(&self, desc: &wgpu::TextureDescriptor) -> wgpu::Texture {
        use crate::texture_memory::{dedicated_texture, TextureMemory};
        if self.texture_memory == TextureMemory::Dedicated {
            if let Some(t) = dedicated_texture(&self.adapter, &self.device, &self.queue, desc) {
                self.dedicated_textures
                    .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                return t;
            }
        }
        self.device.create_texture(desc)
    }

    /// This run's texture memory, where the backend allows it (dedicated needs Vulkan).
    pub fn set_texture_memory(&mut self, m: crate::texture_memory::TextureMemory) {
        self.texture_memory = match (m, self.adapter.get_info().backend) {
            (crate::texture_memory::TextureMemory::Dedicated, wgpu::Backend::Vulkan) => m,
            _ => crate::texture_memory::TextureMemory::Pooled,
        };
    }

    /// The limits granted and the profile they came from, for [`crate::limits`]'s checks.
    pub fn held(&self) -> crate::limits::Held<'_> {
        (&self.limits, self.profile)
    }

    pub fn has(&self, f: wgpu::Features) -> bool {
        self.features.contains(f)
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| CoreError::Gpu(format!("poll failed: {e}")))
    }

    /// Waits until the GPU is idle, so that what earlier work dropped is freed (wgpu destroys a
    /// dropped resource only once the submissions that used it are known to be done, which the
    /// waiting poll finds out): the next allocations see the same memory whatever ran before.
    pub fn settle(&self) -> Result<()> {
        self.wait()
    }

    /// A 1×1 sampled texture of `format`, bound where a layout declares a texture that a
    /// pipeline variant never reads.
    pub fn stand_in_texture(&self, label: &str, format: wgpu::TextureFormat) -> wgpu::Texture {
        self.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: 1,
                height: 1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
    }

    pub fn check_lost(&self) -> Result<()> {
        match self.lost.lock().unwrap().clone() {
            Some(r) => Err(CoreError::DeviceLost(r)),
            None => Ok(()),
        }
    }

    /// Whether a texture format can be a render target here (GL downlevel lacks some, e.g. R32Float).
    pub fn renderable(&self, format: wgpu::TextureFormat) -> bool {
        self.adapter
            .get_texture_format_features(format)
            .allowed_usages
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
    }

    /// Reads back a whole buffer (must have MAP_READ or be copied first; this copies).
    pub fn read_buffer(&self, src: &wgpu::Buffer, size: u64) -> Result<Vec<u8>> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(src, 0, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        self.map_read(&staging)
    }

    /// Maps a MAP_READ buffer and copies its bytes out.
    pub fn map_read(&self, buf: &wgpu::Buffer) -> Result<Vec<u8>> {
        self.map_read_range(buf, buf.size())
    }

    /// Maps the first `size` bytes of a MAP_READ buffer and copies them out.
    pub fn map_read_range(&self, buf: &wgpu::Buffer, size: u64) -> Result<Vec<u8>> {
        let (tx, rx) = std::sync::mpsc::channel();
        buf.slice(..size).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|_| CoreError::Gpu("map callback dropped".into()))?
            .map_err(|e| CoreError::Gpu(format!("buffer map failed: {e}")))?;
        let bytes = buf
            .slice(..size)
            .get_mapped_range()
            .map_err(|e| CoreError::Gpu(format!("{e}")))?
            .to_vec();
        buf.unmap();
        Ok(bytes)
    }
}

/// A colour attachment cleared to `color` at the start of the pass and stored at its end.
pub fn cleared(
    view: &wgpu::TextureView,
    color: wgpu::Color,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(color),
            store: wgpu::StoreOp::Store,
        },
    })
}

/// Bytes per row of a texture copy: padded to wgpu's 256-byte alignment.
pub fn padded_row(width: u32, bpp: u32) -> u32 {
    let unpadded = width * bpp;
    unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// Copies a whole 2-D texture (one aspect) into a buffer and returns the tightly packed bytes.
pub fn read_texture(
    gpu: &Gpu,
    tex: &wgpu::Texture,
    bpp: u32,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>> {
    let (w, h) = (tex.width(), tex.height());
    let row = padded_row(w, bpp);
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: row as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: tex,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        tex.size(),
    );
    gpu.queue.submit([enc.finish()]);
    let bytes = gpu.map_read(&staging)?;
    if bytes.len() < (row * h) as usize {
        return Err(CoreError::Gpu("short texture read-back".into()));
    }
    let mut out = Vec::with_capacity((w * h * bpp) as usize);
    for y in 0..h as usize {
        let s = y * row as usize;
        out.extend_from_slice(&bytes[s..s + (w * bpp) as usize]);
    }
    Ok(out)
}

/// Reads an Rgba32Float texture as RGBA pixels.
pub fn read_rgba32f(gpu: &Gpu, tex: &wgpu::Texture) -> Result<Vec<[f32; 4]>> {
    let b = read_texture(gpu, tex, 16, wgpu::TextureAspect::All)?;
    Ok(bytemuck::cast_slice(&b).to_vec())
}

/// A compute kernel with one storage buffer: the clock lift's busy work (`SPIN_WGSL`) and the
/// canary. Here, not in `measure`, so that `Gpu` can cache them without a module cycle.
struct Kernel {
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
}

/// Busy work that raises a lowered SM clock (the clock lift of `measure`): every SM runs
/// dependent FMAs for a few ms (about 2 ms on an H200 at 1980 MHz, by its FMA rate).
const SPIN_WGSL: &str = "
@group(0) @binding(0) var<storage, read_write> sink: array<f32>;
@compute @workgroup_size(WG)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var x = f32(id.x & 255u) * 1e-3;
    for (var i = 0u; i < 65536u; i = i + 1u) {
        x = fma(x, 0.9999, 1e-4);
    }
    // Never true; keeps the loop from being removed as dead code.
    if x == 12345.0 {
        sink[id.x & 255u] = x;
    }
}";

impl Kernel {
    /// Entry `main` of `wgsl` with its one storage buffer (`bytes`, zeroed) at group 0, binding 0,
    /// in workgroups of `WG` = 256 threads, or the device's most where that is fewer (WebGPU's
    /// compatibility mode allows 128).
    fn new(device: &wgpu::Device, label: &str, wgsl: &str, bytes: u64) -> Kernel {
        let l = device.limits();
        let wg = 256
            .min(l.max_compute_invocations_per_workgroup)
            .min(l.max_compute_workgroup_size_x)
            .max(1);
        let wgsl = format!("const WG: u32 = {wg}u;\n{wgsl}");
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(wgsl.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: buffer.as_entire_binding(),
            }],
        });
        Kernel { pipeline, bind }
    }

    /// Records one dispatch of `workgroups` workgroups, timestamped when `stamps` is given.
    fn dispatch(
        &self,
        enc: &mut wgpu::CommandEncoder,
        label: &str,
        workgroups: u32,
        stamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: stamps,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        pass.dispatch_workgroups(workgroups, 1, 1);
    }
}

/// A fixed amount of mixed work (a streaming read of 16 MiB and a dependent FMA chain per
/// thread, about 20–40 µs on an H200), timed with its own timestamps: how fast the GPU is right
/// now, independent of the point being measured. See `mfx_stats::canary`.
/// Its own two timestamps (not `timing::GpuTimer`: `timing` depends on this module).
struct Canary {
    kernel: Kernel,
    /// Query set of 2, resolve and read-back buffers; None without timestamp queries.
    stamps: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    baseline: mfx_stats::CanaryBaseline,
}

const CANARY_WGSL: &str = "
@group(0) @binding(0) var<storage, read_write> buf: array<vec4<f32>>;
@compute @workgroup_size(WG)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let n = arrayLength(&buf);
    let stride = nw.x * WG;
    var acc = vec4<f32>(0.0);
    for (var i = id.x; i < n; i = i + stride) {
        acc = acc + buf[i];
    }
    var x = acc.x + acc.y + acc.z + acc.w + f32(id.x & 255u) * 1e-3;
    for (var k = 0u; k < 2048u; k = k + 1u) {
        x = fma(x, 0.9999, 1e-4);
    }
    // Never true (the buffer is zeros); keeps both loops alive.
    if x == 12345.0 {
        buf[id.x] = vec4<f32>(x);
    }
}";

/// Canary size: 16 MiB read by 264 workgroups (two per SM of a 132-SM GPU).
const CANARY_BYTES: u64 = 16 << 20;
const CANARY_WORKGROUPS: u32 = 264;

impl Canary {
    fn new(gpu: &Gpu) -> Canary {
        let device = &gpu.device;
        let kernel = Kernel::new(device, "canary", CANARY_WGSL, CANARY_BYTES);
        let stamps = gpu.has(wgpu::Features::TIMESTAMP_QUERY).then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("canary"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let buf = |label, usage| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: 16,
                    usage,
                    mapped_at_creation: false,
                })
            };
            let resolve = buf(
                "canary resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            );
            let read = buf(
                "canary read-back",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            );
            (set, resolve, read)
        });
        Canary {
            kernel,
            stamps,
            baseline: Default::default(),
        }
    }
}

impl Gpu {
    /// Runs the canary kernel once, waited for: (its GPU ms, its ratio to the fastest canary of
    /// this process). `None` without timestamp queries.
    pub fn canary(&self) -> Result<Option<(f64, f64)>> {
        let c = self.canary.get_or_init(|| Mutex::new(Canary::new(self)));
        let mut c = c.lock().unwrap();
        let Some(ms) = self.canary_ms(&c)? else {
            return Ok(None);
        };
        Ok(c.baseline.push(ms).map(|r| (ms, r)))
    }

    /// The cross-GPU calibration set (issue 33): the canary kernel run `n` times after a clock
    /// lift, its median GPU ms. The canary's baseline is not touched, so a run's discards are
    /// the same with or without it. `None` without timestamp queries.
    pub fn calibration_ms(&self, n: usize) -> Result<Option<f64>> {
        for _ in 0..4 {
            self.spin()?;
        }
        let c = self.canary.get_or_init(|| Mutex::new(Canary::new(self)));
        let c = c.lock().unwrap();
        let mut v = Vec::with_capacity(n);
        for _ in 0..n.max(1) {
            match self.canary_ms(&c)? {
                Some(ms) => v.push(ms),
                None => return Ok(None),
            }
        }
        v.sort_by(f64::total_cmp);
        Ok(Some(v[v.len() / 2]))
    }

    /// One canary dispatch, waited for: its GPU ms.
    fn canary_ms(&self, c: &Canary) -> Result<Option<f64>> {
        let Some((set, resolve, read)) = &c.stamps else {
            return Ok(None);
        };
        let mut enc = self.device.create_command_encoder(&Default::default());
        c.kernel.dispatch(
            &mut enc,
            "canary",
            CANARY_WORKGROUPS,
            Some(wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(0),
                end_of_pass_write_index: Some(1),
            }),
        );
        enc.resolve_query_set(set, 0..2, resolve, 0);
        enc.copy_buffer_to_buffer(resolve, 0, read, 0, 16);
        self.queue.submit([enc.finish()]);
        self.wait()?;
        let t: Vec<u64> = bytemuck::pod_collect_to_vec(&self.map_read_range(read, 16)?);
        let ticks = t[1].wrapping_sub(t[0]);
        if ticks > u64::MAX / 2 {
            return Ok(None); // a wrapped delta: not timed reliably
        }
        Ok(Some(
            ticks as f64 * self.queue.get_timestamp_period() as f64 * 1e-6,
        ))
    }

    /// The memory roofs of this adapter, measured on the first call (`mfx sweep` makes it
    /// before any point, as the calibration set) and kept: None without timestamp queries or
    /// when the measurement failed (it says why on stderr; a row then has no roof).
    pub fn roofs(&self) -> Option<&crate::roofs::Roofs> {
        self.roofs
            .get_or_init(|| {
                let (max_binding, _) = crate::limits::storage_binding_limit(self.held());
                let d = crate::roofs::Device {
                    device: &self.device,
                    queue: &self.queue,
                    adapter_name: &self.facts.name,
                    software: self.facts.is_software,
                    max_binding,
                    timestamps: self.has(wgpu::Features::TIMESTAMP_QUERY),
                };
                let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
                let r = crate::roofs::measure(&d);
                let r = match pollster::block_on(scope.pop()) {
                    Some(e) => Err(CoreError::Gpu(e.to_string())),
                    None => r,
                };
                r.unwrap_or_else(|e| {
                    eprintln!("mfx: memory roofs not measured: {e}");
                    None
                })
            })
            .as_ref()
    }

    /// Notes a bind group layout's entries against the profile's per-stage storage limits
    /// (`limits::check_stage_storage`; only compatibility mode has them). Layout helpers call it.
    pub fn note_layout(&self, what: &str, entries: &[wgpu::BindGroupLayoutEntry]) {
        if let Err(why) = crate::limits::check_stage_storage(self.profile, what, entries) {
            self.stage_violation
                .lock()
                .unwrap()
                .get_or_insert(why.into());
        }
    }

    /// The per-stage storage limit a layout went over since the last call, if one did.
    pub fn take_stage_violation(&self) -> Option<String> {
        self.stage_violation.lock().unwrap().take()
    }

    /// The roofs if they were measured ([`Gpu::roofs`]), without measuring them.
    pub fn measured_roofs(&self) -> Option<&crate::roofs::Roofs> {
        self.roofs.get().and_then(|r| r.as_ref())
    }

    /// Bytes `--timing cold=true` clears before each sample: twice the L2 (measured or known),
    /// else 256 MiB on hardware (16 MiB on a software adapter), within the largest buffer.
    pub fn l2_flush_bytes(&self) -> u64 {
        let l2 = self
            .measured_roofs()
            .map(|r| r.l2_bytes)
            .or_else(|| crate::roofs::known_l2(&self.facts.name));
        let bytes = match (l2, self.facts.is_software) {
            (Some(l2), _) => 2 * l2,
            (None, false) => 256 << 20,
            (None, true) => 16 << 20,
        };
        bytes.max(1 << 20).min(self.limits.max_buffer_size) & !3
    }

    /// Flushes the L2 (`--timing cold=true`, nvbench's cold mode): an untimed clear of
    /// [`Gpu::l2_flush_bytes`], waited for, so the next frame finds none of its data cached.
    pub fn flush_l2(&self) -> Result<()> {
        let buf = self.l2_flush.get_or_init(|| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("L2 flush"),
                size: self.l2_flush_bytes(),
                usage: wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.clear_buffer(buf, 0, None);
        self.queue.submit([enc.finish()]);
        self.wait()
    }

    /// One untimed busy dispatch, waited for.
    pub fn spin(&self) -> Result<()> {
        let spin = self
            .spin
            .get_or_init(|| Kernel::new(&self.device, "clock lift", SPIN_WGSL, 1024));
        let mut enc = self.device.create_command_encoder(&Default::default());
        // 4096 workgroups × 256 threads: every SM of a large GPU busy.
        spin.dispatch(&mut enc, "clock lift", 4096, None);
        self.queue.submit([enc.finish()]);
        self.wait()
    }
}
