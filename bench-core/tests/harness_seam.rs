//! The seam the crate split (issue 40) cuts along: no harness module imports a study module.
//! The harness (device, timing, rows, runner, floors, the binding table, the `Study` trait)
//! times and records whatever a study hands it and names no study; the studies (the
//! multi-fragment methods with their reference, judge, effects and twins; shading; shadows;
//! geometry) build on it. Until the studies are crates of their own, this test is the boundary.

#[path = "../../tests/support/module_graph.rs"]
mod module_graph;

use module_graph::{crate_files, graph_of};

/// Top-level modules of the studies (and `studies/<kind>` below the `studies` trait module).
const STUDY: &[&str] = &[
    "aa",
    "effects",
    "judge",
    "method",
    "methods",
    "metrics",
    "oit",
    "reference",
    "shading",
];

/// Test scaffolding that reaches both sides until the move splits it.
const NEITHER: &[&str] = &["testing"];

fn is_study(m: &[String]) -> bool {
    match m.first().map(String::as_str) {
        Some("studies") => m.len() > 1,
        Some(top) => STUDY.contains(&top),
        None => false,
    }
}

#[test]
fn no_harness_module_imports_a_study_module() {
    let g = graph_of(&crate_files(env!("CARGO_MANIFEST_DIR")));
    let mut bad = Vec::new();
    let mut harness = 0;
    for (from, to) in &g {
        if is_study(from) || from.first().is_some_and(|t| NEITHER.contains(&t.as_str())) {
            continue;
        }
        harness += 1;
        for t in to.iter().filter(|t| is_study(t)) {
            bad.push(format!("{} → {}", from.join("/"), t.join("/")));
        }
    }
    assert!(harness >= 20, "found only {harness} harness files");
    assert!(
        bad.is_empty(),
        "harness modules import studies:\n{}",
        bad.join("\n")
    );
}
