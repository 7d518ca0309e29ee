//! The hazard-free atomic k-slot capture behind `kbuffer_atomic` and `hybrid`: 32-bit
//! atomicMax bubbling of depth keys (keys pass), a payload pass in which each captured fragment
//! claims its slot, then the k-slot resolve; `keep = first` claims in arrival order in one pass;
//! `tail = blend` returns what was not captured to the tail targets. See `kbuffer_atomic` for
//! the method and the WGSL header for why not 64-bit atomicMin.

use super::entry::SlotConfig;
use super::{entries_split, kslots_entries, kslots_layout, KSlots, Races};
use crate::aa::{self, AaCapture, AaMode};
use crate::effects::FOLD_WGSL;
use crate::methods::shared::packing::PACKING_WGSL;
use crate::methods::shared::store::{dummy_depth_ms, storage_pass_with, storage_pipeline_ms};
use crate::methods::shared::tail::{self, Bounding, TailTargets, RESOLVE_WGSL, TAIL_WGSL};
use crate::methods::{Capture, FrameStats, Prepared};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::{per_sample_source, pixel_pass, shader_source, COMMON_WGSL, STORAGE_RW};
use bench_core::timing::GpuTimer;
use bench_core::Result;
use mfx_reference::oit::Keep;
use mfx_reference::FragmentLists;

const WGSL: &str = include_str!("kbuffer_atomic.wgsl");

pub(crate) struct PreparedAtomic {
    /// The keys pass (`keep = nearest`); `keep = first` has only the claim pass.
    keys_pass: Option<wgpu::RenderPipeline>,
    payload_pass: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    resolve_bind: Option<wgpu::BindGroup>,
    depth: wgpu::TextureView,
    slots: KSlots,
    claims: wgpu::Buffer,
    bounding: Bounding,
    tail: Option<TailTargets>,
    tailed: u64,
    alloc: AllocCounter,
}

impl PreparedAtomic {
    /// Transparency (colour slots), single-sample: `hybrid` and `ssaa2x2`.
    pub(crate) fn new(gpu: &Gpu, scene: &GpuScene, k: u32, bounding: Bounding) -> Result<Self> {
        Self::new_ms(gpu, scene, (k, SlotConfig::transparency()), bounding, 1)
    }

    /// `samples` > 1: k slots per sample, both passes per sample (MSAA, `aa_capture = sample`).
    pub(crate) fn new_ms(
        gpu: &Gpu,
        scene: &GpuScene,
        (k, slot): (u32, SlotConfig),
        bounding: Bounding,
        samples: u32,
    ) -> Result<Self> {
        let d = &gpu.device;
        let split = entries_split(gpu, scene, (k, &slot), samples)?;
        let src = format!(
            "{COMMON_WGSL}\n{WGSL}\n{}\n{}\n{PACKING_WGSL}\n{FOLD_WGSL}\n{TAIL_WGSL}\n{RESOLVE_WGSL}",
            split.wgsl("entries", "Entry", 2),
            slot.wgsl()
        );
        let src = if samples > 1 {
            per_sample_source(&src)
        } else {
            src
        };
        let module = shader_source(gpu, "kbuffer_atomic", src);
        let bgl = kslots_layout(gpu, 1, &split);
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("kbuffer_atomic"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let kc = [("K", k as f64), ("SAMPLES", samples as f64)];
        let [keep_first, mean_alpha] = bounding.constants();
        let mut rc = slot.effect.constants();
        rc.extend([kc[0], kc[1], keep_first, mean_alpha]);
        let blend = bounding.blends();
        let targets = if blend {
            TailTargets::color_targets()
        } else {
            Vec::new()
        };
        let nearest = bounding.keep == Keep::Nearest;
        let keys_pass = nearest.then(|| {
            storage_pipeline_ms(
                gpu,
                "kbuffer_atomic keys",
                &layout,
                &module,
                ("fs_keys", &kc),
                &[],
                samples,
            )
        });
        let fs = match (nearest, blend) {
            (true, false) => "fs_payload",
            (true, true) => "fs_payload_tail",
            (false, false) => "fs_first",
            (false, true) => "fs_first_tail",
        };
        let payload_pass = storage_pipeline_ms(
            gpu,
            "kbuffer_atomic payload",
            &layout,
            &module,
            (fs, &kc),
            &targets,
            samples,
        );
        let (resolve_bgl, resolve) = tail::resolve_pipeline(
            gpu,
            "kbuffer_atomic",
            &layout,
            &module,
            &rc,
            blend.then(|| kslots_entries(1, &split)),
        );
        let mut alloc = AllocCounter::default();
        let depth = dummy_depth_ms(gpu, &mut alloc, scene, samples);
        let slots = KSlots::per_sample(gpu, &mut alloc, scene, (k, &slot), samples)?;
        let claims = alloc.buffer(
            gpu,
            "k-buffer claims",
            scene.pixels() as u64 * samples as u64 * k as u64 * 4,
            STORAGE_RW,
        );
        let buffers = [
            &scene.camera,
            &slots.keys,
            &slots.entries,
            &slots.image,
            &claims,
        ];
        let bind = slots.bind(gpu, &bgl, &buffers, None);
        let tail = blend.then(|| TailTargets::new(gpu, &mut alloc, scene));
        let resolve_bind = resolve_bgl
            .as_ref()
            .zip(tail.as_ref())
            .map(|(l, t)| slots.bind(gpu, l, &buffers, Some(t)));
        Ok(PreparedAtomic {
            keys_pass,
            payload_pass,
            resolve,
            bind,
            resolve_bind,
            depth,
            slots,
            claims,
            bounding,
            tail,
            tailed: 0,
            alloc,
        })
    }
}

impl bench_core::timed::Timed for PreparedAtomic {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.slots.keys, 0, None);
        enc.clear_buffer(&self.claims, 0, None);
        if let Some(keys) = &self.keys_pass {
            let mut pass = storage_pass_with(&mut enc, &self.depth, &[], timer, "keys");
            pass.set_pipeline(keys);
            pass.set_bind_group(0, &self.bind, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        {
            let colors = self.tail.as_ref().map_or(Vec::new(), |t| t.attachments());
            let mut pass = storage_pass_with(&mut enc, &self.depth, &colors, timer, "payload");
            pass.set_pipeline(&self.payload_pass);
            pass.set_bind_group(0, &self.bind, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        pixel_pass(
            &mut enc,
            timer,
            "resolve",
            &self.resolve,
            self.resolve_bind.as_ref().unwrap_or(&self.bind),
            scene,
        );
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: if self.keys_pass.is_some() { 2 } else { 1 },
            layers: self.slots.k,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl Prepared for PreparedAtomic {
    fn split(&self) -> Option<String> {
        self.slots.split.column()
    }
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        self.tailed = match &self.tail {
            Some(t) => t.tailed(gpu)?,
            None => 0,
        };
        let mut cap = self.slots.readback(gpu, scene)?;
        let samples = self.slots.samples;
        if samples > 1 {
            cap.aa = Some(AaMode::Msaa(samples));
            cap.aa_capture = Some(AaCapture::Sample);
            cap.sample_positions = Some(aa::sample_positions(gpu, samples));
        }
        Ok(cap)
    }

    fn judge(&mut self, cap: &mut Capture, reference: &FragmentLists) {
        if self.bounding.keep == Keep::Nearest {
            self.slots.judge(cap, reference, Races::None);
        } else {
            cap.notes = "keep = first: no k-nearest hazard judge (the first k are the GPU's arrival order, judged against primitive order in *_vs_k)".into();
        }
        self.bounding.report(cap, reference, self.tailed);
        cap.definition = self.bounding.definition(reference, self.slots.k as usize);
    }

    fn image_buffer(&self) -> Option<&wgpu::Buffer> {
        Some(&self.slots.image)
    }
}
