//! Multi-layer alpha blending (Salvi & Vaidyanathan, I3D 2014): k blend layers per pixel kept in
//! depth order as fragments arrive, the two farthest merged on overflow (CPU twin
//! [`mfx_reference::oit::mlab`]). The result depends on arrival order, and the paper relies on
//! rasterizer-ordered views to serialise each pixel's fragments in primitive order; wgpu has
//! none. So, as for the k-buffer, two builds:
//!
//! - `mlab`: one geometry pass of unguarded read-modify-write of each pixel's layers in storage,
//!   then a compute resolve. Concurrent fragments of one pixel race (lost or mixed insertions).
//!   `hazard_pixels` counts pixels whose image differs from the ideal-order twin beyond f32
//!   rounding, so the rate is measured, not assumed (none on lavapipe, which runs a pixel's
//!   fragments in order).
//! - `mlab_ideal`: compute_abuffer's exact capture, each pixel's fragments replayed in primitive
//!   order through the same rule: what MLAB gives with ordering hardware. Its time is the
//!   A-buffer's, not MLAB's; it exists to separate the algorithm's error from the race.
//!
//! Both fill `Capture.definition` with the twin on the reference fragments in primitive order,
//! so `*_vs_k` is the race (plus f32 rounding) for `mlab` and f32 rounding for `mlab_ideal`.
//!
//! Axes: `layers` = k (1–16); `tail = merge | drop | blend`: `merge` is MLAB (default); `drop` and
//! `blend` replace the merge by dropping the farthest layer or blending it into an out-of-order
//! tail (methods/shared/tail), which keeps the k nearest (the twin `oit::tail_blend`, keep = nearest).
//! Fragments beyond k per pixel are reported: `overflow_pixels`, and `fragments_dropped` /
//! `fragments_tailed` (merges are counted in the notes).
//!
//! Memory per pixel (race build): k × 20 B layers + 4 B arrival count + 16 B image + 4 B stand-in
//! depth (+ 24 B tail targets with `tail = blend`).

use super::shared::counted_capture::{PreparedAbuffer, Replay};
use super::shared::race::judge_race;
use super::shared::store::{dummy_depth, split_buffers, storage_pass_with, storage_pipeline_with};
use super::shared::tail::{self, TailTargets, TAIL_WGSL};
use super::{Capture, Expected, FrameStats, Method, Prepared};
use bench_core::axes::{Axis, Point};
use bench_core::bind::{pipeline_layout, Bindings, Kind as B, Res, FC, FLOAT};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::{compute_pipeline, pixel_pass, read_vec, shader, STORAGE_RW};
use bench_core::limits;
use bench_core::record::cols;
use bench_core::timing::GpuTimer;
use bench_core::Result;
use mfx_reference::oit::{self, Keep, Order, TailMode};
use mfx_reference::FragmentLists;

const RULE_WGSL: &str = include_str!("mlab.wgsl");
const RACE_WGSL: &str = include_str!("race.wgsl");
const IDEAL_WGSL: &str = include_str!("ideal.wgsl");
/// Largest k (`KMAX` in mlab.wgsl).
pub const MAX_K: i64 = 16;
/// Bytes of one layer in storage (depth, premultiplied RGB, transmittance).
const LAYER_BYTES: u64 = 20;
const LAYERS: Axis = Axis::int(cols::LAYERS, "k: blend layers per pixel", 4, 1, MAX_K);
const TAIL: Axis = Axis::choice(
    cols::TAIL,
    "merge: MLAB's merge of the two farthest layers; drop / blend: the farthest layer is dropped or blended into an out-of-order tail (keeps the k nearest)",
    "merge",
    &["merge", "drop", "blend"],
);

/// The overflow rule of a point: `None` is MLAB's merge.
fn tail_rule(point: &Point) -> Option<TailMode> {
    TailMode::parse(&point.choice(&TAIL))
}

fn tail_constant(rule: Option<TailMode>) -> f64 {
    match rule {
        None => 0.0,
        Some(TailMode::Drop) => 1.0,
        Some(TailMode::Blend) => 2.0,
    }
}

/// The twin's image of the reference fragments in primitive order: MLAB, or the k nearest with
/// the farthest dropped or tailed.
pub fn definition(lists: &FragmentLists, k: usize, rule: Option<TailMode>) -> Vec<[f64; 4]> {
    oit::image(lists, true, |list| match rule {
        None => oit::mlab::mlab_pixel(list, k, Order::Arrival).0,
        Some(mode) => oit::tail_blend(list, k, Keep::Nearest, mode).rgba,
    })
}

/// Reports fragments beyond k: overflow pixels, and dropped or tailed fragments by rule.
fn report_overflow(cap: &mut Capture, rule: Option<TailMode>, pixels: u64, beyond: u64) {
    cap.overflow_pixels = Some(pixels);
    match rule {
        None => {
            cap.notes = format!("{beyond} merges in {pixels} pixels");
        }
        Some(TailMode::Drop) => {
            cap.dropped_fragments = Some(beyond);
            cap.notes = format!("{beyond} fragments dropped in {pixels} pixels");
        }
        Some(TailMode::Blend) => {
            cap.tailed_fragments = Some(beyond);
            cap.notes = format!("{beyond} fragments blended into the tail in {pixels} pixels");
        }
    }
}

pub struct Mlab;
pub struct MlabIdeal;

impl Method for Mlab {
    fn name(&self) -> &'static str {
        "mlab"
    }
    fn describe(&self) -> &'static str {
        "Salvi & Vaidyanathan 2014 multi-layer alpha blending: k layers by unguarded read-modify-write (no rasterizer-ordered views: races measured as hazard_rate vs the ideal-order twin), two farthest merged on overflow (tail = drop|blend: farthest dropped or tailed); approximate (exact for depth complexity ≤ k); 1 geometry pass + resolve; k × 20 B + 24 B per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        vec![LAYERS, TAIL]
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        if tail_rule(point) == Some(TailMode::Blend) {
            tail::supports(gpu, 0)?;
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let k = point.int(&LAYERS) as u32;
        Ok(Box::new(PreparedRace::new(
            gpu,
            scene,
            k,
            tail_rule(point),
        )?))
    }
}

impl Method for MlabIdeal {
    fn name(&self) -> &'static str {
        "mlab_ideal"
    }
    fn describe(&self) -> &'static str {
        "multi-layer alpha blending as ordering hardware gives it: compute_abuffer's exact capture replayed per pixel in primitive order (the reference for mlab's race, not a fast path); approximate (exact for depth complexity ≤ k); compute_abuffer's passes; 8 B per fragment + 20 B per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        vec![LAYERS, TAIL]
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let k = point.int(&LAYERS) as u32;
        let rule = tail_rule(point);
        let replay = Replay {
            wgsl: format!("{TAIL_WGSL}\n{RULE_WGSL}\n{IDEAL_WGSL}"),
            entry: "replay_mlab",
            constants: vec![("K", k as f64), ("TAIL_MODE", tail_constant(rule))],
        };
        Ok(Box::new(PreparedIdeal {
            inner: PreparedAbuffer::replay(gpu, scene, &replay)?,
            k,
            rule,
        }))
    }
}

struct PreparedRace {
    k: u32,
    rule: Option<TailMode>,
    /// The `split` column: how the layers lie over storage bindings.
    split: Option<String>,
    insert: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
    bind_capture: wgpu::BindGroup,
    bind_resolve: wgpu::BindGroup,
    depth: wgpu::TextureView,
    arrived: wgpu::Buffer,
    counters: wgpu::Buffer,
    image: wgpu::Buffer,
    tail: Option<TailTargets>,
    alloc: AllocCounter,
}

impl PreparedRace {
    fn new(gpu: &Gpu, scene: &GpuScene, k: u32, rule: Option<TailMode>) -> Result<Self> {
        let px = scene.pixels() as u64;
        // The layers over as many storage bindings as the device needs (4K with 16 layers:
        // 2.65 GB, over a 2 GiB binding); the resolve binds 3 other storage buffers.
        let split = limits::split_storage(
            gpu.held(),
            "mlab layers",
            (px * k as u64 * LAYER_BYTES / 4, 4),
            3,
        )?;
        let module = shader(
            gpu,
            "mlab",
            &format!(
                "{}\n{TAIL_WGSL}\n{RULE_WGSL}\n{RACE_WGSL}",
                split.wgsl("layers", "u32", 1)
            ),
        );
        let more: Vec<(u32, B)> = split.more_bindings().map(|b| (b, B::Storage)).collect();
        // Camera, layers, arrivals; the resolve adds the image, the counters and the tail.
        let mut rows = vec![(0, B::Camera), (1, B::Storage), (7, B::Storage)];
        rows.extend(more.iter().copied());
        let capture_table = Bindings::new(gpu, "mlab capture", FC, &rows);
        let mut rows = vec![(0, B::Camera), (1, B::Storage), (2, B::Storage)];
        rows.extend([(3, B::Storage), (7, B::Storage)]);
        rows.extend(more.iter().copied());
        rows.extend(TailTargets::rows(4, B::Texture(FLOAT)));
        let resolve_table = Bindings::new(gpu, "mlab resolve", FC, &rows);
        let layout = |t: &Bindings| pipeline_layout(gpu, "mlab", &[&t.layout]);
        let constants = [("K", k as f64), ("TAIL_MODE", tail_constant(rule))];
        let blend = rule == Some(TailMode::Blend);
        let (fs, targets) = if blend {
            ("fs_mlab_tail", TailTargets::color_targets())
        } else {
            ("fs_mlab", Vec::new())
        };
        let insert = storage_pipeline_with(
            gpu,
            "mlab insert",
            &layout(&capture_table),
            &module,
            fs,
            &constants,
            &targets,
        );
        let resolve = compute_pipeline(
            gpu,
            "mlab resolve",
            &layout(&resolve_table),
            &module,
            "resolve",
            &constants,
            false,
        );
        let mut alloc = AllocCounter::default();
        let mut parts = split_buffers(gpu, &mut alloc, "mlab layers", &split);
        let layers = parts.remove(0);
        let arrived = alloc.buffer(gpu, "mlab arrivals", px * 4, STORAGE_RW);
        let image = alloc.buffer(gpu, "mlab image", px * 16, STORAGE_RW);
        let counters = alloc.buffer(gpu, "mlab counters", 8, STORAGE_RW);
        let depth = dummy_depth(gpu, &mut alloc, scene);
        let tail = blend.then(|| TailTargets::new(gpu, &mut alloc, scene));
        // Without a tail the resolve's (dead) tail reads see 1×1 stand-ins.
        let stand_in = (!blend).then(|| TailTargets::stand_ins(gpu));
        let mut res: Vec<Res> = [&scene.camera, &layers, &arrived].map(Res::Buf).to_vec();
        res.extend(parts.iter().map(Res::Buf));
        let bind_capture = capture_table.group(gpu, &res);
        let t = tail.as_ref().or(stand_in.as_ref()).expect("one of them");
        let bufs = [&scene.camera, &layers, &image, &counters, &arrived];
        // In the table's order: the buffers, the layers' further parts, the tail.
        let mut res = bufs.map(Res::Buf).to_vec();
        res.extend(parts.iter().map(Res::Buf));
        res.extend(t.views());
        let bind_resolve = resolve_table.group(gpu, &res);
        Ok(PreparedRace {
            k,
            rule,
            split: split.column(),
            insert,
            resolve,
            bind_capture,
            bind_resolve,
            depth,
            arrived,
            counters,
            image,
            tail,
            alloc,
        })
    }
}

impl bench_core::timed::Timed for PreparedRace {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.arrived, 0, None);
        enc.clear_buffer(&self.counters, 0, None);
        {
            let colors = self.tail.as_ref().map_or(Vec::new(), |t| t.attachments());
            let mut pass = storage_pass_with(&mut enc, &self.depth, &colors, timer, "insert");
            pass.set_pipeline(&self.insert);
            pass.set_bind_group(0, &self.bind_capture, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        pixel_pass(
            &mut enc,
            timer,
            "resolve",
            &self.resolve,
            &self.bind_resolve,
            scene,
        );
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: 1,
            layers: self.k,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl Prepared for PreparedRace {
    fn split(&self) -> Option<String> {
        self.split.clone()
    }
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, scene.pixels())?);
        cap.expected = Expected::All;
        let c = read_vec::<u32>(gpu, &self.counters, 2)?;
        report_overflow(&mut cap, self.rule, c[0] as u64, c[1] as u64);
        cap.notes = format!(
            "{}; unguarded read-modify-write (no rasterizer-ordered views in wgpu)",
            cap.notes
        );
        Ok(cap)
    }

    /// The ideal-order twin as the definition; pixels that differ from it are hazards.
    fn judge(&mut self, cap: &mut Capture, reference: &FragmentLists) {
        let def = definition(reference, self.k as usize, self.rule);
        judge_race(cap, def, reference.width);
    }
}

struct PreparedIdeal {
    inner: PreparedAbuffer,
    k: u32,
    rule: Option<TailMode>,
}

impl bench_core::timed::Timed for PreparedIdeal {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut f = self.inner.frame(gpu, scene, timer)?;
        f.layers = self.k;
        Ok(f)
    }

    fn bytes_allocated(&self) -> u64 {
        self.inner.bytes_allocated()
    }

    fn bytes_overhead(&self) -> Option<u64> {
        self.inner.bytes_overhead()
    }
}

impl Prepared for PreparedIdeal {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let mut cap = self.inner.readback(gpu, scene)?;
        // The A-buffer's counts are its capture, not what MLAB keeps.
        cap.counts = None;
        let capture_notes = std::mem::take(&mut cap.notes);
        let c = self.inner.replay_counters(gpu)?;
        report_overflow(&mut cap, self.rule, c[0] as u64, c[1] as u64);
        cap.notes = format!(
            "{}; replayed in primitive order from compute_abuffer's capture ({capture_notes})",
            cap.notes
        );
        Ok(cap)
    }

    fn judge(&mut self, cap: &mut Capture, reference: &FragmentLists) {
        cap.definition = Some(definition(reference, self.k as usize, self.rule));
    }
}

#[cfg(test)]
mod tests;
