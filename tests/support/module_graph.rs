//! A file-level dependency-cycle guard, shared by every crate's `tests/module_graph.rs`
//! (included with `#[path = "../../tests/support/module_graph.rs"] mod module_graph;`). Nodes
//! are files; an edge is a `crate::a::b` or `super::b` path in a file's code (comments
//! skipped, tests included) resolved to the file that defines it. A parent's `mod child;` is
//! not an edge. With no file-level cycle a crate reads bottom-up, one file at a time.
#![allow(
    dead_code,
    reason = "included by every crate's tests/module_graph.rs; each uses a part"
)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

pub type Graph = BTreeMap<Vec<String>, BTreeSet<Vec<String>>>;

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
    if parts.last().is_some_and(|l| l == "mod" || l == "lib")
        || (parts.len() == 1 && parts[0] == "main")
    {
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

pub fn cycle(graph: &Graph) -> Option<Vec<String>> {
    // Depth-first search with colours; returns one cycle as "a → b → a".
    fn visit(
        n: &Vec<String>,
        g: &Graph,
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

pub fn graph_of(files: &[(Vec<String>, String)]) -> Graph {
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

/// The `.rs` files under `crate_dir/src`, as (module path, text).
pub fn crate_files(crate_dir: &str) -> Vec<(Vec<String>, String)> {
    let src = Path::new(crate_dir).join("src");
    let mut paths = Vec::new();
    rust_files(&src, &mut paths);
    paths.sort();
    paths
        .iter()
        .map(|p| (module_path(&src, p), std::fs::read_to_string(p).unwrap()))
        .collect()
}

/// The graph with each node cut to its first `depth` segments (depth 1: top-level modules),
/// edges within one node dropped.
pub fn coarsen(graph: &Graph, depth: usize) -> Graph {
    let cut = |n: &Vec<String>| n[..n.len().min(depth)].to_vec();
    let mut out: Graph = BTreeMap::new();
    for (n, es) in graph {
        let from = cut(n);
        let e = out.entry(from.clone()).or_default();
        e.extend(es.iter().map(cut).filter(|t| *t != from));
    }
    out
}

/// Panics, naming the cycle, when the files of `crate_dir/src` (at least `min_files`) have a
/// file-level dependency cycle.
pub fn assert_no_file_cycle(crate_dir: &str, min_files: usize) {
    assert_no_file_cycle_but(crate_dir, min_files, &[]);
}

/// As [`assert_no_file_cycle`], with `known` edges (`"a/b" → "c"`, file module paths) left out
/// of the graph: cycles not yet cut, each named where it is allowed. A known edge that no
/// longer exists fails too, so the list only shrinks.
pub fn assert_no_file_cycle_but(crate_dir: &str, min_files: usize, known: &[(&str, &str)]) {
    let files = crate_files(crate_dir);
    assert!(
        files.len() >= min_files,
        "{crate_dir}: found only {} files",
        files.len()
    );
    let mut graph = graph_of(&files);
    let path = |s: &str| -> Vec<String> { s.split('/').map(String::from).collect() };
    for (from, to) in known {
        let removed = graph
            .get_mut(&path(from))
            .is_some_and(|es| es.remove(&path(to)));
        assert!(
            removed,
            "{crate_dir}: the known edge {from} → {to} is gone: remove it from the list"
        );
    }
    if let Some(c) = cycle(&graph) {
        panic!("file-level cycle in {crate_dir}/src: {}", c.join(" → "));
    }
}
