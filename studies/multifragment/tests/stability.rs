//! The stiff and extreme cases of the stability suite (issue 5), each as a small lavapipe test of
//! depth peeling against the f64 reference: no case produces NaN/Inf, the stable thickness stays
//! within its reasoned bound where the naive one does not, and losses are counted where the
//! study flags them. The suite-level flags (overflow, lost_coplanar, precision) are checked by
//! running the stability suite's own tables through the runner at the end.

use bench_core::record::{Flag, Row, Status};
use bench_core::runner::{self};
use mfx_multifragment::effects::{signed_view_z, EffectConfig};
use mfx_multifragment::methods::{self, Capture};
use mfx_multifragment::testing;
use mfx_multifragment::STUDIES;
use mfx_reference::metrics::{image_error, ImageError, BAD_PIXEL_TOL};
use mfx_reference::{rasterize, FragmentLists};
use scenarios::{ParamValue, Params, SceneSpec, Suite};
use schema::cols;

fn s(v: &str) -> ParamValue {
    ParamValue::Str(v.into())
}
fn f(v: f64) -> ParamValue {
    ParamValue::Float(v)
}
fn i(v: i64) -> ParamValue {
    ParamValue::Int(v)
}

struct Run {
    cap: Capture,
    lists: FragmentLists,
    e: ImageError,
}

impl Run {
    /// Fragments within capacity the method did not capture.
    fn lost(&self) -> u64 {
        let k = match self.cap.expected {
            mfx_multifragment::methods::Expected::All => u32::MAX,
            mfx_multifragment::methods::Expected::FirstK(k) => k,
        };
        self.lists
            .depth_complexity()
            .iter()
            .zip(self.cap.counts.as_ref().unwrap())
            .map(|(&d, &c)| d.min(k).saturating_sub(c) as u64)
            .sum()
    }
}

fn run(spec: &SceneSpec, params: &Params, w: u32) -> Run {
    let gpu = testing::gpu();
    let scene = spec.build().unwrap();
    let (cap, _) = testing::render(gpu, &scene, &*methods::get("depth_peel"), params, w, w);
    let lists = rasterize(&scene, w, w);
    let reference = EffectConfig::from_point(&testing::point(&*methods::get("depth_peel"), params))
        .unwrap()
        .reference(&scene, &lists, cap.expected);
    let e = image_error(&reference, cap.image.as_ref().unwrap(), BAD_PIXEL_TOL);
    assert_eq!(
        e.non_finite,
        0,
        "{} {}: NaN/Inf in the output",
        spec.label(),
        params.label()
    );
    Run { cap, lists, e }
}

fn quads(d: i64) -> Params {
    Params::new().with("depth_complexity", i(d))
}

// ---- 1. near/far ratio, standard and reversed-Z ----

#[test]
fn near_far_1e9_standard_z_merges_layers_reversed_z_keeps_them_32px() {
    // Layers 0.33 apart at distance ~4 with near = 1e-6: in standard Z their window depths differ
    // by n·Δz/z² ≈ 2e-8, below half an f32 ulp at 1 (3e-8), so layers merge and peeling loses
    // them; reversed-Z keeps depth ≈ n/z near 0, where f32 resolves them easily.
    for (reversed, near) in [(false, 1e-2), (true, 1e-2), (false, 1e-6), (true, 1e-6)] {
        let spec = SceneSpec::new(
            "quads",
            quads(6)
                .with("near", f(near))
                .with("far", f(1e3))
                .with("reversed_z", ParamValue::Bool(reversed)),
        );
        let r = run(&spec, &Params::new(), 32);
        if reversed || near > 1e-3 {
            assert_eq!(r.lost(), 0, "{}: no layer lost", spec.label());
            assert!(
                r.e.max_abs <= 1e-4,
                "{}: max abs {}",
                spec.label(),
                r.e.max_abs
            );
        } else {
            assert!(
                r.lost() > 0,
                "{}: standard Z at far/near = 1e9 should merge layers",
                spec.label()
            );
        }
    }
}

// ---- 2. coplanar duplicates ----

#[test]
fn coplanar_duplicates_classic_loses_them_tiebreak_keeps_them_32px() {
    let spec = SceneSpec::new(
        "coplanar",
        Params::new().with("layers", i(3)).with("copies", i(3)),
    );
    let classic = run(&spec, &Params::new(), 32);
    assert!(
        classic.lost() > 0,
        "strict peeling must lose coplanar copies"
    );
    assert!(
        mfx_multifragment::studies::methods::has_depth_ties(&classic.lists),
        "the reference has exact ties"
    );
    let tb = run(
        &spec,
        &Params::new().with("tiebreak", ParamValue::Bool(true)),
        32,
    );
    assert_eq!(tb.lost(), 0, "tiebreak peels every copy");
    assert_eq!(
        tb.cap.counts.as_ref().unwrap(),
        &tb.lists.depth_complexity()
    );
    assert!(
        tb.e.max_abs <= 1e-4,
        "tiebreak composites in the reference's tie order: {}",
        tb.e.max_abs
    );
    // Reversed-Z: the depth test is Greater, and equal depths still keep the first submitted.
    let spec = SceneSpec::new(
        "coplanar",
        Params::new()
            .with("layers", i(2))
            .with("copies", i(4))
            .with("reversed_z", ParamValue::Bool(true)),
    );
    let tb = run(
        &spec,
        &Params::new().with("tiebreak", ParamValue::Bool(true)),
        32,
    );
    assert_eq!(tb.lost(), 0, "{}: tiebreak with reversed-Z", spec.label());
}

// ---- 3. layers closer than a bucket / an ADP bin ----

#[test]
fn layers_closer_than_one_adp_bin_are_exact_for_depth_peeling_32px() {
    // 8 layers in 1e-3 world units at distance 4: window-depth gaps ≈ 1e-6, far below 1/1024 of
    // the scene's depth range (the bucket methods' resolution) but many f32 ulps apart.
    let spec = SceneSpec::new("quads", quads(8).with("span", f(1e-3)));
    let r = run(&spec, &Params::new(), 32);
    assert_eq!(r.lost(), 0);
    assert!(r.e.max_abs <= 1e-4, "max abs {}", r.e.max_abs);
}

// ---- 4. very high depth complexity ----

#[test]
fn depth_complexity_256_with_64_layers_is_bounded_and_counted_32px() {
    let spec = SceneSpec::new("quads", quads(256));
    let p = Params::new()
        .with("max_layers", i(64))
        .with("occlusion_stop", ParamValue::Bool(false));
    let r = run(&spec, &p, 32);
    assert!(
        r.lists.max_depth_complexity() > 64,
        "the case must overflow"
    );
    let counts = r.cap.counts.as_ref().unwrap();
    assert_eq!(
        *counts.iter().max().unwrap(),
        64,
        "capture stops at capacity"
    );
    assert_eq!(
        r.lost(),
        0,
        "nothing within capacity is lost: the rest is overflow"
    );
    assert!(
        r.e.max_abs <= 1e-4,
        "the 64 nearest composite exactly: {}",
        r.e.max_abs
    );
}

// ---- 5. thickness: σ·l ≫ 1, σ·l ≪ 1, thin shells far away ----

fn shells() -> SceneSpec {
    SceneSpec::new(
        "shells",
        Params::new().with("count", i(3)).with("segments", i(16)),
    )
}

#[test]
fn translucency_sigma_l_huge_gives_zero_not_nan_32px() {
    for sigma in [1e30, 1e300] {
        let p = Params::new()
            .with("effect", s("translucency"))
            .with("sigma", f(sigma));
        let r = run(&shells(), &p, 32);
        let img = r.cap.image.unwrap();
        for (px, c) in img.iter().enumerate() {
            if !r.lists.pixel(px).is_empty() {
                assert_eq!(c[0], 0.0, "σ={sigma}: pixel {px} transmittance {}", c[0]);
                assert_eq!(c[3], 1.0);
            }
        }
    }
}

#[test]
fn translucency_sigma_l_tiny_keeps_the_thickness_32px() {
    // σ = 1e-6: 1 − T ≈ σ·l ≈ 1e-6. In f32, 1 − exp(−x) would keep it to ±6e-8 absolute; the
    // fold's series keeps f32 relative precision (1e-3 allowed), plus the view_z interpolation
    // error at silhouettes (Δl ≤ 2e-3, see tests/effects.rs) times σ: 2e-9 absolute.
    let p = Params::new()
        .with("effect", s("translucency"))
        .with("sigma", f(1e-6));
    let r = run(&shells(), &p, 32);
    let img = r.cap.image.unwrap();
    let scene = shells().build().unwrap();
    let reference = EffectConfig::from_point(&testing::point(&*methods::get("depth_peel"), &p))
        .unwrap()
        .reference(&scene, &r.lists, r.cap.expected);
    let mut checked = 0;
    for (px, (g, want)) in img.iter().zip(&reference).enumerate() {
        if want[3] > 1e-8 {
            let err = (g[3] as f64 - want[3]).abs();
            let bound = 1e-3 * want[3] + 1e-6 * 2e-3;
            assert!(
                err <= bound,
                "pixel {px}: 1 − T = {} vs {} (err {err:.2e} > {bound:.2e})",
                g[3],
                want[3]
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "the shells cover the image");
}

#[test]
fn thin_shells_far_away_stable_thickness_within_bound_naive_not_32px() {
    // 4×4 stacks of 64 nested boxes (walls 0.1) at distance 1e5; σ chosen so σ·l_max = 1.
    // Bound (reasoned, RMS over pixels): every fragment's view_z carries an f32 rounding of
    // about ±ulp(D)/2 (uniform: std ulp(D)/√12), independent across the 2n fragments, so
    // std(Δl) ≈ √(2n/12)·ulp(D) and |ΔT| ≤ σ·|Δl|; we allow 3× that for interpolation. The naive
    // running sum passes through magnitudes up to n·D, whose ulp is n times larger.
    let (n, d) = (64i64, 1e5f64);
    let spec = SceneSpec::new(
        "slabs",
        Params::new()
            .with("count", i(n))
            .with("distance", f(d))
            .with("wall", f(0.1)),
    );
    let scene = spec.build().unwrap();
    let lists = rasterize(&scene, 32, 32);
    let lmax = (0..lists.pixels())
        .map(|p| lists.pixel(p).iter().map(signed_view_z).sum::<f64>())
        .fold(0.0, f64::max);
    let sigma = 1.0 / lmax;
    let ulp_d = (d as f32).next_up() as f64 - d;
    let bound = 3.0 * sigma * (2.0 * n as f64 / 12.0).sqrt() * ulp_d;
    let rmse = |variant: &str| {
        let p = Params::new()
            .with("effect", s("translucency"))
            .with("thickness", s(variant))
            .with("sigma", f(sigma))
            .with("max_layers", i(4096));
        let r = run(&spec, &p, 32);
        assert_eq!(r.lost(), 0, "{variant}: every layer peeled");
        r.e.rmse
    };
    let (stable, naive) = (rmse("stable"), rmse("naive"));
    assert!(
        stable <= bound,
        "stable RMSE {stable:.3e} > bound {bound:.3e}"
    );
    assert!(
        naive > bound,
        "naive RMSE {naive:.3e} within bound {bound:.3e}: the case shows nothing"
    );
}

// ---- 6. alpha = 0, 1, 1e-4 over many layers ----

#[test]
fn alpha_0_1_and_1e4_over_64_layers_composite_exactly_32px() {
    for alpha in [0.0, 1.0, 1e-4] {
        let spec = SceneSpec::new("quads", quads(64).with("alpha", f(alpha)));
        let r = run(
            &spec,
            &Params::new()
                .with("max_layers", i(64))
                .with("occlusion_stop", ParamValue::Bool(false)),
            32,
        );
        assert!(
            r.e.max_abs <= 1e-5,
            "alpha {alpha}: max abs {}",
            r.e.max_abs
        );
    }
}

// ---- 8. degenerate and huge triangles, vertices at ±1e7 ----

#[test]
fn degenerate_and_huge_triangles_render_finite_and_match_32px() {
    for coord in [1e3, 1e7] {
        let spec = SceneSpec::new("extreme", Params::new().with("coord", f(coord)));
        let r = run(&spec, &Params::new(), 32);
        // Triangles with a vertex at ±coord have edges crossing the image: the GPU clips them to
        // its guard band before snapping, the reference snaps the unclipped f64 position, so a
        // pixel on such an edge may differ; allow 2% of pixels, require the rest exact.
        assert!(
            r.e.bad_pixel_frac <= 0.02,
            "coord {coord}: bad pixels {}",
            r.e.bad_pixel_frac
        );
    }
    // At ±1e20 the GPU's f32 guard-band clipping of a view-covering triangle is no longer
    // exact (the suite records the error); the output must still be finite (checked in `run`),
    // and so must the reference (it clips x and y to a guard band in f64 first) and the error.
    let r = run(
        &SceneSpec::new("extreme", Params::new().with("coord", f(1e20))),
        &Params::new(),
        32,
    );
    assert!(r.e.rmse.is_finite(), "reference at 1e20: rmse {}", r.e.rmse);
}

// ---- the suite's own tables through the runner: flags are set, nothing is silent ----

#[test]
fn stability_suite_software_profile_flags_every_known_failure() {
    let gpu = testing::gpu();
    // stability_ci: the stability suite's cases with fewer passes (lavapipe pays per pass).
    let suite = Suite::load("stability_ci").unwrap();
    let all = runner::run_checked(gpu, STUDIES, &suite).unwrap();
    let rows: Vec<&Row> = all
        .iter()
        .filter(|r| !r.get(cols::METHOD).unwrap_or("").starts_with("floor_"))
        .collect();
    for r in &rows {
        let key = r.get(cols::POINT_KEY).unwrap_or("?");
        assert_ne!(
            r.status(),
            Some(Status::Failed),
            "{key}: {:?}",
            r.get(cols::REASON)
        );
        if r.is_ok() {
            let nf: u64 = r
                .get(cols::NON_FINITE)
                .map(|v| v.parse().unwrap())
                .unwrap_or(0);
            assert!(
                nf == 0 || r.get(cols::FLAG).is_some(),
                "{key}: NaN/Inf without a flag"
            );
            assert!(
                r.get(cols::STIFFNESS_VALUE).is_some(),
                "{key}: no stiffness value"
            );
        }
    }
    let flagged = |case: &str, flag: Flag| {
        rows.iter()
            .any(|r| r.get(cols::STABILITY_CASE) == Some(case) && r.has_flag(flag))
    };
    let flags_of = |case: &str| -> Vec<String> {
        rows.iter()
            .filter(|r| r.get(cols::STABILITY_CASE) == Some(case))
            .map(|r| {
                format!(
                    "{}: {}",
                    r.get(cols::METHOD).unwrap_or("?"),
                    r.get(cols::FLAG).unwrap_or("")
                )
            })
            .collect()
    };
    assert!(
        flagged("coplanar", Flag::LostCoplanar),
        "classic peeling's coplanar loss is flagged: {:?}",
        flags_of("coplanar")
    );
    assert!(
        flagged("high_complexity", Flag::Overflow),
        "overflow is flagged"
    );
    assert!(
        flagged("near_far", Flag::Precision),
        "standard-Z depth precision loss is flagged"
    );
}
