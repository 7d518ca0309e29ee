//! `bdp` — uniform bucket depth peeling (Liu et al., "Multi-Fragment Effects on the GPU Using
//! Bucket Sort", GPU Pro ch. 1). Approximate: a depth-range pre-pass, then one geometry pass
//! scatters fragments into `bucket_count` uniform sub-intervals of [zmin, zmax] on up to 8
//! RGBA32F targets with MAX blending; a compute resolve walks the buckets nearest first through
//! the effects fold. Exact (up to the colour packing) when no two fragments share a bucket;
//! otherwise fragments collide and are counted (`collision_rate`, flag `collision`).
//! `bucket_pairing = paired` keeps the nearest and the farthest fragment of each bucket (two
//! channels per bucket, so at most 16 buckets). Shared machinery and CPU twins: `methods::shared::bucket`.

use super::shared::bucket::{self, Config, Kind};
use super::{Method, Prepared};
use crate::effects;
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::record::cols;
use bench_core::study::InvalidPoint;
use bench_core::Result;

const WGSL: &str = include_str!("bdp.wgsl");

pub struct Bdp;

const SPEC: bucket::Spec = bucket::Spec {
    config,
    fx,
    wgsl: WGSL,
};

const MODE: Axis = Axis::choice(
    cols::BUCKET_MODE,
    "uniform: the depth range split evenly (adaptive buckets are the adp method)",
    "uniform",
    &["uniform"],
);
const PAIRING: Axis = Axis::choice(
    cols::BUCKET_PAIRING,
    "single: one fragment per bucket; paired: its nearest and farthest (2 channels)",
    "single",
    &["single", "paired"],
);

/// The configuration a point asks for, or the reason it cannot run.
pub fn config(point: &Point) -> std::result::Result<Config, InvalidPoint> {
    let paired = point.choice(&PAIRING) == "paired";
    let buckets = bucket::buckets_fx(point, paired)?.0;
    Ok(Config {
        kind: Kind::Uniform { paired },
        buckets,
    })
}

/// The point's effect (translucency and fresnel on (depth, normal) bucket pairs).
fn fx(point: &Point) -> std::result::Result<bucket::Fx, InvalidPoint> {
    bucket::Fx::read(point)
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
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![bucket::BUCKET_COUNT, PAIRING, MODE, bucket::RANGE_PASS];
        v.extend_from_slice(effects::AXES);
        v
    }
    fn required_features(&self) -> wgpu::Features {
        SPEC.required_features()
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        SPEC.supports(gpu, point)
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        SPEC.prepare(gpu, scene, point)
    }
}

/// bdp's WGSL, for the registry's test that holds adp against it.
#[cfg(test)]
pub(crate) fn tests_wgsl() -> &'static str {
    WGSL
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::shared::bucket::testing::{quads, quads_z, quantised_reference, run};
    use crate::methods::shared::bucket::{keyed_color, pack_color, pack_keyed, unpack_color};
    use bench_core::record::Flag;

    #[test]
    fn bdp_quads4_48px_32_single_buckets_no_shared_bucket_is_exact_up_to_the_packing() {
        let cfg = Config {
            kind: Kind::Uniform { paired: false },
            buckets: 32,
        };
        let r = run(cfg, WGSL, &quads(4, 1), 48);
        assert_eq!(
            r.assert_counts_match_twin(&cfg),
            0,
            "precondition: the twin routes no two layers into one bucket"
        );
        assert!(r.capture.flag.is_empty(), "{}", r.capture.flag);
        // Against the reference with pack_color's quantisation applied: only f32 compositing differs.
        let (e, p) = r.max_err(&quantised_reference(&r.lists, |c| {
            unpack_color(pack_color(c))
        }));
        assert!(e < 1e-5, "pixel {p}: {e} from the packed twin");
        // Against the exact reference: a colour half-step (1/254) bounds the colour error, and each
        // of the ≤ 4 layers' alpha half-steps (1/2030) moves the composite by at most 2×.
        let (e, p) = r.max_err(&r.lists.composite());
        assert!(
            e <= 0.5 / 127.0 + 4.0 * 2.0 * 0.5 / 1015.0,
            "pixel {p}: {e} from the reference"
        );
    }

    #[test]
    fn bdp_paired_and_bdp2_quads4_48px_resolve_nearest_first_under_both_depth_conventions() {
        // 4 layers in 8 buckets, two slots per bucket: no collision, so the image is the
        // reference with the keyed packing's RGBA6 colours, if and only if the resolve walks
        // the pairs (near/far, or pass 2 before pass 1) in the right order.
        let bdp2_wgsl = include_str!("../bdp2/bdp2.wgsl");
        for reversed in [false, true] {
            let scene = quads_z(4, 5, reversed);
            for (kind, wgsl) in [
                (Kind::Uniform { paired: true }, WGSL),
                (Kind::TwoPass { paired: false }, bdp2_wgsl),
            ] {
                let cfg = Config { kind, buckets: 8 };
                let r = run(cfg, wgsl, &scene, 48);
                assert_eq!(
                    r.assert_counts_match_twin(&cfg),
                    0,
                    "{kind:?} reversed {reversed}"
                );
                let want = quantised_reference(&r.lists, |c| keyed_color(pack_keyed(0, c)));
                let (e, p) = r.max_err(&want);
                assert!(
                    e < 1e-5,
                    "{kind:?} reversed {reversed}: pixel {p} off by {e}"
                );
            }
        }
    }

    #[test]
    fn bdp_reversed_z_quads4_48px_32_buckets_matches_the_packed_reference() {
        let cfg = Config {
            kind: Kind::Uniform { paired: false },
            buckets: 32,
        };
        let r = run(cfg, WGSL, &quads_z(4, 1, true), 48);
        assert_eq!(r.assert_counts_match_twin(&cfg), 0);
        let (e, p) = r.max_err(&quantised_reference(&r.lists, |c| {
            unpack_color(pack_color(c))
        }));
        assert!(e < 1e-5, "pixel {p}: {e} from the packed twin");
    }

    #[test]
    fn bdp_quads16_48px_8_buckets_collision_count_equals_the_twin_single_and_paired() {
        let scene = quads(16, 1);
        let mut lost = Vec::new();
        for paired in [false, true] {
            let cfg = Config {
                kind: Kind::Uniform { paired },
                buckets: 8,
            };
            let r = run(cfg, WGSL, &scene, 48);
            let twin = r.assert_counts_match_twin(&cfg);
            assert!(
                twin > 0,
                "16 layers in 8 buckets must collide (paired: {paired})"
            );
            assert_eq!(r.capture.flag, Flag::Collision.into());
            lost.push(twin);
        }
        assert!(lost[1] < lost[0], "paired keeps two per bucket: {lost:?}");
    }
}
