//! Shared plumbing of the methods that write fragments into storage buffers from the fragment
//! stage (k-buffers, linked lists): a pass with no colour output (wgpu refuses a render pass
//! without attachments, so a depth attachment with an always-pass, never-write test stands in),
//! compute pipelines with the `EFFECT` override, and the k-nearest judge (hazards).

use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::STORAGE_RW;
use bench_core::limits::Split;
use bench_core::timing::GpuTimer;
use mfx_reference::{FragmentLists, RefFragment};

/// Layout of `struct Entry` in the WGSL (32 B): what a captured fragment keeps for the fold.
pub const ENTRY_BYTES: u64 = 32;

/// The stand-in depth attachment of a storage-only pass (never tested, never written).
pub fn dummy_depth(gpu: &Gpu, alloc: &mut AllocCounter, scene: &GpuScene) -> wgpu::TextureView {
    dummy_depth_ms(gpu, alloc, scene, 1)
}

/// [`dummy_depth`] with `samples` samples per pixel (the pass of an MSAA storage pipeline).
pub fn dummy_depth_ms(
    gpu: &Gpu,
    alloc: &mut AllocCounter,
    scene: &GpuScene,
    samples: u32,
) -> wgpu::TextureView {
    alloc
        .texture_ms(
            gpu,
            "storage pass depth (unused)",
            scene.width,
            scene.height,
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
            samples,
        )
        .create_view(&Default::default())
}

/// A render pipeline over the full vertex stage whose fragment stage only writes storage.
pub fn storage_pipeline(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    fs: &str,
    constants: &[(&str, f64)],
) -> wgpu::RenderPipeline {
    storage_pipeline_with(gpu, label, layout, module, fs, constants, &[])
}

/// [`storage_pipeline`] whose fragment stage also writes colour `targets` (a blended tail).
pub fn storage_pipeline_with(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    fs: &str,
    constants: &[(&str, f64)],
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    storage_pipeline_ms(gpu, label, layout, module, (fs, constants), targets, 1)
}

/// [`storage_pipeline_with`] rasterising `samples` samples per pixel (MSAA).
pub fn storage_pipeline_ms(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (fs, constants): (&str, &[(&str, f64)]),
    targets: &[Option<wgpu::ColorTargetState>],
    samples: u32,
) -> wgpu::RenderPipeline {
    let stand_in = wgpu::DepthStencilState {
        format: wgpu::TextureFormat::Depth32Float,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil: Default::default(),
        bias: Default::default(),
    };
    full_pipeline_ms(
        gpu,
        label,
        layout,
        module,
        (fs, constants),
        targets,
        Some(stand_in),
        samples,
    )
}

/// A raster pipeline over `vs_full` (every attribute), both faces (transparency sees back faces
/// too, like the reference), with `depth` (or none) and colour `targets`.
#[allow(
    clippy::too_many_arguments,
    reason = "a pipeline's layout, shader, entry, constants, targets and depth, each named"
)]
pub fn full_pipeline(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    fs: &str,
    constants: &[(&str, f64)],
    targets: &[Option<wgpu::ColorTargetState>],
    depth: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    full_pipeline_ms(
        gpu,
        label,
        layout,
        module,
        (fs, constants),
        targets,
        depth,
        1,
    )
}

/// [`full_pipeline`] rasterising `samples` samples per pixel (MSAA).
#[allow(
    clippy::too_many_arguments,
    reason = "a pipeline's layout, shader, entry, constants, targets, depth and samples, each named"
)]
pub fn full_pipeline_ms(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (fs, constants): (&str, &[(&str, f64)]),
    targets: &[Option<wgpu::ColorTargetState>],
    depth: Option<wgpu::DepthStencilState>,
    samples: u32,
) -> wgpu::RenderPipeline {
    let layouts: Vec<_> = GpuScene::layouts(Attrs::ALL)
        .into_iter()
        .map(Some)
        .collect();
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_full"),
                compilation_options: Default::default(),
                buffers: &layouts,
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: depth,
            multisample: bench_core::gpu_util::multisample(samples),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(fs),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    zero_initialize_workgroup_memory: false,
                },
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
}

/// Begins a storage-only render pass on the stand-in depth attachment.
pub fn storage_pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    depth: &wgpu::TextureView,
    timer: &mut GpuTimer,
    label: &str,
) -> wgpu::RenderPass<'e> {
    storage_pass_with(enc, depth, &[], timer, label)
}

/// [`storage_pass`] with colour attachments (a blended tail).
pub fn storage_pass_with<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    depth: &wgpu::TextureView,
    colors: &[Option<wgpu::RenderPassColorAttachment<'_>>],
    timer: &mut GpuTimer,
    label: &str,
) -> wgpu::RenderPass<'e> {
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: colors,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Discard,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: timer.render_pass(label),
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Window depth of a k-buffer key (the WGSL `near_key`: larger = nearer, 0 = empty).
pub fn key_depth(key: u32, reversed: bool) -> f32 {
    f32::from_bits(if reversed { key } else { !key })
}

/// Near-tie tolerance of the k-nearest judge (window depth).
pub const DEPTH_TOL: f64 = 1e-5;

/// How far, in pixels, a GPU's depth set-up point may sit from the reference's, times a
/// fragment's `depth_slope` ([`depth_tol`]): the reference interpolates depth on vertices snapped
/// to 1/256 px, a GPU may set depth up from the unsnapped ones (lavapipe does), ≤ 1/512 px per
/// coordinate apart; twice that covers the second-order change of a sliver's plane.
pub const SETUP_SNAP_PX: f64 = 1.0 / 256.0;

/// The depth tolerance of one reference fragment in the k-nearest judge: [`DEPTH_TOL`] (the
/// GPU's f32 arithmetic) plus what its triangle's depth slope makes of the set-up's snap. On
/// tets (4³ cells, 64²) a 0.63 px² sliver (slope 5.6e-2 a pixel) sat 1.55e-5 from the reference
/// on lavapipe, beyond `DEPTH_TOL` alone: it was judged a hazard with every fragment captured.
pub fn depth_tol(f: &RefFragment) -> f64 {
    DEPTH_TOL + f64::from(f.depth_slope) * SETUP_SNAP_PX
}

/// Pixels whose captured depths (nearest first, `k` slots per pixel, `None` = empty) are not
/// the reference's true k nearest: count and the first such pixel.
pub fn k_nearest_mismatch(captured: &[Option<f32>], k: usize, lists: &FragmentLists) -> Mismatch {
    use rayon::prelude::*;
    // Pixels in parallel, in chunks; the default suite judged 1024² k-buffers at ~0.7 s a point
    // on one core (most of its judging time on the H200).
    const CHUNK: usize = 4096;
    let pixels = lists.pixels();
    (0..pixels.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut m = Mismatch::default();
            for p in c * CHUNK..((c + 1) * CHUNK).min(pixels) {
                let truth = lists.pixel(p);
                if !same_k_nearest(&captured[p * k..(p + 1) * k], truth, k) {
                    if f32_tie_among_nearest(truth, k) {
                        m.ties += 1;
                        m.first_tie.get_or_insert(p);
                    } else {
                        m.hazards += 1;
                        m.first_hazard.get_or_insert(p);
                    }
                }
            }
            m
        })
        .reduce(Mismatch::default, Mismatch::merge)
}

/// Pixels whose captured set is not the true k nearest, split by cause.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct Mismatch {
    /// No f32 depth tie among the pixel's k + 1 nearest: a read-modify-write race (or a raster
    /// coverage disagreement with the reference, see `KSlots::judge`).
    pub hazards: u64,
    pub first_hazard: Option<usize>,
    /// Two of the pixel's k + 1 nearest fragments have the same f32 depth: the GPU cannot order
    /// (or keep both of) them, exactly as depth peeling loses such fragments (`lost_coplanar`).
    pub ties: u64,
    pub first_tie: Option<usize>,
}

impl Mismatch {
    /// Both tallies; the first pixels are the lower of each (chunks may merge in any order).
    fn merge(a: Mismatch, b: Mismatch) -> Mismatch {
        let first = |x: Option<usize>, y: Option<usize>| match (x, y) {
            (Some(x), Some(y)) => Some(x.min(y)),
            (x, y) => x.or(y),
        };
        Mismatch {
            hazards: a.hazards + b.hazards,
            first_hazard: first(a.first_hazard, b.first_hazard),
            ties: a.ties + b.ties,
            first_tie: first(a.first_tie, b.first_tie),
        }
    }
}

/// Whether two of the k + 1 nearest fragments' depths round to the same f32.
pub fn f32_tie_among_nearest(truth: &[RefFragment], k: usize) -> bool {
    let n = truth.len().min(k + 1);
    truth[..n]
        .windows(2)
        .any(|w| w[0].depth as f32 == w[1].depth as f32)
}

/// Whether `slots` (nearest first) hold the k nearest of `truth` (all of a pixel's fragments,
/// nearest first). The GPU interpolates depth in f32 and may set its plane up from other vertex
/// positions than the reference's snapped ones, so a captured depth can sit up to
/// [`depth_tol`] of its fragment from the f64 value (~1e-4 on slivers seen edge-on): each
/// captured depth is matched to the true fragment nearest in units of that fragment's
/// tolerance, and the capture is right when the matches are exactly the first k fragments, each
/// once. A lost or duplicated fragment breaks that; near-ties (gap under the GPU's error) may
/// match crosswise, so sorted depths each within its fragment's tolerance also count as right.
pub fn same_k_nearest(slots: &[Option<f32>], truth: &[RefFragment], k: usize) -> bool {
    let n = truth.len().min(k);
    if slots.iter().take_while(|s| s.is_some()).count() != n {
        return false;
    }
    let got = || {
        slots[..n]
            .iter()
            .map(|s| f64::from(s.expect("counted above")))
    };
    // The common case first, without allocating: sorted depths each within its tolerance.
    if got()
        .zip(truth)
        .all(|(g, w)| (g - w.depth).abs() <= depth_tol(w))
    {
        return true;
    }
    let off = |g: f64, w: &RefFragment| (w.depth - g).abs() / depth_tol(w);
    let mut used = vec![false; truth.len()];
    got().all(|g| {
        let j = (0..truth.len())
            .min_by(|&a, &b| off(g, &truth[a]).total_cmp(&off(g, &truth[b])))
            .expect("n > 0 here");
        let fresh = j < n && !used[j];
        used[j] = true;
        fresh
    })
}

/// The storage buffers of `split`'s parts, `"{label} 0"`, `"{label} 1"`, … (the first bound
/// at the buffer's own binding, the rest at `split.more_bindings()`).
pub fn split_buffers(
    gpu: &Gpu,
    alloc: &mut AllocCounter,
    label: &str,
    split: &Split,
) -> Vec<wgpu::Buffer> {
    (0..split.parts)
        .map(|i| {
            let bytes = split.part_elems(i) * split.elem_bytes;
            alloc.buffer(gpu, &format!("{label} {i}"), bytes, STORAGE_RW)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{f32_tie_among_nearest, k_nearest_mismatch, same_k_nearest, DEPTH_TOL};
    use mfx_reference::{FragmentLists, RefFragment};

    /// Fragments at `depths` (nearest first) on triangles of depth slope `slope`.
    fn frags(depths: &[f64], slope: f32) -> Vec<RefFragment> {
        depths
            .iter()
            .enumerate()
            .map(|(i, &z)| RefFragment {
                depth: z,
                view_z: z,
                color: [0.5; 4],
                normal: [0.0, 0.0, 1.0],
                object_id: 0,
                front_facing: true,
                prim: i as u32,
                depth_slope: slope,
            })
            .collect()
    }

    /// `w` pixels in one row, each with fragments at depths 0.1, 0.2, 0.3 (pixel `tie_at`: the
    /// 2nd and 3rd share one f32 depth).
    fn row(w: u32, tie_at: usize) -> FragmentLists {
        let mut offsets = vec![0u32];
        let mut frags = Vec::new();
        for p in 0..w as usize {
            for (i, z) in [0.1, 0.2, 0.3].into_iter().enumerate() {
                let z = if p == tie_at && i == 2 {
                    0.2 + 1e-12
                } else {
                    z
                };
                frags.push(RefFragment {
                    depth: z,
                    view_z: z,
                    color: [0.5; 4],
                    normal: [0.0, 0.0, 1.0],
                    object_id: i as u32,
                    front_facing: true,
                    prim: i as u32,
                    depth_slope: 0.0,
                });
            }
            offsets.push(frags.len() as u32);
        }
        FragmentLists {
            width: w,
            height: 1,
            reversed_z: false,
            offsets,
            frags,
        }
    }

    #[test]
    fn mismatches_over_many_chunks_count_every_pixel_and_keep_the_first() {
        // Three chunks' worth of pixels; k = 2 keeps 0.1 and 0.2 except where it is broken.
        let (w, k) = (3 * 4096 + 17, 2);
        let lists = row(w, 9000);
        let mut cap: Vec<Option<f32>> = (0..w).flat_map(|_| [Some(0.1), Some(0.2)]).collect();
        assert_eq!(k_nearest_mismatch(&cap, k, &lists).hazards, 0);
        // Hazards (the 3rd fragment kept instead of the 2nd) in the last and the second chunk.
        for p in [12_300usize, 5000, 12_304] {
            cap[p * k + 1] = Some(0.3);
        }
        // At the tie pixel the 2nd is replaced by its f32 twin: a tie, not a hazard.
        cap[9000 * k + 1] = None;
        let m = k_nearest_mismatch(&cap, k, &lists);
        assert_eq!((m.hazards, m.first_hazard), (3, Some(5000)));
        assert_eq!((m.ties, m.first_tie), (1, Some(9000)));
    }

    #[test]
    fn a_capture_is_right_within_the_depth_tolerance_and_wrong_with_a_duplicate() {
        let truth = frags(&[0.1, 0.2, 0.3], 0.0);
        assert!(same_k_nearest(&[Some(0.1), Some(0.2)], &truth, 2));
        // Crosswise near-tie matches are right; a fragment kept twice is not.
        assert!(same_k_nearest(&[Some(0.2), Some(0.1)], &truth, 2));
        assert!(!same_k_nearest(&[Some(0.1), Some(0.1)], &truth, 2));
        assert!(!same_k_nearest(&[Some(0.1), None], &truth, 2));
        assert!(same_k_nearest(&[], &[], 2));
    }

    #[test]
    fn a_sliver_s_depth_is_judged_within_its_slope_and_a_lost_one_is_still_wrong() {
        // tets (4³ cells) at 64², pixel (30,40) on lavapipe: every one of the 13 fragments
        // captured, but of three near-equal-depth ones (behind a 4th at 0.9765) the farthest is
        // a 0.63 px² sliver (|∂z/∂x| + |∂z/∂y| = 5.55e-2) whose depth lavapipe sets up from the
        // unsnapped vertices: 0.9792365 against the reference's 0.979251964 (1.55e-5, beyond
        // DEPTH_TOL).
        let depths = [0.976518208, 0.979221961, 0.979222530, 0.979251964];
        let mut truth = frags(&depths, 5.8e-4);
        truth[3].depth_slope = 5.55e-2;
        let got = [
            Some(0.97651863f32),
            Some(0.9792222),
            Some(0.9792224),
            Some(0.9792365),
        ];
        assert!((f64::from(got[3].unwrap()) - depths[3]).abs() > DEPTH_TOL);
        assert!(same_k_nearest(&got, &truth, 4), "the sliver's own depth");
        // Without its slope the same capture reads as a lost fragment (the hazard it was
        // flagged): the tolerance is what changed, not the rule.
        assert!(!same_k_nearest(&got, &frags(&depths, 0.0), 4));
        // A fragment lost and another kept twice (a race's lost update), or a slot left empty,
        // is still wrong. (A loss is told by depth only beyond the tolerances: a duplicate within
        // the sliver's ±2.3e-4 reads as the sliver, as one within DEPTH_TOL always did.)
        let dup = [got[0], got[0], got[2], got[3]];
        assert!(!same_k_nearest(&dup, &truth, 4));
        assert!(!same_k_nearest(&[got[0], got[1], got[2], None], &truth, 4));
    }

    #[test]
    fn ties_are_f32_equal_depths_among_the_k_plus_one_nearest() {
        let d = 0.5f64;
        let next = f64::from(f32::from_bits((d as f32).to_bits() + 1));
        // Distinct in f64, one f32 value: the 2nd and 3rd nearest tie, inside k + 1 for k = 2.
        let tie = |z: &[f64], k| f32_tie_among_nearest(&frags(z, 0.0), k);
        assert!(tie(&[0.1, d, d + 1e-12], 2));
        // One f32 ulp apart: not a tie.
        assert!(!tie(&[0.1, d, next], 4));
        // A tie beyond the k + 1 nearest does not explain a k-nearest mismatch.
        assert!(!tie(&[0.1, 0.2, d, d + 1e-12], 1));
        assert!(!tie(&[], 4));
    }
}
