//! `bdpn` — multi-pass bucket depth peeling (Liu et al., GPU Pro ch. 1 §1.4: "Theoretically, we
//! can obtain accurate results by enabling the occlusion query and looping in the same way until
//! all the fragments have been captured."). Uniform bucket pairs as `bdp2 bucket_pairing =
//! paired`: pass 1 keeps each bucket's nearest and farthest fragment, every further pass the
//! nearest and farthest strictly between the previous pass's, until an occlusion query counts no
//! fragment (one CPU read a pass, as depth peeling's) or `max_layers` passes have run. Exact up
//! to the keyed packing (RGBA6 colour) when no two fragments of a bucket share an in-bucket key
//! (1/127 of a bucket); those merge and are counted as collisions, as are fragments left when
//! `max_layers` stops the loop. Memory: every pass's pairs are kept (8·K B a pass a pixel), the
//! "sparse layout ... memory exhaustion" the chapter warns of. Transparency only.

use super::shared::bucket::{self, Config, Kind};
use super::{Method, Prepared};
use crate::effects;
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::record::cols;
use bench_core::study::InvalidPoint;
use bench_core::Result;

const WGSL: &str = concat!(
    include_str!("../bdp2/bdp2.wgsl"),
    "\n",
    include_str!("bdpn.wgsl")
);

pub struct Bdpn;

const SPEC: bucket::Spec = bucket::Spec {
    config,
    fx,
    wgsl: WGSL,
};

const MODE: Axis = Axis::choice(
    cols::BUCKET_MODE,
    "uniform: the depth range split evenly",
    "uniform",
    &["uniform"],
);
const MAX_PASSES: Axis = Axis::int(
    cols::MAX_LAYERS,
    "most geometry passes of bucket pairs after the range pass (the loop stops earlier at the first pass an occlusion query finds empty); memory grows 8·K B a pixel per pass",
    8,
    1,
    32,
);

/// The configuration a point asks for: bucket pairs, so at most 16 buckets.
pub fn config(point: &Point) -> std::result::Result<Config, InvalidPoint> {
    Ok(Config {
        kind: Kind::UntilCaptured {
            max_passes: point.int(&MAX_PASSES) as u32,
        },
        buckets: bucket::buckets(point, true)?,
    })
}

/// Transparency only: a pass keeps two keyed colours per bucket.
fn fx(point: &Point) -> std::result::Result<bucket::Fx, InvalidPoint> {
    let fx = bucket::Fx::read(point)?;
    if fx.pairs {
        return Err(InvalidPoint::combination(format!(
            "bdpn keeps (near, far) colour pairs per bucket: {} needs (depth, normal) pairs, offered on bdp and adp",
            fx.effect.effect.name()
        )));
    }
    Ok(fx)
}

impl Method for Bdpn {
    fn name(&self) -> &'static str {
        "bdpn"
    }
    fn describe(&self) -> &'static str {
        "Liu et al. (GPU Pro ch. 1 §1.4) multi-pass bucket depth peeling: bucket pairs, passes until an occlusion query counts nothing (≤ max_layers); exact up to the keyed packing unless two fragments share an in-bucket key (collisions counted)"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![bucket::BUCKET_COUNT, MAX_PASSES, MODE, bucket::RANGE_PASS];
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::shared::bucket::testing::{quads, quantised_reference, run};
    use crate::methods::shared::bucket::{keyed_color, pack_keyed, twin_collisions};

    fn until(buckets: u32, max_passes: u32) -> Config {
        Config {
            kind: Kind::UntilCaptured { max_passes },
            buckets,
        }
    }

    #[test]
    fn bdpn_quads12_48px_2_buckets_loops_past_two_passes_and_matches_the_reference() {
        // 12 layers in 2 bucket pairs: one pass captures ≤ 4, two passes (bdp2 paired) ≤ 8, so
        // the loop must run further; with no shared in-bucket key it captures every fragment and
        // the image is the f64 reference with the keyed packing's colours.
        let scene = quads(12, 2);
        let cfg = until(2, 16);
        let r = run(cfg, WGSL, &scene, 48);
        let two_pass = Config {
            kind: Kind::TwoPass { paired: true },
            buckets: 2,
        };
        assert!(
            twin_collisions(&two_pass, &r.lists) > 0,
            "precondition: two passes of pairs lose fragments here"
        );
        assert_eq!(
            r.assert_counts_match_twin(&cfg),
            0,
            "precondition: no two fragments of a bucket share a key"
        );
        let passes = r.prepared.last_passes;
        assert!(passes >= 3, "ran {passes} passes");
        // Every filled pass, then the one its occlusion query found empty.
        assert_eq!(r.geometry_passes, 1 + passes + 1);
        assert!(r.capture.flag.is_empty(), "{}", r.capture.flag);
        let want = quantised_reference(&r.lists, |c| keyed_color(pack_keyed(0, c)));
        let (e, p) = r.max_err(&want);
        assert!(e < 1e-5, "pixel {p}: {e} from the keyed reference");
    }

    #[test]
    fn bdpn_quads12_48px_max_layers_2_stops_the_loop_and_counts_what_is_left() {
        let cfg = until(2, 2);
        let r = run(cfg, WGSL, &quads(12, 2), 48);
        assert_eq!(r.prepared.last_passes, 2);
        assert_eq!(r.geometry_passes, 1 + 2);
        assert!(r.assert_counts_match_twin(&cfg) > 0);
    }

    #[test]
    fn bdpn_refuses_effects_and_32_pairs_naming_them() {
        use scenarios::{ParamValue, Params};
        let axes = Bdpn.axes();
        let at = |p: Params| bench_core::axes::Point::resolve(&axes, &p).unwrap();
        let e = fx(&at(
            Params::new().with("effect", ParamValue::Str("translucency".into()))
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("translucency"), "{e}");
        let e = config(&at(Params::new().with("bucket_count", ParamValue::Int(32))))
            .unwrap_err()
            .to_string();
        assert!(e.contains("bucket_count = 32"), "{e}");
        let bad = Params::new().with("max_layers", ParamValue::Int(0));
        assert!(bench_core::axes::Point::resolve(&axes, &bad)
            .unwrap_err()
            .join(" ")
            .contains("max_layers"));
    }
}
