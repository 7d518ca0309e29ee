//! The `continuum-ci` suite (issue 16) through the runner on lavapipe: every exact and
//! approximate method of the continuum runs (no `failed` row), and every approximate method's
//! rows carry finite errors against the ground truth, so the continuum's fronts can be drawn
//! from them. (The suite's structure is checked by `mfx check`; this runs it.)

use mfx_multifragment::STUDIES;
use std::collections::BTreeSet;

use bench_core::runner::{expand, run_suite};
use mfx_multifragment::methods;
use mfx_multifragment::testing;
use schema::{cols, Status};

const SUITE: &str = include_str!("../../../scenarios/suites/continuum-ci.toml");

#[test]
fn continuum_ci_runs_every_method_and_every_approximate_row_has_finite_errors() {
    let t = std::time::Instant::now();
    let rows =
        run_suite(testing::gpu(), STUDIES, SUITE, "continuum-ci.toml").expect("the suite runs");
    eprintln!(
        "continuum-ci: {} rows in {:.1} s",
        rows.len(),
        t.elapsed().as_secs_f64()
    );
    let mut seen = BTreeSet::new();
    for r in &rows {
        let method = r.get(cols::METHOD).unwrap_or("?").to_string();
        let status = r.status();
        let what = format!(
            "{method} on {} ({})",
            r.get(cols::SCENE_LABEL).unwrap_or("?"),
            r.get(cols::POINT_KEY).unwrap_or("?")
        );
        assert_ne!(
            status,
            Some(Status::Failed),
            "{what}: {}",
            r.get(cols::REASON).unwrap_or("")
        );
        if method.starts_with("floor_") {
            continue;
        }
        assert_eq!(
            status,
            Some(Status::Ok),
            "{what}: {}",
            r.get(cols::REASON).unwrap_or("")
        );
        seen.insert(method.clone());
        if !methods::get(&method).exact() {
            for c in [cols::RMSE, cols::MAX_ABS_ERR] {
                let v = r.get_f(c).unwrap_or(f64::NAN);
                assert!(v.is_finite(), "{what}: {} = {v}", c.name);
            }
            assert_eq!(r.get(cols::NON_FINITE), Some("0"), "{what}");
        }
    }
    let want: BTreeSet<String> = [
        "depth_peel",
        "compute_abuffer",
        "linked_list",
        "kbuffer_rmw",
        "kbuffer_atomic",
        "hybrid",
        "mlab",
        "mlab_ideal",
        "adaptive",
        "adaptive_ideal",
        "wboit",
        "moments",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    assert_eq!(seen, want, "every continuum method has ok rows");
}

#[test]
fn continuum_sweeps_every_method_on_the_four_scenes_at_1024_and_the_opacity_sweep() {
    let text = include_str!("../../../scenarios/suites/continuum.toml");
    let suite = scenarios::Suite::parse(text, "continuum.toml").expect("parses");
    assert!(
        bench_core::check::check_suite(STUDIES, &suite).is_empty(),
        "checks clean"
    );
    let groups = expand(STUDIES, &suite, false).expect("expands");
    let main: Vec<_> = groups.iter().filter(|g| g.study_index == 0).collect();
    let scenes: BTreeSet<String> = main.iter().map(|g| g.scene.generator.clone()).collect();
    assert_eq!(
        scenes,
        ["grass", "hair", "particles", "shells"]
            .map(String::from)
            .into(),
        "the four scenes"
    );
    for g in &main {
        assert_eq!((g.width, g.height), (1024, 1024));
        let m: BTreeSet<&str> = g.points.iter().map(|p| p.method.as_str()).collect();
        for want in [
            "mlab",
            "mlab_ideal",
            "adaptive",
            "adaptive_ideal",
            "hybrid",
            "moments",
            "wboit",
        ] {
            assert!(m.contains(want), "{want} in {}", g.scene.label());
        }
        let ks: BTreeSet<String> = g
            .points
            .iter()
            .filter(|p| p.method == "mlab")
            .map(|p| p.point.get("layers").unwrap().to_string())
            .collect();
        assert_eq!(ks, ["1", "2", "4", "8"].map(String::from).into());
    }
    let alphas: BTreeSet<String> = groups
        .iter()
        .filter(|g| g.study_index >= 2)
        .map(|g| g.scene.params.get("alpha").unwrap().to_string())
        .collect();
    assert_eq!(alphas.len(), 5, "{alphas:?}");
    assert!(
        alphas.contains("0.05") && alphas.contains("0.95"),
        "{alphas:?}"
    );
}
