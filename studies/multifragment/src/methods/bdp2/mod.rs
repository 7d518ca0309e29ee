//! `bdp2` — two-pass bucket depth peeling (Liu et al., GPU Pro ch. 1). Approximate: uniform
//! buckets as in `bdp`, but pass 1 keeps each bucket's farthest fragment (keyed packing: an
//! in-bucket order key of 127 levels above RGBA6) and pass 2 keeps the next one below it, so a
//! bucket holds two fragments and a collision needs three (or two within 1/127 of a bucket).
//! 3 geometry passes (depth range + 2); two sets of `bucket_count` channels.

use super::shared::bucket::{self, Config, Kind, PreparedBucket};
use super::{Method, Prepared};
use crate::effects;
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::record::cols;
use bench_core::{CoreError, Result};

const WGSL: &str = include_str!("bdp2.wgsl");

pub struct Bdp2;

const MODE: Axis = Axis::choice(
    cols::BUCKET_MODE,
    "uniform: the depth range split evenly (adaptive buckets are the adp method)",
    "uniform",
    &["uniform"],
);

pub fn config(point: &Point) -> std::result::Result<Config, String> {
    Ok(Config {
        kind: Kind::TwoPass,
        buckets: bucket::buckets_fx(point, false)?.0,
    })
}

/// The point's effect: translucency on (depth, normal) pairs, not fresnel: a bucket here holds
/// two fragments by design, and a MAX-blended normal channel cannot follow the farther one's
/// depth (the chapter shows Fresnel by ADP only).
fn fx(point: &Point) -> std::result::Result<bucket::Fx, String> {
    let fx = bucket::Fx::read(point)?;
    if fx.effect.effect == effects::Effect::Fresnel {
        return Err("bdp2 keeps two fragments per bucket, and a MAX-blended normal channel cannot follow the farther one's depth: fresnel is offered on bdp (single) and adp, as in the chapter".into());
    }
    Ok(fx)
}

impl Method for Bdp2 {
    fn name(&self) -> &'static str {
        "bdp2"
    }
    fn describe(&self) -> &'static str {
        "Liu et al. (GPU Pro ch. 1) two-pass uniform bucket depth peeling: approximate (collisions counted), 3 geometry passes, 2 × ≤8 RGBA32F MAX-blended targets; keyed colour packing"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![bucket::BUCKET_COUNT, MODE, bucket::RANGE_PASS];
        v.extend_from_slice(effects::AXES);
        v
    }
    fn required_features(&self) -> wgpu::Features {
        wgpu::Features::FLOAT32_BLENDABLE
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        let fx = fx(point)?;
        bucket::supports_targets_fx(gpu, &config(point)?, fx.pairs)
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let cfg = config(point).map_err(CoreError::Param)?;
        let fx = fx(point).map_err(CoreError::Param)?;
        Ok(Box::new(PreparedBucket::with_range(
            gpu,
            scene,
            cfg,
            WGSL,
            fx,
            bucket::RangePass::read(point),
        )?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::shared::bucket::testing::{quads, run};
    use crate::methods::shared::bucket::twin_collisions;

    #[test]
    fn bdp2_quads16_48px_8_buckets_collision_count_equals_the_twin_and_beats_one_pass() {
        let cfg = Config {
            kind: Kind::TwoPass,
            buckets: 8,
        };
        let r = run(cfg, WGSL, &quads(16, 1), 48);
        assert_eq!(r.geometry_passes, 3);
        let twin = r.assert_counts_match_twin(&cfg);
        assert!(
            twin > 0,
            "16 layers in 8 buckets of 2 must still collide somewhere"
        );
        let one_pass = Config {
            kind: Kind::Uniform { paired: false },
            buckets: 8,
        };
        let single = twin_collisions(&one_pass, &r.lists);
        assert!(twin < single, "bdp2 lost {twin}, one pass {single}");
    }
}
