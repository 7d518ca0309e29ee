//! `bdp2` — two-pass bucket depth peeling (Liu et al., GPU Pro ch. 1). Approximate: uniform
//! buckets as in `bdp`, but pass 1 keeps each bucket's farthest fragment (keyed packing: an
//! in-bucket order key of 127 levels above RGBA6) and pass 2 keeps the next one below it, so a
//! bucket holds two fragments and a collision needs three (or two within 1/127 of a bucket).
//! 3 geometry passes (depth range + 2); two sets of `bucket_count` channels.

use super::shared::bucket::{self, Config, Kind};
use super::{Method, Prepared};
use crate::effects;
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::record::cols;
use bench_core::study::InvalidPoint;
use bench_core::Result;

const WGSL: &str = include_str!("bdp2.wgsl");

pub struct Bdp2;

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

/// The configuration a point asks for, or the reason it cannot run. `bucket_pairing = paired` is
/// §1.4's two-pass BDP as the chapter describes it (16 bucket pairs a pass); unset or `single`
/// is mfx's two-pass of single buckets (the farthest, then the next below it).
pub fn config(point: &Point) -> std::result::Result<Config, InvalidPoint> {
    let paired = bucket::pairing_of(point)?;
    Ok(Config {
        kind: Kind::TwoPass { paired },
        buckets: bucket::buckets_fx(point, paired)?.0,
    })
}

/// The point's effect: translucency on (depth, normal) pairs, not fresnel: a bucket here holds
/// two fragments by design, and a MAX-blended normal channel cannot follow the farther one's
/// depth (the chapter shows Fresnel by ADP only).
fn fx(point: &Point) -> std::result::Result<bucket::Fx, InvalidPoint> {
    let fx = bucket::Fx::read(point)?;
    if fx.effect.effect == effects::Effect::Fresnel {
        return Err(InvalidPoint::combination("bdp2 keeps two fragments per bucket, and a MAX-blended normal channel cannot follow the farther one's depth: fresnel is offered on bdp (single) and adp, as in the chapter"));
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
        let mut v = vec![
            bucket::BUCKET_COUNT,
            bucket::PAIRING_TEXT,
            MODE,
            bucket::RANGE_PASS,
        ];
        v.extend_from_slice(effects::AXES);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        bucket::pairing_of(point).map(|_| ())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::shared::bucket::testing::{quads, quads_at, quantised_reference, run};
    use crate::methods::shared::bucket::{keyed_color, pack_keyed, twin_collisions};
    use bench_core::record::Flag;
    use scenarios::{ParamValue, Params};

    fn paired(buckets: u32) -> Config {
        Config {
            kind: Kind::TwoPass { paired: true },
            buckets,
        }
    }

    #[test]
    fn bdp2_paired_quads_at_8_layers_48px_2_buckets_captures_four_per_bucket_and_matches_the_reference(
    ) {
        // §1.4: pass 1 keeps each bucket's nearest and farthest, pass 2 the nearest and farthest
        // strictly between them. Eight layers in two buckets: one pass of pairs must lose some,
        // the two passes of pairs none, and the image is then the f64 reference with the keyed
        // packing's RGBA6 colours, only if the resolve walks dmin¹, dmin², dmax², dmax¹.
        let zs: Vec<f32> = (0..8).map(|i| 1.5 - 0.4 * i as f32).collect();
        let scene = quads_at(&zs, 0.4);
        let cfg = paired(2);
        let r = run(cfg, WGSL, &scene, 48);
        assert_eq!(r.geometry_passes, 3);
        let one_pass = Config {
            kind: Kind::Uniform { paired: true },
            buckets: 2,
        };
        assert!(
            twin_collisions(&one_pass, &r.lists) > 0,
            "precondition: one pass of pairs must lose fragments here"
        );
        assert_eq!(
            r.assert_counts_match_twin(&cfg),
            0,
            "precondition: ≤ 4 distinct keys per bucket"
        );
        assert!(r.capture.flag.is_empty(), "{}", r.capture.flag);
        let want = quantised_reference(&r.lists, |c| keyed_color(pack_keyed(0, c)));
        let (e, p) = r.max_err(&want);
        assert!(e < 1e-5, "pixel {p}: {e} from the keyed reference");
    }

    #[test]
    fn bdp2_paired_quads16_48px_4_buckets_collision_count_equals_the_twin_and_beats_single() {
        let scene = quads(16, 1);
        let r = run(paired(4), WGSL, &scene, 48);
        let lost = r.assert_counts_match_twin(&paired(4));
        let single = Config {
            kind: Kind::TwoPass { paired: false },
            buckets: 4,
        };
        let lost_single = twin_collisions(&single, &r.lists);
        assert!(lost_single > 0, "16 layers in 4 buckets of 2 must collide");
        assert!(
            lost < lost_single,
            "paired lost {lost}, single {lost_single}"
        );
        if lost > 0 {
            assert_eq!(r.capture.flag, Flag::Collision.into());
        }
    }

    #[test]
    fn bdp2_bucket_pairing_is_checked_naming_the_axis() {
        let axes = Bdp2.axes();
        let point = |v: &str| {
            let given = Params::new().with("bucket_pairing", ParamValue::Str(v.into()));
            bench_core::axes::Point::resolve(&axes, &given).unwrap()
        };
        let e = Bdp2.validate(&point("pairs")).unwrap_err();
        assert!(
            matches!(&e, InvalidPoint::Value { axis, .. } if axis == "bucket_pairing"),
            "{e:?}"
        );
        let e = e.to_string();
        assert!(e.contains("bucket_pairing") && e.contains("pairs"), "{e}");
        assert!(Bdp2.validate(&point("paired")).is_ok());
        assert_eq!(
            config(&point("paired")).unwrap().kind,
            Kind::TwoPass { paired: true }
        );
        let unset = bench_core::axes::Point::resolve(&axes, &Params::new()).unwrap();
        assert_eq!(
            config(&unset).unwrap().kind,
            Kind::TwoPass { paired: false }
        );
        // 32 pairs need 64 channels: refused by the point's config (a skipped row), not the axis.
        let big = Params::new()
            .with("bucket_pairing", ParamValue::Str("paired".into()))
            .with("bucket_count", ParamValue::Int(32));
        let big = bench_core::axes::Point::resolve(&axes, &big).unwrap();
        assert!(Bdp2.validate(&big).is_ok());
        assert!(config(&big)
            .unwrap_err()
            .to_string()
            .contains("64 float channels"));
    }

    #[test]
    fn bdp2_quads16_48px_8_buckets_collision_count_equals_the_twin_and_beats_one_pass() {
        let cfg = Config {
            kind: Kind::TwoPass { paired: false },
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
