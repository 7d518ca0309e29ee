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

use super::shared::bucket::{self, Config, Kind};
use super::{Method, Prepared};
use crate::effects;
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::record::cols;
use bench_core::study::InvalidPoint;
use bench_core::Result;

/// adp's WGSL, for the registry's test that holds it against bdp.
#[cfg(test)]
pub(crate) fn tests_wgsl() -> &'static str {
    WGSL
}

const WGSL: &str = include_str!("adp.wgsl");

pub struct Adp;

const SPEC: bucket::Spec = bucket::Spec {
    config,
    fx,
    wgsl: WGSL,
};

const MODE: Axis = Axis::choice(
    cols::BUCKET_MODE,
    "adaptive: buckets equalised by a per-pixel depth histogram (uniform buckets are bdp, bdp2)",
    "adaptive",
    &["adaptive"],
);
const HIST_BINS: Axis = Axis::int(
    cols::HIST_BINS,
    "bins of the per-pixel depth-occupancy histogram (a multiple of 32)",
    1024,
    32,
    8192,
);

pub fn config(point: &Point) -> std::result::Result<Config, InvalidPoint> {
    let hist_bins = point.int(&HIST_BINS) as u32;
    if !hist_bins.is_multiple_of(32) {
        return Err(InvalidPoint::value(
            HIST_BINS.name(),
            hist_bins,
            "must be a multiple of 32 (32-bit words)",
        ));
    }
    // §1.5: "we can further reduce collisions by binding the buckets into pairs and performing
    // dual depth peeling within each non-empty subinterval" (bucket_pairing = paired).
    let paired = bucket::pairing_of(point)?;
    Ok(Config {
        kind: Kind::Adaptive { hist_bins, paired },
        buckets: bucket::buckets_fx(point, paired)?.0,
    })
}

/// The point's effect (translucency and fresnel on (depth, normal) bucket pairs).
fn fx(point: &Point) -> std::result::Result<bucket::Fx, InvalidPoint> {
    bucket::Fx::read(point)
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
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![
            bucket::BUCKET_COUNT,
            bucket::PAIRING_TEXT,
            HIST_BINS,
            MODE,
            bucket::RANGE_PASS,
        ];
        v.extend_from_slice(effects::AXES);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        let bins = point.int(&HIST_BINS);
        if bins % 32 != 0 {
            return Err(InvalidPoint::value(
                HIST_BINS.name(),
                bins,
                "must be a multiple of 32 (32-bit words)",
            ));
        }
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
    use crate::methods::shared::bucket::testing::{gpu, quads, quads_at, quantised_reference, run};
    use crate::methods::shared::bucket::{
        adp_equalise, keyed_color, pack_color, pack_keyed, route_pixel, twin_collisions,
        unpack_color,
    };
    use scenarios::{ParamValue, Params};

    #[test]
    fn adp_paired_quads_at_close_layers_48px_keeps_both_fragments_of_a_shared_bin() {
        // §1.5: "collisions might still happen when two close layers ... are routed to the same
        // bucket ... we can further reduce collisions by binding the buckets into pairs". Two
        // layers 0.01 apart share one of 32 bins: single buckets lose one, pairs keep both, and
        // the image is the f64 reference with the keyed packing's colours.
        let scene = quads_at(&[1.0, 0.99, 0.0, -1.0], 0.5);
        let cfg = Config {
            kind: Kind::Adaptive {
                hist_bins: 32,
                paired: true,
            },
            buckets: 4,
        };
        let r = run(cfg, WGSL, &scene, 48);
        assert!(
            twin_collisions(&adp(4, 32), &r.lists) > 0,
            "precondition: two layers share a bin"
        );
        assert_eq!(r.assert_counts_match_twin(&cfg), 0);
        assert!(r.capture.flag.is_empty(), "{}", r.capture.flag);
        let want = quantised_reference(&r.lists, |c| keyed_color(pack_keyed(0, c)));
        let (e, p) = r.max_err(&want);
        assert!(e < 1e-5, "pixel {p}: {e} from the keyed reference");
    }

    #[test]
    fn adp_paired_quads40_48px_runs_passes_of_8_pairs_and_counts_equal_the_twin() {
        let cfg = Config {
            kind: Kind::Adaptive {
                hist_bins: 256,
                paired: true,
            },
            buckets: 8,
        };
        let r = run(cfg, WGSL, &quads(40, 3), 48);
        assert!(r.prepared.last_passes >= 2);
        assert_eq!(r.geometry_passes, 2 + r.prepared.last_passes);
        let lost = r.assert_counts_match_twin(&cfg);
        assert!(lost <= twin_collisions(&adp(8, 256), &r.lists));
    }

    #[test]
    fn adp_bucket_pairing_is_checked_naming_the_axis() {
        let axes = Adp.axes();
        let given = Params::new().with("bucket_pairing", ParamValue::Str("both".into()));
        let point = bench_core::axes::Point::resolve(&axes, &given).unwrap();
        let e = Adp.validate(&point).unwrap_err().to_string();
        assert!(e.contains("bucket_pairing") && e.contains("both"), "{e}");
    }

    fn adp(buckets: u32, hist_bins: u32) -> Config {
        Config {
            kind: Kind::Adaptive {
                hist_bins,
                paired: false,
            },
            buckets,
        }
    }

    #[test]
    fn adp_quads12_48px_gpu_histogram_and_equalised_bounds_equal_the_twins() {
        // 12 layers, 8 buckets: the centre needs a second pass; the bounds buffer holds pass 2's.
        let cfg = adp(8, 256);
        let r = run(cfg, WGSL, &quads(12, 2), 48);
        let passes = r.prepared.last_passes;
        assert_eq!(passes, 2);
        assert_eq!(r.geometry_passes, 2 + passes);
        let (hist, bounds) = r.prepared.read_adp(gpu(), &r.gscene).unwrap();
        let words = 256 / 32;
        let w = r.lists.width as usize;
        for p in 0..r.lists.pixels() {
            let h = &hist[p * words..(p + 1) * words];
            let mut twin_hist = vec![0u32; words];
            for f in route_pixel(&cfg, r.lists.pixel(p), r.lists.reversed_z) {
                twin_hist[(f.bucket / 32) as usize] |= 1 << (f.bucket % 32);
            }
            assert_eq!(
                h,
                &twin_hist[..],
                "pixel ({}, {}): histogram bits",
                p % w,
                p / w
            );
            assert_eq!(
                &bounds[p * 8..(p + 1) * 8],
                &adp_equalise(h, 8, passes - 1)[..],
                "pixel ({}, {}): equalised bounds of pass {}",
                p % w,
                p / w,
                passes - 1
            );
        }
        assert_eq!(r.assert_counts_match_twin(&cfg), 0);
        let (e, p) = r.max_err(&quantised_reference(&r.lists, |c| {
            unpack_color(pack_color(c))
        }));
        assert!(
            e < 1e-5,
            "pixel {p}: {e} from the packed twin across two passes"
        );
    }

    #[test]
    fn adp_quads40_48px_runs_passes_of_8_and_matches_the_twin() {
        let cfg = adp(8, 2048);
        let r = run(cfg, WGSL, &quads(40, 3), 48);
        let passes = r.prepared.last_passes;
        assert!(passes >= 5, "40 layers need ≥ 5 passes of 8, ran {passes}");
        assert_eq!(r.geometry_passes, 2 + passes);
        let lost = r.assert_counts_match_twin(&cfg);
        if lost == 0 {
            let (e, p) = r.max_err(&quantised_reference(&r.lists, |c| {
                unpack_color(pack_color(c))
            }));
            assert!(e < 1e-5, "pixel {p}: {e} from the packed twin");
        }
    }
}
