//! The suites this work added (`perf-abuffer`, `scaling`) expand into the points their
//! descriptions promise, with axis values the methods accept and scenes of the stated sizes.

use mfx_multifragment::STUDIES;
use scenarios::suite::Suite;
use scenarios::ParamValue::Int;
use scenarios::SceneSpec;

use bench_core::runner::expand;
use bench_core::study::Group;
use mfx_multifragment::testing::scene;

fn load(name: &str) -> Vec<Group> {
    let path = format!(
        "{}/../../scenarios/suites/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let suite = Suite::load(&path).expect("the suite parses");
    expand(STUDIES, &suite, false).expect("the suite expands")
}

fn int(s: &SceneSpec, k: &str) -> i64 {
    match s.params.get(k) {
        Some(Int(i)) => *i,
        other => panic!("{}: {k} = {other:?}", s.label()),
    }
}

#[test]
fn perf_abuffer_sweeps_the_full_product_of_both_methods_axes() {
    let groups = load("perf-abuffer");
    // 5 scenes × 512², 1024², 2048².
    assert_eq!(groups.len(), 15);
    for g in &groups {
        let ca: Vec<_> = g
            .points
            .iter()
            .filter(|p| p.method == "compute_abuffer")
            .collect();
        let ll: Vec<_> = g
            .points
            .iter()
            .filter(|p| p.method == "linked_list")
            .collect();
        assert_eq!((ca.len(), ll.len()), (8, 4), "{}", g.scene.label());
        let mut seen = std::collections::BTreeSet::new();
        for p in &ca {
            let v = |a: &str| p.point.get(a).map(|v| v.to_string()).unwrap_or_default();
            seen.insert((v("transform"), v("coverage"), v("resolve_sort")));
        }
        assert_eq!(seen.len(), 8, "every transform × coverage × resolve_sort");
        let mut seen = std::collections::BTreeSet::new();
        for p in &ll {
            let v = |a: &str| p.point.get(a).map(|v| v.to_string()).unwrap_or_default();
            seen.insert((v("pool"), v("pool_slack"), v("node")));
        }
        assert_eq!(seen.len(), 4, "every pool × node");
    }
    assert!(groups
        .iter()
        .any(|g| g.scene.params.get("path").map(|p| p.to_string())
            == Some("models/bunny-stack16.obj".into())));
}

#[test]
fn scaling_spans_the_stated_triangles_resolutions_and_depth_complexities() {
    // shells: count · segments · (segments − 2) triangles (segments/2 rings of 2 per quad,
    // one at each pole).
    let s = scene("shells", &[("count", Int(3)), ("segments", Int(24))]);
    assert_eq!(s.mesh.triangle_count(), 3 * 24 * 22);
    let tris = |s: &SceneSpec| {
        let seg = int(s, "segments");
        (int(s, "count") * seg * (seg - 2)) as f64
    };
    let groups = load("scaling");
    let in_study = |i: usize| groups.iter().filter(move |g| g.study_index == i);
    for g in &groups {
        let methods: Vec<_> = g.points.iter().map(|p| p.method.as_str()).collect();
        if g.study_index == 2 {
            continue; // the 4K study, below
        }
        assert_eq!(
            methods,
            ["depth_peel", "linked_list", "compute_abuffer", "wboit"],
            "{}",
            g.scene.label()
        );
    }
    // 4K (3840×2160) with 16 layers, issue 34 goal 3: every bounded capture beside the exact
    // ones, the atomic k-buffer's uber entries too (split over bindings).
    let k4: Vec<_> = in_study(2).collect();
    assert_eq!(k4.len(), 1);
    assert_eq!((k4[0].width, k4[0].height), (3840, 2160));
    let m: Vec<_> = k4[0].points.iter().map(|p| p.method.as_str()).collect();
    for want in [
        "depth_peel",
        "kbuffer_atomic",
        "kbuffer_rmw",
        "hybrid",
        "mlab",
        "adaptive",
        "linked_list",
        "compute_abuffer",
        "wboit",
    ] {
        assert!(m.contains(&want), "{want} not at 4K: {m:?}");
    }
    // Triangles 0.25M → 16M at 16 layers, doubling.
    let t: Vec<f64> = in_study(0).map(|g| tris(&g.scene)).collect();
    assert_eq!(t.len(), 7);
    for (k, n) in t.iter().enumerate() {
        let want = 0.25e6 * 2f64.powi(k as i32);
        assert!(
            (n / want - 1.0).abs() < 0.05,
            "{n} triangles, want ≈ {want}"
        );
    }
    // Resolutions 512² → 4096².
    let r: Vec<u32> = in_study(1).map(|g| g.width).collect();
    assert_eq!(r, [512, 1024, 2048, 4096]);
    // Depth complexity 8 → 256 (2 · count) at ≈ 1M triangles.
    for (k, g) in in_study(3).enumerate() {
        assert_eq!(2 * int(&g.scene, "count"), 8 << k);
        let n = tris(&g.scene);
        assert!(
            (n / 1e6 - 1.0).abs() < 0.05,
            "{}: {n} triangles",
            g.scene.label()
        );
    }
    assert_eq!(in_study(3).count(), 6);
}

#[test]
fn perf_binned_puts_both_captures_and_the_methods_choice_on_every_scene_and_resolution() {
    let groups = load("perf-binned");
    // quads ×3, shells ×4, grass ×2, the bunnies: 10 scenes × 512², 1024², 2048².
    assert_eq!(groups.len(), 30);
    for g in &groups {
        let captures: std::collections::BTreeSet<String> = g
            .points
            .iter()
            .filter(|p| p.method == "compute_abuffer")
            .map(|p| {
                p.point
                    .get("capture")
                    .map(|v| v.to_string())
                    .unwrap_or_default()
            })
            .collect();
        let want: std::collections::BTreeSet<String> = ["auto", "pixels", "tiles"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(captures, want, "{}", g.scene.label());
    }
}

#[test]
fn stacked_scans_time_the_linked_list_and_the_compute_abuffer_on_two_stacked_meshes() {
    let groups = load("stacked-scans");
    // The bunnies and the ogres × 512², 1024², 2048².
    assert_eq!(groups.len(), 6);
    let paths: std::collections::BTreeSet<String> = groups
        .iter()
        .map(|g| match g.scene.params.get("path") {
            Some(scenarios::ParamValue::Str(s)) => s.clone(),
            other => panic!("{}: path = {other:?}", g.scene.label()),
        })
        .collect();
    let want: std::collections::BTreeSet<String> =
        ["models/bunny-stack16.obj", "models/ogre-stack16.obj"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    assert_eq!(paths, want);
    // The runner adds each group's floors (x_blend, x_floor) to these.
    for g in &groups {
        let methods: std::collections::BTreeSet<&str> =
            g.points.iter().map(|p| p.method.as_str()).collect();
        let want: std::collections::BTreeSet<&str> =
            ["linked_list", "compute_abuffer"].into_iter().collect();
        assert_eq!(methods, want, "{}", g.scene.label());
    }
}

#[test]
fn perf_issue41_crosses_every_axis_of_the_ab_on_every_scene_and_resolution() {
    let path = format!(
        "{}/../../scenarios/suites/perf-issue41.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    // Every key and axis value is declared; the stacks are baked on the device machine only.
    let problems: Vec<_> = bench_core::check::check_suite(STUDIES, &Suite::load(&path).unwrap())
        .into_iter()
        .filter(|p| !p.message.contains("not found"))
        .collect();
    assert!(problems.is_empty(), "{problems:?}");
    let groups = load("perf-issue41");
    // quads ×3, shells ×4, grass ×2, the two stacks: 11 scenes × 512², 1024², 2048².
    assert_eq!(groups.len(), 33);
    for g in &groups {
        let of = |m: &'static str| g.points.iter().filter(move |p| p.method == m);
        let ca: std::collections::BTreeSet<String> = of("compute_abuffer")
            .map(|p| {
                ["attributes", "bindings", "capture"]
                    .map(|k| p.point.get(k).map(|v| v.to_string()).unwrap_or_default())
                    .join(",")
            })
            .collect();
        assert_eq!(ca.len(), 2 * 2 * 3, "{}: {ca:?}", g.scene.label());
        let pools: std::collections::BTreeSet<String> = of("linked_list")
            .map(|p| {
                p.point
                    .get("pool")
                    .map(|v| v.to_string())
                    .unwrap_or_default()
            })
            .collect();
        assert_eq!(pools.len(), 2, "{}: {pools:?}", g.scene.label());
    }
}
