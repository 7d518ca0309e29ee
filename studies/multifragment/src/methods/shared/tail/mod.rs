//! Tail blending for bounded captures (issue 16: `tail = drop | blend`, `keep = nearest |
//! first`; CPU twin [`mfx_reference::oit::tail`]): the fragments a capture cannot keep are either
//! dropped (counted) or blended out of order into a tail composited behind the kept ones.
//!
//! On the GPU the tail is three render targets with fixed-function blending (no float atomics
//! are needed, and blending is exact up to f32 rounding and order-free): `sums` (RGBA32F,
//! additive: Σ α·c, Σ α), `trans` (R32F, multiplicative: Π(1 − α)) and `count` (R32F, additive:
//! n). A capture pass whose fragment stage decides what falls out (the k-buffers' rejected or
//! evicted fragment, MLAB's evicted layer) returns it as a `TailOut` (`tail.wgsl`); its resolve
//! calls `tail_behind`. A compute resolve that sees every fragment (linked lists, the ideal-order
//! replays) keeps the same sums in registers instead.

use bench_core::axes::Axis;
use bench_core::bind::{Kind, Res};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::gpu_util::{compute_pipeline, texture_entry};
use bench_core::record::cols;
use mfx_reference::oit::{Keep, TailMode};

pub const TAIL_WGSL: &str = include_str!("tail.wgsl");
/// The k-buffers' tail resolve (`with_tail`; textures at bindings 5–7), after [`TAIL_WGSL`].
pub const RESOLVE_WGSL: &str = include_str!("resolve.wgsl");
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

pub fn tail_mode(point: &bench_core::axes::Point) -> TailMode {
    TailMode::parse(&point.choice(&TAIL)).expect("declared choices")
}

pub fn keep(point: &bench_core::axes::Point) -> Keep {
    Keep::parse(&point.choice(&KEEP)).expect("declared choices")
}

/// Whether the adapter can blend the tail targets; `Err` is a `skipped` row's reason.
pub fn supports(
    gpu: &Gpu,
    extra_bytes_per_sample: u32,
) -> std::result::Result<(), bench_core::Unsupported> {
    if !gpu.has(wgpu::Features::FLOAT32_BLENDABLE) {
        return Err(
            "tail = blend blends into RGBA32F/R32F: adapter lacks FLOAT32_BLENDABLE".into(),
        );
    }
    for f in [SUMS, TRANS, COUNT] {
        if !gpu.renderable(f) {
            return Err(format!("tail = blend: {f:?} is not renderable on this adapter").into());
        }
    }
    let need = TAIL_BYTES as u32 + extra_bytes_per_sample;
    let have = gpu.limits.max_color_attachment_bytes_per_sample;
    if need > have {
        return Err(format!(
            "tail = blend writes {need} B per sample, {} allows {have}",
            gpu.profile.who()
        )
        .into());
    }
    Ok(())
}

/// The three tail targets of one capture.
pub struct TailTargets {
    pub sums: wgpu::TextureView,
    pub trans: wgpu::TextureView,
    pub count: wgpu::TextureView,
    /// The count texture, read back for `fragments_tailed` (`None` for stand-ins).
    count_texture: Option<wgpu::Texture>,
}

impl TailTargets {
    pub fn new(gpu: &Gpu, alloc: &mut AllocCounter, scene: &GpuScene) -> TailTargets {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let (w, h) = (scene.width, scene.height);
        let mut tex = |label, f| alloc.texture(gpu, label, w, h, f, usage);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let count = tex("tail count", COUNT);
        TailTargets {
            sums: view(&tex("tail sums", SUMS)),
            trans: view(&tex("tail transmittance", TRANS)),
            count: view(&count),
            count_texture: Some(count),
        }
    }

    /// 1×1 textures for a resolve layout that declares the tail but has none (never read).
    pub fn stand_ins(gpu: &Gpu) -> TailTargets {
        let t = |f| {
            gpu.stand_in_texture("tail (unused)", f)
                .create_view(&Default::default())
        };
        TailTargets {
            sums: t(SUMS),
            trans: t(TRANS),
            count: t(COUNT),
            count_texture: None,
        }
    }

    /// Fragments blended into the tail in the last frame (the count target's sum).
    pub fn tailed(&self, gpu: &Gpu) -> bench_core::Result<u64> {
        let Some(tex) = &self.count_texture else {
            return Ok(0);
        };
        let bytes = bench_core::gpu::read_texture(gpu, tex, 4, wgpu::TextureAspect::All)?;
        let counts: &[f32] = bytemuck::cast_slice(&bytes);
        // Each count is a sum of 1.0s, exact in f32 below 2^24 per pixel.
        Ok(counts.iter().map(|&c| c as u64).sum())
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
            bench_core::gpu::cleared(&self.sums, c(0.0)),
            bench_core::gpu::cleared(&self.trans, c(1.0)),
            bench_core::gpu::cleared(&self.count, c(0.0)),
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

    /// The tail textures as bind-table rows from binding `first` (sums, transmittance, count).
    pub fn rows(first: u32, kind: Kind) -> [(u32, Kind); 3] {
        [(first, kind), (first + 1, kind), (first + 2, kind)]
    }

    /// The resources of [`Self::rows`], in order.
    pub fn views(&self) -> [Res<'_>; 3] {
        [&self.sums, &self.trans, &self.count].map(Res::View)
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

/// What a k-buffer point keeps and does with the rest: `keep`, `tail`, and hybrid
/// transparency's mean-alpha tail opacity (`mean_alpha`, set by `hybrid` only).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bounding {
    pub keep: Keep,
    pub tail: TailMode,
    pub mean_alpha: bool,
}

impl Bounding {
    /// What the k-buffers always did: the k nearest, the rest dropped.
    pub const DEFAULT: Bounding = Bounding {
        keep: Keep::Nearest,
        tail: TailMode::Drop,
        mean_alpha: false,
    };

    /// The `keep` and `tail` axes of a point (`keep` only where the method declares it).
    pub fn of(point: &bench_core::axes::Point, has_keep: bool) -> Bounding {
        Bounding {
            keep: if has_keep { keep(point) } else { Keep::Nearest },
            tail: tail_mode(point),
            mean_alpha: false,
        }
    }

    pub fn blends(&self) -> bool {
        self.tail == TailMode::Blend
    }

    /// Pipeline constants of the k-buffer WGSL (`KEEP_FIRST`, and `MEAN_ALPHA` of the tail
    /// resolve).
    pub fn constants(&self) -> [(&'static str, f64); 2] {
        let b = |x: bool| if x { 1.0 } else { 0.0 };
        [
            ("KEEP_FIRST", b(self.keep == Keep::First)),
            ("MEAN_ALPHA", b(self.mean_alpha)),
        ]
    }

    /// The method's own definition on the reference fragments in primitive order, where it is
    /// not the k-truncated composite (`None` for the default).
    pub fn definition(
        &self,
        lists: &mfx_reference::FragmentLists,
        k: usize,
    ) -> Option<Vec<[f64; 4]>> {
        if *self == Bounding::DEFAULT {
            return None;
        }
        let b = *self;
        Some(mfx_reference::oit::image(lists, true, move |list| {
            if b.mean_alpha {
                mfx_reference::oit::hybrid(list, k)
            } else {
                mfx_reference::oit::tail_blend(list, k, b.keep, b.tail).rgba
            }
        }))
    }

    /// `fragments_dropped` (true fragments neither kept nor tailed: the capture's counts against
    /// the reference) and `fragments_tailed` (the tail's count target), and a note.
    pub fn report(
        &self,
        cap: &mut crate::method::Capture,
        lists: &mfx_reference::FragmentLists,
        tailed: u64,
    ) {
        let Some(counts) = &cap.counts else { return };
        let kept: u64 = counts.iter().map(|&c| c as u64).sum();
        let missing = lists.total_fragments().saturating_sub(kept);
        if self.blends() {
            cap.tailed_fragments = Some(tailed);
            cap.dropped_fragments = Some(missing.saturating_sub(tailed));
        } else {
            cap.dropped_fragments = Some(missing);
        }
        if *self != Bounding::DEFAULT {
            let note = format!(
                "keep = {}, tail = {}{}: {kept} fragments kept, {} tailed, {} dropped",
                self.keep.name(),
                self.tail.name(),
                if self.mean_alpha {
                    " (mean-alpha opacity)"
                } else {
                    ""
                },
                cap.tailed_fragments.unwrap_or(0),
                cap.dropped_fragments.unwrap_or(0)
            );
            cap.notes = if cap.notes.is_empty() {
                note
            } else {
                format!("{}; {note}", cap.notes)
            };
        }
    }
}

/// `entries` plus the tail textures at bindings 5–7 (`resolve.wgsl`), for a k-buffer's resolve.
pub fn resolve_layout(
    gpu: &Gpu,
    mut entries: Vec<wgpu::BindGroupLayoutEntry>,
) -> wgpu::BindGroupLayout {
    entries.extend(TailTargets::layout_entries(
        5,
        wgpu::ShaderStages::COMPUTE | wgpu::ShaderStages::FRAGMENT,
    ));
    gpu.note_layout("k-buffer tail resolve", &entries);
    gpu.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("k-buffer tail resolve"),
            entries: &entries,
        })
}

/// A k-buffer's resolve pipeline: the `resolve` entry on `layout`, or with `entries` (the
/// k-buffer's bindings) the `resolve_tail` entry on a layout that adds the tail targets, whose
/// bind-group layout is returned for [`resolve_bind`].
pub fn resolve_pipeline(
    gpu: &Gpu,
    name: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    constants: &[(&str, f64)],
    entries: Option<Vec<wgpu::BindGroupLayoutEntry>>,
) -> (Option<wgpu::BindGroupLayout>, wgpu::ComputePipeline) {
    let Some(entries) = entries else {
        let label = format!("{name} resolve");
        let p = compute_pipeline(gpu, &label, layout, module, "resolve", constants, false);
        return (None, p);
    };
    let bgl = resolve_layout(gpu, entries);
    let label = format!("{name} tail resolve");
    let l = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&label),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
    let p = compute_pipeline(gpu, &label, &l, module, "resolve_tail", constants, false);
    (Some(bgl), p)
}

/// A bind group of `buffers` at bindings 0, 1, … and the tail textures at 5–7.
pub fn resolve_bind(
    gpu: &Gpu,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
    tail: &TailTargets,
) -> wgpu::BindGroup {
    let mut e: Vec<wgpu::BindGroupEntry<'_>> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    e.extend(tail.bind_entries(5));
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("k-buffer tail resolve"),
        layout,
        entries: &e,
    })
}

/// Every (keep, tail) pair of a k-buffer on layered scenes: the image equals the method's own
/// definition (the k-truncated reference for the default, else the twin `oit::tail_blend` in
/// primitive order), and what did not fit is counted as dropped or tailed.
#[cfg(test)]
pub(crate) fn check_tail_and_keep(method: &dyn crate::method::Method, tol: f64) {
    use crate::testing::{params, run, scene};
    use scenarios::ParamValue::{Float, Int, Str};
    let scenes = [
        scene("quads", &[("depth_complexity", Int(9))]),
        scene("shells", &[("count", Int(4)), ("segments", Int(12))]),
        scene("particles", &[("count", Int(400)), ("size", Float(0.5))]),
    ];
    for s in &scenes {
        for k in [1i64, 3, 8] {
            for keep in ["nearest", "first"] {
                for mode in ["drop", "blend"] {
                    let what = format!(
                        "{} {} k {k} keep {keep} tail {mode}",
                        method.name(),
                        s.label()
                    );
                    let p = params(&[
                        ("layers", Int(k)),
                        ("keep", Str(keep.into())),
                        ("tail", Str(mode.into())),
                    ]);
                    let (cap, lists) = run(method, s, 40, 40, &p);
                    let want = match &cap.definition {
                        Some(d) => d.clone(),
                        None => {
                            assert_eq!((keep, mode), ("nearest", "drop"), "{what}: a definition");
                            lists.composite_first(k as usize)
                        }
                    };
                    let img = cap.image.as_ref().unwrap();
                    let (mut worst, mut at) = (0.0f64, 0);
                    for (p, (g, d)) in img.iter().zip(&want).enumerate() {
                        let e = (0..4)
                            .map(|c| (g[c] as f64 - d[c]).abs())
                            .fold(0.0, f64::max);
                        if e.is_nan() || e > worst {
                            (worst, at) = (e, p);
                        }
                    }
                    assert!(worst <= tol, "{what}: {worst:.2e} at {at}: {}", cap.notes);
                    if keep == "nearest" {
                        // lavapipe runs one pixel's fragments in order: no race.
                        assert_eq!(cap.hazard_pixels, Some(0), "{what}");
                    }
                    let beyond: u64 = lists
                        .depth_complexity()
                        .iter()
                        .map(|&d| d.saturating_sub(k as u32) as u64)
                        .sum();
                    let (dropped, tailed) = if mode == "blend" {
                        (Some(0), Some(beyond))
                    } else {
                        (Some(beyond), None)
                    };
                    assert_eq!(
                        (cap.dropped_fragments, cap.tailed_fragments),
                        (dropped, tailed),
                        "{what}"
                    );
                }
            }
        }
    }
}
