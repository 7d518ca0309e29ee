//! Every effect on depth peeling against its f64 CPU reference (bench_core::effects), on
//! lavapipe at 48×48, specialised and uber. Tolerances: max abs error ≤ 1e-4 where the effect
//! reads colour, window depth or ids (the GPU runs the same fold in f32: ~1e-6 per fragment over
//! ≤ 8 fragments; one pixel of different coverage gives an error near 1 and fails). Effects that
//! read interpolated view depth or normals get max abs ≤ 2e-3 and RMSE ≤ 2e-4: the GPU sets up
//! attribute interpolation from unsnapped vertex positions while the reference snaps to 1/256 px,
//! so where view_z changes fast (sphere silhouettes, ~0.5 per pixel) a fragment's view_z differs
//! by up to 0.5/512 ≈ 1e-3, and σ·Δl ≤ 1e-3 with σ ≤ 1.

use bench_core::effects::EffectConfig;
use bench_core::methods;
use bench_core::metrics::{image_error, BAD_PIXEL_TOL};
use bench_core::reference::rasterize;
use bench_core::testing;
use scenarios::{ParamValue, Params, SceneSpec};
use schema::cols;

const W: u32 = 48;

fn s(v: &str) -> ParamValue {
    ParamValue::Str(v.into())
}

/// Renders `scene` with `method` and `params`, returns (max abs, RMSE) vs the reference.
fn err(method: &str, spec: &SceneSpec, params: &Params) -> (f64, f64) {
    let gpu = testing::gpu();
    let scene = spec.build().unwrap();
    let m = methods::get(method);
    let params = &testing::declared(&*m, params);
    let (cap, _) = testing::render(gpu, &scene, &*m, params, W, W);
    let lists = rasterize(&scene, W, W);
    let cfg = EffectConfig::from_point(&testing::point(&*m, params)).unwrap();
    let reference = cfg.reference(&scene, &lists, cap.expected);
    let img = cap.image.unwrap();
    assert_eq!(img.len(), reference.len(), "{}: image size", spec.label());
    let e = image_error(&reference, &img, BAD_PIXEL_TOL);
    assert_eq!(
        e.non_finite,
        0,
        "{} {}: NaN/Inf",
        spec.label(),
        params.label()
    );
    (e.max_abs, e.rmse)
}

/// Depth peeling (specialised and uber), the compute A-buffer (attributes re-derived from the
/// primitive: every effect) and the linked list (one pass; its default compact nodes re-derive
/// attributes from the primitive too).
const RUNS: &[(&str, Option<&str>)] = &[
    ("depth_peel", Some("specialised")),
    ("depth_peel", Some("uber")),
    ("compute_abuffer", None),
    ("linked_list", None),
];

fn check_tol(spec: SceneSpec, params: Params, max_tol: f64, rmse_tol: f64) {
    check_runs(RUNS, spec, params, max_tol, rmse_tol)
}

fn check_runs(
    runs: &[(&str, Option<&str>)],
    spec: SceneSpec,
    params: Params,
    max_tol: f64,
    rmse_tol: f64,
) {
    for &(method, spec_mode) in runs {
        let p = match spec_mode {
            Some(m) => params.clone().with("specialisation", s(m)),
            None => params.clone().with("layers", ParamValue::Int(16)),
        };
        let (m, r) = err(method, &spec, &p);
        assert!(
            m <= max_tol,
            "{method} {} {}: max abs error {m} > {max_tol}",
            spec.label(),
            p.label()
        );
        assert!(
            r <= rmse_tol,
            "{method} {} {}: RMSE {r} > {rmse_tol}",
            spec.label(),
            p.label()
        );
    }
}

fn check(spec: SceneSpec, params: Params) {
    check_tol(spec, params, 1e-4, 1e-4);
}

/// For effects that read interpolated view depth or normals (see the header).
fn check_interp(spec: SceneSpec, params: Params) {
    check_tol(spec, params, 2e-3, 2e-4);
}

fn shells() -> SceneSpec {
    SceneSpec::new(
        "shells",
        Params::new()
            .with("count", ParamValue::Int(3))
            .with("segments", ParamValue::Int(16)),
    )
}

#[test]
fn transparency_48px_matches_reference() {
    check(shells(), Params::new().with("effect", s("transparency")));
}

#[test]
fn translucency_stable_and_naive_48px_match_reference_near_the_eye() {
    for v in ["stable", "naive"] {
        check_interp(
            shells(),
            Params::new()
                .with("effect", s("translucency"))
                .with("sigma", ParamValue::Float(0.8))
                .with("thickness", s(v)),
        );
    }
}

#[test]
fn fresnel_48px_matches_reference() {
    // The linked list's compact nodes (its default) re-derive the normal; its full nodes carry
    // none: it reports fresnel as unsupported for them (below).
    check_runs(
        RUNS,
        shells(),
        Params::new()
            .with("effect", s("fresnel"))
            .with("sigma", ParamValue::Float(0.5)),
        2e-3,
        2e-4,
    );
    let gpu = testing::gpu();
    let ll = methods::get("linked_list");
    let why = ll
        .supports(
            gpu,
            &testing::point(
                &*ll,
                &Params::new()
                    .with("effect", s("fresnel"))
                    .with("node", s("full")),
            ),
        )
        .unwrap_err();
    assert!(why.contains("normal"), "{why}");
}

#[test]
fn csg_and_or_sub_48px_match_reference() {
    for shape in ["sphere", "box"] {
        let spec = SceneSpec::new(
            "csg_pair",
            Params::new()
                .with("shape", s(shape))
                .with("segments", ParamValue::Int(16)),
        );
        for op in ["csg_and", "csg_or", "csg_sub"] {
            check(
                spec.clone(),
                Params::new()
                    .with("effect", s(op))
                    .with("csg_a", ParamValue::Int(0))
                    .with("csg_b", ParamValue::Int(1)),
            );
        }
    }
}

#[test]
fn dof_three_partitions_48px_match_reference() {
    let spec = SceneSpec::new(
        "quads",
        Params::new().with("depth_complexity", ParamValue::Int(6)),
    );
    check(
        spec,
        Params::new()
            .with("effect", s("dof"))
            .with("dof_near", ParamValue::Float(3.6))
            .with("dof_far", ParamValue::Float(4.4)),
    );
}

#[test]
fn effects_differ_from_each_other() {
    // Guards against a fold that ignores EFFECT: translucency and transparency images differ.
    let gpu = testing::gpu();
    let scene = shells().build().unwrap();
    let a = testing::render(
        gpu,
        &scene,
        &*methods::get("depth_peel"),
        &Params::new().with("effect", s("transparency")),
        W,
        W,
    )
    .0;
    let b = testing::render(
        gpu,
        &scene,
        &*methods::get("depth_peel"),
        &Params::new().with("effect", s("translucency")),
        W,
        W,
    )
    .0;
    assert_ne!(a.image, b.image);
}

// ---- the effect axis in the methods study ----

fn sweep(text: &str) -> bench_core::Result<Vec<bench_core::record::Row>> {
    bench_core::runner::run_suite(testing::gpu(), text, "test")
}

#[test]
fn effect_axis_rows_are_judged_per_effect_and_a_method_without_a_fold_is_skipped_16px() {
    let rows = sweep(
        r#"
        resolutions = [[16, 16]]
        [timing]
        min_samples = 1
        max_samples = 1
        warmup_frames = 0
        [[study]]
        kind = "methods"
        methods = ["depth_peel", "floor_opaque"]
        axes = { effect = ["transparency", "csg_and"], specialisation = ["specialised", "uber"] }
        [[study.scenes]]
        generator = "csg_pair"
        segments = 8
    "#,
    )
    .unwrap();
    let get = |m: &str, e: &str, sp: Option<&str>| {
        rows.iter()
            .find(|r| {
                r.get(cols::METHOD) == Some(m)
                    && r.get(cols::EFFECT) == Some(e)
                    && sp.is_none_or(|sp| r.get(cols::SPECIALISATION) == Some(sp))
            })
            .unwrap_or_else(|| panic!("no row {m} {e} {sp:?}"))
    };
    let csg = get("depth_peel", "csg_and", Some("specialised"));
    assert_eq!(csg.get(cols::STATUS), Some("ok"));
    assert_eq!(csg.get(cols::PAYLOAD), Some("depth_id"));
    assert_eq!(
        csg.get(cols::MAX_ABS_ERR)
            .map(|v| v.parse::<f64>().unwrap() <= 1e-4),
        Some(true)
    );
    assert_eq!(
        get("depth_peel", "csg_and", Some("uber")).get(cols::PAYLOAD),
        Some("all")
    );
    let floor = get("floor_opaque", "csg_and", None);
    assert_eq!(floor.get(cols::STATUS), Some("skipped"));
    assert!(
        floor.get(cols::REASON).unwrap().contains("csg_and"),
        "{:?}",
        floor.get(cols::REASON)
    );
}

#[test]
fn an_unknown_effect_in_a_suite_is_an_error_naming_it() {
    let err = sweep(
        r#"
        [[study]]
        kind = "methods"
        methods = ["depth_peel"]
        axes = { effect = ["glow"] }
        [[study.scenes]]
        generator = "quads"
    "#,
    )
    .unwrap_err();
    assert!(err.to_string().contains("glow"), "{err}");
}
