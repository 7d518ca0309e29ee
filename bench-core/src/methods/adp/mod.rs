//! `adp` — adaptive bucket depth peeling (Liu et al., GPU Pro ch. 1). Approximate: after the
//! depth-range pre-pass, a histogram pass sets one bit per occupied depth bin (`hist_bins` bins
//! of [zmin, zmax] per pixel). The paper ORs into 8 RGBA32UI targets with 32-bit logic-op
//! blending; wgpu has no logic ops, so this uses atomicOr on a storage buffer from the fragment
//! shader. A compute equalisation turns the set bits into bucket bounds (bucket j = the j-th
//! occupied bin), a routing pass sends each fragment to its own bucket, and pixels with more
//! occupied bins than `bucket_count` take further passes of `bucket_count` (one CPU read of the
//! most occupied pixel decides how many). Fragments sharing a bin collide (counted).
//! Geometry passes: 2 + ⌈max occupied bins / bucket_count⌉; memory per pixel: hist_bins/8 B
//! histogram + 4·K B bounds + K·4 B buckets.

use scenarios::Params;

use super::bucket::{self, Config, Kind, PreparedBucket};
use super::{int_param, str_param, Method, Prepared};
use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::{CoreError, Result};

const WGSL: &str = include_str!("adp.wgsl");

pub struct Adp;

pub fn config(params: &Params) -> std::result::Result<Config, String> {
    str_param(params, "bucket_mode", "adaptive", &["adaptive"])
        .map_err(|e| format!("{e} (adp is adaptive; uniform buckets are `bdp` / `bdp2`)"))?;
    let hist_bins = int_param(params, "hist_bins", 1024, 32, 8192)? as u32;
    if hist_bins % 32 != 0 {
        return Err(format!(
            "hist_bins = {hist_bins} must be a multiple of 32 (32-bit words)"
        ));
    }
    Ok(Config {
        kind: Kind::Adaptive { hist_bins },
        buckets: bucket::buckets_param(params, false)?,
    })
}

impl Method for Adp {
    fn name(&self) -> &'static str {
        "adp"
    }
    fn describe(&self) -> &'static str {
        "Liu et al. (GPU Pro ch. 1) adaptive bucket depth peeling: approximate (same-bin collisions counted); depth range + histogram (atomicOr on a storage buffer: wgpu has no logic-op blending) + ⌈occupied bins/K⌉ routing passes; hist_bins/8 B + 8·K B per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> &'static [&'static str] {
        &["bucket_count", "hist_bins", "bucket_mode"]
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
