//! The `continuum-ci` suite (issue 16) through the runner on lavapipe: every exact and
//! approximate method of the continuum runs (no `failed` row), and every approximate method's
//! rows carry finite errors against the ground truth, so the continuum's fronts can be drawn
//! from them. (The suite's structure is checked by `mfx check`; this runs it.)

use std::collections::BTreeSet;

use bench_core::methods;
use bench_core::runner::run_suite;
use bench_core::testing;
use schema::cols;

const SUITE: &str = include_str!("../../scenarios/suites/continuum-ci.toml");

#[test]
fn continuum_ci_runs_every_method_and_every_approximate_row_has_finite_errors() {
    let t = std::time::Instant::now();
    let rows = run_suite(testing::gpu(), SUITE, "continuum-ci.toml").expect("the suite runs");
    eprintln!(
        "continuum-ci: {} rows in {:.1} s",
        rows.len(),
        t.elapsed().as_secs_f64()
    );
    let mut seen = BTreeSet::new();
    for r in &rows {
        let method = r.get(cols::METHOD).unwrap_or("?").to_string();
        let status = r.get(cols::STATUS).unwrap_or("?");
        let what = format!(
            "{method} on {} ({})",
            r.get(cols::SCENE_LABEL).unwrap_or("?"),
            r.get(cols::POINT_KEY).unwrap_or("?")
        );
        assert_ne!(
            status,
            "failed",
            "{what}: {}",
            r.get(cols::REASON).unwrap_or("")
        );
        if method.starts_with("floor_") {
            continue;
        }
        assert_eq!(
            status,
            "ok",
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
