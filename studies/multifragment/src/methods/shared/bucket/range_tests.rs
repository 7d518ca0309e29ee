//! `range_pass = bounding_box` on lavapipe: bdp, bdp2 and adp with the depth range drawn from the
//! scene's padded bounding box, their captured fragments per pixel against the CPU twin routing
//! the f64 reference's fragments in the reference's own box range, and their images against the
//! reference where nothing collides.

use super::testing::{quads, quads_z, quantised_reference, run_range};
use super::*;

const BDP: &str = include_str!("../../bdp/bdp.wgsl");
const BDP2: &str = include_str!("../../bdp2/bdp2.wgsl");
const ADP: &str = include_str!("../../adp/adp.wgsl");

fn every_method() -> [(Config, &'static str); 4] {
    let c = |kind, buckets| Config { kind, buckets };
    [
        (c(Kind::Uniform { paired: false }, 32), BDP),
        (c(Kind::Uniform { paired: true }, 16), BDP),
        (c(Kind::TwoPass { paired: false }, 16), BDP2),
        (
            c(
                Kind::Adaptive {
                    hist_bins: 1024,
                    paired: false,
                },
                16,
            ),
            ADP,
        ),
    ]
}

#[test]
fn bounding_box_range_48px_every_bucket_method_matches_the_twin_and_the_reference() {
    for reversed in [false, true] {
        let scene = quads_z(4, 6, reversed);
        for (cfg, wgsl) in every_method() {
            let r = run_range(cfg, wgsl, &scene, 48, RangePass::BoundingBox);
            let lost = r.assert_counts_match_twin(&cfg);
            assert_eq!(
                lost, 0,
                "{cfg:?} reversed {reversed}: 4 layers, no collision"
            );
            assert!(
                r.capture.notes.contains("bounding box"),
                "{}",
                r.capture.notes
            );
            let want = match cfg.kind {
                Kind::Uniform { paired: false } | Kind::Adaptive { .. } => {
                    quantised_reference(&r.lists, |c| unpack_color(pack_color(c)))
                }
                _ => quantised_reference(&r.lists, |c| keyed_color(pack_keyed(0, c))),
            };
            let (e, p) = r.max_err(&want);
            assert!(
                e < 1e-5,
                "{cfg:?} reversed {reversed}: pixel {p} off by {e}"
            );
        }
    }
}

#[test]
fn bounding_box_range_48px_drops_the_mesh_range_pass_and_counts_collisions_as_the_twin() {
    // 16 layers in 8 single buckets collide; the box range (wider than the fragments' own) moves
    // which ones, and the GPU count must still equal the twin's in every pixel.
    let scene = quads(16, 1);
    let cfg = Config {
        kind: Kind::Uniform { paired: false },
        buckets: 8,
    };
    let mesh = run_range(cfg, BDP, &scene, 48, RangePass::Mesh);
    let boxed = run_range(cfg, BDP, &scene, 48, RangePass::BoundingBox);
    assert_eq!(mesh.geometry_passes, 2);
    assert_eq!(
        boxed.geometry_passes, 1,
        "the box is not a pass over the scene"
    );
    assert!(boxed.assert_counts_match_twin(&cfg) > 0);
    mesh.assert_counts_match_twin(&cfg);
}
