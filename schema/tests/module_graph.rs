//! schema's files form no dependency cycle (the shared guard: tests/support/module_graph.rs).

#[path = "../../tests/support/module_graph.rs"]
mod module_graph;

#[test]
fn schema_has_no_file_level_cycle() {
    module_graph::assert_no_file_cycle(env!("CARGO_MANIFEST_DIR"), 2);
}
