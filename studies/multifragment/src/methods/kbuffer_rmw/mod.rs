//! The k-buffer as in the thesis (Bavoil 2007, ch. 4): k fragments per pixel kept sorted by
//! insertion sort with read-modify-write of per-pixel storage in the fragment shader, without
//! atomics, so the RMW hazards really happen; a compute resolve folds the slots nearest first.
//!
//! `heuristics` (the thesis's two hazard-reducing heuristics, §4.3.2: "Our first heuristic is to
//! sort the primitives by their centroid depth. [...] Our second heuristic is to batch triangles
//! and flush the graphics pipeline after each batch by rendering a full-screen quadrilateral with
//! a `GL_FALSE` color mask"; §6.4's SPwH: "sorting all the triangles by their centroid on the CPU
//! and batching them in sorted order with 32 triangles per batch"):
//! - `false`: the scene as given, one draw.
//! - `sort`: the centroid sort alone (Fig. 4.2's "depth sort" against "original mesh order"),
//!   one draw. Sorted once in `prepare`: the camera is static, so the order is the one a
//!   per-frame sort would give.
//! - `sort_flush`: the thesis's SPwH. Every frame, inside the timed frame, the centroid view
//!   depths are recomputed from the camera, the triangles sorted on the CPU and the sorted index
//!   buffer uploaded (the thesis's sort ran on the CPU each frame); then each 32-triangle batch
//!   is its own render pass ending with a full-screen triangle drawn with no colour writes. The
//!   full-screen draw is the thesis's flush as written (its fill cost is in the frame); the pass
//!   boundary is what makes it a flush in wgpu: draws of one render pass get no barrier between
//!   them, while wgpu orders read-write storage between passes, so batch n + 1's fragments read
//!   what batch n wrote. Timed as one `insert` span, first pass's start to last pass's end.
//! - `true`: mfx's earlier choice, kept as a named variant: sorted once in `prepare`, the batches
//!   as 32-triangle draws of one render pass with nothing between them (the driver may overlap
//!   them, as unbatched triangles; said in the rows' notes).
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
use bench_core::study::InvalidPoint;
use bench_core::timing::GpuTimer;
use bench_core::Result;
use mfx_reference::oit::Keep;
use mfx_reference::FragmentLists;

const WGSL: &str = include_str!("kbuffer_rmw.wgsl");
/// Triangles per draw in the `heuristics` variant (the thesis's batch size).
pub const BATCH_TRIANGLES: u32 = 32;

pub struct KBufferRmw;

const HEURISTICS: Axis = Axis::choice(
    cols::HEURISTICS,
    "the thesis's hazard heuristics: false (mesh order), sort (centroid sort only), sort_flush (sorted on the CPU every frame, 32-triangle batches, a flush after each: Table 6.1's SPwH), true (sorted once, batches as draws of one pass, no flush)",
    "false",
    &["false", "true", "sort", "sort_flush"],
);

/// Frames captured and judged for hazards (issue 45 item 8: Fig. 4.2's verdict on hazard_rate
/// needs an interval; a race's outcome changes from frame to frame).
const HAZARD_CAPTURES: Axis = Axis::int(
    cols::HAZARD_CAPTURES,
    "frames captured and judged for hazards after timing: 1 the timed frame's; more give hazard_rate_ci_lo/hi (min–max over them)",
    1,
    1,
    64,
);

/// [`HEURISTICS`]'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Heuristics {
    Off,
    /// `true`: sorted once, batches as draws of one pass.
    SortedOnce,
    Sort,
    SortFlush,
}

impl Heuristics {
    fn read(point: &Point) -> Heuristics {
        match point.choice(&HEURISTICS).as_str() {
            "true" => Heuristics::SortedOnce,
            "sort" => Heuristics::Sort,
            "sort_flush" => Heuristics::SortFlush,
            _ => Heuristics::Off,
        }
    }
}

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
        let mut v = vec![
            LAYERS,
            HEURISTICS,
            HAZARD_CAPTURES,
            tail::TAIL,
            tail::KEEP,
            SPECIALISATION,
        ];
        v.extend_from_slice(effects::AXES);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        SlotConfig::read(point).map(|_| ())
    }
    fn payload(&self, point: &Point) -> Option<&'static str> {
        SlotConfig::read(point).ok().map(|c| c.payload.name())
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        let blends = Bounding::of(point, true).blends();
        SlotConfig::read(point)?.check(blends)?;
        if blends {
            tail::supports(gpu, 0)?;
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let k = point.int(&LAYERS) as u32;
        let slot = SlotConfig::read(point)?;
        let mut p = PreparedRmw::new(
            gpu,
            scene,
            (k, slot),
            Heuristics::read(point),
            Bounding::of(point, true),
        )?;
        p.captures = point.int(&HAZARD_CAPTURES) as u32;
        Ok(Box::new(p))
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
    heuristics: Heuristics,
    /// Every heuristic: the front-to-back sorted index buffer.
    sorted: Option<wgpu::Buffer>,
    /// `sort_flush`: the mesh on the CPU, re-sorted every frame, and the flush pipeline.
    resort: Option<(Triangles, wgpu::RenderPipeline)>,
    bounding: Bounding,
    tail: Option<TailTargets>,
    tailed: u64,
    alloc: AllocCounter,
    /// `hazard_captures`.
    captures: u32,
}

impl PreparedRmw {
    fn new(
        gpu: &Gpu,
        scene: &GpuScene,
        (k, slot): (u32, SlotConfig),
        heuristics: Heuristics,
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
        let (sorted, resort) = match heuristics {
            Heuristics::Off => (None, None),
            Heuristics::Sort | Heuristics::SortedOnce => {
                let tris = Triangles::read(gpu, scene)?;
                (Some(tris.upload(gpu, &tris.sorted(scene))), None)
            }
            Heuristics::SortFlush => {
                let tris = Triangles::read(gpu, scene)?;
                let buf = tris.upload(gpu, &tris.sorted(scene));
                let flush = flush_pipeline(gpu, (&layout, &module, &kc), &targets);
                (Some(buf), Some((tris, flush)))
            }
        };
        Ok(PreparedRmw {
            insert,
            resolve,
            bind,
            resolve_bind,
            depth,
            slots,
            heuristics,
            sorted,
            resort,
            bounding,
            tail,
            tailed: 0,
            alloc,
            captures: 1,
        })
    }
}

/// The scene's triangles on the CPU (read back once: `prepare` is given the uploaded scene
/// only), to sort by centroid view depth.
struct Triangles {
    indices: Vec<[u32; 3]>,
    positions: Vec<[f32; 3]>,
}

impl Triangles {
    fn read(gpu: &Gpu, scene: &GpuScene) -> Result<Triangles> {
        let idx = read_vec::<u32>(gpu, &scene.indices, scene.index_count as usize)?;
        let nverts = (scene.positions.size() / 12) as usize;
        Ok(Triangles {
            indices: idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            positions: read_vec::<[f32; 3]>(gpu, &scene.positions, nverts)?,
        })
    }

    /// The indices sorted nearest first by centroid view depth under the scene's camera (equal
    /// depths keep mesh order). One thread, as the thesis's CPU sort: its cost is part of SPwH.
    fn sorted(&self, scene: &GpuScene) -> Vec<u32> {
        let v = glam::Mat4::from_cols_array_2d(&scene.camera_data.view_from_world);
        let dist = |i: u32| -(v * glam::Vec3::from(self.positions[i as usize]).extend(1.0)).z;
        let mut keyed: Vec<(f32, u32)> = self
            .indices
            .iter()
            .enumerate()
            .map(|(n, t)| ((dist(t[0]) + dist(t[1]) + dist(t[2])) / 3.0, n as u32))
            .collect();
        keyed.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        keyed
            .iter()
            .flat_map(|&(_, n)| self.indices[n as usize])
            .collect()
    }

    fn upload(&self, gpu: &Gpu, flat: &[u32]) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        gpu.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("kbuffer sorted indices"),
                contents: bytemuck::cast_slice(flat),
                usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
            })
    }
}

/// `sort_flush`'s flush: a full-screen triangle with every colour write off (the thesis's
/// "full-screen quadrilateral with a `GL_FALSE` color mask"), on the insert pass's attachments.
fn flush_pipeline(
    gpu: &Gpu,
    (layout, module, constants): (&wgpu::PipelineLayout, &wgpu::ShaderModule, &[(&str, f64)]),
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    // The module's override constants, given to both stages as the insert pipeline gives them.
    let options = || wgpu::PipelineCompilationOptions {
        constants,
        zero_initialize_workgroup_memory: false,
    };
    let masked: Vec<_> = targets
        .iter()
        .map(|t| {
            t.clone().map(|t| wgpu::ColorTargetState {
                write_mask: wgpu::ColorWrites::empty(),
                ..t
            })
        })
        .collect();
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("kbuffer_rmw flush"),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_flush"),
                compilation_options: options(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: bench_core::gpu_util::multisample(1),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some("fs_flush"),
                compilation_options: options(),
                targets: &masked,
            }),
            multiview_mask: None,
            cache: None,
        })
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
        match (&self.sorted, &self.resort) {
            (Some(sorted), Some((tris, flush))) => {
                // The thesis's per-frame CPU sort and upload, inside the timed frame.
                let flat = tris.sorted(scene);
                gpu.queue
                    .write_buffer(sorted, 0, bytemuck::cast_slice(&flat));
                self.flushed_batches(&mut enc, scene, timer, sorted, flush);
            }
            _ => {
                let colors = self.tail.as_ref().map_or(Vec::new(), |t| t.attachments());
                let mut pass = storage_pass_with(&mut enc, &self.depth, &colors, timer, "insert");
                pass.set_pipeline(&self.insert);
                pass.set_bind_group(0, &self.bind, &[]);
                match (&self.sorted, self.heuristics) {
                    (Some(sorted), Heuristics::SortedOnce) => {
                        bind_all_attrs(&mut pass, scene, sorted);
                        let step = BATCH_TRIANGLES * 3;
                        let mut first = 0;
                        while first < scene.index_count {
                            let end = (first + step).min(scene.index_count);
                            pass.draw_indexed(first..end, 0, 0..1);
                            first = end;
                        }
                    }
                    (Some(sorted), _) => {
                        bind_all_attrs(&mut pass, scene, sorted);
                        pass.draw_indexed(0..scene.index_count, 0, 0..1);
                    }
                    (None, _) => scene.draw(&mut pass, bench_core::gpu_scene::Attrs::ALL),
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

impl PreparedRmw {
    /// `sort_flush`: a render pass per 32-triangle batch, each ending with the flush draw; one
    /// `insert` span from the first pass's start to the last pass's end.
    fn flushed_batches(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        sorted: &wgpu::Buffer,
        flush: &wgpu::RenderPipeline,
    ) {
        let span = timer.reserve("insert");
        let step = BATCH_TRIANGLES * 3;
        let mut first = 0;
        while first < scene.index_count {
            let end = (first + step).min(scene.index_count);
            let mut colors = self.tail.as_ref().map_or(Vec::new(), |t| t.attachments());
            if first > 0 {
                // Later batches add to the tail the earlier ones blended.
                for c in colors.iter_mut().flatten() {
                    c.ops.load = wgpu::LoadOp::Load;
                }
            }
            let writes = timer.query_set().zip(span).and_then(|(set, (b, e))| {
                let b = (first == 0).then_some(b);
                let e = (end == scene.index_count).then_some(e);
                (b.is_some() || e.is_some()).then_some(wgpu::RenderPassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: b,
                    end_of_pass_write_index: e,
                })
            });
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("insert batch"),
                color_attachments: &colors,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    // The stand-in depth is never tested or written (compare always).
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: writes,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.insert);
            pass.set_bind_group(0, &self.bind, &[]);
            bind_all_attrs(&mut pass, scene, sorted);
            pass.draw_indexed(first..end, 0, 0..1);
            pass.set_pipeline(flush);
            pass.draw(0..3, 0..1);
            first = end;
        }
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
        cap.notes = match self.heuristics {
            Heuristics::Off => cap.notes,
            Heuristics::Sort => "heuristics: centroid-sorted triangles (sorted once: static camera), one draw".into(),
            Heuristics::SortFlush => format!(
                "heuristics: centroid sort on the CPU every frame (timed), a render pass per {BATCH_TRIANGLES} triangles ending with a full-screen draw, colour writes off"
            ),
            Heuristics::SortedOnce => format!(
                "heuristics: centroid-sorted triangles, one draw per {BATCH_TRIANGLES} (no barrier between draws in wgpu)"
            ),
        };
        Ok(cap)
    }

    fn hazard_captures(&self) -> u32 {
        // keep = first has no hazard judge (below): nothing to repeat.
        if self.bounding.keep == Keep::Nearest {
            self.captures
        } else {
            1
        }
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
    use scenarios::ParamValue::{Bool, Int, Str};

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
        // Every heuristic: the k nearest whatever the order, batches and flushes (quads has
        // 2 triangles a layer: sort_flush draws 6 batch passes of one flush each at most).
        for variant in ["false", "true", "sort", "sort_flush"] {
            let p = params(&[("layers", Int(4)), ("heuristics", Str(variant.into()))]);
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
                assert!(
                    store::same_k_nearest(&twin, lists.pixel(px), 4),
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
    fn heuristics_takes_its_four_values_and_the_old_booleans_and_refuses_others() {
        let axes = KBufferRmw.axes();
        for (given, want) in [
            (Bool(false), "false"),
            (Bool(true), "true"),
            (Str("sort".into()), "sort"),
            (Str("sort_flush".into()), "sort_flush"),
        ] {
            let p = Point::resolve(&axes, &params(&[("heuristics", given)])).unwrap();
            assert_eq!(p.choice(&HEURISTICS), want);
        }
        let err = Point::resolve(&axes, &params(&[("heuristics", Str("flush".into()))]))
            .unwrap_err()
            .join("; ");
        assert!(
            err.contains("heuristics") && err.contains("sort_flush"),
            "{err}"
        );
        let err = Point::resolve(&axes, &params(&[("hazard_captures", Int(0))]))
            .unwrap_err()
            .join("; ");
        assert!(err.contains("hazard_captures"), "{err}");
    }

    #[test]
    fn z_only_at_k16_captures_the_16_nearest_depths_of_the_reference() {
        // Table 6.1's "16 Z" rows (issue 45 item 11): translucency with specialised slots
        // stores depth only. 20 layers in the centre: the 16 nearest must be kept, in order.
        let s = scene("quads", &[("depth_complexity", Int(20))]);
        let p = params(&[
            ("layers", Int(16)),
            ("effect", Str("translucency".into())),
            ("specialisation", Str("specialised".into())),
        ]);
        let pt = crate::testing::point(&KBufferRmw, &p);
        assert_eq!(KBufferRmw.payload(&pt), Some("depth"));
        let (cap, lists) = run(&KBufferRmw, &s, 48, 48, &p);
        assert!(
            lists.max_depth_complexity() > 16,
            "the scene overflows k = 16"
        );
        // The judge compares every pixel's 16 captured depths with the f64 reference's 16
        // nearest (lavapipe: one thread a pixel, so no hazard may excuse a difference).
        assert_eq!(cap.hazard_pixels, Some(0), "{}", cap.notes);
        let (bad, first) = count_mismatch(&cap, &lists, 16);
        assert_eq!(bad, 0, "counts differ first at pixel {first:?}");
    }

    #[test]
    fn hazard_captures_repeat_the_capture_and_keep_their_range() {
        let s = scene("quads", &[("depth_complexity", Int(6))]);
        let p = params(&[("layers", Int(4)), ("hazard_captures", Int(3))]);
        let pt = crate::testing::point(&KBufferRmw, &p);
        let gpu = crate::testing::gpu();
        let gs = GpuScene::upload(gpu, &s, 32, 32);
        let prepared = KBufferRmw.prepare(gpu, &gs, &pt).unwrap();
        assert_eq!(prepared.hazard_captures(), 3);
        let first = params(&[("layers", Int(4)), ("keep", Str("first".into()))]);
        let pt = crate::testing::point(&KBufferRmw, &first);
        let prepared = KBufferRmw.prepare(gpu, &gs, &pt).unwrap();
        assert_eq!(
            prepared.hazard_captures(),
            1,
            "keep = first has no hazard judge"
        );
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
