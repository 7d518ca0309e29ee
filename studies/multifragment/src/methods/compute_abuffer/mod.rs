//! `compute_abuffer`: the exact A-buffer rasterised in compute (Maule et al. 2012's dynamic
//! fragment buffer, count → scan → fill → sort and fold). The capture itself is
//! `shared::counted_capture` (its doc and results/reference/2026-12-03-h200-resolve/perf-abuffer/PERF.md say how and what the speed axes trade),
//! which `mlab_ideal` and `adaptive_ideal` replay; this module is the method: its axes, what it
//! needs of the adapter, and `prepare`.

use super::shared::counted_capture::{PreparedAbuffer, Variants, STORAGE_BUFFERS};
use super::shared::ssaa;
use super::{Method, Prepared};
use crate::aa::{self, AaConfig, AaMode, AaSupport};
use crate::effects::{self, EffectConfig};
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::record::cols;
use bench_core::{CoreError, Result};

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
    "pixels: count, scan and fill an 8 B fragment per pixel slot, then sort; tiles: triangles over small_max binned to 8×8 tiles instead, each tile's pixels test them (their fragments never stored)",
    "pixels",
    &["pixels", "tiles"],
);
const ATTRIBUTES: Axis = Axis::choice(
    cols::ATTRIBUTES,
    "clip: attributes weighted by the unsnapped clip-space triangle (2D homogeneous); snapped: by the snapped screen triangle's perspective-corrected barycentrics (exact integer edges), as the reference",
    "clip",
    &["clip", "snapped"],
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
        "Maule et al. 2012 dynamic fragment buffer, rasterised in compute (no raster pipeline): count, prefix sum, fill, sort; exact (coverage rule for rule as the reference); vertices transformed once (transform=vertex), integer edge functions stepped and big triangles' tiles classified (coverage=stepped), short lists sorted in workgroup memory (resolve_sort=workgroup); 2 geometry passes + scan + resolve; 4 B offset + 16 B image per pixel + exactly 8 B per fragment (+ 24 B per vertex: clip and snapped screen position); capture=tiles bins the triangles over small_max to 8×8 tiles instead of storing their fragments (8 B per tile and triangle, + 8 B per pixel) and each tile's pixels test them, those fragments never leaving workgroup memory; attributes=snapped weights a fragment's attributes as its snapped screen triangle's (the reference's), not its clip-space triangle's"
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
        ];
        v.extend_from_slice(effects::AXES);
        v.extend([aa::AA, aa::AA_CAPTURE]);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), String> {
        EffectConfig::from_point(point).map(|_| ())
    }
    fn supports(&self, gpu: &Gpu, point: &Point) -> std::result::Result<(), String> {
        let have = gpu.limits.max_storage_buffers_per_shader_stage;
        if have < STORAGE_BUFFERS {
            return Err(format!(
                "needs {STORAGE_BUFFERS} storage buffers per shader stage, {} allows {have}",
                gpu.profile.who()
            ));
        }
        let v = variants(point);
        let wg = gpu.limits.max_compute_workgroup_storage_size;
        let need = v.workgroup_bytes();
        if need > wg {
            return Err(format!(
                "{} needs {need} B of workgroup memory, {} allows {wg}",
                v.name(),
                gpu.profile.who()
            ));
        }
        let aa = AaConfig::from_point(point);
        if v.binned && aa.msaa() > 1 {
            return Err(format!(
                "capture = tiles tests pixel centres only (no coverage masks): aa = {} needs capture = pixels",
                point.choice(&aa::AA)
            ));
        }
        AA_SUPPORT.check(self.name(), aa)
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let small = point.int(&SMALL_MAX) as u32;
        let effect = EffectConfig::from_point(point).map_err(CoreError::Param)?;
        let v = variants(point);
        let aa = AaConfig::from_point(point);
        if aa.mode == AaMode::Ssaa2x2 {
            return ssaa::prepare(gpu, scene, |big| {
                Ok(Box::new(PreparedAbuffer::new(
                    gpu, big, small, &effect, v, None,
                )?))
            });
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

fn variants(point: &Point) -> Variants {
    Variants {
        pretransform: point.choice(&TRANSFORM) == "vertex",
        stepped: point.choice(&COVERAGE) == "stepped",
        wg_sort: point.choice(&RESOLVE_SORT) == "workgroup",
        aa_samples: 1,
        binned: point.choice(&CAPTURE) == "tiles",
        snapped_attrs: point.choice(&ATTRIBUTES) == "snapped",
    }
}

#[cfg(test)]
mod tests;
