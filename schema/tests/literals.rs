//! No `status` or `flag` word is spelt outside this crate (issue 29): every other crate's
//! sources, tests included, name them through `Status`, `Flag` and `FlagSet`, so a renamed or
//! added word is one edit here and a misspelt one does not compile. The guard reads every `.rs`
//! file of the workspace outside `schema/` and fails on a string literal that is such a word,
//! or has one as a `|`-separated part.

use std::path::{Path, PathBuf};

use schema::{Flag, Status};

/// Directories never scanned: build output, data, and this crate (which declares the words).
const SKIP: &[&str] = &["target", "results", "shared", "schema", "node_modules"];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if p.is_dir() {
            if !name.starts_with('.') && !SKIP.contains(&name.as_str()) {
                rust_files(&p, out);
            }
        } else if name.ends_with(".rs") {
            out.push(p);
        }
    }
}

/// The string literals of Rust source (plain, byte and raw), with their line numbers; comments
/// and char literals skipped.
fn string_literals(src: &str) -> Vec<(usize, String)> {
    let c: Vec<char> = src.chars().collect();
    let (mut out, mut i, mut line) = (Vec::new(), 0, 1);
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    while i < c.len() {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    line += (c[i] == '\n') as usize;
                    i += 1;
                }
            }
        } else if ch == '\'' {
            // A char literal ('x', '\n', '"'), or a lifetime ('a) left as code.
            if c.get(i + 1) == Some(&'\\') {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
        } else if ident(ch) {
            // A whole identifier; `r` or `br` before `"` or `#"` opens a raw string.
            let w0 = i;
            while i < c.len() && ident(c[i]) {
                i += 1;
            }
            let word: String = c[w0..i].iter().collect();
            let mut j = i;
            while c.get(j) == Some(&'#') {
                j += 1;
            }
            if (word == "r" || word == "br") && c.get(j) == Some(&'"') {
                let hashes = j - i;
                let (start, at) = (j + 1, line);
                j += 1;
                while j < c.len()
                    && !(c[j] == '"' && (1..=hashes).all(|h| c.get(j + h) == Some(&'#')))
                {
                    line += (c[j] == '\n') as usize;
                    j += 1;
                }
                out.push((at, c[start..j.min(c.len())].iter().collect()));
                i = j + 1 + hashes;
            }
        } else if ch == '"' {
            let (at, mut s) = (line, String::new());
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    s.push(c[i]);
                    i += 1;
                }
                if i < c.len() {
                    line += (c[i] == '\n') as usize;
                    s.push(c[i]);
                    i += 1;
                }
            }
            out.push((at, s));
            i += 1;
        } else {
            i += 1;
        }
    }
    out
}

/// The declared words: every status and every flag.
fn words() -> Vec<String> {
    Status::ALL
        .iter()
        .map(|s| s.to_string())
        .chain(Flag::ALL.iter().map(|f| f.to_string()))
        .collect()
}

/// Whether a literal spells a status or flag word (alone or as a `|`-separated part).
fn spells_a_word(lit: &str, words: &[String]) -> bool {
    lit.split('|').any(|p| words.iter().any(|w| w == p))
}

#[test]
fn no_status_or_flag_literal_outside_schema() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    assert!(files.len() > 50, "found only {} files", files.len());
    let words = words();
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (line, lit) in string_literals(&text) {
            if spells_a_word(&lit, &words) {
                let rel = f.strip_prefix(&root).unwrap_or(f).display().to_string();
                found.push(format!("{rel}:{line}: \"{lit}\""));
            }
        }
    }
    assert!(
        found.is_empty(),
        "status/flag words spelt outside schema (use schema::values::{{Status, Flag, FlagSet}}):\n{}",
        found.join("\n")
    );
}

#[test]
fn the_scanner_finds_literals_and_skips_comments_and_chars() {
    let (noisy, ok) = (Flag::Noisy.to_string(), Status::Ok.to_string());
    let src = format!(
        "// \"{noisy}\" in a comment\nlet q = '\"'; let l: &'a str = \"x|{noisy}\";\n/* \"{ok}\" */ let r = r#\"{ok}\"#;\nlet b = b\"y\";"
    );
    let lits = string_literals(&src);
    let texts: Vec<&str> = lits.iter().map(|(_, s)| s.as_str()).collect();
    assert_eq!(texts, [format!("x|{noisy}").as_str(), ok.as_str(), "y"]);
    assert_eq!(lits[0].0, 2);
    assert_eq!(lits[1].0, 3);
    let words = words();
    assert!(spells_a_word(texts[0], &words) && spells_a_word(texts[1], &words));
    assert!(!spells_a_word("noisy_run", &words) && !spells_a_word("", &words));
}

/// The calls that read a row's cell, or a timed frame's part, by a name given as text: a
/// literal there that is a declared column should be `cols::X` (or `cols::X.name`).
const BY_NAME: &[&str] = &["get_name(", "f_name(", "part_median(", "parts.get("];
/// The same, and a row's map written by hand (`rec.0.insert(`), where `.0` is a row: in the
/// crates that read runs.csv (elsewhere `.0` is an axis map, keyed by axis names).
const ROW_BY_NAME: &[&str] = &[
    "get_name(",
    "f_name(",
    "part_median(",
    "parts.get(",
    "0.insert(",
];

/// `call("name"` sites in `src` (for each of `calls`) whose literal is a declared column, with
/// their line numbers (comment lines skipped).
fn column_literals(src: &str, calls: &[&str]) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in src.lines().enumerate() {
        if line.trim_start().starts_with("//") {
            continue;
        }
        for call in calls {
            for (at, _) in line.match_indices(call) {
                let rest = line[at + call.len()..].trim_start();
                let Some(lit) = rest.strip_prefix('"').and_then(|r| r.split('"').next()) else {
                    continue;
                };
                if schema::by_name(lit).is_some() {
                    out.push((i + 1, format!("{call}\"{lit}\"")));
                }
            }
        }
    }
    out
}

/// Column names only through `schema` (issue 40, item 5): where a row's cell or a frame's
/// timed part is read or written by name, the name is `cols::X`, never a literal that a rename
/// would leave behind.
#[test]
fn no_column_read_by_a_literal_name() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut found = Vec::new();
    let mut n = 0;
    for (dir, calls) in [
        ("report", ROW_BY_NAME),
        ("analysis", ROW_BY_NAME),
        ("studies", BY_NAME),
        ("bench-core", BY_NAME),
        ("src", BY_NAME),
        ("table", BY_NAME),
    ] {
        let mut files = Vec::new();
        rust_files(&root.join(dir), &mut files);
        n += files.len();
        for f in &files {
            let src = std::fs::read_to_string(f).unwrap();
            for (line, site) in column_literals(&src, calls) {
                let rel = f.strip_prefix(&root).unwrap_or(f).display().to_string();
                found.push(format!("{rel}:{line}: {site}"));
            }
        }
    }
    assert!(n > 50, "found only {n} files");
    assert!(
        found.is_empty(),
        "column names spelt as literals (use schema::cols::X, or cols::X.name):\n{}",
        found.join("\n")
    );
}

#[test]
fn the_column_scanner_finds_calls_with_a_declared_name_only() {
    let src = "let a = r.f_name(\"gpu_ms_median\");\n// r.get_name(\"method\")\nlet b = r.get_name( \"method\"); let c = r.f_name(\"reps\"); m.part_median(name);\nr.0.insert(\"method\".into(), m);";
    assert_eq!(
        column_literals(src, BY_NAME),
        [
            (1, "f_name(\"gpu_ms_median\"".to_string()),
            (3, "get_name(\"method\"".to_string())
        ]
    );
    assert_eq!(
        column_literals(src, ROW_BY_NAME).len(),
        3,
        "a row written by hand"
    );
}
