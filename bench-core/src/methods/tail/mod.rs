//! Tail blending for bounded captures (issue 16: `tail = drop | blend`, `keep = nearest |
//! first`; CPU twin [`crate::oit::tail`]): the fragments a capture cannot keep are either
//! dropped (counted) or blended out of order into a tail composited behind the kept ones.
//!
//! On the GPU the tail is three render targets with fixed-function blending (no float atomics
//! are needed, and blending is exact up to f32 rounding and order-free): `sums` (RGBA32F,
//! additive: Σ α·c, Σ α), `trans` (R32F, multiplicative: Π(1 − α)) and `count` (R32F, additive:
//! n). A capture pass whose fragment stage decides what falls out (the k-buffers' rejected or
//! evicted fragment, MLAB's evicted layer) returns it as a `TailOut` (`tail.wgsl`); its resolve
//! calls `tail_behind`. A compute resolve that sees every fragment (linked lists, the ideal-order
//! replays) keeps the same sums in registers instead.

use crate::axes::Axis;
use crate::gpu::Gpu;
use crate::gpu_scene::{AllocCounter, GpuScene};
use crate::gpu_util::texture_entry;
use crate::oit::{Keep, TailMode};
use crate::record::cols;

pub const TAIL_WGSL: &str = include_str!("tail.wgsl");
pub const SUMS: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const TRANS: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
pub const COUNT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// Bytes per pixel of the three targets.
pub const TAIL_BYTES: u64 = 24;

/// `tail` of the k-buffers and linked lists (default `drop`: what they always did).
pub const TAIL: Axis = Axis::choice(
    cols::TAIL,
    "fragments that do not fit: drop (counted) | blend (out of order into a tail composited behind the kept ones)",
    "drop",
    &["drop", "blend"],
);
/// `keep` of the k-buffers.
pub const KEEP: Axis = Axis::choice(
    cols::KEEP,
    "which k are kept: nearest (the k nearest) | first (the first k to arrive)",
    "nearest",
    &["nearest", "first"],
);

pub fn tail_mode(point: &crate::axes::Point) -> TailMode {
    TailMode::parse(&point.choice(&TAIL)).expect("declared choices")
}

pub fn keep(point: &crate::axes::Point) -> Keep {
    Keep::parse(&point.choice(&KEEP)).expect("declared choices")
}

/// Whether the adapter can blend the tail targets; `Err` is a `skipped` row's reason.
pub fn supports(gpu: &Gpu, extra_bytes_per_sample: u32) -> Result<(), String> {
    if !gpu.has(wgpu::Features::FLOAT32_BLENDABLE) {
        return Err(
            "tail = blend blends into RGBA32F/R32F: adapter lacks FLOAT32_BLENDABLE".into(),
        );
    }
    for f in [SUMS, TRANS, COUNT] {
        if !gpu.renderable(f) {
            return Err(format!(
                "tail = blend: {f:?} is not renderable on this adapter"
            ));
        }
    }
    let need = TAIL_BYTES as u32 + extra_bytes_per_sample;
    let have = gpu.limits.max_color_attachment_bytes_per_sample;
    if need > have {
        return Err(format!(
            "tail = blend writes {need} B per sample, the adapter allows {have}"
        ));
    }
    Ok(())
}

/// The three tail targets of one capture.
pub struct TailTargets {
    pub sums: wgpu::TextureView,
    pub trans: wgpu::TextureView,
    pub count: wgpu::TextureView,
}

impl TailTargets {
    pub fn new(gpu: &Gpu, alloc: &mut AllocCounter, scene: &GpuScene) -> TailTargets {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let (w, h) = (scene.width, scene.height);
        let mut view = |label, f| {
            alloc
                .texture(gpu, label, w, h, f, usage)
                .create_view(&Default::default())
        };
        TailTargets {
            sums: view("tail sums", SUMS),
            trans: view("tail transmittance", TRANS),
            count: view("tail count", COUNT),
        }
    }

    /// Colour target states in `TailOut`'s location order: additive, multiplicative, additive.
    pub fn color_targets() -> Vec<Option<wgpu::ColorTargetState>> {
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        // dst · (1 − src): the transmittance product.
        let mul = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::OneMinusSrc,
            operation: wgpu::BlendOperation::Add,
        };
        [(SUMS, add), (TRANS, mul), (COUNT, add)]
            .into_iter()
            .map(|(format, c)| {
                Some(wgpu::ColorTargetState {
                    format,
                    blend: Some(wgpu::BlendState { color: c, alpha: c }),
                    write_mask: wgpu::ColorWrites::ALL,
                })
            })
            .collect()
    }

    /// The targets cleared to an empty tail (sums 0, transmittance 1, count 0).
    pub fn attachments(&self) -> Vec<Option<wgpu::RenderPassColorAttachment<'_>>> {
        let c = |v: f64| wgpu::Color {
            r: v,
            g: v,
            b: v,
            a: v,
        };
        vec![
            crate::gpu::cleared(&self.sums, c(0.0)),
            crate::gpu::cleared(&self.trans, c(1.0)),
            crate::gpu::cleared(&self.count, c(0.0)),
        ]
    }

    /// Layout entries of the three textures at `first`, `first + 1`, `first + 2`.
    pub fn layout_entries(
        first: u32,
        stages: wgpu::ShaderStages,
    ) -> Vec<wgpu::BindGroupLayoutEntry> {
        let float = wgpu::TextureSampleType::Float { filterable: false };
        (0..3)
            .map(|i| texture_entry(first + i, float, stages))
            .collect()
    }

    /// Bind group entries matching [`Self::layout_entries`].
    pub fn bind_entries(&self, first: u32) -> Vec<wgpu::BindGroupEntry<'_>> {
        [&self.sums, &self.trans, &self.count]
            .into_iter()
            .enumerate()
            .map(|(i, v)| wgpu::BindGroupEntry {
                binding: first + i as u32,
                resource: wgpu::BindingResource::TextureView(v),
            })
            .collect()
    }
}
