//! The run for a paper, from a committed H200 run as a fresh clone has it: `report::build`
//! writes `latex/numbers.tex` (a macro per headline figure, letters-only names, none twice),
//! booktabs tables, and a PDF beside every SVG chart with its font embedded; and the sample
//! document that `\input`s them compiles with pdflatex. Without pdflatex the compile is skipped
//! with a message on a developer's machine, and fails in CI (`CI=true`), where scripts/setup.sh
//! installs it.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

fn committed(run: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../results/reference")
        .join(run)
}

/// A copy of a committed run's data files in a temporary folder (the tree is never written).
fn copy_run(run: &str) -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    for f in ["runs.csv", "run.json"] {
        let src = committed(run).join(f);
        if src.is_file() {
            std::fs::copy(&src, d.path().join(f)).unwrap();
        }
    }
    d
}

fn pdflatex() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|p| p.join("pdflatex"))
        .find(|p| p.is_file())
}

#[test]
fn an_h200_run_gives_numbers_tables_and_pdf_charts_that_compile() {
    let d = copy_run("2026-12-03-h200-resolve/default");
    report::build(d.path(), None).unwrap();
    let out = d.path().join("report");
    let latex = out.join("latex");
    for f in report::latex::FILES {
        assert!(latex.join(f).is_file(), "{f} missing");
    }
    // A macro per headline figure: letters-only names, each defined once.
    let numbers = std::fs::read_to_string(latex.join("numbers.tex")).unwrap();
    let names: Vec<&str> = numbers
        .lines()
        .filter_map(|l| l.strip_prefix("\\newcommand{\\"))
        .map(|l| l.split_once('}').unwrap().0)
        .collect();
    assert!(names.len() >= 10, "{numbers}");
    assert!(names
        .iter()
        .all(|n| n.chars().all(|c| c.is_ascii_alphabetic())));
    let distinct: BTreeSet<&&str> = names.iter().collect();
    assert_eq!(distinct.len(), names.len(), "a macro defined twice");
    // Every comment names a key whose macros follow it, spelt by `macro_name`.
    let mut key = None;
    for l in numbers.lines() {
        if let Some(k) = l.strip_prefix("% ").filter(|k| k.contains('|')) {
            key = Some(k.to_string());
        } else if let Some(rest) = l.strip_prefix("\\newcommand{\\") {
            let (name, _) = rest.split_once('}').unwrap();
            let k = key.as_deref().expect("a key comment before its macros");
            let q = name.rsplit_once('V').unwrap().1;
            assert_eq!(name, report::latex::macro_name(k, q));
        }
    }
    let verdict = std::fs::read_to_string(latex.join("verdict.tex")).unwrap();
    assert!(
        verdict.contains("\\toprule") && verdict.contains("\\bottomrule"),
        "{verdict}"
    );
    let bounds = std::fs::read_to_string(latex.join("bounds.tex")).unwrap();
    assert!(bounds.contains("\\midrule"), "{bounds}");
    // Past LONG_ROWS rows a table breaks across pages (a longtable), its header repeated.
    let rows = bounds.lines().filter(|l| l.ends_with("\\\\")).count() - 1;
    assert_eq!(
        bounds.contains("\\begin{longtable}") && bounds.contains("\\endhead"),
        rows > report::latex::LONG_ROWS,
        "{rows} rows"
    );
    // Every SVG chart has its PDF, with a font embedded (a TrueType font file stream).
    let svgs: Vec<PathBuf> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "svg"))
        .collect();
    assert!(svgs.len() >= 5, "{} charts", svgs.len());
    for svg in &svgs {
        let pdf = std::fs::read(svg.with_extension("pdf"))
            .unwrap_or_else(|e| panic!("{}: no PDF ({e})", svg.display()));
        assert!(pdf.starts_with(b"%PDF-"), "{}", svg.display());
        let has = |what: &[u8]| pdf.windows(what.len()).any(|w| w == what);
        assert!(
            has(b"/FontFile2") && has(b"DejaVu"),
            "{}: no embedded font",
            svg.display()
        );
    }
    // The sample document builds.
    let Some(tex) = pdflatex() else {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "pdflatex is missing in CI: scripts/setup.sh installs texlive-latex-base and \
             texlive-latex-recommended"
        );
        eprintln!(
            "SKIPPED the pdflatex build of sample.tex: no pdflatex on PATH (Debian: apt-get \
             install texlive-latex-base texlive-latex-recommended; scripts/setup.sh does it as root)"
        );
        return;
    };
    let o = Command::new(tex)
        .args(["-interaction=nonstopmode", "-halt-on-error", "sample.tex"])
        .current_dir(&latex)
        .output()
        .unwrap();
    assert!(
        o.status.success() && latex.join("sample.pdf").is_file(),
        "pdflatex failed:\n{}",
        String::from_utf8_lossy(&o.stdout)
    );
}

#[test]
fn a_run_without_image_studies_still_writes_every_file() {
    // Shadows only: no verdict table, no bounds; the files say so in a comment.
    let d = copy_run("2026-12-02-h200-shadows-bunny");
    report::build(d.path(), None).unwrap();
    let latex = d.path().join("report/latex");
    let v = std::fs::read_to_string(latex.join("verdict.tex")).unwrap();
    assert!(v.starts_with("% mfx report: no verdict"), "{v}");
    let r = std::fs::read_to_string(latex.join("reproduction.tex")).unwrap();
    assert!(r.starts_with("% mfx report: no "), "{r}");
}

#[test]
fn a_run_without_a_verdict_table_says_so_in_numbers_tex() {
    // The H200 views run: every row is a path's, none is in a verdict table.
    let d = copy_run("2026-12-05-h200-merged/views");
    report::build(d.path(), None).unwrap();
    let numbers = std::fs::read_to_string(d.path().join("report/latex/numbers.tex")).unwrap();
    assert!(!numbers.contains("\\newcommand"), "{numbers}");
    assert!(numbers.ends_with(report::latex::NO_MACRO), "{numbers}");
}
