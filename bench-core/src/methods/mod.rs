//! Multi-fragment methods: the table of contents.
//!
//! | name           | source                         | exact?                     | geometry passes | memory per pixel          |
//! |----------------|--------------------------------|----------------------------|-----------------|---------------------------|
//! | `floor_depth`  | the yardstick (issue "Compare GPUs") | — (no image)          | 1               | 4 B depth                 |
//! | `floor_opaque` | the yardstick, one colour       | — (no image)              | 1               | 4 B depth + 4 B RGBA8     |
//! | `floor_blend`  | the yardstick of unsorted transparency (LucidRaster's ratio) | — (not judged: primitive order) | 1 | 4 B RGBA8 |
//! | `depth_peel`   | Everitt 2001, classic front-to-back peeling; every effect via the fold | exact up to `max_layers`; coplanar ties lost (`variant=tiebreak` keeps them) | layers + 1 | 2×4 B depth + 4–36 B layer payload + 64 B fold state + 16 B per output image + 4 B count |
//! | `dual_peel`    | Bavoil & Myers 2008, dual depth peeling (MAX blending, nearest + farthest per pass) | exact up to `max_layers`; coplanar ties merged | ⌈layers/2⌉ + 1 | 2×8 B depth + 2×16 B layers + 2×16 B accumulation + 16 B image + 4 B count |
//! | `kbuffer_rmw`  | Bavoil 2007 ch. 4, k-buffer by non-atomic read-modify-write insertion | k nearest, but RMW hazards (measured: `hazard_rate`) | 1 (+ resolve) | k × (4 B key + 32 B entry) + 16 B image |
//! | `kbuffer_atomic` | hazard-free k-buffer: 32-bit atomicMax bubbling of depth keys, then a payload pass | exact k nearest (ties get their own slots) | 2 (+ resolve) | k × (4 B key + 4 B claim + 32 B entry) + 16 B image |
//! | `linked_list`  | Yang et al. 2010, per-pixel linked lists (atomic heads; per-8×8-tile node pools counted at prepare, or one layers × pixels pool), sorted in the resolve; compact nodes re-derived per primitive | exact within the pool; overflow counted | 1 (+ resolve) | 32 B (head, lost, count, image, stand-in depth) + 12 B per true fragment (compact, counted; 32 B full nodes, or layers × nodes when fixed) |
//! | `compute_abuffer` | Maule et al. 2012 dynamic fragment buffer, rasterised in compute (no render pass; Laine & Karras 2011 in spirit), attributes re-derived per primitive (visibility buffer) | exact: coverage rule for rule as the reference, sized by a prepare-time count; lists over 128 counted | 2 (count, fill) + scan + resolve | 4 B offset + 16 B image + exactly 8 B per fragment (+ 16 B per vertex with `transform = vertex`) |
//! | `wboit`        | McGuire & Bavoil 2013, weighted blended OIT | approximate (exact for one layer or one colour/alpha) | 1 (+ resolve) | 8 B RGBA16F + 2 B R16F + 16 B result |
//! | `bdp`          | Liu et al., GPU Pro ch. 1, uniform bucket depth peeling | approximate: exact iff ≤1 fragment per bucket (2 if paired); collisions counted | 2 | 8 B range + 4 B × channels (≤32) + 68 B resolve |
//! | `bdp2`         | Liu et al., GPU Pro ch. 1, two-pass BDP | approximate: 2 fragments per bucket; collisions counted | 3 | 8 B range + 2 × 4 B × K + 68 B resolve |
//! | `adp`          | Liu et al., GPU Pro ch. 1, adaptive (histogram-equalised) BDP | approximate: fragments sharing a histogram bin collide | 2 + ⌈occupied bins / K⌉ | hist_bins/8 B + 8 B × K + 8 B range + 68 B resolve |
//!
//! Every method implements [`Method`] (what it is, which axes and features it needs, and
//! `prepare`, which creates every GPU object) and [`Prepared`] (`frame`, the timed per-frame
//! work, and `readback`). Nothing assumes a render pass: a compute-only method only has to fill
//! the same [`Capture`]. The shared vertex stage is `common.wgsl`, prepended to each method's WGSL;
//! `effects.wgsl` ([`EFFECTS_WGSL`]) is the effects fold, and `packing` the float colour packing
//! shared with the bucket methods.

pub mod adp;
pub mod bdp;
pub mod bdp2;
pub mod bucket;
pub mod compute_abuffer;
pub mod depth_peel;
pub mod dual_peel;
pub mod floor;
pub mod kbuffer_atomic;
pub mod kbuffer_rmw;
pub mod linked_list;
pub mod packing;
pub mod store;
pub mod wboit;

use scenarios::Params;

use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::timing::GpuTimer;
use crate::Result;

/// WGSL shared by every raster method: the camera uniform and the standard vertex stage.
pub const COMMON_WGSL: &str = include_str!("common.wgsl");

/// The effects fold (`fold_init_at` / `fold_step` / `fold_finish_image`, override `EFFECT`):
/// prepend it to a method's WGSL and set `effects::EffectConfig::constants` on the pipelines
/// that call the fold.
pub const EFFECTS_WGSL: &str = include_str!("effects.wgsl");

/// Bytes of one `FoldState` in `effects.wgsl` (three vec4 + two u32, padded to 16): methods that
/// keep fold states in a per-pixel buffer between passes size it with this.
pub const FOLD_STATE_BYTES: u64 = 64;

/// Which reference a capture is judged against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expected {
    /// Every fragment of every pixel.
    All,
    /// The `k` nearest fragments of every pixel.
    FirstK(u32),
}

/// What a method hands back after a frame, read from the GPU.
#[derive(Clone, Debug)]
pub struct Capture {
    /// Premultiplied RGBA per pixel (row-major, top-left first), A = 1 − transmittance;
    /// `None` for methods that make no image (the floors).
    pub image: Option<Vec<[f32; 4]>>,
    /// Fragments captured per pixel.
    pub counts: Option<Vec<u32>>,
    pub expected: Expected,
    /// Pixels whose fragments exceeded capacity (reported, never silent).
    pub overflow_pixels: Option<u64>,
    /// True fragments merged or lost by bucket collisions.
    pub collision_fragments: Option<u64>,
    /// Pixels whose captured set differs from the true k nearest (k-buffer RMW hazards).
    pub hazard_pixels: Option<u64>,
    /// A knowingly-failed mode (overflow, collision, lost_coplanar, precision, hazard).
    pub flag: Option<String>,
    pub notes: String,
}

impl Capture {
    pub fn empty() -> Capture {
        Capture {
            image: None,
            counts: None,
            expected: Expected::All,
            overflow_pixels: None,
            collision_fragments: None,
            hazard_pixels: None,
            flag: None,
            notes: String::new(),
        }
    }
}

/// What one frame did.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameStats {
    /// Times the scene's geometry was submitted.
    pub geometry_passes: u32,
    /// Layers (or passes of capture) that produced fragments.
    pub layers: u32,
}

/// A multi-fragment method (or a floor): description, requirements, and preparation.
pub trait Method: Send + Sync {
    fn name(&self) -> &'static str;
    /// One line: source, exact or approximate, passes, memory.
    fn describe(&self) -> &'static str;
    /// True when the method captures every fragment (within its capacity).
    fn exact(&self) -> bool;
    /// Sweep axes this method reads; the suite's product is taken over these only.
    fn axes(&self) -> &'static [&'static str] {
        &[]
    }
    /// Optional adapter features it cannot run without.
    fn required_features(&self) -> wgpu::Features {
        wgpu::Features::empty()
    }
    /// Whether this point can run here; `Err(reason)` becomes a `skipped` row.
    fn supports(&self, gpu: &Gpu, params: &Params) -> std::result::Result<(), String> {
        let missing = self.required_features() - gpu.features;
        if !missing.is_empty() {
            return Err(format!("adapter lacks {missing:?}"));
        }
        let _ = params;
        Ok(())
    }
    /// Creates every pipeline, buffer and texture the frames need (never inside a timed region).
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, params: &Params) -> Result<Box<dyn Prepared>>;
}

/// A method ready to run on one scene at one resolution.
pub trait Prepared {
    /// One frame's work: encode, submit (as often as it needs), timestamp each pass with `timer`.
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats>;
    /// Reads the last frame's output.
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture>;
    /// Bytes of buffers and textures this method allocated.
    fn bytes_allocated(&self) -> u64;
    /// Judges what only the method can judge against the exact reference (e.g. the k-buffer's
    /// captured depths vs the true k nearest → `hazard_pixels`); called after `readback`.
    fn judge(&mut self, cap: &mut Capture, reference: &crate::reference::FragmentLists) {
        let _ = (cap, reference);
    }
}

/// Every method, in listing order.
pub fn all() -> Vec<Box<dyn Method>> {
    vec![
        Box::new(floor::FloorDepth),
        Box::new(floor::FloorOpaque),
        Box::new(floor::FloorBlend),
        Box::new(depth_peel::DepthPeel),
        Box::new(dual_peel::DualPeel),
        Box::new(kbuffer_rmw::KBufferRmw),
        Box::new(kbuffer_atomic::KBufferAtomic),
        Box::new(linked_list::LinkedList),
        Box::new(compute_abuffer::ComputeAbuffer),
        Box::new(wboit::Wboit),
        Box::new(bdp::Bdp),
        Box::new(bdp2::Bdp2),
        Box::new(adp::Adp),
    ]
}

pub fn by_name(name: &str) -> Option<Box<dyn Method>> {
    all().into_iter().find(|m| m.name() == name)
}

/// Reads an integer axis with a default and a range; out of range is an error naming the value.
pub fn int_param(
    params: &Params,
    name: &str,
    default: i64,
    min: i64,
    max: i64,
) -> std::result::Result<i64, String> {
    let v = match params.get(name) {
        None => default,
        Some(scenarios::ParamValue::Int(i)) => *i,
        Some(other) => return Err(format!("axis '{name}' must be an integer, got {other}")),
    };
    if v < min || v > max {
        return Err(format!("axis '{name}' = {v} is out of range {min}..={max}"));
    }
    Ok(v)
}

pub fn bool_param(params: &Params, name: &str, default: bool) -> std::result::Result<bool, String> {
    match params.get(name) {
        None => Ok(default),
        Some(scenarios::ParamValue::Bool(b)) => Ok(*b),
        Some(other) => Err(format!("axis '{name}' must be true or false, got {other}")),
    }
}

pub fn str_param(
    params: &Params,
    name: &str,
    default: &str,
    allowed: &[&str],
) -> std::result::Result<String, String> {
    let v = match params.get(name) {
        None => default.to_string(),
        Some(scenarios::ParamValue::Str(s)) => s.clone(),
        Some(other) => return Err(format!("axis '{name}' must be a string, got {other}")),
    };
    if !allowed.is_empty() && !allowed.contains(&v.as_str()) {
        return Err(format!(
            "axis '{name}' = '{v}' is not one of {}",
            allowed.join(", ")
        ));
    }
    Ok(v)
}

/// Bind group layout entry for the camera uniform at `binding`.
pub fn camera_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX
            | wgpu::ShaderStages::FRAGMENT
            | wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Storage buffer entry (compute and fragment visible).
pub fn storage_entry(
    binding: u32,
    read_only: bool,
    stages: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stages,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Texture entry for `textureLoad` (no sampler).
pub fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
    stages: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stages,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Compiles `COMMON_WGSL` + `body` into one module.
pub fn shader(gpu: &Gpu, label: &str, body: &str) -> wgpu::ShaderModule {
    let src = format!("{COMMON_WGSL}\n{body}");
    gpu.device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(src.into()),
        })
}

/// Reads a storage buffer of `T` back to the CPU.
pub fn read_vec<T: bytemuck::Pod>(gpu: &Gpu, buf: &wgpu::Buffer, count: usize) -> Result<Vec<T>> {
    let bytes = gpu.read_buffer(buf, (count * std::mem::size_of::<T>()) as u64)?;
    Ok(bytemuck::cast_slice(&bytes).to_vec())
}
