//! A hazard-free k-buffer: the k nearest fragments per pixel via 32-bit atomicMax bubbling of
//! depth keys (pass 1), then a payload pass in which each captured fragment claims its slot
//! (pass 2), then the same resolve as `kbuffer_rmw` (effects fold, nearest first). Its hazard
//! rate is judged exactly like `kbuffer_rmw`'s and is 0 by construction (tested). Why not one
//! pass of 64-bit atomicMin of (depth, payload): see the WGSL header (naga allows 64-bit min/max
//! only without a return value, and the insertion needs it).
//!
//! `tail = blend` (default `drop`): the payload pass returns every fragment that was not
//! captured to the blended tail (methods/shared/tail), composited behind the k in the resolve.
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
//! (`specialisation`), as `kbuffer_rmw` (`shared::kslots::entry`); antialiasing is offered for
//! transparency only (an averaged per-sample fold of another effect has no judged truth here).

use super::shared::axes::SPECIALISATION;
use super::shared::kslots::atomic::PreparedAtomic;
use super::shared::kslots::{entry::SlotConfig, LAYERS};
use super::shared::ssaa;
use super::shared::tail::{self, Bounding};
use super::{Method, Prepared};
use crate::aa::{self, AaConfig, AaMode, AaSupport};
use crate::effects::{self, Effect};
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::study::InvalidPoint;
use bench_core::Result;

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
        let cfg = AaConfig::from_point(point);
        AA_SUPPORT.check(self.name(), cfg)?;
        let slot = SlotConfig::read(point)?;
        slot.check(Bounding::of(point, true).blends())?;
        if cfg.mode != AaMode::None && slot.effect.effect != Effect::Transparency {
            return Err(format!(
                "antialiasing is offered for transparency only: an averaged per-sample {} fold has no judged truth",
                slot.effect.effect.name()
            ).into());
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
        let slot = SlotConfig::read(point)?;
        let cfg = AaConfig::from_point(point);
        if cfg.mode == AaMode::Ssaa2x2 {
            return ssaa::prepare(gpu, scene, |big| {
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

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::Int;

    use super::*;
    use crate::testing::{assert_matches_reference, params, scene};

    /// Composite of up to 16 layers in f32 vs f64: a few f32 ulps per step.
    const IMAGE_TOL: f64 = 2e-5;

    #[test]
    fn captures_the_true_k_nearest_with_no_hazard() {
        let shells = scene("shells", &[("count", Int(4)), ("segments", Int(12))]);
        let quads = scene("quads", &[("depth_complexity", Int(9))]);
        let grass = scene("grass", &[("blades", Int(200))]);
        let ks: Vec<_> = [1, 3, 8, 16].map(|k| params(&[("layers", Int(k))])).into();
        assert_matches_reference(
            &KBufferAtomic,
            &[&shells, &quads, &grass],
            &ks,
            (40, 40),
            IMAGE_TOL,
            "k layers composited in f32",
            |name, cap| assert_eq!(cap.hazard_pixels, Some(0), "{name}: {}", cap.notes),
        );
    }

    #[test]
    fn tail_and_keep_modes_equal_their_definition_and_count_what_did_not_fit() {
        // Up to 8 kept layers composited in f32, plus f32 tail sums (≤ 30 terms here).
        tail::check_tail_and_keep(&KBufferAtomic, 2.0 * IMAGE_TOL);
    }
}
