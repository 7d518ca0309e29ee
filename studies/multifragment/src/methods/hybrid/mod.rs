//! Hybrid transparency (Maule, Comba, Torchelsen & Bastos, I3D 2013): the k nearest fragments of
//! each pixel composited exactly and the rest accumulated order-independently, composited behind
//! them (CPU twin [`mfx_reference::oit::hybrid`]). The core is the hazard-free atomic k-buffer
//! (`kbuffer_atomic`: keys pass, payload pass, resolve); every fragment the payload pass does not
//! capture is blended into the tail targets (methods/shared/tail, `tail.wgsl`), whose opacity is the
//! paper's weighted average (Bavoil & Myers 2008): 1 − (1 − Σα/n)ⁿ, colour Σαc/Σα. Its WGSL is
//! the k-buffer's and the tail's (`tail_behind` with `MEAN_ALPHA`): no shader of its own.
//!
//! Exact for depth complexity ≤ k; order-independent (the core is the k nearest whatever the
//! order, the tail sums commute), so one build. `judge` sets the twin's image as the definition
//! and the k-buffer's hazard count (0 by construction); fragments tailed are counted.
//!
//! Memory per pixel: k × 40 B (key, claim, entry) + 16 B image + 24 B tail + 4 B stand-in depth.

use super::shared::kslots::atomic::PreparedAtomic;
use super::shared::kslots::LAYERS;
use super::shared::tail::{self, Bounding};
use super::{Method, Prepared};
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::Result;
use mfx_reference::oit::{Keep, TailMode};

pub struct Hybrid;

/// The atomic k-buffer's k nearest with the rest in a mean-alpha tail.
pub const BOUNDING: Bounding = Bounding {
    keep: Keep::Nearest,
    tail: TailMode::Blend,
    mean_alpha: true,
};

impl Method for Hybrid {
    fn name(&self) -> &'static str {
        "hybrid"
    }
    fn describe(&self) -> &'static str {
        "Maule et al. 2013 hybrid transparency: the k nearest exact (hazard-free atomic k-buffer) + the rest blended order-independently (weighted average, mean-alpha opacity) behind them; approximate (exact for depth complexity ≤ k); 2 geometry passes + resolve; k × 40 B + 44 B per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        vec![LAYERS]
    }
    fn supports(&self, gpu: &Gpu, _: &Point) -> std::result::Result<(), bench_core::Unsupported> {
        tail::supports(gpu, 0)
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let k = point.int(&LAYERS) as u32;
        Ok(Box::new(PreparedAtomic::new(gpu, scene, k, BOUNDING)?))
    }
}

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::{Float, Int};

    use super::*;
    use crate::method::Capture;
    use crate::testing::{params, run, scene};

    fn vs(image: &[[f32; 4]], want: &[[f64; 4]]) -> (f64, usize) {
        let mut worst = (0.0f64, 0usize);
        for (p, (g, d)) in image.iter().zip(want).enumerate() {
            for c in 0..4 {
                let e = (d[c] - g[c] as f64).abs();
                if e.is_nan() || e > worst.0 {
                    worst = (if e.is_nan() { f64::INFINITY } else { e }, p);
                }
            }
        }
        worst
    }

    fn image(cap: &Capture) -> &[[f32; 4]] {
        cap.image.as_ref().unwrap()
    }

    #[test]
    fn exact_where_depth_complexity_is_at_most_k_and_the_twin_elsewhere() {
        let scenes = [
            scene("quads", &[("depth_complexity", Int(6))]),
            scene("shells", &[("count", Int(3)), ("segments", Int(12))]),
            scene("particles", &[("count", Int(400)), ("size", Float(0.5))]),
            scene("hair", &[("strands", Int(300))]),
        ];
        for s in &scenes {
            for k in [1, 2, 4, 8] {
                let what = format!("{} k {k}", s.label());
                let (cap, lists) = run(&Hybrid, s, 40, 40, &params(&[("layers", Int(k))]));
                let def = cap.definition.as_ref().expect("the twin's image");
                // k ≤ 8 layers composited in f32 plus f32 tail sums and one pow (≤ 64 terms).
                let (e, at) = vs(image(&cap), def);
                assert!(
                    e <= 2e-5,
                    "{what}: {e:.2e} at {at} vs the twin: {}",
                    cap.notes
                );
                assert_eq!(cap.hazard_pixels, Some(0), "{what}");
                let dc = lists.depth_complexity();
                let beyond: u64 = dc.iter().map(|&d| d.saturating_sub(k as u32) as u64).sum();
                assert_eq!(cap.tailed_fragments, Some(beyond), "{what}");
                assert_eq!(cap.dropped_fragments, Some(0), "{what}");
                // Where nothing was tailed the twin is the exact composite.
                let truth = lists.composite();
                for (p, &d) in dc.iter().enumerate() {
                    if d <= k as u32 {
                        let e = (0..4)
                            .map(|c| (image(&cap)[p][c] as f64 - truth[p][c]).abs())
                            .fold(0.0, f64::max);
                        assert!(e <= 2e-5, "{what}: pixel {p} with {d} layers: {e:.2e}");
                    }
                }
            }
        }
    }
}
