//! The page and the terminal text of `mfx compare BASE NEW`: `mfx_analysis::ab` computes the
//! comparison (typed: `AbReport`); this module only writes it down, as Markdown for the
//! terminal and as `compare.html` (tables and an inline SVG of the ratios).

use std::fmt::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use maud::{html, Markup, PreEscaped, DOCTYPE};
use mfx_analysis::ab::{fmt_ms, fmt_p, fmt_ratio, AbReport, PointCmp, Side};
use mfx_analysis::bands::{Alarms, BandSource, Calibration};
use mfx_stats::{Basis, Verdict, MODE_MIN_FRAC, MODE_MIN_SEP};

pub fn side_line(s: &Side) -> String {
    format!(
        "{} — schema {}, run {}, git {}, platform {}, {}",
        s.runs_csv.display(),
        s.schema,
        s.run_ids.join(", "),
        s.git_revs.join(", "),
        s.platforms.join("; "),
        match &s.samples_csv {
            Some(p) => format!(
                "raw samples ({})",
                p.file_name().unwrap_or_default().to_string_lossy()
            ),
            None => "no samples.csv: summary columns only".to_string(),
        }
    )
}

/// The rule in one paragraph, with this comparison's settings.
pub fn rule_text(r: &AbReport) -> String {
    let o = &r.opts.verdict;
    format!(
        "Ratio = NEW/BASE median GPU time (> 1: NEW slower), with a bootstrap 95 % CI \
         ({} resamples). SAME: the ratio is within ±{:.1} % (the noise band). SLOWER / \
         FASTER: beyond the band, Mann–Whitney U p < {} and the CI excludes 1. UNSURE: \
         beyond the band without that evidence, or fewer than {} samples on a side \
         (then SAME only if every NEW/BASE sample ratio is within the band). What is \
         compared with what (first match): where both sides' samples show two modes \
         whose gaps agree within the band, the fast mode with the fast and the slow with \
         the slow, the point taking their common verdict (else UNSURE; ratio: the two \
         ratios' geometric mean); where both sides hold an odd number ≥ 3 of sessions \
         ([timing] sessions: each prepared afresh, in one memory state), the median \
         session of each (a minority of sessions in another state cannot move it); \
         otherwise the CI resamples sessions, then samples within them, and \
         \"significant\" means that CI excludes 1 (no p is shown). From \
         summary columns only (no samples.csv), \"significant\" means the two medians' CIs \
         (else min–max ranges) do not overlap. Cycles = time × SM clock. An error column \
         moved when |Δ| > max({:e}, {:.0} % of the larger value). {}",
        o.resamples,
        o.noise_band * 100.0,
        o.alpha,
        o.min_samples,
        r.opts.err_abs_tol,
        r.opts.err_rel_tol * 100.0,
        band_text(r)
    )
}

/// How the bands were set, and the hold-back rule (part of [`Self::rule_text`]).
fn band_text(r: &AbReport) -> String {
    let floor = r.opts.verdict.noise_band * 100.0;
    let mut t = match &r.opts.calibration {
        Some(c) => {
            let n = |s: BandSource| r.points.iter().filter(|p| p.band_source == s).count();
            let mut bands: Vec<f64> = r.points.iter().map(|p| p.band).collect();
            bands.sort_by(f64::total_cmp);
            format!(
                "Bands measured by `mfx calibrate` on {} A/A runs ({}), never below ±{floor:.1} %: \
                 {} points by their own spread, {} by their class (method × scene kind), {} at \
                 the floor; median band ±{:.1} %, largest ±{:.1} %.",
                c.runs.len(),
                c.runs.join(", "),
                n(BandSource::Point),
                n(BandSource::Class),
                n(BandSource::Fixed),
                bands.get(bands.len() / 2).copied().unwrap_or(0.0) * 100.0,
                bands.last().copied().unwrap_or(0.0) * 100.0
            )
        }
        None => format!(
            "The band is ±{floor:.1} % on every point (fixed, not calibrated: `mfx calibrate` \
             measures one per point, `--band-from` uses it)."
        ),
    };
    let _ = write!(
        t,
        " Held back (UNSURE, the point's own instability could explain it): a FASTER / \
         SLOWER where the samples compared (not mode-matched) show two frame-time modes on a \
         side (the widest split of its sorted samples leaves two groups of ≥ {:.0} % of \
         them, medians ≥ {:.1} % apart) and a mode of NEW matches a mode of BASE within the \
         band (low with low, high with high when both have two; a side with one mode is \
         its median); where median sessions were compared and the point's band is not its \
         own calibrated one, a median session within the band of a session of the other \
         side (a change of session state); and, where both sides are noisy and the modes \
         were not matched, one within ±(floor + their larger session spread).",
        MODE_MIN_FRAC * 100.0,
        MODE_MIN_SEP * 100.0
    );
    if r.opts.scale_new != 1.0 {
        let _ = write!(
            t,
            " SYNTHETIC: every NEW time was multiplied by {} (--scale-new).",
            r.opts.scale_new
        );
    }
    t
}

pub fn headline(r: &AbReport) -> Vec<String> {
    let mut v = Vec::new();
    let c = r.counts();
    v.push(format!(
        "{} points compared ({} only in BASE, {} only in NEW, {} without GPU time): {}",
        r.points.len(),
        r.only_base.len(),
        r.only_new.len(),
        r.untimed.len(),
        c.iter()
            .map(|(k, n)| format!("{k} {n}"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let cc = r.cycle_counts();
    if !cc.is_empty() {
        v.push(format!(
            "In cycles (time × SM clock, {} points): {}",
            cc.values().sum::<usize>(),
            cc.iter()
                .map(|(k, n)| format!("{k} {n}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if let Some((hi, lo)) = r.extremes() {
        v.push(format!(
            "Largest ratio {:.3} ({}), smallest {:.3} ({})",
            hi.time.ratio, hi.key, lo.time.ratio, lo.key
        ));
    }
    let s = r.summary_only();
    if s > 0 {
        v.push(format!(
            "{s} of {} verdicts are from summary columns only (no raw samples on a side): \
             mostly UNSURE unless the intervals separate",
            r.points.len()
        ));
    }
    if r.base.platforms != r.new.platforms {
        v.push(format!(
            "Different platforms: BASE {} vs NEW {}",
            r.base.platforms.join("; "),
            r.new.platforms.join("; ")
        ));
    }
    if let Some(g) = r.gpu_ratio() {
        let within = r
            .points
            .iter()
            .filter(|p| {
                matches!(p.time.verdict, Verdict::Faster | Verdict::Slower)
                    && (p.time.ratio - 1.0).abs() <= (g - 1.0).abs()
            })
            .count();
        v.push(format!(
            "GPU calibration set: NEW's GPU took {g:.3}× BASE's; {within} FASTER / SLOWER \
             verdicts lie within that difference (may be the GPUs, not the methods)"
        ));
    }
    v
}

/// The comparison as Markdown, for the terminal.
pub fn markdown(r: &AbReport) -> String {
    let md = |s: &str| s.replace('|', "\\|");
    let mut m = String::new();
    let _ = writeln!(m, "# mfx compare\n");
    let _ = writeln!(m, "- BASE: {}", md(&side_line(&r.base)));
    let _ = writeln!(m, "- NEW: {}", md(&side_line(&r.new)));
    for l in headline(r) {
        let _ = writeln!(m, "- {}", md(&l));
    }
    let _ = writeln!(m, "\n{}\n", rule_text(r));
    let _ = writeln!(
        m,
        "| point | BASE ms | NEW ms | NEW/BASE [95 % CI] | p | time | cycles | note |\n\
         |---|---:|---:|---|---:|---|---|---|"
    );
    for p in &r.points {
        let mut note = Vec::new();
        if p.base_noisy || p.new_noisy {
            note.push(format!(
                "noisy on {}",
                match (p.base_noisy, p.new_noisy) {
                    (true, true) => "both",
                    (true, false) => "BASE",
                    _ => "NEW",
                }
            ));
        }
        if p.time.basis == Basis::Summary {
            note.push("summary columns".into());
        }
        if p.time.verdict == Verdict::Unsure {
            note.push(p.time.why.clone());
        }
        if p.band_source != BandSource::Fixed {
            note.push(p.band_note());
        }
        if let Some(g) = r.gpu_ratio() {
            if matches!(p.time.verdict, Verdict::Faster | Verdict::Slower)
                && (p.time.ratio - 1.0).abs() <= (g - 1.0).abs()
            {
                note.push(format!(
                    "within the GPUs' difference on the calibration set ({g:.3}×)"
                ));
            }
        }
        let _ = writeln!(
            m,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            md(&p.key),
            fmt_ms(p.base_median_ms),
            fmt_ms(p.new_median_ms),
            fmt_ratio(&p.time),
            fmt_p(&p.time),
            p.time.verdict,
            p.cycles
                .as_ref()
                .map(|c| format!("{} ({:.3})", c.verdict, c.ratio))
                .unwrap_or_else(|| "–".into()),
            md(&note.join("; "))
        );
    }
    if !r.errors.is_empty() {
        let _ = writeln!(
            m,
            "\n## Errors that moved ({})\n\n| point | column | BASE | NEW |\n|---|---|---|---|",
            r.errors.len()
        );
        for e in &r.errors {
            let _ = writeln!(
                m,
                "| {} | {} | {} | {} |",
                md(&e.key),
                e.column,
                e.base,
                e.new
            );
        }
    }
    if !r.status_changes.is_empty() {
        let _ = writeln!(
            m,
            "\n## Status changes ({})\n\n| point | BASE | NEW | reason |\n|---|---|---|---|",
            r.status_changes.len()
        );
        for s in &r.status_changes {
            let _ = writeln!(
                m,
                "| {} | {} | {} | {} |",
                md(&s.key),
                s.base,
                s.new,
                md(&s.reason)
            );
        }
    }
    for (title, keys) in [
        ("Only in BASE", &r.only_base),
        ("Only in NEW", &r.only_new),
        ("Without GPU time", &r.untimed),
    ] {
        if !keys.is_empty() {
            let _ = writeln!(m, "\n## {title} ({})\n", keys.len());
            for k in keys {
                let _ = writeln!(m, "- {k}");
            }
        }
    }
    m
}

/// Writes `dir/compare.html` (tables and a ratio chart); returns its path.
pub fn write_html(r: &AbReport, dir: &Path) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join("compare.html");
    std::fs::write(&path, html_page(r).into_string())
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1300px;margin:2em auto;color:#222}\
table{border-collapse:collapse;margin:1em 0;font-size:13px}\
td,th{border:1px solid #ccc;padding:3px 7px;text-align:left}th{background:#f3f3f3}\
td.n{text-align:right;font-variant-numeric:tabular-nums}\
.SLOWER{color:#b00;font-weight:bold}.FASTER{color:#070;font-weight:bold}\
.UNSURE{color:#a60}.SAME{color:#555}";

/// The page.
pub fn html_page(r: &AbReport) -> Markup {
    let mhz = |v: Option<f64>| v.map(|x| format!("{x:.0}")).unwrap_or_default();
    let noisy = |n: bool| if n { " (noisy)" } else { "" };
    html! {
        (DOCTYPE)
        html {
            head { meta charset="utf-8"; title { "mfx compare" } style { (PreEscaped(STYLE)) } }
            body {
                h1 { "mfx compare" }
                ul {
                    li { "BASE: " (side_line(&r.base)) }
                    li { "NEW: " (side_line(&r.new)) }
                    @for l in headline(r) { li { (l) } }
                }
                p { (rule_text(r)) }
                (ratio_svg(r))
                h2 { "Points" }
                table id="points" {
                    tr {
                        th { "point" } th { "BASE ms" } th { "NEW ms" } th { "NEW/BASE [95 % CI]" }
                        th { "p" } th { "time" } th { "BASE MHz" } th { "NEW MHz" } th { "cycles" }
                        th { "basis" } th { "why" }
                    }
                    @for p in &r.points {
                        tr {
                            td { (p.key) }
                            td.n { (fmt_ms(p.base_median_ms)) (noisy(p.base_noisy)) }
                            td.n { (fmt_ms(p.new_median_ms)) (noisy(p.new_noisy)) }
                            td.n { (fmt_ratio(&p.time)) }
                            td.n { (fmt_p(&p.time)) }
                            td class=(p.time.verdict) { (p.time.verdict) }
                            td.n { (mhz(p.base_sm_mhz)) }
                            td.n { (mhz(p.new_sm_mhz)) }
                            td {
                                @if let Some(c) = &p.cycles { (c.verdict) " (" (fmt_ratio(c)) ")" }
                            }
                            td { (format!("{:?}", p.time.basis)) }
                            td { (p.time.why) "; " (p.band_note()) }
                        }
                    }
                }
                @if !r.errors.is_empty() {
                    h2 { "Errors that moved" }
                    table id="errors" {
                        tr { th { "point" } th { "column" } th { "BASE" } th { "NEW" } }
                        @for e in &r.errors {
                            tr { td { (e.key) } td { (e.column.name) } td { (e.base) } td { (e.new) } }
                        }
                    }
                }
                @if !r.status_changes.is_empty() {
                    h2 { "Status changes" }
                    table id="status" {
                        tr { th { "point" } th { "BASE" } th { "NEW" } th { "reason" } }
                        @for s in &r.status_changes {
                            tr { td { (s.key) } td { (s.base) } td { (s.new) } td { (s.reason) } }
                        }
                    }
                }
                @for (title, keys) in [
                    ("Only in BASE", &r.only_base),
                    ("Only in NEW", &r.only_new),
                    ("Without GPU time", &r.untimed),
                ] {
                    @if !keys.is_empty() {
                        h2 { (title) " (" (keys.len()) ")" }
                        ul { @for k in keys { li { (k) } } }
                    }
                }
            }
        }
    }
}

/// The ratio chart's scale: ratios outside it are drawn as off-scale arrows with their value.
pub const RATIO_MIN: f64 = 0.25;
pub const RATIO_MAX: f64 = 4.0;

/// One row per point: the ratio (dot, coloured by verdict) and its 95 % CI (bar) on a log
/// axis, with the noise band shaded.
fn ratio_svg(r: &AbReport) -> Markup {
    let pts: Vec<&PointCmp> = r
        .points
        .iter()
        .filter(|p| p.time.ratio.is_finite() && p.time.ratio > 0.0)
        .collect();
    if pts.is_empty() {
        return html! {};
    }
    let band = r.opts.verdict.noise_band;
    let finite = |v: f64| v.is_finite() && v > 0.0;
    let mut lo = 1.0 - band;
    let mut hi = 1.0 + band;
    for p in &pts {
        let (a, b) = p.time.ratio_ci;
        for v in [p.time.ratio, a, b] {
            if finite(v) {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    let (lo, hi) = (
        (lo / 1.05).max(RATIO_MIN).ln(),
        (hi * 1.05).min(RATIO_MAX).ln(),
    );
    let (label_w, plot_w, row_h, top) = (470.0, 560.0, 14.0, 30.0);
    let x = |v: f64| label_w + (v.clamp(RATIO_MIN, RATIO_MAX).ln() - lo) / (hi - lo) * plot_w;
    let height = top + row_h * pts.len() as f64 + 10.0;
    let f1 = |v: f64| format!("{v:.1}");
    let ticks: Vec<f64> = [0.25f64, 0.5, 0.8, 0.9, 1.0, 1.1, 1.25, 1.5, 2.0, 4.0]
        .into_iter()
        .filter(|t| t.ln() >= lo && t.ln() <= hi)
        .collect();
    html! {
        h2 { "Ratios" }
        svg xmlns="http://www.w3.org/2000/svg" width=(label_w + plot_w + 20.0) height=(height)
            font-family="sans-serif" font-size="10" {
            rect x=(f1(x(1.0 - band))) y=(top) width=(f1(x(1.0 + band) - x(1.0 - band)))
                height=(f1(row_h * pts.len() as f64)) fill="#eee" {}
            @for t in &ticks {
                line x1=(f1(x(*t))) x2=(f1(x(*t))) y1=(top) y2=(f1(height - 10.0))
                    stroke=(if *t == 1.0 { "#444" } else { "#ddd" }) {}
                text x=(f1(x(*t))) y=(top - 8.0) text-anchor="middle" { (t) }
            }
            @for (i, p) in pts.iter().enumerate() {
                (ratio_row(p, top + row_h * (i as f64 + 0.5), label_w, &x))
            }
        }
    }
}

/// One point's row of the ratio chart: its key, its CI bar, and its dot (or an arrow at the
/// edge with the value written beside it when off the scale, never a dot drawn at the edge as
/// if it were the value).
fn ratio_row(p: &PointCmp, y: f64, label_w: f64, x: &dyn Fn(f64) -> f64) -> Markup {
    let colour = match p.time.verdict {
        Verdict::Slower => "#b00",
        Verdict::Faster => "#070",
        Verdict::Unsure => "#d80",
        Verdict::Same => "#777",
    };
    let f1 = |v: f64| format!("{v:.1}");
    let label: String = p.key.chars().take(80).collect();
    let finite = |v: f64| v.is_finite() && v > 0.0;
    let (a, b) = p.time.ratio_ci;
    let r = p.time.ratio;
    let (tip, dir, anchor) = if r > RATIO_MAX {
        (x(RATIO_MAX), 1.0, "end")
    } else {
        (x(RATIO_MIN), -1.0, "start")
    };
    html! {
        text x=(f1(label_w - 6.0)) y=(f1(y + 3.5)) text-anchor="end" { (label) }
        @if finite(a) && finite(b) {
            line x1=(f1(x(a))) x2=(f1(x(b))) y1=(f1(y)) y2=(f1(y)) stroke=(colour) stroke-width="2" {}
        }
        @if (RATIO_MIN..=RATIO_MAX).contains(&r) {
            circle cx=(f1(x(r))) cy=(f1(y)) r="3.5" fill=(colour) {
                title { (p.key) " " (fmt_ratio(&p.time)) }
            }
        } @else {
            path class="offscale" data-value=(r)
                d=(format!("M{:.1},{:.1} L{:.1},{:.1} L{:.1},{:.1} Z", tip, y, tip - dir * 8.0, y - 4.5, tip - dir * 8.0, y + 4.5))
                fill=(colour) {
                title { (p.key) " " (fmt_ratio(&p.time)) " (off the scale)" }
            }
            text x=(f1(tip - dir * 11.0)) y=(f1(y + 3.5)) text-anchor=(anchor) fill=(colour) {
                (crate::cells::short(Some(r))) "×"
            }
        }
    }
}

/// The calibration as Markdown: false alarms per family, the widest bands, the drift.
pub fn calibration_markdown(c: &Calibration) -> String {
    let mut m = String::new();
    let _ = writeln!(m, "# mfx calibrate\n");
    let _ = writeln!(m, "- A/A runs: {}", c.runs.join(", "));
    let total = c
        .false_alarms
        .values()
        .fold(Alarms::default(), |a, b| Alarms {
            compared: a.compared + b.compared,
            same: a.same + b.same,
            faster: a.faster + b.faster,
            slower: a.slower + b.slower,
            unsure: a.unsure + b.unsure,
        });
    let _ = writeln!(
        m,
        "- At the fixed ±{:.1} % band, over every pair: {} comparisons, SAME {}, FASTER {}, \
         SLOWER {}, UNSURE {}: false-alarm rate {:.2} %",
        c.floor * 100.0,
        total.compared,
        total.same,
        total.faster,
        total.slower,
        total.unsure,
        total.false_alarm_rate() * 100.0
    );
    let wide = c.points.values().filter(|b| **b > c.floor).count();
    let _ = writeln!(
        m,
        "- Bands: {} points ({} above the ±{:.1} % floor; margin ×{}), {} classes\n",
        c.points.len(),
        wide,
        c.floor * 100.0,
        c.margin,
        c.classes.len()
    );
    let _ = writeln!(
        m,
        "| method family | compared | SAME | FASTER | SLOWER | UNSURE | false alarms |\n\
         |---|---:|---:|---:|---:|---:|---:|"
    );
    for (f, a) in &c.false_alarms {
        let _ = writeln!(
            m,
            "| {f} | {} | {} | {} | {} | {} | {:.2} % |",
            a.compared,
            a.same,
            a.faster,
            a.slower,
            a.unsure,
            a.false_alarm_rate() * 100.0
        );
    }
    let mut top: Vec<(&String, &f64)> = c.points.iter().filter(|(_, b)| **b > c.floor).collect();
    top.sort_by(|a, b| b.1.total_cmp(a.1));
    if !top.is_empty() {
        let _ = writeln!(m, "\n## Points wider than the floor ({})\n", top.len());
        let _ = writeln!(m, "| point | band |\n|---|---:|");
        for (k, b) in top {
            let _ = writeln!(m, "| {} | ±{:.1} % |", k.replace('|', "\\|"), b * 100.0);
        }
    }
    let _ = writeln!(
        m,
        "\n## Canary drift per run (ratio to its fastest run)\n\n| run | first 15 s | after 60 s |\n|---|---:|---:|"
    );
    let f = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.3}"));
    for d in &c.drift {
        let _ = writeln!(
            m,
            "| {} | {} | {} |",
            d.run,
            f(d.canary_first_15s),
            f(d.canary_after_60s)
        );
    }
    m
}
