//! The harness's files form no dependency cycle, nor do its top-level modules: each module may
//! use only the modules below it, so a reader can learn the crate bottom-up (gpu → gpu_scene →
//! timing → timed → measure → record → study → runner). That the harness imports no study is
//! no longer a test: it depends on no study crate. The guard is shared:
//! tests/support/module_graph.rs.

#[path = "../../tests/support/module_graph.rs"]
mod module_graph;

use module_graph::{coarsen, crate_files, cycle, graph_of};

#[test]
fn bench_core_has_no_file_level_cycle() {
    module_graph::assert_no_file_cycle(env!("CARGO_MANIFEST_DIR"), 20);
}

#[test]
fn bench_core_modules_have_no_dependency_cycle() {
    let g = coarsen(&graph_of(&crate_files(env!("CARGO_MANIFEST_DIR"))), 1);
    if let Some(c) = cycle(&g) {
        panic!("bench-core module cycle: {}", c.join(" → "));
    }
}
