//! The root package's files (src/main.rs, src/sweep.rs) form no dependency cycle, and the
//! shared guard (tests/support/module_graph.rs, included by every crate's
//! `tests/module_graph.rs`) sees what it must.

#[path = "support/module_graph.rs"]
mod module_graph;

use module_graph::{coarsen, cycle, graph_of};

#[test]
fn mfx_has_no_file_level_cycle() {
    module_graph::assert_no_file_cycle(env!("CARGO_MANIFEST_DIR"), 2);
}

fn p(s: &str) -> Vec<String> {
    s.split('/')
        .filter(|x| !x.is_empty())
        .map(String::from)
        .collect()
}

#[test]
fn the_guard_sees_a_cycle_through_braces_and_super() {
    let files = vec![
        (p("a"), "use crate::{b::f, c};".to_string()),
        (p("b"), "fn f() { crate::d::x::g() }".to_string()),
        (p("c"), String::new()),
        (
            p("d/x"),
            "// crate::c in a comment is no edge\nuse super::super::a;".to_string(),
        ),
        (p("d"), String::new()),
    ];
    // d/x: `super::super::a` is the root's `a`.
    let g = graph_of(&files);
    assert!(g[&p("a")].contains(&p("b")) && g[&p("a")].contains(&p("c")));
    let dx = &g[&p("d/x")];
    assert!(dx.contains(&p("a")) && !dx.contains(&p("c")));
    // a → b → d/x → a: a file-level cycle, and at depth 1 (a → b → d → a) a module cycle.
    assert!(cycle(&g).is_some());
    assert!(cycle(&coarsen(&g, 1)).is_some());
    let two = vec![
        (p("a"), "use crate::b;".to_string()),
        (p("b"), "use crate::a::thing;".to_string()),
    ];
    assert!(cycle(&graph_of(&two)).is_some());
    assert!(cycle(&graph_of(&files[2..3])).is_none());
    // Files of one module using each other are no cycle between modules.
    let within = vec![
        (p("m/x"), "use super::y;".to_string()),
        (p("m/y"), "use crate::m::z;".to_string()),
        (p("m/z"), "use crate::n;".to_string()),
        (p("n"), String::new()),
    ];
    assert!(cycle(&coarsen(&graph_of(&within), 1)).is_none());
}
