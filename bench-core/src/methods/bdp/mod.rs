//! `bdp` — uniform bucket depth peeling (Liu et al., "Multi-Fragment Effects on the GPU Using
//! Bucket Sort", GPU Pro ch. 1). Approximate: a depth-range pre-pass, then one geometry pass
//! scatters fragments into `bucket_count` uniform sub-intervals of [zmin, zmax] on up to 8
//! RGBA32F targets with MAX blending; a compute resolve walks the buckets nearest first through
//! the effects fold. Exact (up to the colour packing) when no two fragments share a bucket;
//! otherwise fragments collide and are counted (`collision_rate`, flag `collision`).
//! `bucket_pairing = paired` keeps the nearest and the farthest fragment of each bucket (two
//! channels per bucket, so at most 16 buckets). Shared machinery and CPU twins: `methods::bucket`.

use scenarios::Params;

use super::bucket::{self, Config, Kind, PreparedBucket};
use super::{str_param, Method, Prepared};
use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::{CoreError, Result};

const WGSL: &str = include_str!("bdp.wgsl");

pub struct Bdp;

/// The configuration a point asks for, or the reason it cannot run.
pub fn config(params: &Params) -> std::result::Result<Config, String> {
    str_param(params, "bucket_mode", "uniform", &["uniform"])
        .map_err(|e| format!("{e} (bdp is uniform; adaptive buckets are the `adp` method)"))?;
    let paired = str_param(params, "bucket_pairing", "single", &["single", "paired"])? == "paired";
    let buckets = bucket::buckets_param(params, paired)?;
    Ok(Config {
        kind: Kind::Uniform { paired },
        buckets,
    })
}

impl Method for Bdp {
    fn name(&self) -> &'static str {
        "bdp"
    }
    fn describe(&self) -> &'static str {
        "Liu et al. (GPU Pro ch. 1) uniform bucket depth peeling: approximate (collisions counted), 2 geometry passes (depth range + route), ≤8 RGBA32F MAX-blended targets; colour packed in one float per fragment"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> &'static [&'static str] {
        &["bucket_count", "bucket_pairing", "bucket_mode"]
    }
    fn required_features(&self) -> wgpu::Features {
        wgpu::Features::FLOAT32_BLENDABLE
    }
    fn supports(&self, gpu: &Gpu, params: &Params) -> std::result::Result<(), String> {
        bucket::supports_targets(gpu, &config(params)?)
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, params: &Params) -> Result<Box<dyn Prepared>> {
        let cfg = config(params).map_err(CoreError::Param)?;
        Ok(Box::new(PreparedBucket::new(gpu, scene, cfg, WGSL)?))
    }
}
