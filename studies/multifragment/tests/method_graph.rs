//! The shape of `src/methods/`: no method folder imports another method (shared pieces live in
//! `methods/shared/`, named for what they are), and no method constructor is longer than a
//! page (bindings and pipelines are declared through `methods/shared/bind.rs`, so a
//! constructor reads as its passes). Both are read from the source.

use std::path::{Path, PathBuf};

fn methods_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src/methods")
}

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

/// Source without `//` comments (doc comments name other methods freely).
fn code(text: &str) -> String {
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The method modules: every child of `methods/` but `shared` and the registry `mod.rs`.
fn method_modules() -> Vec<String> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(methods_dir()).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().to_string();
        if name == "mod" || name == "shared" {
            continue;
        }
        if p.is_dir() || p.extension().is_some_and(|x| x == "rs") {
            out.push(name);
        }
    }
    out.sort();
    out
}

/// The method modules `text` names by path: `methods::X`, `super::X` or `super::super::X`
/// (a file one or two folders below `methods/`), including inside `use super::{X, …}` groups.
fn methods_named(text: &str, modules: &[String]) -> Vec<String> {
    let code = code(text);
    let mut out = Vec::new();
    for prefix in ["methods::", "super::", "super::super::"] {
        let mut rest = code.as_str();
        while let Some(i) = rest.find(prefix) {
            let before = rest[..i].chars().last();
            rest = &rest[i + prefix.len()..];
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let names: Vec<String> = if let Some(body) = rest.strip_prefix('{') {
                let end = body.find('}').unwrap_or(body.len());
                body[..end]
                    .split(',')
                    .map(|s| s.trim().split("::").next().unwrap_or("").to_string())
                    .collect()
            } else {
                vec![rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect()]
            };
            out.extend(names.into_iter().filter(|n| modules.contains(n)));
        }
    }
    out.sort();
    out.dedup();
    out
}

#[test]
fn no_method_folder_imports_another_method() {
    let dir = methods_dir();
    let modules = method_modules();
    assert!(
        modules.iter().any(|m| m == "depth_peel") && modules.iter().any(|m| m == "mlab"),
        "method modules not found in {}: {modules:?}",
        dir.display()
    );
    let mut files = Vec::new();
    rust_files(&dir, &mut files);
    let mut bad = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&dir).unwrap();
        let own = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        let text = std::fs::read_to_string(f).unwrap();
        // A shared piece may not reach up into a method either.
        let shared = own == "shared";
        if !shared && !modules.contains(&own) {
            continue; // the registry, mod.rs
        }
        for m in methods_named(&text, &modules) {
            if m != own {
                bad.push(format!("{} names method `{m}`", rel.display()));
            }
        }
    }
    assert!(bad.is_empty(), "cross-method imports:\n{}", bad.join("\n"));
}

#[test]
fn the_cross_method_scan_sees_the_forms_it_forbids() {
    let modules = vec!["bdp".to_string(), "mlab".to_string()];
    assert_eq!(
        methods_named("use super::mlab::judge_race;", &modules),
        ["mlab"]
    );
    assert_eq!(
        methods_named("use crate::methods::bdp::X;", &modules),
        ["bdp"]
    );
    assert_eq!(
        methods_named("run(c, super::super::bdp::tests_wgsl())", &modules),
        ["bdp"]
    );
    assert_eq!(
        methods_named("use super::{bdp, shared};", &modules),
        ["bdp"]
    );
    assert!(methods_named("use super::shared::store; // super::mlab", &modules).is_empty());
}

/// Longest a method constructor may be: a page. Longer, and it is writing out descriptors
/// the bind table and pipeline helpers declare in a line.
const MAX_CONSTRUCTOR_LINES: usize = 150;

/// Constructors exempt from the limit for now: (file under `methods/`, fn, why). An entry
/// must still name a constructor over the limit (a stale one fails), so the list only shrinks.
const NOT_YET: &[(&str, &str, &str)] = &[];

/// `(name, first line, lines)` of every `fn new`, `fn new_*` and `fn prepare` in `text`,
/// from the `fn` line to its closing brace.
fn constructors(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let Some(at) = t.find("fn ") else { continue };
        let head = &t[..at];
        if !(head.is_empty() || head.trim_end().ends_with("pub") || head.trim_end().ends_with(')'))
        {
            continue;
        }
        let name: String = t[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if !(name == "new" || name.starts_with("new_") || name == "prepare") {
            continue;
        }
        if t.contains('{') && t.matches('{').count() == t.matches('}').count() {
            out.push((name, i + 1, 1));
            continue;
        }
        let indent = l.len() - t.len();
        let end = (i..lines.len()).find(|&j| {
            let m = lines[j];
            m.len() - m.trim_start().len() == indent && m.trim_start().starts_with('}')
        });
        if let Some(end) = end {
            out.push((name, i + 1, end - i + 1));
        }
    }
    out
}

#[test]
fn no_method_constructor_is_longer_than_a_page() {
    let dir = methods_dir();
    let mut files = Vec::new();
    rust_files(&dir, &mut files);
    let mut seen = 0;
    let mut long = Vec::new();
    let mut exempt_seen = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let rel = f
            .strip_prefix(&dir)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        for (name, line, n) in constructors(&text) {
            seen += 1;
            if n <= MAX_CONSTRUCTOR_LINES {
                continue;
            }
            if NOT_YET.iter().any(|(f, fun, _)| *f == rel && *fun == name) {
                exempt_seen.push((rel.clone(), name));
            } else {
                long.push(format!("{rel}:{line} fn {name}: {n} lines"));
            }
        }
    }
    assert!(
        seen > 20,
        "only {seen} constructors found: the scan is broken"
    );
    for (f, fun, why) in NOT_YET {
        assert!(
            exempt_seen.iter().any(|(r, n)| r == f && n == fun),
            "{f} fn {fun} is exempt ({why}) but no longer over {MAX_CONSTRUCTOR_LINES} lines: drop it from NOT_YET"
        );
    }
    assert!(
        long.is_empty(),
        "constructors over {MAX_CONSTRUCTOR_LINES} lines:\n{}",
        long.join("\n")
    );
}

#[test]
fn the_constructor_scan_measures_from_fn_to_its_brace() {
    let src = "impl A {\n    pub(crate) fn new_ms(\n        x: u32,\n    ) -> Self {\n        A\n    }\n    fn new_one() -> u32 { 1 }\n    fn other() {}\n}\nfn prepare() {\n}\n";
    assert_eq!(
        constructors(src),
        [
            ("new_ms".to_string(), 2, 5),
            ("new_one".to_string(), 7, 1),
            ("prepare".to_string(), 10, 2)
        ]
    );
}
