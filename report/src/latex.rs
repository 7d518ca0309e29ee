//! The run for a paper: `report/latex/` beside the HTML, written by every `mfx report`.
//!
//! - `numbers.tex`: one `\newcommand` per headline figure, so a paper `\input`s the numbers and
//!   never retypes them (BenchExec's `\newcommand` per summary cell, sosy-lab/benchexec #242).
//!   The headline figures are the verdict's: for every configuration a verdict names (the
//!   fastest exact by construction, the fastest exact in this run only, the fastest within each
//!   RMSE budget) and for each scene's depth-only floor, its median GPU time (`ms`), the ends of
//!   its interval (`lo`, `hi`), its kept samples (`n`), its multiple of the floor (`xfloor`) and
//!   its RMSE (`rmse`), each where the row has it.
//! - `verdict.tex`, `reproduction.tex`, `bounds.tex`: booktabs tables (`\toprule`, `\midrule`,
//!   `\bottomrule`; `\usepackage{booktabs}`) of the verdict table, the sources' figures beside
//!   ours and what bounds each point. Each is a bare `tabular` to wrap in a `table` float, or
//!   past `LONG_ROWS` rows a `longtable` (`\usepackage{longtable}`) that breaks across pages.
//! - `sample.tex`: a document that `\input`s all of them (the test compiles it).
//!
//! Every chart is also a PDF beside its SVG (`charts::output`), fonts embedded.
//!
//! **How a point key becomes a macro name.** A TeX control word is letters only, so the key is
//! spelt in letters by a code in which no token is a prefix of another (so two keys never give
//! one name), then `V` and the quantity (`V` starts no token, so key and quantity cannot run
//! into each other), after the prefix `mfx`:
//!
//! | in the key | in the name |
//! |---|---|
//! | `a`–`z` | itself |
//! | `0`–`9` | `A`–`J` |
//! | `A`–`Z` | `K` and the letter in lower case |
//! | `\|` `=` `_` `(` `)` `,` `.` `-` | `Z` `Y` `U` `P` `Q` `W` `N` `M` |
//! | any other byte | `X` and its two hex digits as `A`–`P` |
//!
//! So `methods|quads(depth_complexity=8)|64x64|depth_peel|` and `ms` give
//! `\mfxmethodsZquadsPdepthUcomplexityYIQZGExGEZdepthUpeelZVms`. `numbers.tex` writes the key
//! in a comment above its macros: search it for the key.

use std::collections::BTreeSet;
use std::fmt::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use schema::cols;

use crate::bounds::bounds;
use crate::cells::short;
use crate::labels::{scene_name, ConfigLabels};
use mfx_analysis::data::{Rec, Runs};
use mfx_analysis::verdict::{verdicts, Verdict, BUDGETS};

/// The files written, in `dir`.
pub const FILES: [&str; 5] = [
    "numbers.tex",
    "verdict.tex",
    "reproduction.tex",
    "bounds.tex",
    "sample.tex",
];

/// The control word (without the backslash) of one quantity of one point key: see the module
/// notes. Letters only, and a different key or quantity never gives the same name.
pub fn macro_name(key: &str, quantity: &str) -> String {
    let mut s = String::from("mfx");
    for b in key.bytes() {
        match b {
            b'a'..=b'z' => s.push(b as char),
            b'0'..=b'9' => s.push((b'A' + (b - b'0')) as char),
            b'A'..=b'Z' => {
                s.push('K');
                s.push(b.to_ascii_lowercase() as char);
            }
            b'|' => s.push('Z'),
            b'=' => s.push('Y'),
            b'_' => s.push('U'),
            b'(' => s.push('P'),
            b')' => s.push('Q'),
            b',' => s.push('W'),
            b'.' => s.push('N'),
            b'-' => s.push('M'),
            _ => {
                s.push('X');
                s.push((b'A' + (b >> 4)) as char);
                s.push((b'A' + (b & 15)) as char);
            }
        }
    }
    s.push('V');
    for c in quantity.chars().filter(|c| c.is_ascii_lowercase()) {
        s.push(c);
    }
    s
}

/// Text set in LaTeX: its special characters escaped and the report's few non-ASCII signs
/// spelt in LaTeX, so pdflatex without extra packages sets it.
pub fn tex(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\\' => o.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                o.push('\\');
                o.push(c);
            }
            '~' => o.push_str("\\textasciitilde{}"),
            '^' => o.push_str("\\textasciicircum{}"),
            '<' => o.push_str("\\textless{}"),
            '>' => o.push_str("\\textgreater{}"),
            '|' => o.push_str("\\textbar{}"),
            '×' => o.push_str("$\\times$"),
            '≤' => o.push_str("$\\le$"),
            '≥' => o.push_str("$\\ge$"),
            '±' => o.push_str("$\\pm$"),
            '÷' => o.push_str("$\\div$"),
            '≈' => o.push_str("$\\approx$"),
            '–' => o.push_str("--"),
            '—' => o.push_str("---"),
            '…' => o.push_str("\\ldots{}"),
            '²' => o.push_str("\\textsuperscript{2}"),
            'µ' | 'μ' => o.push_str("$\\mu$"),
            '’' => o.push('\''),
            '“' => o.push_str("``"),
            '”' => o.push_str("''"),
            c if c.is_ascii() => o.push(c),
            // Anything else is named rather than dropped or left to break the build.
            c => {
                let _ = write!(o, "[U+{:04X}]", c as u32);
            }
        }
    }
    o
}

/// A number as the report writes it (three significant digits), in LaTeX: `1.23`, or
/// `$1.23\times10^{-6}$` for e notation.
pub fn tex_num(v: f64) -> String {
    let s = short(Some(v));
    match s.split_once('e') {
        Some((m, e)) => format!("$\\mathrm{{{m}}}\\times10^{{{e}}}$"),
        None => s,
    }
}

/// One macro line per quantity the row has, under a comment naming its key.
fn macros_of(r: &Rec, seen: &mut BTreeSet<String>, out: &mut String) {
    let key = r.get(cols::POINT_KEY);
    if key.is_empty() || !seen.insert(key.to_string()) {
        return;
    }
    let ci = r.gpu_ci();
    let q: [(&str, Option<f64>); 6] = [
        ("ms", r.trusted_ms()),
        ("lo", ci.map(|c| c.0).filter(|_| r.time_trusted())),
        ("hi", ci.map(|c| c.1).filter(|_| r.time_trusted())),
        ("n", r.samples().map(|n| n as f64)),
        ("xfloor", r.f(cols::X_FLOOR).filter(|_| r.time_trusted())),
        ("rmse", r.f(cols::RMSE)),
    ];
    if q.iter().all(|(_, v)| v.is_none()) {
        return;
    }
    let _ = writeln!(out, "% {}", key.replace('\n', " "));
    for (name, v) in q {
        if let Some(v) = v.filter(|v| v.is_finite()) {
            let _ = writeln!(
                out,
                "\\newcommand{{\\{}}}{{{}}}",
                macro_name(key, name),
                tex_num(v)
            );
        }
    }
}

/// `numbers.tex`.
pub fn numbers(runs: &Runs) -> String {
    let mut out = String::from(
        "% mfx report: the verdict's numbers, one macro per figure. A macro's name spells the\n\
         % point key in letters (report/src/latex.rs says how); the key is in the comment above.\n\
         % Quantities: ms = median GPU ms per frame; lo, hi = its interval (95 % CI or min-max,\n\
         % see the report); n = kept samples; xfloor = multiple of floor_depth; rmse = vs the truth.\n",
    );
    let mut seen = BTreeSet::new();
    for (_, v) in verdicts(runs) {
        let floor = v.rows.first().and_then(|r0| {
            runs.rows.iter().find(|r| {
                r.ok()
                    && r.get(cols::METHOD) == "floor_depth"
                    && r.get(cols::SCENE_LABEL) == r0.get(cols::SCENE_LABEL)
                    && r.get(cols::WIDTH) == r0.get(cols::WIDTH)
                    && r.get(cols::HEIGHT) == r0.get(cols::HEIGHT)
                    && r.get(cols::STUDY) == r0.get(cols::STUDY)
                    && mfx_analysis::data::platform(r) == mfx_analysis::data::platform(r0)
            })
        });
        let named = v
            .fastest_exact
            .iter()
            .chain(v.exact_in_run.iter())
            .chain(v.budgets.iter().filter_map(|(_, p)| p.as_ref()))
            .map(|p| p.row)
            .chain(floor);
        for r in named {
            macros_of(r, &mut seen, &mut out);
        }
    }
    if seen.is_empty() {
        // Said, so that a reader (and scripts/check-report.sh) can tell an empty file from a
        // broken one: runs of views or seeds-* suites have no verdict table.
        out.push_str(NO_MACRO);
    }
    out
}

/// The line `numbers.tex` ends with when the run has no verdict row to name.
pub const NO_MACRO: &str =
    "% (none: no row of this run is in a verdict table, as in a views or seeds-* run)\n";

/// Rows above which a table is a `longtable` (it breaks across pages, its header repeated; not
/// inside a float) rather than a `tabular` (one page, fits a `table` float).
pub const LONG_ROWS: usize = 40;

/// A booktabs table of `header` and `rows` (cells already LaTeX), `spec` its columns: a
/// `tabular`, or a `longtable` past `LONG_ROWS` rows.
fn booktabs(spec: &str, header: &[&str], rows: &[Vec<String>]) -> String {
    let env = if rows.len() > LONG_ROWS {
        "longtable"
    } else {
        "tabular"
    };
    let mut t = format!("\\begin{{{env}}}{{{spec}}}\n\\toprule\n");
    let h: Vec<String> = header
        .iter()
        .map(|c| format!("\\textbf{{{}}}", tex(c)))
        .collect();
    let _ = writeln!(t, "{} \\\\\n\\midrule", h.join(" & "));
    if env == "longtable" {
        t.push_str("\\endhead\n");
    }
    for r in rows {
        let _ = writeln!(t, "{} \\\\", r.join(" & "));
    }
    let _ = writeln!(t, "\\bottomrule\n\\end{{{env}}}");
    t
}

/// What a table file holds when the run has no rows for it: a comment, so `\input` sets nothing.
fn empty(what: &str) -> String {
    format!("% mfx report: no {what} in this run.\n")
}

/// A verdict pick as "name, 1.23 ms".
fn pick_cell(labels: &ConfigLabels, r: &Rec) -> String {
    format!(
        "{}, {} ms",
        tex(&labels.get(r)),
        r.trusted_ms().map(tex_num).unwrap_or_default()
    )
}

/// `verdict.tex`: one row per scene × resolution of the image studies.
pub fn verdict_table(runs: &Runs) -> String {
    let vs = verdicts(runs);
    if vs.is_empty() {
        return empty("verdict (no image study)");
    }
    let all: Vec<&Rec> = vs
        .iter()
        .flat_map(|(_, v)| v.rows.iter().copied())
        .collect();
    let labels = ConfigLabels::new(all.iter().copied());
    let plats = Runs::distinct_strings(vs.iter().map(|(p, _)| p.as_str()));
    let row = |p: &str, v: &Verdict| {
        let mut scene = scene_name(&v.scene);
        if !v.effect.is_empty() {
            scene = format!("{scene}, {}", v.effect);
        }
        if plats.len() > 1 {
            scene = format!("{scene} [{p}]");
        }
        let exact = match (&v.fastest_exact, &v.exact_in_run) {
            (Some(f), _) => pick_cell(&labels, f.row),
            (None, Some(_)) => "none by construction".into(),
            (None, None) => "none".into(),
        };
        let in_run = v
            .exact_in_run
            .as_ref()
            .map(|p| pick_cell(&labels, p.row))
            .unwrap_or_else(|| "--".into());
        let x = match (&v.fastest_exact, v.floor_ms) {
            (Some(p), Some(f)) if f > 0.0 => p
                .row
                .trusted_ms()
                .map(|t| format!("{}$\\times$", tex_num(t / f)))
                .unwrap_or_default(),
            _ => String::new(),
        };
        let mut cells = vec![tex(&scene), tex(&v.res), exact, in_run, x];
        for (_, b) in &v.budgets {
            cells.push(
                b.as_ref()
                    .map(|p| pick_cell(&labels, p.row))
                    .unwrap_or_else(|| "none".into()),
            );
        }
        cells
    };
    let rows: Vec<Vec<String>> = vs.iter().map(|(p, v)| row(p, v)).collect();
    let budget_heads: Vec<String> = BUDGETS
        .iter()
        .map(|b| format!("fastest with RMSE ≤ {b:.0e}"))
        .collect();
    let mut header = vec![
        "scene",
        "resolution",
        "fastest exact (by construction)",
        "exact in this run only",
        "× floor_depth",
    ];
    header.extend(budget_heads.iter().map(|s| s.as_str()));
    booktabs(
        &format!("ll{}", "l".repeat(header.len() - 2)),
        &header,
        &rows,
    )
}

/// `reproduction.tex`: the sources' figures beside ours, one table per papers file.
pub fn reproduction_table(runs: &Runs, bands: &crate::reproduction::Bands) -> String {
    let tables = crate::reproduction::tables(runs, bands);
    if tables.is_empty() {
        return empty("row of a suite a papers file points to");
    }
    let mut out = format!("% {}\n", crate::reproduction::NOTE);
    for t in &tables {
        let _ = writeln!(out, "% {}", t.heading);
        let rows: Vec<Vec<String>> = t
            .lines
            .iter()
            .map(|l| l.cells.iter().map(|c| tex(c)).collect())
            .collect();
        out.push_str(&booktabs(
            "lllllllp{6cm}",
            &crate::reproduction::HEADER,
            &rows,
        ));
    }
    out
}

/// `bounds.tex`: what bounds each point (the bounds section's table).
pub fn bounds_table(runs: &Runs) -> String {
    let b = bounds(runs);
    if b.is_empty() {
        return empty("row with per-pass times");
    }
    let pct = |v: Option<f64>| v.map(|v| format!("{} \\%", tex_num(v * 100.0)));
    let rows: Vec<Vec<String>> = b
        .iter()
        .map(|b| {
            vec![
                tex(&scene_name(&b.scene)),
                tex(&b.resolution),
                tex(&b.config),
                tex_num(b.gpu_ms),
                format!(
                    "{} ({} ms, {})",
                    tex(&b.pass),
                    tex_num(b.pass_ms),
                    pct(Some(b.share)).unwrap_or_default()
                ),
                b.floor_ms.map(tex_num).unwrap_or_default(),
                pct(b.peak_frac).unwrap_or_default(),
                tex(&b.verdict()),
            ]
        })
        .collect();
    booktabs(
        "llllllp{3cm}p{5cm}",
        &[
            "scene",
            "resolution",
            "configuration",
            "GPU ms",
            "slowest pass",
            "floor_depth ms",
            "of peak bandwidth",
            "bound",
        ],
        &rows,
    )
}

/// A document that inputs every table, uses the first macro and includes the first PDF chart:
/// what a paper does.
fn sample(numbers: &str, chart: Option<&str>) -> String {
    let first = numbers
        .lines()
        .find_map(|l| l.strip_prefix("\\newcommand{\\"))
        .and_then(|l| l.split_once('}'))
        .map(|(name, _)| format!("The first figure of numbers.tex: \\{name}.\n"))
        .unwrap_or_default();
    let figure = chart
        .map(|stem| {
            format!(
                "\\section*{{A chart}}\n\\includegraphics[width=0.6\\linewidth]{{../{stem}.pdf}}\n"
            )
        })
        .unwrap_or_default();
    format!(
        "% Compiles the files beside it: pdflatex sample.tex, twice (longtable sets its column widths on the second run)\n\
         \\documentclass{{article}}\n\
         \\usepackage[T1]{{fontenc}}\n\
         \\usepackage[utf8]{{inputenc}}\n\
         \\usepackage{{booktabs}}\n\
         \\usepackage{{longtable}}\n\
         \\usepackage{{graphicx}}\n\
         \\usepackage[a3paper,landscape,margin=1cm]{{geometry}}\n\
         \\input{{numbers.tex}}\n\
         \\begin{{document}}\n\
         {first}\
         \\section*{{Verdict}}\n{{\\scriptsize\\input{{verdict.tex}}}}\n\
         \\section*{{Reproduction}}\n{{\\scriptsize\\input{{reproduction.tex}}}}\n\
         \\section*{{Bounds}}\n{{\\scriptsize\\input{{bounds.tex}}}}\n\
         {figure}\
         \\end{{document}}\n"
    )
}

/// Writes `out/latex/` (see the module notes); returns the folder.
pub fn write(runs: &Runs, bands: &crate::reproduction::Bands, out: &Path) -> Result<PathBuf> {
    let dir = out.join("latex");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let numbers = numbers(runs);
    // The first PDF chart of the report folder (drawn before this), by name.
    let mut pdfs: Vec<String> = std::fs::read_dir(out)
        .with_context(|| format!("reading {}", out.display()))?
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().to_str().map(String::from))
        .filter_map(|n| n.strip_suffix(".pdf").map(String::from))
        .collect();
    pdfs.sort();
    let files = [
        (
            "sample.tex",
            sample(&numbers, pdfs.first().map(|s| s.as_str())),
        ),
        ("numbers.tex", numbers),
        ("verdict.tex", verdict_table(runs)),
        ("reproduction.tex", reproduction_table(runs, bands)),
        ("bounds.tex", bounds_table(runs)),
    ];
    for (name, text) in files {
        let p = dir.join(name);
        std::fs::write(&p, text).with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_macro_name_is_letters_only_and_names_one_key_and_quantity() {
        let keys = [
            "methods|quads(depth_complexity=8)|64x64|depth_peel|",
            "methods|quads(depth_complexity=8)|64x64|depth_peel|max_layers=8",
            "methods|quads(depth_complexity=8)|64x64|depth_peel|max_layers=80",
            "methods|Quads|64x64|a|",
            "methods|quads|64x64|a|",
            "methods|obj(path=m/a.obj)|64x64|a|",
            "methods|obj(path=m/a-b.obj)|64x64|a|",
            "deferred|s|64x64|naive|lights=1,2",
            "x|é|1x1|a|",
            "x|ä|1x1|a|",
        ];
        let mut seen = BTreeSet::new();
        for k in keys {
            for q in ["ms", "lo", "hi", "n", "xfloor", "rmse"] {
                let n = macro_name(k, q);
                assert!(n.chars().all(|c| c.is_ascii_alphabetic()), "{n}");
                assert!(seen.insert(n.clone()), "{k} {q} collides: {n}");
            }
        }
        assert_eq!(
            macro_name("methods|quads(depth_complexity=8)|64x64|depth_peel|", "ms"),
            "mfxmethodsZquadsPdepthUcomplexityYIQZGExGEZdepthUpeelZVms"
        );
    }

    #[test]
    fn text_and_numbers_are_latex_safe() {
        assert_eq!(
            tex("a_b & 50 % × ≤ {x}"),
            "a\\_b \\& 50 \\% $\\times$ $\\le$ \\{x\\}"
        );
        assert_eq!(tex_num(1.5e-6), "$\\mathrm{1.5}\\times10^{-6}$");
        assert_eq!(tex_num(12.345), "12.3");
    }
}
