//! Adaptive transparency (Salvi, Montgomery & Lefohn, HPG 2011): each pixel's visibility
//! function compressed to k nodes as fragments arrive, the node whose removal changes the area
//! under it least dropped on overflow; a second pass shades every fragment through it (CPU twin
//! [`mfx_reference::oit::adaptive`]). Order-dependent like MLAB, so built twice:
//!
//! - `adaptive`: pass 1 unguarded read-modify-write of each pixel's nodes in storage (races
//!   measured: `hazard_pixels` counts pixels whose image differs from the ideal-order twin beyond
//!   f32 rounding), pass 2 additive blending of vis(z)·α·c, then a compute composite.
//! - `adaptive_ideal`: compute_abuffer's exact capture replayed per pixel in primitive order
//!   through the same rule: what the method gives with ordering hardware (its time is the
//!   A-buffer's).
//!
//! Both fill `Capture.definition` with the twin on the reference fragments in primitive order.
//! Axis: `layers` = k nodes (1–16). Fragments beyond k per pixel: `overflow_pixels`, node removals
//! in the notes (nothing is dropped: absorption moves forward, so the image darkens).
//!
//! Memory per pixel (race build): k × 8 B nodes + 4 B arrival count + 16 B resolve sum + 16 B
//! image + 4 B stand-in depth.

use super::shared::counted_capture::{PreparedAbuffer, Replay};
use super::shared::race::judge_race;
use super::shared::store::{dummy_depth, storage_pass, storage_pipeline};
use super::{Capture, Expected, FrameStats, Method, Prepared};
use bench_core::axes::{Axis, Point};
use bench_core::bind::{blended, pipeline_layout, Bindings, Kind as B, Res, ADD, FC, FLOAT};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::{
    check_storage_size, compute_pipeline, pixel_pass, read_vec, shader, STORAGE_RW,
};
use bench_core::record::cols;
use bench_core::timing::GpuTimer;
use bench_core::Result;
use mfx_reference::oit::{self, Order};
use mfx_reference::FragmentLists;

const RULE_WGSL: &str = include_str!("adaptive.wgsl");
const RACE_WGSL: &str = include_str!("race.wgsl");
const IDEAL_WGSL: &str = include_str!("ideal.wgsl");
/// Largest k (`KMAX` in adaptive.wgsl).
pub const MAX_K: i64 = 16;
const ACCUM: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

const LAYERS: Axis = Axis::int(cols::LAYERS, "k: visibility nodes per pixel", 4, 1, MAX_K);

/// The twin's image of the reference fragments in primitive order.
pub fn definition(lists: &FragmentLists, k: usize) -> Vec<[f64; 4]> {
    oit::image(lists, true, |list| {
        oit::adaptive::adaptive_pixel(list, k, Order::Arrival).0
    })
}

fn report(cap: &mut Capture, pixels: u64, removals: u64) {
    cap.overflow_pixels = Some(pixels);
    cap.notes = format!("{removals} node removals in {pixels} pixels");
}

pub struct Adaptive;
pub struct AdaptiveIdeal;

impl Method for Adaptive {
    fn name(&self) -> &'static str {
        "adaptive"
    }
    fn describe(&self) -> &'static str {
        "Salvi et al. 2011 adaptive transparency: k visibility nodes by unguarded read-modify-write (no rasterizer-ordered views: races measured as hazard_rate vs the ideal-order twin), least-area node removed on overflow, then a shading pass; approximate (exact for depth complexity ≤ k); 2 geometry passes + composite; k × 8 B + 40 B per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        vec![LAYERS]
    }
    fn supports(&self, gpu: &Gpu, _: &Point) -> std::result::Result<(), bench_core::Unsupported> {
        if !gpu.has(wgpu::Features::FLOAT32_BLENDABLE) {
            return Err("adapter lacks FLOAT32_BLENDABLE (additive blending into RGBA32F)".into());
        }
        if !gpu.renderable(ACCUM) {
            return Err(format!("{ACCUM:?} is not renderable on this adapter").into());
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let k = point.int(&LAYERS) as u32;
        Ok(Box::new(PreparedRace::new(gpu, scene, k)?))
    }
}

impl Method for AdaptiveIdeal {
    fn name(&self) -> &'static str {
        "adaptive_ideal"
    }
    fn describe(&self) -> &'static str {
        "adaptive transparency as ordering hardware gives it: compute_abuffer's exact capture replayed per pixel in primitive order (the reference for adaptive's race, not a fast path); approximate (exact for depth complexity ≤ k); compute_abuffer's passes; 8 B per fragment + 20 B per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        vec![LAYERS]
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let k = point.int(&LAYERS) as u32;
        let replay = Replay {
            wgsl: format!("{RULE_WGSL}\n{IDEAL_WGSL}"),
            entry: "replay_adaptive",
            constants: vec![("K", k as f64)],
        };
        Ok(Box::new(PreparedIdeal {
            inner: PreparedAbuffer::replay(gpu, scene, &replay)?,
            k,
        }))
    }
}

struct PreparedRace {
    k: u32,
    insert: wgpu::RenderPipeline,
    shade: wgpu::RenderPipeline,
    composite: wgpu::ComputePipeline,
    bind_capture: wgpu::BindGroup,
    bind_composite: wgpu::BindGroup,
    depth: wgpu::TextureView,
    accum: wgpu::TextureView,
    arrived: wgpu::Buffer,
    counters: wgpu::Buffer,
    image: wgpu::Buffer,
    alloc: AllocCounter,
}

impl PreparedRace {
    fn new(gpu: &Gpu, scene: &GpuScene, k: u32) -> Result<Self> {
        let module = shader(gpu, "adaptive", &format!("{RULE_WGSL}\n{RACE_WGSL}"));
        // Camera, nodes, arrivals; the composite adds the image, the counters, the colour sum.
        let capture_table = Bindings::seq(
            gpu,
            "adaptive capture",
            FC,
            &[B::Camera, B::Storage, B::Storage],
        );
        let mut rows = vec![B::Camera];
        rows.extend([B::Storage; 4]);
        rows.push(B::Texture(FLOAT));
        let composite_table = Bindings::seq(gpu, "adaptive composite", FC, &rows);
        let layout = |t: &Bindings| pipeline_layout(gpu, "adaptive", &[&t.layout]);
        let constants = [("K", k as f64)];
        let capture_layout = layout(&capture_table);
        let insert = storage_pipeline(
            gpu,
            "adaptive nodes",
            &capture_layout,
            &module,
            "fs_nodes",
            &constants,
        );
        let shade = super::shared::store::storage_pipeline_with(
            gpu,
            "adaptive shade",
            &capture_layout,
            &module,
            "fs_shade",
            &constants,
            &[blended(ACCUM, ADD)],
        );
        let composite = compute_pipeline(
            gpu,
            "adaptive composite",
            &layout(&composite_table),
            &module,
            "composite",
            &constants,
            false,
        );
        let mut alloc = AllocCounter::default();
        let px = scene.pixels() as u64;
        let node_bytes = px * k as u64 * 8;
        check_storage_size(gpu, "adaptive nodes", node_bytes)?;
        let nodes = alloc.buffer(gpu, "adaptive nodes", node_bytes, STORAGE_RW);
        let arrived = alloc.buffer(gpu, "adaptive arrivals", px * 4, STORAGE_RW);
        let image = alloc.buffer(gpu, "adaptive image", px * 16, STORAGE_RW);
        let counters = alloc.buffer(gpu, "adaptive counters", 8, STORAGE_RW);
        let depth = dummy_depth(gpu, &mut alloc, scene);
        let accum = alloc
            .texture(
                gpu,
                "adaptive colour sum",
                scene.width,
                scene.height,
                ACCUM,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            )
            .create_view(&Default::default());
        let bind_capture =
            capture_table.group(gpu, &[&scene.camera, &nodes, &arrived].map(Res::Buf));
        let bufs = [&scene.camera, &nodes, &arrived, &image, &counters];
        let mut res = bufs.map(Res::Buf).to_vec();
        res.push((&accum).into());
        let bind_composite = composite_table.group(gpu, &res);
        Ok(PreparedRace {
            k,
            insert,
            shade,
            composite,
            bind_capture,
            bind_composite,
            depth,
            accum,
            arrived,
            counters,
            image,
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
            let mut pass = storage_pass(&mut enc, &self.depth, timer, "nodes");
            pass.set_pipeline(&self.insert);
            pass.set_bind_group(0, &self.bind_capture, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        {
            let colors = [bench_core::gpu::cleared(
                &self.accum,
                wgpu::Color::TRANSPARENT,
            )];
            let mut pass = super::shared::store::storage_pass_with(
                &mut enc,
                &self.depth,
                &colors,
                timer,
                "shade",
            );
            pass.set_pipeline(&self.shade);
            pass.set_bind_group(0, &self.bind_capture, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        pixel_pass(
            &mut enc,
            timer,
            "composite",
            &self.composite,
            &self.bind_composite,
            scene,
        );
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: 2,
            layers: self.k,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl Prepared for PreparedRace {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, scene.pixels())?);
        cap.expected = Expected::All;
        let c = read_vec::<u32>(gpu, &self.counters, 2)?;
        report(&mut cap, c[0] as u64, c[1] as u64);
        cap.notes = format!(
            "{}; unguarded read-modify-write (no rasterizer-ordered views in wgpu)",
            cap.notes
        );
        Ok(cap)
    }

    fn judge(&mut self, cap: &mut Capture, reference: &FragmentLists) {
        judge_race(cap, definition(reference, self.k as usize), reference.width);
    }
}

struct PreparedIdeal {
    inner: PreparedAbuffer,
    k: u32,
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
        cap.counts = None;
        let capture_notes = std::mem::take(&mut cap.notes);
        let c = self.inner.replay_counters(gpu)?;
        report(&mut cap, c[0] as u64, c[1] as u64);
        cap.notes = format!(
            "{}; replayed in primitive order from compute_abuffer's capture ({capture_notes})",
            cap.notes
        );
        Ok(cap)
    }

    fn judge(&mut self, cap: &mut Capture, reference: &FragmentLists) {
        cap.definition = Some(definition(reference, self.k as usize));
    }
}

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::{Float, Int};

    use super::*;
    use crate::testing::{max_err, params, run, scene};

    fn vs_definition(cap: &Capture) -> (f64, usize) {
        let def = cap.definition.as_ref().expect("judge sets the definition");
        let img = cap.image.as_ref().unwrap();
        let mut worst = (0.0f64, 0usize);
        for (p, (d, g)) in def.iter().zip(img).enumerate() {
            for c in 0..4 {
                let e = (d[c] - g[c] as f64).abs();
                if e.is_nan() || e > worst.0 {
                    worst = (if e.is_nan() { f64::INFINITY } else { e }, p);
                }
            }
        }
        worst
    }

    #[test]
    fn both_builds_are_exact_where_depth_complexity_is_at_most_k() {
        let quads = scene("quads", &[("depth_complexity", Int(4))]);
        let shells = scene("shells", &[("count", Int(2)), ("segments", Int(12))]);
        for s in [&quads, &shells] {
            for m in [&Adaptive as &dyn Method, &AdaptiveIdeal] {
                for k in [4, 8] {
                    let (cap, lists) = run(m, s, 40, 40, &params(&[("layers", Int(k))]));
                    assert!(lists.max_depth_complexity() <= 4);
                    let (e, at) = max_err(&cap, &lists);
                    // ≤ 4 layers shaded in f32 through exact products of their transmittances.
                    assert!(
                        e <= 1e-5,
                        "{} {} k {k}: {e:.2e} at {at}",
                        m.name(),
                        s.label()
                    );
                    assert_eq!(cap.overflow_pixels, Some(0));
                }
            }
        }
    }

    #[test]
    fn both_builds_equal_the_twin_in_primitive_order_alpha_exact_and_darker() {
        let scenes = [
            scene("shells", &[("count", Int(3)), ("segments", Int(12))]),
            scene("particles", &[("count", Int(400)), ("size", Float(0.5))]),
            scene("hair", &[("strands", Int(300))]),
        ];
        for s in &scenes {
            for m in [&Adaptive as &dyn Method, &AdaptiveIdeal] {
                for k in [1, 2, 4, 8] {
                    let what = format!("{} {} k {k}", m.name(), s.label());
                    let (cap, lists) = run(m, s, 40, 40, &params(&[("layers", Int(k))]));
                    let (e, at) = vs_definition(&cap);
                    // f32 arithmetic alone (oit::adaptive's adaptive_f32_twin_follows_f64_to_1e5).
                    assert!(e <= 1e-5, "{what}: {e:.2e} at {at}: {}", cap.notes);
                    if m.name() == "adaptive" {
                        // lavapipe runs one pixel's fragments in order: no race to see.
                        assert_eq!(cap.hazard_pixels, Some(0), "{what}: {}", cap.notes);
                    }
                    let dc = lists.depth_complexity();
                    let over = dc.iter().filter(|&&d| d > k as u32).count() as u64;
                    assert_eq!(cap.overflow_pixels, Some(over), "{what}");
                    // The twin's properties, on the GPU image: A exact (removals keep the last
                    // node), colour never above the exact one (absorption moves forward); f32
                    // rounding over ≤ 64 layers allows 1e-5.
                    let img = cap.image.as_ref().unwrap();
                    for (p, t) in lists.composite().iter().enumerate() {
                        assert!((img[p][3] as f64 - t[3]).abs() <= 1e-5, "{what}: A at {p}");
                        for c in 0..3 {
                            assert!(img[p][c] as f64 <= t[c] + 1e-5, "{what}: brighter at {p}");
                        }
                    }
                }
            }
        }
    }
}
