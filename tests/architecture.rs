//! ARCHITECTURE.md is the map a newcomer reads first: every path it names must exist. A path is a
//! backticked or tree-listed name with a `/` or a file extension; tree lines under a crate heading
//! (`bench-core/`, `report/`, …) are relative to that crate.

use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Candidate paths of one token: as written, and under each crate folder.
fn exists(token: &str) -> bool {
    let t = token.trim_end_matches([',', '.', ':', ')']);
    let bases = [
        "",
        "bench-core",
        "reference",
        "studies/multifragment",
        "studies/shading",
        "studies/shadows",
        "studies/geometry",
        "report",
        "scenarios",
        "schema",
        "stats",
        "analysis",
        "flip",
        "table",
    ];
    // `packing.rs/.wgsl` names two files.
    let names: Vec<String> = match t.split_once("/.") {
        Some((a, ext)) if !a.contains('/') || a.ends_with(".rs") => {
            let stem = a.rsplit_once('.').map(|(s, _)| s).unwrap_or(a);
            vec![a.to_string(), format!("{stem}.{ext}")]
        }
        _ => vec![t.to_string()],
    };
    names.iter().all(|n| {
        bases.iter().any(|b| root().join(b).join(n).exists())
            || [
                "bench-core/src",
                "studies/multifragment/src",
                "studies/multifragment/src/methods",
                "report/src",
                "scenarios/src",
            ]
            .iter()
            .any(|b| root().join(b).join(n).exists())
    })
}

fn is_path(t: &str) -> bool {
    let t = t.trim_end_matches([',', '.', ':', ')']);
    !t.is_empty()
        && !t.contains(['<', '*', ' ', '{', '(', '&', '"', '='])
        && !t.starts_with("--")
        && !t.contains("::")
        && (t.contains('/')
            || [".rs", ".wgsl", ".toml", ".sh", ".md"]
                .iter()
                .any(|e| t.ends_with(e)))
        && t.chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphanumeric() || c == '.')
}

#[test]
fn every_path_architecture_md_names_exists() {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let mut tokens = Vec::new();
    // Backticked names.
    for (i, part) in text.split('`').enumerate() {
        if i % 2 == 1 && is_path(part) {
            tokens.push(part.to_string());
        }
    }
    // The first word of each line of the tree at the top (inside the first ``` block).
    if let Some(tree) = text.split("```").nth(1) {
        for line in tree.lines() {
            if let Some(w) = line.split_whitespace().next() {
                if is_path(w) {
                    tokens.push(w.to_string());
                }
            }
        }
    }
    assert!(tokens.len() > 20, "too few paths found: {tokens:?}");
    let missing: Vec<&String> = tokens.iter().filter(|t| !exists(t)).collect();
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md names paths that do not exist: {missing:?}"
    );
}
