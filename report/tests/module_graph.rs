//! The report's files form no dependency cycle, so it reads as stages: data (data, labels,
//! pareto, cells) → charts (charts/, points) → figures per study (studies/) → pages (summary,
//! html, compare, ab, flip, lib). Nodes are files; an edge is a `crate::a::b` or `super::b`
//! path in a file's code (comments skipped, tests included) resolved to the file that defines
//! it. A parent's `mod child;` is not an edge.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module path of a file under src (`studies/methods.rs` → ["studies", "methods"]).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| {
            c.as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string()
        })
        .collect();
    if parts.last().is_some_and(|l| l == "mod" || l == "lib") {
        parts.pop();
    }
    parts
}

/// Code without line comments.
fn code(text: &str) -> String {
    text.lines()
        .map(|l| l.find("//").map_or(l, |i| &l[..i]))
        .collect::<Vec<_>>()
        .join("\n")
}

fn ident(s: &str) -> String {
    s.chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// Every path that follows `prefix` (`crate::` or `super::`), as segments; a brace group
/// yields each of its top-level members.
fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        // `super::` inside `crate::…::super::` cannot occur; `xsuper::` is not `super::`.
        let before = rest[..i].chars().last();
        rest = &rest[i + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let mut segs = Vec::new();
        let mut r = rest;
        loop {
            if let Some(body) = r.strip_prefix('{') {
                let mut depth = 1;
                let mut end = body.len();
                for (j, ch) in body.char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = j;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                let mut d = 0;
                let mut part = String::new();
                for ch in body[..end].chars().chain(std::iter::once(',')) {
                    match ch {
                        '{' => d += 1,
                        '}' => d -= 1,
                        _ => {}
                    }
                    if ch == ',' && d == 0 {
                        let mut s = segs.clone();
                        s.extend(part.trim().split("::").map(ident).filter(|x| !x.is_empty()));
                        out.push(s);
                        part.clear();
                    } else {
                        part.push(ch);
                    }
                }
                segs.clear();
                break;
            }
            let id = ident(r);
            if id.is_empty() {
                break;
            }
            r = &r[id.len()..];
            segs.push(id);
            match r.strip_prefix("::") {
                Some(n) => r = n,
                None => break,
            }
        }
        if !segs.is_empty() {
            out.push(segs);
        }
    }
    out
}

/// The file (by module path) that the longest prefix of `segs` names.
fn resolve(modules: &BTreeSet<Vec<String>>, segs: &[String]) -> Option<Vec<String>> {
    (1..=segs.len())
        .rev()
        .map(|n| segs[..n].to_vec())
        .find(|p| modules.contains(p))
}

fn cycle(graph: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Option<Vec<String>> {
    // Depth-first search with colours; returns one cycle as "a → b → a".
    fn visit(
        n: &Vec<String>,
        g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        state: &mut BTreeMap<Vec<String>, u8>,
        stack: &mut Vec<Vec<String>>,
    ) -> Option<Vec<String>> {
        state.insert(n.clone(), 1);
        stack.push(n.clone());
        for m in g.get(n).into_iter().flatten() {
            match state.get(m).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|s| s == m).unwrap();
                    let mut c: Vec<String> = stack[at..].iter().map(|s| s.join("/")).collect();
                    c.push(m.join("/"));
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(m, g, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(n.clone(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        if state.get(n).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(n, graph, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

fn graph_of(files: &[(Vec<String>, String)]) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(m, _)| m.clone()).collect();
    let mut graph = BTreeMap::new();
    for (m, text) in files {
        let c = code(text);
        let mut edges = BTreeSet::new();
        for segs in paths_after(&c, "crate::") {
            if let Some(t) = resolve(&modules, &segs) {
                edges.insert(t);
            }
        }
        // `super::` from a file's own test module means the file itself; from `a/b.rs` it means `a`.
        for segs in paths_after(&c, "super::") {
            let mut full = m[..m.len().saturating_sub(1)].to_vec();
            let mut segs = segs.as_slice();
            while segs.first().is_some_and(|s| s == "super") {
                full.pop();
                segs = &segs[1..];
            }
            full.extend(segs.iter().cloned());
            if let Some(t) = resolve(&modules, &full) {
                edges.insert(t);
            }
        }
        edges.remove(m);
        graph.insert(m.clone(), edges);
    }
    graph
}

#[test]
fn the_report_has_no_file_level_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut paths = Vec::new();
    rust_files(&src, &mut paths);
    let files: Vec<(Vec<String>, String)> = paths
        .iter()
        .map(|p| (module_path(&src, p), std::fs::read_to_string(p).unwrap()))
        .collect();
    let graph = graph_of(&files);
    assert!(graph.len() > 10, "found only {} files", graph.len());
    if let Some(c) = cycle(&graph) {
        panic!("file-level cycle in the report crate: {}", c.join(" → "));
    }
}

#[test]
fn the_guard_sees_a_cycle_through_braces_and_super() {
    let files = vec![
        (vec!["a".to_string()], "use crate::{b::f, c};".to_string()),
        (
            vec!["b".to_string()],
            "fn f() { crate::d::x::g() }".to_string(),
        ),
        (vec!["c".to_string()], String::new()),
        (
            vec!["d".to_string(), "x".to_string()],
            "// crate::c in a comment is no edge\nuse super::super::a;".to_string(),
        ),
        (vec!["d".to_string()], String::new()),
    ];
    // d/x: `super::super::a` is the root's `a`.
    let g = graph_of(&files);
    assert!(g[&vec!["a".to_string()]].contains(&vec!["b".to_string()]));
    assert!(g[&vec!["a".to_string()]].contains(&vec!["c".to_string()]));
    let dx = &g[&vec!["d".to_string(), "x".to_string()]];
    assert!(dx.contains(&vec!["a".to_string()]) && !dx.contains(&vec!["c".to_string()]));
    let files2 = vec![
        (vec!["a".to_string()], "use crate::b;".to_string()),
        (vec!["b".to_string()], "use crate::a::thing;".to_string()),
    ];
    assert!(cycle(&graph_of(&files2)).is_some());
    assert!(cycle(&graph_of(&files[2..3])).is_none());
}
