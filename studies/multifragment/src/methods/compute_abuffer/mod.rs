//! `compute_abuffer`: the exact A-buffer rasterised in compute (Maule et al. 2012's dynamic
//! fragment buffer, count → scan → fill → sort and fold). The capture itself is
//! `shared::counted_capture` (its doc and results/reference/2026-12-03-h200-resolve/perf-abuffer/PERF.md say how and what the speed axes trade),
//! which `mlab_ideal` and `adaptive_ideal` replay; this module is the method: its axes, what it
//! needs of the adapter, and `prepare`.

use super::shared::counted_capture::plan::{self, PACKED_BUFFERS};
use super::shared::counted_capture::{PreparedAbuffer, Variants};
use super::shared::ssaa;
use super::{Method, Prepared};
use crate::aa::{self, AaConfig, AaMode, AaSupport};
use crate::effects::{self, EffectConfig};
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::record::cols;
use bench_core::study::InvalidPoint;
use bench_core::Result;

pub struct ComputeAbuffer;

const AA_SUPPORT: AaSupport = AaSupport {
    sample: false,
    coverage: true,
    ssaa: true,
    why: "compute_abuffer keeps one fragment per pixel with its coverage mask (aa_capture = coverage)",
};

const SMALL_MAX: Axis = Axis::int(
    cols::SMALL_MAX,
    "largest triangle bounding box (pixels) one thread rasterises; larger ones are shared",
    256,
    1,
    1 << 20,
);
const TRANSFORM: Axis = Axis::choice(
    cols::TRANSFORM,
    "vertex: each vertex transformed once into a clip buffer; triangle: per triangle in every kernel",
    "vertex",
    &["vertex", "triangle"],
);
const COVERAGE: Axis = Axis::choice(
    cols::COVERAGE,
    "stepped: integer edge functions stepped, big triangles' tiles classified; direct: 64-bit products per pixel",
    "stepped",
    &["stepped", "direct"],
);
const CAPTURE: Axis = Axis::choice(
    cols::CAPTURE,
    "pixels: count, scan and fill an 8 B fragment per pixel slot, then sort; tiles: triangles over small_max binned to 8×8 tiles instead, each tile's pixels test them (their fragments never stored); auto: tiles where the triangles over small_max make at least 3 fragments a pixel, else pixels (decided at prepare; the default: the method, not the suite, chooses)",
    "auto",
    &["pixels", "tiles", "auto"],
);
/// `capture = auto`: binned fragments per pixel (of the whole image) from which the scene is
/// captured by tiles. First 4.0, from the H200's `perf-binned` (2026-12-03: quads(8), 2.5 a
/// pixel, faster by pixels; quads(32), 11 a pixel, by tiles). The H100's `perf-issue41`
/// (2026-12-05, `results/reference/2026-12-05-h100-perf-issue41`, pixels, tiles and auto side
/// by side on 33 scene × resolution points) put points between: shells(4, 16) at 3.04–3.05 a
/// pixel and shells(4, 48) at 3.09–3.13 ran 1.6–20 % faster by tiles at 1024² and 2048² (auto
/// took pixels), quads(8) at 2.54 and shells(16, 256) at 2048² at 3.88 ran 2–18 % faster by
/// pixels. 3.0 takes the first six and loses 2 % on the last; no single count separates them
/// all (shells(4, 48) at 512², 2.32 a pixel, is 3 % faster by tiles). Fit on that run: an A/B
/// on another run says whether it holds.
const AUTO_BINNED_PER_PIXEL: f64 = 3.0;
const ATTRIBUTES: Axis = Axis::choice(
    cols::ATTRIBUTES,
    "clip: attributes weighted by the unsnapped clip-space triangle (2D homogeneous); snapped: by the snapped screen triangle's perspective-corrected barycentrics (exact integer edges), as the reference",
    "clip",
    &["clip", "snapped"],
);
const BINDINGS: Axis = Axis::choice(
    cols::BINDINGS,
    "auto: the native 10 storage buffers per stage where allowed, else packed; packed: 6 (mesh packed at prepare, work after the offsets), within WebGPU's 8",
    "auto",
    &["auto", "packed"],
);
const RESOLVE_SORT: Axis = Axis::choice(
    cols::RESOLVE_SORT,
    "workgroup: short lists sorted in workgroup memory; private: every list in a per-thread array",
    "workgroup",
    &["workgroup", "private"],
);

impl Method for ComputeAbuffer {
    fn name(&self) -> &'static str {
        "compute_abuffer"
    }
    fn describe(&self) -> &'static str {
        "Maule et al. 2012 dynamic fragment buffer, rasterised in compute (no raster pipeline): count, prefix sum, fill, sort; exact (coverage rule for rule as the reference); vertices transformed once (transform=vertex), integer edge functions stepped and big triangles' tiles classified (coverage=stepped), short lists sorted in workgroup memory (resolve_sort=workgroup); 2 geometry passes + scan + resolve; 4 B offset + 16 B image per pixel + exactly 8 B per fragment (+ 24 B per vertex: clip and snapped screen position); capture=tiles bins the triangles over small_max to 8×8 tiles instead of storing their fragments (8 B per tile and triangle, + 8 B per pixel) and each tile's pixels test them, those fragments never leaving workgroup memory; attributes=snapped weights a fragment's attributes as its snapped screen triangle's (the reference's), not its clip-space triangle's; capture=auto picks tiles where the triangles over small_max make ≥ 3 fragments a pixel; bindings=auto packs its 10 storage buffers into 6 where the device allows fewer (WebGPU: 8), the fragments then split over up to 3 bindings"
    }
    fn exact(&self) -> bool {
        true
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![
            SMALL_MAX,
            TRANSFORM,
            COVERAGE,
            CAPTURE,
            ATTRIBUTES,
            RESOLVE_SORT,
            BINDINGS,
        ];
        v.extend_from_slice(effects::AXES);
        v.extend([aa::AA, aa::AA_CAPTURE]);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        EffectConfig::from_point(point).map(|_| ())
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        let have = gpu.limits.max_storage_buffers_per_shader_stage;
        if have < PACKED_BUFFERS {
            return Err(format!(
                "needs {PACKED_BUFFERS} storage buffers per shader stage (packed bindings), {} allows {have}",
                gpu.profile.who()
            ).into());
        }
        let v = variants(point);
        let wg = gpu.limits.max_compute_workgroup_storage_size;
        if v.fit_workgroup(wg).is_none() {
            let need = Variants {
                ring: plan::RING_SHORT,
                ..v
            }
            .workgroup_bytes();
            return Err(format!(
                "{} needs {need} B of workgroup memory (a ring of {}), {} allows {wg}",
                v.name(),
                plan::RING_SHORT,
                gpu.profile.who()
            )
            .into());
        }
        let aa = AaConfig::from_point(point);
        // capture = auto falls back to pixels under MSAA (the binned resolve has no masks).
        if v.binned && aa.msaa() > 1 {
            return Err(format!(
                "capture = tiles tests pixel centres only (no coverage masks): aa = {} needs capture = pixels",
                point.choice(&aa::AA)
            ).into());
        }
        AA_SUPPORT.check(self.name(), aa)
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let small = point.int(&SMALL_MAX) as u32;
        let effect = EffectConfig::from_point(point)?;
        let wg = gpu.limits.max_compute_workgroup_storage_size;
        let v = variants(point).fit_workgroup(wg).unwrap_or(variants(point));
        let aa = AaConfig::from_point(point);
        let auto = point.choice(&CAPTURE) == "auto";
        if aa.mode == AaMode::Ssaa2x2 {
            return ssaa::prepare(gpu, scene, |big| {
                Ok(Box::new(match auto {
                    true => prepare_auto(gpu, big, small, &effect, v)?,
                    false => PreparedAbuffer::new(gpu, big, small, &effect, v, None)?,
                }))
            });
        }
        if auto && aa.msaa() == 1 {
            return Ok(Box::new(prepare_auto(gpu, scene, small, &effect, v)?));
        }
        let v = Variants {
            aa_samples: aa.msaa(),
            ..v
        };
        Ok(Box::new(PreparedAbuffer::new(
            gpu, scene, small, &effect, v, None,
        )?))
    }
}

/// `capture = auto`: the tiles' routing (triangles over `small` binned), kept where the binned
/// triangles make at least [`AUTO_BINNED_PER_PIXEL`] fragments a pixel (counted in one untimed
/// frame), else the pixel capture; the notes say which and why.
fn prepare_auto(
    gpu: &Gpu,
    scene: &GpuScene,
    small: u32,
    effect: &EffectConfig,
    v: Variants,
) -> Result<PreparedAbuffer> {
    let wg = gpu.limits.max_compute_workgroup_storage_size;
    let pixels = Variants { binned: false, ..v };
    let Some(tiles) = Variants { binned: true, ..v }.fit_workgroup(wg) else {
        let mut p = PreparedAbuffer::new(gpu, scene, small, effect, pixels, None)?;
        p.add_note("capture auto: pixels (the binned resolve does not fit workgroup memory)");
        return Ok(p);
    };
    let mut t = PreparedAbuffer::new(gpu, scene, small, effect, tiles, None)?;
    let (all, unbinned) = t.fragment_census(gpu, scene)?;
    let per_px = all.saturating_sub(unbinned) as f64 / scene.pixels().max(1) as f64;
    let why = format!(
        "{per_px:.2} fragments a pixel from triangles over small_max {small} (of {all} in all), {} {AUTO_BINNED_PER_PIXEL}",
        if per_px >= AUTO_BINNED_PER_PIXEL { "≥" } else { "<" }
    );
    if per_px >= AUTO_BINNED_PER_PIXEL {
        t.add_note(&format!("capture auto: tiles ({why})"));
        return Ok(t);
    }
    drop(t);
    let mut p = PreparedAbuffer::new(gpu, scene, small, effect, pixels, None)?;
    p.add_note(&format!("capture auto: pixels ({why})"));
    Ok(p)
}

fn variants(point: &Point) -> Variants {
    Variants {
        pretransform: point.choice(&TRANSFORM) == "vertex",
        stepped: point.choice(&COVERAGE) == "stepped",
        wg_sort: point.choice(&RESOLVE_SORT) == "workgroup",
        aa_samples: 1,
        binned: point.choice(&CAPTURE) == "tiles",
        snapped_attrs: point.choice(&ATTRIBUTES) == "snapped",
        packed: point.choice(&BINDINGS) == "packed",
        ring: plan::RING,
    }
}

#[cfg(test)]
mod tests;
