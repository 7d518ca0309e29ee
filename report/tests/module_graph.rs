//! The report's files form no dependency cycle, so it reads as stages: data (data, labels,
//! pareto, cells) → charts (charts/, points) → figures per study (studies/) → pages (summary,
//! html, compare, ab, flip, lib). The guard is shared: tests/support/module_graph.rs.

#[path = "../../tests/support/module_graph.rs"]
mod module_graph;

#[test]
fn the_report_has_no_file_level_cycle() {
    module_graph::assert_no_file_cycle(env!("CARGO_MANIFEST_DIR"), 10);
}
