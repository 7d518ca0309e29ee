//! scenarios' files form no dependency cycle (the shared guard: tests/support/module_graph.rs).
//! The scene types and the loaders' shared geometry live in scenes/scene.rs, below both the
//! builder (scenes/mod.rs) and the loaders (obj, ply, gltf) that it calls.

#[path = "../../tests/support/module_graph.rs"]
mod module_graph;

#[test]
fn scenarios_has_no_file_level_cycle() {
    module_graph::assert_no_file_cycle(env!("CARGO_MANIFEST_DIR"), 10);
}
