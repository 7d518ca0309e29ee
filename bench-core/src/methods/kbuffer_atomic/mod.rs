//! A hazard-free k-buffer: the k nearest fragments per pixel via 32-bit atomicMax bubbling of
//! depth keys (pass 1), then a payload pass in which each captured fragment claims its slot
//! (pass 2), then the same resolve as `kbuffer_rmw` (effects fold, nearest first). Its hazard
//! rate is judged exactly like `kbuffer_rmw`'s and is 0 by construction (tested). Why not one
//! pass of 64-bit atomicMin of (depth, payload): see the WGSL header (naga allows 64-bit min/max
//! only without a return value, and the insertion needs it).
//!
//! `tail = blend` (default `drop`): the payload pass returns every fragment that was not
//! captured to the blended tail (methods/tail), composited behind the k in the resolve.
//! `keep = first` (default `nearest`): one pass instead of keys + payload, in which the first k
//! fragments to arrive claim the slots (an atomic counter per pixel; which fragments are "first"
//! is the GPU's order, judged against primitive order); the resolve sorts them. The hazard judge
//! applies to `keep = nearest` only. `hybrid` is this capture with a mean-alpha tail.
//!
//! Antialiasing: `aa = msaa*` with `aa_capture = sample` gives every sample its own k slots
//! (memory × samples; both passes run per sample) and the resolve averages the samples' folds,
//! judged against each sample's k nearest; `ssaa2x2` wraps the single-sample k-buffer. A
//! coverage-mask k-buffer is not offered: it would keep the k nearest fragments of the pixel,
//! not of each sample, a rule with no per-sample definition to judge it by.
//!
//! Effects: every effect of the fold, on slots of the effect's payload or everything
//! (`specialisation`), as `kbuffer_rmw` (`kbuffer_rmw::entry`); antialiasing is offered for
//! transparency only (an averaged per-sample fold of another effect has no judged truth here).

use super::kbuffer_rmw::entry::SlotConfig;
use super::kbuffer_rmw::{entries_split, kslots_entries, kslots_layout, KSlots, LAYERS};
use super::store::{dummy_depth_ms, storage_pass_with, storage_pipeline_ms};
use super::tail::{self, Bounding, TailTargets, RESOLVE_WGSL, TAIL_WGSL};
use super::{Capture, FrameStats, Method, Prepared};
use crate::aa::{self, AaCapture, AaConfig, AaMode, AaSupport};
use crate::axes::{Axis, Point};
use crate::effects::{self, Effect, FOLD_WGSL};
use crate::gpu::Gpu;
use crate::gpu_scene::{AllocCounter, Attrs, GpuScene};
use crate::gpu_util::{per_sample_source, pixel_pass, shader_source, COMMON_WGSL, STORAGE_RW};
use crate::methods::depth_peel::SPECIALISATION;
use crate::methods::packing::PACKING_WGSL;
use crate::oit::Keep;
use crate::reference::FragmentLists;
use crate::timing::GpuTimer;
use crate::Result;

const WGSL: &str = include_str!("kbuffer_atomic.wgsl");

pub struct KBufferAtomic;

impl Method for KBufferAtomic {
    fn name(&self) -> &'static str {
        "kbuffer_atomic"
    }
    fn describe(&self) -> &'static str {
        "hazard-free k-buffer: 32-bit atomicMax bubbling of depth keys + payload claim pass; exact k nearest; 2 geometry passes + resolve; k × 40 B + 16 B per pixel"
    }
    fn exact(&self) -> bool {
        true
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![LAYERS, tail::TAIL, tail::KEEP, aa::AA, aa::AA_CAPTURE];
        v.push(SPECIALISATION);
        v.extend_from_slice(effects::AXES);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), String> {
        SlotConfig::read(point).map(|_| ())
    }
    fn payload(&self, point: &Point) -> Option<&'static str> {
        SlotConfig::read(point).ok().map(|c| c.payload.name())
    }
    fn supports(&self, gpu: &Gpu, point: &Point) -> std::result::Result<(), String> {
        let cfg = AaConfig::from_point(point);
        AA_SUPPORT.check(self.name(), cfg)?;
        let slot = SlotConfig::read(point)?;
        slot.check(Bounding::of(point, true).blends())?;
        if cfg.mode != AaMode::None && slot.effect.effect != Effect::Transparency {
            return Err(format!(
                "antialiasing is offered for transparency only: an averaged per-sample {} fold has no judged truth",
                slot.effect.effect.name()
            ));
        }
        if cfg.msaa() > 1 {
            if Bounding::of(point, true) != Bounding::DEFAULT {
                return Err("per-sample k slots keep each sample's k nearest and drop the rest: tail = blend and keep = first are single-sample".into());
            }
            aa::check_adapter(gpu, cfg, &[wgpu::TextureFormat::Depth32Float])?;
        }
        if Bounding::of(point, true).blends() {
            tail::supports(gpu, 0)?;
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let k = point.int(&LAYERS) as u32;
        let bounding = Bounding::of(point, true);
        let slot = SlotConfig::read(point).map_err(crate::CoreError::Param)?;
        let cfg = AaConfig::from_point(point);
        if cfg.mode == AaMode::Ssaa2x2 {
            return super::ssaa::prepare(gpu, scene, |big| {
                Ok(Box::new(PreparedAtomic::new(gpu, big, k, bounding)?))
            });
        }
        let samples = cfg.msaa();
        Ok(Box::new(PreparedAtomic::new_ms(
            gpu,
            scene,
            (k, slot),
            bounding,
            samples,
        )?))
    }
}

/// Per-sample slots and supersampling; no coverage masks (module doc).
const AA_SUPPORT: AaSupport = AaSupport {
    sample: true,
    coverage: false,
    ssaa: true,
    why: "a coverage-mask k-buffer keeps the k nearest of the pixel, not of each sample: no per-sample rule to judge it by (aa_capture = sample keeps k per sample)",
};

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
    fn new_ms(
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

impl crate::timed::Timed for PreparedAtomic {
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
            self.slots
                .judge(cap, reference, crate::methods::kbuffer_rmw::Races::None);
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

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::Int;

    use super::*;
    use crate::testing::{count_mismatch, max_err, params, run, scene};

    /// Composite of up to 16 layers in f32 vs f64: a few f32 ulps per step.
    const IMAGE_TOL: f64 = 2e-5;

    #[test]
    fn captures_the_true_k_nearest_with_no_hazard() {
        let shells = scene("shells", &[("count", Int(4)), ("segments", Int(12))]);
        let quads = scene("quads", &[("depth_complexity", Int(9))]);
        let grass = scene("grass", &[("blades", Int(200))]);
        for (name, s) in [("shells", &shells), ("quads", &quads), ("grass", &grass)] {
            for k in [1, 3, 8, 16] {
                let (cap, lists) = run(&KBufferAtomic, s, 40, 40, &params(&[("layers", Int(k))]));
                assert_eq!(cap.hazard_pixels, Some(0), "{name} k={k}: {}", cap.notes);
                let (e, at) = max_err(&cap, &lists);
                assert!(e <= IMAGE_TOL, "{name} k={k}: error {e} at pixel {at}");
                let (bad, first) = count_mismatch(&cap, &lists, k as u32);
                assert_eq!(bad, 0, "{name} k={k}: counts differ first at {first:?}");
            }
        }
    }

    #[test]
    fn tail_and_keep_modes_equal_their_definition_and_count_what_did_not_fit() {
        // Up to 8 kept layers composited in f32, plus f32 tail sums (≤ 30 terms here).
        crate::methods::tail::check_tail_and_keep(&KBufferAtomic, 2.0 * IMAGE_TOL);
    }
}
