//! Per-pixel linked-list A-buffer (Yang, Hensley, Grün & Thibieroz 2010): one geometry pass
//! appends every fragment to its pixel's list (atomic head pointers, one node pool); a compute
//! resolve sorts each list and folds it nearest first (the effects fold: every effect but Fresnel,
//! whose normal the nodes do not store). The pool is fixed:
//! `layers` × pixels nodes (`layers` = average nodes per pixel). Fragments that find the pool
//! full, or lists longer than the resolve's sort capacity (128), are counted on the GPU and
//! reported (`overflow_pixels`, flag `overflow`, lost fragments in notes), never silent.

use crate::effects::FOLD_WGSL;
use crate::gpu_util::{
    bind_buffers, camera_entry, check_storage_size, compute_pipeline, read_vec, shader,
    storage_entry, STORAGE_RW,
};

use super::store::{dummy_depth, storage_pass, storage_pipeline, ENTRY_BYTES};
use super::{Capture, Expected, FrameStats, Method, Prepared};
use crate::axes::{Axis, Point};
use crate::effects::{self, Effect, EffectConfig};
use crate::gpu::Gpu;
use crate::gpu_scene::{AllocCounter, Attrs, GpuScene};
use crate::record::cols;
use crate::timing::GpuTimer;
use crate::{CoreError, Result};

const WGSL: &str = include_str!("linked_list.wgsl");
/// The resolve's per-pixel sort capacity (`SORT_MAX` in the WGSL).
pub const SORT_MAX: u32 = 128;

pub struct LinkedList;

const LAYERS: Axis = Axis::int(
    cols::LAYERS,
    "node pool size in nodes per pixel on average (pool = layers × pixels)",
    8,
    1,
    1024,
);

impl Method for LinkedList {
    fn name(&self) -> &'static str {
        "linked_list"
    }
    fn describe(&self) -> &'static str {
        "Yang et al. 2010: per-pixel linked lists in one node pool (layers × pixels nodes), sorted in a compute resolve; exact within the pool, overflow counted; 1 geometry pass + resolve; 28 B + layers × 32 B per pixel"
    }
    fn exact(&self) -> bool {
        true
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![LAYERS];
        v.extend_from_slice(effects::AXES);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), String> {
        EffectConfig::from_point(point).map(|_| ())
    }
    fn supports(&self, _: &Gpu, point: &Point) -> std::result::Result<(), String> {
        effect_config(point).map(|_| ())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let layers = point.int(&LAYERS) as u64;
        let effect = effect_config(point).map_err(CoreError::Param)?;
        Ok(Box::new(PreparedList::new(gpu, scene, layers, &effect)?))
    }
}

/// The effect of a point: a node stores colour, window depth, view depth, object id and facing,
/// so every effect but Fresnel (which needs the normal) folds from it.
fn effect_config(point: &Point) -> std::result::Result<EffectConfig, String> {
    let e = EffectConfig::from_point(point)?;
    if e.effect == Effect::Fresnel {
        return Err("linked_list nodes store no normal: fresnel needs one".into());
    }
    Ok(e)
}

struct PreparedList {
    append: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    depth: wgpu::TextureView,
    heads: wgpu::Buffer,
    image: wgpu::Buffer,
    counters: wgpu::Buffer,
    lost: wgpu::Buffer,
    counts: wgpu::Buffer,
    pool: u64,
    images: usize,
    alloc: AllocCounter,
}

impl PreparedList {
    fn new(gpu: &Gpu, scene: &GpuScene, layers: u64, effect: &EffectConfig) -> Result<Self> {
        let d = &gpu.device;
        let px = scene.pixels() as u64;
        let pool = layers * px;
        if pool >= u32::MAX as u64 {
            return Err(CoreError::Param(format!(
                "linked_list pool of {pool} nodes does not fit 32-bit node indices"
            )));
        }
        check_storage_size(gpu, "linked_list node pool", pool * ENTRY_BYTES)?;
        let src = format!("{WGSL}\n{FOLD_WGSL}");
        let module = shader(gpu, "linked_list", &src);
        let fc = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![camera_entry(0)];
        entries.extend((1..7).map(|b| storage_entry(b, false, fc)));
        let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("linked_list"),
            entries: &entries,
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("linked_list"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let pc = [("POOL", pool as f64)];
        let mut rc = vec![("POOL", pool as f64)];
        rc.extend(effect.constants());
        let images = effect.effect.image_count();
        let append = storage_pipeline(
            gpu,
            "linked_list append",
            &layout,
            &module,
            "fs_append",
            &pc,
        );
        let resolve = compute_pipeline(
            gpu,
            "linked_list resolve",
            &layout,
            &module,
            "resolve",
            &rc,
            false,
        );
        let mut alloc = AllocCounter::default();
        let depth = dummy_depth(gpu, &mut alloc, scene);
        let heads = alloc.buffer(gpu, "list heads", px * 4, STORAGE_RW);
        let nodes = alloc.buffer(gpu, "list nodes", pool * ENTRY_BYTES, STORAGE_RW);
        let image = alloc.buffer(gpu, "list image", px * 16 * images as u64, STORAGE_RW);
        let counters = alloc.buffer(gpu, "list counters", 16, STORAGE_RW);
        let lost = alloc.buffer(gpu, "list lost", px * 4, STORAGE_RW);
        let counts = alloc.buffer(gpu, "list counts", px * 4, STORAGE_RW);
        let bind = bind_buffers(
            gpu,
            "linked_list",
            &bgl,
            &[
                &scene.camera,
                &heads,
                &nodes,
                &image,
                &counters,
                &lost,
                &counts,
            ],
        );
        Ok(PreparedList {
            append,
            resolve,
            bind,
            depth,
            heads,
            image,
            counters,
            lost,
            counts,
            pool,
            images,
            alloc,
        })
    }
}

impl Prepared for PreparedList {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.heads, 0, None);
        enc.clear_buffer(&self.counters, 0, None);
        enc.clear_buffer(&self.lost, 0, None);
        {
            let mut pass = storage_pass(&mut enc, &self.depth, timer, "append");
            pass.set_pipeline(&self.append);
            pass.set_bind_group(0, &self.bind, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("resolve"),
                timestamp_writes: timer.compute_pass("resolve"),
            });
            pass.set_pipeline(&self.resolve);
            pass.set_bind_group(0, &self.bind, &[]);
            pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
        }
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: 1,
            layers: 0,
        })
    }

    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let n = scene.pixels();
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, n * self.images)?);
        cap.counts = Some(read_vec::<u32>(gpu, &self.counts, n)?);
        cap.expected = Expected::All;
        let c = read_vec::<u32>(gpu, &self.counters, 4)?;
        let (used, ovf, lost) = (c[0] as u64, c[1] as u64, c[2] as u64);
        cap.overflow_pixels = Some(ovf);
        if ovf > 0 {
            cap.flag = Some("overflow".into());
        }
        cap.notes = format!(
            "pool {} nodes, {used} fragments arrived, {ovf} overflowed pixels, {lost} lost fragments",
            self.pool
        );
        Ok(cap)
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
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
    fn equals_the_reference_within_the_pool() {
        let shells = scene("shells", &[("count", Int(4)), ("segments", Int(12))]);
        let grass = scene("grass", &[("blades", Int(300))]);
        for (name, s) in [("shells", &shells), ("grass", &grass)] {
            // 16 nodes per pixel on average is far more than these scenes' mean depth.
            let (cap, lists) = run(&LinkedList, s, 48, 48, &params(&[("layers", Int(16))]));
            assert_eq!(cap.overflow_pixels, Some(0), "{name}: {}", cap.notes);
            assert!(cap.flag.is_none(), "{name}: {:?}", cap.flag);
            let (e, at) = max_err(&cap, &lists);
            assert!(e <= IMAGE_TOL, "{name}: error {e} at pixel {at}");
            let (bad, first) = count_mismatch(&cap, &lists, u32::MAX);
            assert_eq!(bad, 0, "{name}: counts differ first at {first:?}");
        }
    }

    #[test]
    fn overflow_is_counted_on_a_scene_built_to_overflow() {
        // 12 full-screen-ish quads over the centre with a pool of 1 node per pixel: the pool
        // holds fewer nodes than fragments, so some pixels must lose fragments.
        let s = scene("quads", &[("depth_complexity", Int(12))]);
        let (cap, lists) = run(&LinkedList, &s, 32, 32, &params(&[("layers", Int(1))]));
        let total = lists.total_fragments();
        let pool = 32 * 32;
        assert!(
            total > pool,
            "the scene overflows the pool ({total} fragments)"
        );
        let ovf = cap.overflow_pixels.expect("reported");
        assert!(ovf > 0, "overflow must be counted: {}", cap.notes);
        assert_eq!(cap.flag.as_deref(), Some("overflow"));
        // Pixels that kept every fragment are exact; the count of captured fragments is the pool.
        let counts = cap.counts.as_ref().unwrap();
        assert_eq!(counts.iter().map(|&c| c as u64).sum::<u64>(), pool);
        let dc = lists.depth_complexity();
        let short = (0..dc.len()).filter(|&p| counts[p] < dc[p]).count() as u64;
        assert_eq!(
            short, ovf,
            "overflowed pixels are exactly those missing fragments"
        );
    }
}
