//! bench-core's files form no dependency cycle, nor do its top-level modules: each module may
//! use only the modules below it, so a reader can learn the crate bottom-up (schema → gpu →
//! gpu_util → reference → effects → methods → measure → studies → runner). The guard is
//! shared: tests/support/module_graph.rs.

#[path = "../../tests/support/module_graph.rs"]
mod module_graph;

use module_graph::{coarsen, crate_files, cycle, graph_of};

#[test]
fn bench_core_has_no_file_level_cycle() {
    module_graph::assert_no_file_cycle(env!("CARGO_MANIFEST_DIR"), 30);
}

#[test]
fn bench_core_modules_have_no_dependency_cycle() {
    let g = coarsen(&graph_of(&crate_files(env!("CARGO_MANIFEST_DIR"))), 1);
    if let Some(c) = cycle(&g) {
        panic!("bench-core module cycle: {}", c.join(" → "));
    }
}
