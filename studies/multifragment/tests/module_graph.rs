//! mfx-multifragment's files form no dependency cycle, nor do its top-level modules, so the crate reads
//! bottom-up. The guard is shared: tests/support/module_graph.rs.

#[path = "../../../tests/support/module_graph.rs"]
mod module_graph;

use module_graph::{coarsen, crate_files, cycle, graph_of};

#[test]
fn multifragment_has_no_file_level_cycle() {
    module_graph::assert_no_file_cycle(env!("CARGO_MANIFEST_DIR"), 40);
}

#[test]
fn multifragment_modules_have_no_dependency_cycle() {
    let g = coarsen(&graph_of(&crate_files(env!("CARGO_MANIFEST_DIR"))), 1);
    if let Some(c) = cycle(&g) {
        panic!("mfx-multifragment module cycle: {}", c.join(" → "));
    }
}
