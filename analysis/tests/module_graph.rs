//! The analysis crate's files form no dependency cycle: data → verdict; data → bands → ab →
//! calibrate. The guard is shared: tests/support/module_graph.rs.

#[path = "../../tests/support/module_graph.rs"]
mod module_graph;

#[test]
fn the_analysis_has_no_file_level_cycle() {
    module_graph::assert_no_file_cycle(env!("CARGO_MANIFEST_DIR"), 4);
}
