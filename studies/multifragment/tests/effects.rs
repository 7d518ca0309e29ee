//! Every effect on depth peeling against its f64 CPU reference (mfx_multifragment::effects), on
//! lavapipe at 48×48, specialised and uber. Tolerances: max abs error ≤ 1e-4 where the effect
//! reads colour, window depth or ids (the GPU runs the same fold in f32: ~1e-6 per fragment over
//! ≤ 8 fragments; one pixel of different coverage gives an error near 1 and fails). Effects that
//! read interpolated view depth or normals get max abs ≤ 2e-3 and RMSE ≤ 2e-4: the GPU sets up
//! attribute interpolation from unsnapped vertex positions while the reference snaps to 1/256 px,
//! so where view_z changes fast (sphere silhouettes, ~0.5 per pixel) a fragment's view_z differs
//! by up to 0.5/512 ≈ 1e-3, and σ·Δl ≤ 1e-3 with σ ≤ 1.

use mfx_multifragment::effects::EffectConfig;
use mfx_multifragment::methods;
use mfx_multifragment::testing;
use mfx_multifragment::STUDIES;
use mfx_reference::metrics::{image_error, BAD_PIXEL_TOL};
use mfx_reference::rasterize;
use scenarios::{ParamValue, Params, SceneSpec};
use schema::{cols, Status};

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
/// attributes from the primitive too). The k-buffers (specialised and uber slots, default
/// k = 8 ≥ these scenes' 6 layers, so the k nearest are all: judged like the exact methods; their
/// normal is packed in 4 bytes, < 2e-4 rad, so Fresnel's Schlick term moves by < 1e-3 < 2e-3).
const RUNS: &[(&str, Option<&str>)] = &[
    ("depth_peel", Some("specialised")),
    ("depth_peel", Some("uber")),
    ("kbuffer_rmw", Some("specialised")),
    ("kbuffer_rmw", Some("uber")),
    ("kbuffer_atomic", Some("specialised")),
    ("kbuffer_atomic", Some("uber")),
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
    bench_core::runner::run_suite(testing::gpu(), STUDIES, text, "test")
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
    assert_eq!(csg.status(), Some(Status::Ok));
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
    assert_eq!(floor.status(), Some(Status::Skipped));
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

// ---- bucket methods: translucency and fresnel on (depth, normal) pairs ----

/// Renders `method` and compares it with the reference only where it captured every fragment
/// (counts = true depth complexity): elsewhere fragments collided, which the row reports
/// (`collision_fragments`, flag `collision`) and this checks. Returns the fraction of covered
/// pixels judged, so a test cannot pass on an empty set.
fn bucket_err(method: &str, spec: &SceneSpec, params: &Params, tol: f64) -> f64 {
    let gpu = testing::gpu();
    let scene = spec.build().unwrap();
    let m = methods::get(method);
    let params = &testing::declared(&*m, params);
    let (cap, _) = testing::render(gpu, &scene, &*m, params, W, W);
    let lists = rasterize(&scene, W, W);
    let cfg = EffectConfig::from_point(&testing::point(&*m, params)).unwrap();
    let reference = cfg.reference(&scene, &lists, cap.expected);
    let img = cap.image.as_ref().unwrap();
    let counts = cap.counts.as_ref().unwrap();
    let dc = lists.depth_complexity();
    let (mut judged, mut covered, mut lost) = (0usize, 0usize, 0u64);
    for p in 0..lists.pixels() {
        if dc[p] == 0 {
            continue;
        }
        covered += 1;
        lost += dc[p].saturating_sub(counts[p]) as u64;
        if counts[p] != dc[p] {
            continue;
        }
        judged += 1;
        for c in 0..4 {
            let e = (reference[p][c] - img[p][c] as f64).abs();
            assert!(
                e <= tol,
                "{method} {}: pixel {p} (nothing collided) error {e} > {tol}",
                params.label()
            );
        }
    }
    assert_eq!(
        cap.collision_fragments,
        Some(lost),
        "{method}: reported collisions"
    );
    assert_eq!(!cap.flag.is_empty(), lost > 0, "{method}: collision flag");
    judged as f64 / covered as f64
}

#[test]
fn bucket_translucency_and_fresnel_48px_match_reference_where_nothing_collided() {
    // Tolerance 2e-3 as for the exact methods' interpolated view depth (header); the depth
    // channel is the f32 view depth with the facing in its last bit (1 ulp), and the normal is
    // packed in 4 bytes (octahedral 15:15, < 2e-4 rad: Schlick moves < 1e-3).
    let runs: &[(&str, &str)] = &[
        ("bdp", "translucency"),
        ("bdp", "fresnel"),
        ("bdp2", "translucency"),
        ("adp", "translucency"),
        ("adp", "fresnel"),
    ];
    // Both depth-range passes: seeds-buckets' Fig. 1.3 point is bdp translucency with 16
    // single buckets and the bounding-box range (GPU Pro ch. 1 §1.3).
    for range in ["mesh", "bounding_box"] {
        for &(method, effect) in runs {
            let p = Params::new()
                .with("effect", s(effect))
                .with("sigma", ParamValue::Float(0.8))
                .with("bucket_count", ParamValue::Int(16))
                .with("bucket_pairing", s("single"))
                .with("range_pass", s(range));
            let judged = bucket_err(method, &shells(), &p, 2e-3);
            // 3 shells, ≤ 6 layers in 16 buckets (adp: 1024 bins): most pixels collide nowhere.
            assert!(
                judged >= 0.5,
                "{method} {effect} {range}: only {judged} of covered pixels judged"
            );
        }
    }
}

#[test]
fn bucket_effects_they_cannot_keep_are_skipped_with_the_reason() {
    let gpu = testing::gpu();
    let why = |method: &str, p: Params| {
        let m = methods::get(method);
        m.supports(gpu, &testing::point(&*m, &p)).unwrap_err()
    };
    let e = why("adp", Params::new().with("effect", s("csg_and")));
    assert!(e.contains("csg_and"), "{e}");
    let e = why(
        "bdp",
        Params::new()
            .with("effect", s("translucency"))
            .with("bucket_count", ParamValue::Int(32)),
    );
    assert!(e.contains("64 float channels"), "{e}");
    let e = why("bdp2", Params::new().with("effect", s("fresnel")));
    assert!(e.contains("fresnel"), "{e}");
}
