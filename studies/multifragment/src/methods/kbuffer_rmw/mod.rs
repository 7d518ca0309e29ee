//! The k-buffer as in the thesis (Bavoil 2007, ch. 4): k fragments per pixel kept sorted by
//! insertion sort with read-modify-write of per-pixel storage in the fragment shader, without
//! atomics, so the RMW hazards really happen; a compute resolve folds the slots nearest first.
//!
//! Variants (`variant`): `plain` draws the scene as given; `heuristics` applies the thesis's two
//! hazard-reducing heuristics: triangles sorted front to back by centroid view depth (on the CPU
//! in `prepare`, uploaded as a sorted index buffer) and drawing in batches of 32 triangles, one
//! draw each. The thesis flushes between batches (texture barrier); wgpu cannot place a barrier
//! between draws of one render pass, and a pass per batch would cost ~30 000 passes per frame at
//! 1M triangles, so "flushed" is approximated by separate draws in one pass: the driver is free
//! to, but not obliged to, drain a batch before the next (said in every row's notes).
//!
//! The hazard rate is measured, not assumed: `judge` compares the captured k depths of every
//! pixel with the reference's true k nearest (`hazard_pixels`, flag `hazard`). [`twin_insert`] is
//! the insertion rule on the CPU, applied one fragment at a time (what a hazard-free run keeps).
//!
//! `tail = blend` (default `drop`): the fragment that falls out of a pixel (rejected, or the
//! farthest kept one evicted by a nearer one) is returned to the blended tail (methods/shared/tail).
//! `keep = first` (default `nearest`): a full pixel takes no more fragments, so the first k to
//! arrive stay (the hazard judge then does not apply: its truth is the k nearest).
//!
//! Effects: every effect of the fold (`effects::AXES`), on slots that store the effect's payload
//! (`specialisation = specialised`) or everything (`uber`): see [`entry`]. `specialised`
//! translucency keeps 4 B per slot besides the key (linear depth and facing): the thesis's "Z"
//! k-buffer of Table 6.1, beside transparency's colour ("RGBZ"). The thesis's multipass
//! peeling of k layers (MP) is `depth_peel` with `max_layers = k`.

use super::shared::axes::SPECIALISATION;
use super::shared::kslots::{
    entries_split, entry::SlotConfig, kslots_entries, kslots_layout, KSlots, Races, LAYERS,
};
use super::shared::packing::PACKING_WGSL;
use super::shared::store::{dummy_depth, storage_pass_with, storage_pipeline_with};
use super::shared::tail::{self, Bounding, TailTargets, RESOLVE_WGSL, TAIL_WGSL};
use super::{Capture, FrameStats, Method, Prepared};
use crate::effects::{self, FOLD_WGSL};
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::gpu_util::{pixel_pass, read_vec, shader};
use bench_core::record::cols;
use bench_core::timing::GpuTimer;
use bench_core::Result;
use mfx_reference::oit::Keep;
use mfx_reference::FragmentLists;

const WGSL: &str = include_str!("kbuffer_rmw.wgsl");
/// Triangles per draw in the `heuristics` variant (the thesis's batch size).
pub const BATCH_TRIANGLES: u32 = 32;

pub struct KBufferRmw;

const HEURISTICS: Axis = Axis::bool(
    cols::HEURISTICS,
    "the thesis's hazard heuristics: draws depth-sorted in batches of 32 triangles",
    false,
);

impl Method for KBufferRmw {
    fn name(&self) -> &'static str {
        "kbuffer_rmw"
    }
    fn describe(&self) -> &'static str {
        "Bavoil 2007 ch. 4: k-buffer by non-atomic RMW insertion sort in storage; k nearest with hazards (measured); 1 geometry pass + resolve; k × 36 B + 16 B per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![LAYERS, HEURISTICS, tail::TAIL, tail::KEEP, SPECIALISATION];
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
        let blends = Bounding::of(point, true).blends();
        SlotConfig::read(point)?.check(blends)?;
        if blends {
            tail::supports(gpu, 0)?;
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let k = point.int(&LAYERS) as u32;
        let slot = SlotConfig::read(point).map_err(bench_core::CoreError::Param)?;
        Ok(Box::new(PreparedRmw::new(
            gpu,
            scene,
            (k, slot),
            point.bool(&HEURISTICS),
            Bounding::of(point, true),
        )?))
    }
}

/// The insertion rule on the CPU, one fragment at a time: `slots` hold (depth, payload)
/// nearest first; a fragment not nearer than a full buffer's last is dropped; equal depths keep
/// arrival order. `nearer(a, b)` is the scene's depth convention.
pub fn twin_insert<T: Copy>(
    slots: &mut Vec<(f64, T)>,
    k: usize,
    depth: f64,
    payload: T,
    reversed: bool,
) {
    let nearer = |a: f64, b: f64| if reversed { a > b } else { a < b };
    if slots.len() == k && !nearer(depth, slots[k - 1].0) {
        return;
    }
    let mut j = slots.len();
    while j > 0 && nearer(depth, slots[j - 1].0) {
        j -= 1;
    }
    slots.insert(j, (depth, payload));
    slots.truncate(k);
}

struct PreparedRmw {
    insert: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    resolve_bind: Option<wgpu::BindGroup>,
    depth: wgpu::TextureView,
    slots: KSlots,
    /// `heuristics`: front-to-back sorted index buffer, drawn in batches.
    sorted: Option<wgpu::Buffer>,
    bounding: Bounding,
    tail: Option<TailTargets>,
    tailed: u64,
    alloc: AllocCounter,
}

impl PreparedRmw {
    fn new(
        gpu: &Gpu,
        scene: &GpuScene,
        (k, slot): (u32, SlotConfig),
        heuristics: bool,
        bounding: Bounding,
    ) -> Result<Self> {
        let d = &gpu.device;
        let split = entries_split(gpu, scene, (k, &slot), 1)?;
        let src = format!(
            "{WGSL}\n{}\n{}\n{PACKING_WGSL}\n{FOLD_WGSL}\n{TAIL_WGSL}\n{RESOLVE_WGSL}",
            split.wgsl("entries", "Entry", 2),
            slot.wgsl()
        );
        let module = shader(gpu, "kbuffer_rmw", &src);
        let bgl = kslots_layout(gpu, 0, &split);
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("kbuffer_rmw"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let [keep_first, mean_alpha] = bounding.constants();
        let kc = [("K", k as f64), keep_first];
        let mut rc = slot.effect.constants();
        rc.extend([("K", k as f64), mean_alpha]);
        let blend = bounding.blends();
        let (fs, targets) = if blend {
            ("fs_insert_tail", TailTargets::color_targets())
        } else {
            ("fs_insert", Vec::new())
        };
        let insert = storage_pipeline_with(
            gpu,
            "kbuffer_rmw insert",
            &layout,
            &module,
            fs,
            &kc,
            &targets,
        );
        let (resolve_bgl, resolve) = tail::resolve_pipeline(
            gpu,
            "kbuffer_rmw",
            &layout,
            &module,
            &rc,
            blend.then(|| kslots_entries(0, &split)),
        );
        let mut alloc = AllocCounter::default();
        let depth = dummy_depth(gpu, &mut alloc, scene);
        let slots = KSlots::new(gpu, &mut alloc, scene, k, &slot)?;
        let buffers = [&scene.camera, &slots.keys, &slots.entries, &slots.image];
        let bind = slots.bind(gpu, &bgl, &buffers, None);
        let tail = blend.then(|| TailTargets::new(gpu, &mut alloc, scene));
        let resolve_bind = resolve_bgl
            .as_ref()
            .zip(tail.as_ref())
            .map(|(l, t)| slots.bind(gpu, l, &buffers, Some(t)));
        let sorted = if heuristics {
            Some(sorted_indices(gpu, scene)?)
        } else {
            None
        };
        Ok(PreparedRmw {
            insert,
            resolve,
            bind,
            resolve_bind,
            depth,
            slots,
            sorted,
            bounding,
            tail,
            tailed: 0,
            alloc,
        })
    }
}

/// The scene's triangles sorted nearest first by centroid view depth (stable), as a new index
/// buffer (read back from the GPU: `prepare` is given the uploaded scene only).
fn sorted_indices(gpu: &Gpu, scene: &GpuScene) -> Result<wgpu::Buffer> {
    use wgpu::util::DeviceExt;
    let idx = read_vec::<u32>(gpu, &scene.indices, scene.index_count as usize)?;
    let nverts = (scene.positions.size() / 12) as usize;
    let pos = read_vec::<[f32; 3]>(gpu, &scene.positions, nverts)?;
    let v = glam::Mat4::from_cols_array_2d(&scene.camera_data.view_from_world);
    let dist = |i: u32| -(v * glam::Vec3::from(pos[i as usize]).extend(1.0)).z;
    let mut tris: Vec<(f32, [u32; 3])> = idx
        .chunks_exact(3)
        .map(|t| {
            (
                (dist(t[0]) + dist(t[1]) + dist(t[2])) / 3.0,
                [t[0], t[1], t[2]],
            )
        })
        .collect();
    tris.sort_by(|a, b| a.0.total_cmp(&b.0));
    let flat: Vec<u32> = tris.iter().flat_map(|t| t.1).collect();
    Ok(gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("kbuffer sorted indices"),
            contents: bytemuck::cast_slice(&flat),
            usage: wgpu::BufferUsages::INDEX,
        }))
}

/// Binds every vertex attribute (slot order of `GpuScene::layouts(Attrs::ALL)`) and `indices`.
fn bind_all_attrs<'p>(pass: &mut wgpu::RenderPass<'p>, scene: &GpuScene, indices: &wgpu::Buffer) {
    pass.set_vertex_buffer(0, scene.positions.slice(..));
    pass.set_vertex_buffer(1, scene.normals.slice(..));
    pass.set_vertex_buffer(2, scene.colors.slice(..));
    pass.set_vertex_buffer(3, scene.object_ids.slice(..));
    pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
}

impl bench_core::timed::Timed for PreparedRmw {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.slots.keys, 0, None);
        {
            let colors = self.tail.as_ref().map_or(Vec::new(), |t| t.attachments());
            let mut pass = storage_pass_with(&mut enc, &self.depth, &colors, timer, "insert");
            pass.set_pipeline(&self.insert);
            pass.set_bind_group(0, &self.bind, &[]);
            match &self.sorted {
                None => scene.draw(&mut pass, bench_core::gpu_scene::Attrs::ALL),
                Some(sorted) => {
                    bind_all_attrs(&mut pass, scene, sorted);
                    let step = BATCH_TRIANGLES * 3;
                    let mut first = 0;
                    while first < scene.index_count {
                        let end = (first + step).min(scene.index_count);
                        pass.draw_indexed(first..end, 0, 0..1);
                        first = end;
                    }
                }
            }
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
            geometry_passes: 1,
            layers: self.slots.k,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl Prepared for PreparedRmw {
    fn split(&self) -> Option<String> {
        self.slots.split.column()
    }
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        self.tailed = match &self.tail {
            Some(t) => t.tailed(gpu)?,
            None => 0,
        };
        let mut cap = self.slots.readback(gpu, scene)?;
        if self.sorted.is_some() {
            cap.notes = format!(
                "heuristics: centroid-sorted triangles, one draw per {BATCH_TRIANGLES} (no barrier between draws in wgpu)"
            );
        }
        Ok(cap)
    }

    fn judge(&mut self, cap: &mut Capture, reference: &FragmentLists) {
        if self.bounding.keep == Keep::Nearest {
            self.slots.judge(cap, reference, Races::Possible);
        } else {
            let note = "keep = first: no k-nearest hazard judge (its truth is the k nearest; races show in *_vs_k against primitive order)";
            cap.notes = if cap.notes.is_empty() {
                note.into()
            } else {
                format!("{}; {note}", cap.notes)
            };
        }
        self.bounding.report(cap, reference, self.tailed);
        cap.definition = self.bounding.definition(reference, self.slots.k as usize);
    }
}

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::{Bool, Int};

    use super::*;
    use crate::methods::shared::store;
    use crate::testing::{count_mismatch, max_err, params, run, scene};
    use bench_core::record::Flag;

    /// Composite of 8 layers in f32 vs f64: a few f32 ulps per step.
    const IMAGE_TOL: f64 = 1e-5;

    #[test]
    fn twin_keeps_the_k_nearest_in_order_whatever_the_arrival_order() {
        let mut s = Vec::new();
        for (d, id) in [(0.5, 0), (0.2, 1), (0.9, 2), (0.2, 3), (0.1, 4)] {
            twin_insert(&mut s, 3, d, id, false);
        }
        assert_eq!(s, vec![(0.1, 4), (0.2, 1), (0.2, 3)]);
        let mut r = Vec::new();
        for (d, id) in [(0.5, 0), (0.2, 1), (0.9, 2)] {
            twin_insert(&mut r, 2, d, id, true);
        }
        assert_eq!(r, vec![(0.9, 2), (0.5, 0)], "reversed-Z: larger is nearer");
    }

    #[test]
    fn matches_the_cpu_twin_per_pixel_and_the_reference_image() {
        // quads: 6 layers everywhere in the centre; k = 4 < 6 exercises the full-buffer drop.
        let s = scene("quads", &[("depth_complexity", Int(6))]);
        for variant in ["plain", "heuristics"] {
            let p = params(&[
                ("layers", Int(4)),
                ("heuristics", Bool(variant == "heuristics")),
            ]);
            let (cap, lists) = run(&KBufferRmw, &s, 48, 48, &p);
            // The twin, fed each pixel's fragments in submission order (plain variant).
            let mut prims: Vec<_> = Vec::new();
            for px in 0..lists.pixels() {
                prims.clear();
                prims.extend(lists.pixel(px).iter().map(|f| (f.prim, f.depth)));
                prims.sort_by_key(|f| f.0);
                let mut slots = Vec::new();
                for &(prim, d) in &prims {
                    twin_insert(&mut slots, 4, d, prim, lists.reversed_z);
                }
                let twin: Vec<Option<f32>> =
                    (0..4).map(|i| slots.get(i).map(|s| s.0 as f32)).collect();
                let truth: Vec<f64> = lists.pixel(px).iter().map(|f| f.depth).collect();
                assert!(
                    store::same_k_nearest(&twin, &truth, 4),
                    "twin is wrong at pixel {px}"
                );
            }
            // lavapipe runs one pixel's fragments in order on one thread: no hazard expected.
            assert_eq!(cap.hazard_pixels, Some(0), "{variant}: {}", cap.notes);
            let (e, at) = max_err(&cap, &lists);
            assert!(e <= IMAGE_TOL, "{variant}: error {e} at pixel {at}");
            let (bad, first) = count_mismatch(&cap, &lists, 4);
            assert_eq!(bad, 0, "{variant}: counts differ first at pixel {first:?}");
        }
    }

    #[test]
    fn judge_counts_exactly_the_pixels_a_hazard_corrupted() {
        // A lost update, as two racing fragments produce it: both read the empty buffer, both
        // write slot 0, the first write is lost. The judge must flag that pixel and no other.
        let s = scene("quads", &[("depth_complexity", Int(3))]);
        let p = params(&[("layers", Int(4))]);
        let (_, lists) = run(&KBufferRmw, &s, 32, 32, &p);
        let k = 4;
        let mut captured = vec![None; lists.pixels() * k];
        for px in 0..lists.pixels() {
            for (i, f) in lists.pixel(px).iter().take(k).enumerate() {
                captured[px * k + i] = Some(f.depth as f32);
            }
        }
        let victim = (16 * 32 + 16) as usize;
        assert!(
            lists.pixel(victim).len() >= 2,
            "the victim pixel has layers"
        );
        captured[victim * k] = captured[victim * k + 1];
        let slots = KSlots {
            k: k as u32,
            images: 1,
            samples: 1,
            keys: dummy(),
            entries: dummy(),
            entries_more: vec![],
            split: bench_core::limits::Split::whole(1, 4),
            image: dummy(),
            captured,
        };
        let mut cap = Capture::empty();
        slots.judge(&mut cap, &lists, Races::Possible);
        assert_eq!(cap.hazard_pixels, Some(1));
        assert!(cap.flag.contains(Flag::Hazard), "{}", cap.flag);
        assert!(cap.notes.contains("(16,16)"), "{}", cap.notes);
        // The same wrong pixel from the atomic insertion (kbuffer_atomic), which cannot race: a
        // fragment set that differs from the reference's, not a hazard (issue 32: it was flagged
        // `hazard` wherever the rasteriser's set differed by a few fragments).
        let mut cap = Capture::empty();
        slots.judge(&mut cap, &lists, Races::None);
        assert_eq!(cap.hazard_pixels, Some(0));
        assert!(
            cap.flag.contains(Flag::FragmentsDiffer) && !cap.flag.contains(Flag::Hazard),
            "{}",
            cap.flag
        );
        assert!(cap.notes.contains("(16,16)"), "{}", cap.notes);
    }

    fn dummy() -> wgpu::Buffer {
        crate::testing::gpu()
            .device
            .create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size: 4,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
    }

    #[test]
    fn tail_and_keep_modes_equal_their_definition_and_count_what_did_not_fit() {
        // Up to 8 kept layers composited in f32, plus f32 tail sums (≤ 30 terms here).
        tail::check_tail_and_keep(&KBufferRmw, 2.0 * IMAGE_TOL);
    }
}
