//! "Reproduction": the sources' published figures (`scenarios/papers/*.toml`) beside ours, read
//! from the rows the papers files point to. One table per source: figure, paper value, the
//! paper's ratio, ours (the measured ratio r = baseline / ours of the rule's column, with its
//! 95 % interval), and the verdict by the declared rule ([`papers::judge`]: an effect inside the
//! point's noise band is no measurable effect, a sampled metric without an interval is not a
//! hold, an order holds only whole). A figure whose faithful setup is not built says what it
//! needs, and mfx's own variants follow it on rows of their own, never counted as its verdict.
//! A figure that cannot be reproduced says why. Empty when the run holds no suite a papers file
//! points to.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write;
use std::path::Path;

use scenarios::papers::{self, Fact, Figure, PointRef, Rule, RuleKind, Verdict};
use schema::cols;

use crate::cells::esc;
use crate::data::{Rec, Runs};
use mfx_analysis::bands::Calibration;

/// The noise band of a point: `mfx compare`'s SAME band, from a calibration where the run has
/// one (`calibration.json` beside `runs.csv`, written by `mfx calibrate`), else the fixed ±2 %.
#[derive(Default)]
pub struct Bands {
    calibration: Option<Calibration>,
}

impl Bands {
    /// The fixed band for every point.
    pub fn fixed() -> Bands {
        Bands::default()
    }
    /// The run folder's `calibration.json` if there is one (an unreadable one is an error).
    pub fn for_run(dir: &Path) -> anyhow::Result<Bands> {
        let p = dir.join("calibration.json");
        Ok(Bands {
            calibration: if p.exists() {
                Some(Calibration::load(&p)?)
            } else {
                None
            },
        })
    }
    /// The band of a row (by its point key).
    pub fn of(&self, r: &Rec) -> f64 {
        let floor = mfx_stats::VerdictOptions::default().noise_band;
        match &self.calibration {
            Some(c) => c.band_for(r.get(cols::POINT_KEY), floor).0,
            None => floor,
        }
    }
}

/// What the rows say for a point.
enum Found<'a> {
    /// The row (the first ok one where the point was measured more than once).
    One(&'a Rec),
    None,
    /// Rows of different points match: their keys.
    Ambiguous(Vec<String>),
}

/// The axis names a point key lists (`study|scene|WxH|method|k=v,k=v`).
fn key_axes(key: &str) -> impl Iterator<Item = &str> {
    key.rsplit('|')
        .next()
        .unwrap_or("")
        .split(',')
        .filter_map(|kv| kv.split_once('=').map(|(k, _)| k))
}

/// The rows a point names: same suite, method, scene label, resolution and axis values. Rows
/// whose cells agree on every axis any of their keys lists are one point measured more than
/// once (two study tables giving it differently); rows that disagree are different points.
fn find<'a>(runs: &'a Runs, p: &PointRef) -> Found<'a> {
    let res = [p.resolution[0].to_string(), p.resolution[1].to_string()];
    let hits: Vec<&Rec> = runs
        .rows
        .iter()
        .filter(|r| {
            r.get(cols::SUITE) == p.suite
                && r.get(cols::METHOD) == p.method
                && r.get(cols::SCENE_LABEL) == p.scene
                && r.get(cols::WIDTH) == res[0]
                && r.get(cols::HEIGHT) == res[1]
                && p.axes.iter().all(|(k, v)| same(r.get_name(k), v))
        })
        .collect();
    let Some(first) = hits.first() else {
        return Found::None;
    };
    let axes: BTreeSet<&str> = hits
        .iter()
        .flat_map(|r| key_axes(r.get(cols::POINT_KEY)))
        .collect();
    let identity =
        |r: &Rec| -> Vec<String> { axes.iter().map(|a| r.get_name(a).to_string()).collect() };
    let points: BTreeSet<Vec<String>> = hits.iter().map(|r| identity(r)).collect();
    if points.len() > 1 {
        let keys: BTreeSet<String> = hits
            .iter()
            .map(|r| r.get(cols::POINT_KEY).to_string())
            .collect();
        return Found::Ambiguous(keys.into_iter().collect());
    }
    // Of one point measured under two keys, the row whose key names most of the axes the
    // figure names is the table that studies them (seeds-deferred gives BF3's default point in
    // a thread table with one phase-clock frame and in the diffuse table with nine and their
    // interval); the first ok row among equals.
    let named = |r: &Rec| {
        key_axes(r.get(cols::POINT_KEY))
            .filter(|a| p.axes.contains_key(*a))
            .count()
    };
    let most = hits.iter().map(|r| named(r)).max().unwrap_or(0);
    let best: Vec<&Rec> = hits.iter().copied().filter(|r| named(r) == most).collect();
    let row = best
        .iter()
        .copied()
        .find(|r| r.ok())
        .or_else(|| hits.iter().copied().find(|r| r.ok()))
        .unwrap_or(first);
    Found::One(row)
}

/// A CSV cell equals a TOML value (numbers compared as numbers: "1" is 1.0).
fn same(cell: &str, v: &toml::Value) -> bool {
    match v {
        toml::Value::String(s) => cell == s,
        toml::Value::Boolean(b) => cell == b.to_string(),
        toml::Value::Integer(i) => cell.parse::<f64>().ok() == Some(*i as f64),
        toml::Value::Float(x) => cell.parse::<f64>().ok() == Some(*x),
        _ => false,
    }
}

fn num(x: f64) -> String {
    if x.is_infinite() {
        "∞".into()
    } else if x.abs() >= 100.0 {
        format!("{x:.0}")
    } else if x.abs() >= 0.1 {
        format!("{x:.2}")
    } else {
        format!("{x:.3}")
    }
}

/// The pass times of a row (`pass_ms`), or of their intervals (`pass_ms_ci`: label → [lo, hi]).
fn pass_json(r: &Rec, col: schema::Col) -> Option<serde_json::Map<String, serde_json::Value>> {
    match serde_json::from_str(r.get(col)) {
        Ok(serde_json::Value::Object(m)) => Some(m),
        _ => None,
    }
}

/// Columns whose value is exact for a build (errors against the reference, bytes, counts): a
/// ratio of them needs no interval.
const EXACT: &[schema::Col] = &[
    cols::VIS_BLEED_MEAN,
    cols::VIS_OVERSHADOW_MEAN,
    cols::VIS_RMSE,
    cols::VIS_BIAS,
    cols::VIS_MAX_ABS_ERR,
    cols::RMSE,
    cols::BYTES_PER_PIXEL,
    cols::BYTES_ALLOCATED,
    cols::GEOMETRY_PASSES,
    cols::COLLISION_RATE,
    cols::OVERFLOW_RATE,
];

/// Rates computed as a count over the median GPU time: their interval is the time's, inverted.
const PER_GPU_MS: &[schema::Col] = &[
    cols::TRIANGLES_PER_S,
    cols::VERTICES_PER_S,
    cols::FRAGMENTS_PER_S,
];

/// One side's value and its 95 % interval (None: a sampled metric the row gives no interval
/// for: CPU clocks, hazard rates of one capture, pass times without `pass_ms_ci`, the
/// small-viewport time).
struct Value {
    v: f64,
    interval: Option<(f64, f64)>,
}

/// What a row lacks for a comparison.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
enum Missing {
    /// Every sample was discarded (a throttled or noisy clock): no pass is timed.
    #[error("the row kept no samples ({discarded} discarded, flag {flag}): no pass times")]
    Samples { discarded: String, flag: String },
    /// The study never writes this pass (a suite not run with it).
    #[error("the rows have no pass '{0}'")]
    Pass(String),
    #[error("no {0} in the rows")]
    Column(String),
}

/// A row's value of a column or pass: `Err` says what the row lacks.
fn value(r: &Rec, col: &str, pass: Option<&str>) -> Result<Value, Missing> {
    if let Some(p) = pass {
        let passes = pass_json(r, cols::PASS_MS).unwrap_or_default();
        if passes.is_empty() && r.f(cols::SAMPLES) == Some(0.0) {
            // Every sample was discarded (a throttled or noisy clock): the row times no pass,
            // which is not the same as a study that never writes the pass.
            return Err(Missing::Samples {
                discarded: r.get(cols::SAMPLES_DISCARDED).to_string(),
                flag: r.get(cols::FLAG).to_string(),
            });
        }
        let v = passes
            .get(p)
            .and_then(|v| v.as_f64())
            .ok_or_else(|| Missing::Pass(p.to_string()))?;
        let interval = pass_json(r, cols::PASS_MS_CI).and_then(|m| {
            let a = m.get(p)?.as_array()?;
            Some((a.first()?.as_f64()?, a.get(1)?.as_f64()?))
        });
        return Ok(Value { v, interval });
    }
    let v = r
        .f_name(col)
        .ok_or_else(|| Missing::Column(col.to_string()))?;
    let ci = || Some((r.f(cols::GPU_MS_CI_LO)?, r.f(cols::GPU_MS_CI_HI)?));
    let med = r.f(cols::GPU_MS_MEDIAN);
    let interval = if col == cols::GPU_MS_MEDIAN.name {
        ci()
    } else if PER_GPU_MS.iter().any(|c| c.name == col) {
        ci().zip(med)
            .filter(|((lo, _), m)| *lo > 0.0 && *m > 0.0)
            .map(|((lo, hi), m)| (v * m / hi, v * m / lo))
    } else if EXACT.iter().any(|c| c.name == col) {
        Some((v, v))
    } else {
        // A sampled metric whose row carries its own interval (`<col>_ci_lo`, `<col>_ci_hi`):
        // shade_ns_per_light_quad over repeated phase-clock frames, hazard_rate over repeated
        // captures.
        r.f_name(&format!("{col}_ci_lo"))
            .zip(r.f_name(&format!("{col}_ci_hi")))
    };
    Ok(Value { v, interval })
}

/// What one comparison says.
#[derive(Clone, Debug, PartialEq)]
enum Outcome {
    /// A ruled verdict and the cell "r = … (interval)".
    Ruled(Verdict, String),
    /// The rows are not in this run: why (the suite that makes them).
    NotRun(String),
    /// The rows exist but cannot be compared (skipped, failed, ambiguous, a missing column).
    NotMeasured(String),
}

/// The rows of a figure's or variant's points, each found or not.
fn rows_of<'a>(runs: &'a Runs, points: &[&PointRef]) -> Result<Vec<&'a Rec>, Outcome> {
    let mut out = Vec::new();
    for p in points {
        match find(runs, p) {
            Found::One(r) => out.push(r),
            Found::None => return Err(Outcome::NotRun(format!("not run (suite {})", p.suite))),
            Found::Ambiguous(keys) => {
                return Err(Outcome::NotMeasured(format!(
                    "ambiguous: {} points match ({})",
                    keys.len(),
                    keys.join("; ")
                )))
            }
        }
    }
    for r in &out {
        if !r.ok() {
            return Err(Outcome::NotMeasured(format!(
                "{}: {}",
                r.get(cols::STATUS),
                r.get(cols::REASON)
            )));
        }
    }
    Ok(out)
}

/// A measured ratio: r = baseline / ours, its 95 % interval (None: a side has none), and the
/// pair's noise band (the wider of the two points').
struct Ratio {
    r: f64,
    interval: Option<(f64, f64)>,
    band: f64,
}

/// The ratio of the rule's column (or pass) between two rows.
fn ratio(rule: &Rule, ro: &Rec, rb: &Rec, bands: &Bands) -> Result<Ratio, Missing> {
    let o = value(ro, rule.column(), rule.pass.as_deref())?;
    let b = value(rb, rule.baseline_column(), rule.baseline_pass())?;
    let r = b.v / o.v;
    let interval = match (o.interval, b.interval) {
        (Some((olo, ohi)), Some((blo, bhi))) if olo > 0.0 && ohi >= olo && bhi >= blo => {
            Some((blo / ohi, bhi / olo))
        }
        _ => None,
    };
    Ok(Ratio {
        r,
        interval,
        band: bands.of(ro).max(bands.of(rb)),
    })
}

/// Rules the points (`[ours, baseline]`, or an order) by `rule`.
fn rule_points(
    runs: &Runs,
    bands: &Bands,
    rule: &Rule,
    paper: Option<f64>,
    points: &[&PointRef],
) -> Outcome {
    if points.len() < 2 {
        return Outcome::NotMeasured("no points declared".into());
    }
    let rows = match rows_of(runs, points) {
        Ok(r) => r,
        Err(o) => return o,
    };
    let mut verdicts = Vec::new();
    let mut cells = Vec::new();
    for pair in rows.windows(2) {
        let Ratio { r, interval, band } = match ratio(rule, pair[0], pair[1], bands) {
            Ok(x) => x,
            Err(why) => {
                let suite = &points[0].suite;
                return if matches!(why, Missing::Pass(_)) {
                    Outcome::NotRun(format!("not run: {why} (suite {suite})"))
                } else {
                    Outcome::NotMeasured(why.to_string())
                };
            }
        };
        let Some(v) = papers::judge(rule, paper, r, interval, band) else {
            return Outcome::NotMeasured(format!("r = {r} cannot be ruled"));
        };
        verdicts.push(v);
        cells.push(match interval {
            Some((lo, hi)) if lo != hi => format!("r = {} ({}–{})", num(r), num(lo), num(hi)),
            Some(_) => format!("r = {} (exact)", num(r)),
            None => format!("r = {} (no interval)", num(r)),
        });
    }
    let v = if rule.rule == RuleKind::Order {
        papers::judge_order(&verdicts)
    } else {
        verdicts.first().copied()
    };
    match v {
        Some(v) => Outcome::Ruled(v, cells.join("; ")),
        None => Outcome::NotMeasured("nothing to rule".into()),
    }
}

/// A figure's verdict, for its row and for the tally.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kind {
    Ruled(Verdict),
    /// The faithful setup is not built (`needs`).
    NotBuilt,
    NotRun,
    /// Skipped, failed, ambiguous or missing a column.
    NotMeasured,
    NotReproducible,
}

impl Kind {
    pub fn word(self) -> &'static str {
        match self {
            Kind::Ruled(v) => v.word(),
            Kind::NotBuilt => "not built",
            Kind::NotRun => "not run",
            Kind::NotMeasured => "not measured",
            Kind::NotReproducible => "not reproducible",
        }
    }
}

/// One table row's cells (row, figure, setup, paper, paper ratio, ours, verdict, measured and
/// why) and, for a figure's own row, its kind.
pub(crate) struct Line {
    pub(crate) cells: [String; 8],
    pub(crate) kind: Option<Kind>,
}

fn kind_of(o: &Outcome) -> (Kind, String, String) {
    match o {
        Outcome::Ruled(v, cell) => (Kind::Ruled(*v), cell.clone(), v.word().to_string()),
        Outcome::NotRun(why) => (Kind::NotRun, "—".into(), why.clone()),
        Outcome::NotMeasured(why) => (Kind::NotMeasured, "—".into(), why.clone()),
    }
}

/// The named rows of a figure (`ours`, `variant:baseline`, …) found in the run.
fn named_rows<'a>(runs: &'a Runs, fig: &Figure) -> BTreeMap<String, &'a Rec> {
    fig.named_points()
        .into_iter()
        .filter_map(|(n, p)| match find(runs, p) {
            Found::One(r) => Some((n, r)),
            _ => None,
        })
        .collect()
}

/// Why a fact of a figure has no value.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub(crate) enum FactError {
    #[error("no fact '{0}'")]
    NoFact(String),
    #[error("facts.{fact}: row '{row}' is not in the run")]
    RowNotRun { fact: String, row: String },
    #[error("facts.{fact}: no {column} in row '{row}'")]
    NoColumn {
        fact: String,
        column: String,
        row: String,
    },
    #[error("facts.{fact}: no pass '{pass}' in row '{row}'")]
    NoPass {
        fact: String,
        pass: String,
        row: String,
    },
    #[error("facts.{0}: no column or pass")]
    NoColumnOrPass(String),
    /// A chain of `over` facts that returns to itself.
    #[error("facts.{0}: `over` loops")]
    OverLoops(String),
}

/// A fact's value from the named rows (`Err`: what is missing).
pub(crate) fn fact_value(
    fig: &Figure,
    rows: &BTreeMap<String, &Rec>,
    name: &str,
    depth: usize,
) -> Result<f64, FactError> {
    let f: &Fact = fig
        .facts
        .get(name)
        .ok_or_else(|| FactError::NoFact(name.to_string()))?;
    let r = rows.get(&f.row).ok_or_else(|| FactError::RowNotRun {
        fact: name.to_string(),
        row: f.row.clone(),
    })?;
    let no_column = |column: &str| FactError::NoColumn {
        fact: name.to_string(),
        column: column.to_string(),
        row: f.row.clone(),
    };
    let mut v = match (&f.column, &f.pass) {
        (Some(c), _) => r.f_name(c).ok_or_else(|| no_column(c))?,
        (None, Some(p)) => pass_json(r, cols::PASS_MS)
            .and_then(|m| m.get(p)?.as_f64())
            .ok_or_else(|| FactError::NoPass {
                fact: name.to_string(),
                pass: p.clone(),
                row: f.row.clone(),
            })?,
        (None, None) => return Err(FactError::NoColumnOrPass(name.to_string())),
    };
    if let Some(per) = &f.per {
        v /= r.f_name(per).ok_or_else(|| no_column(per))?;
    }
    if let Some(o) = &f.over {
        if depth > 8 {
            return Err(FactError::OverLoops(name.to_string()));
        }
        v /= fact_value(fig, rows, o, depth + 1)?;
    }
    if f.percent {
        v *= 100.0;
    }
    Ok(v)
}

/// `why_differs` with its facts filled from the rows (a fact the rows lack reads "?").
fn why_text(fig: &Figure, rows: &BTreeMap<String, &Rec>) -> Option<String> {
    let mut text = fig.why_differs.clone()?;
    for name in fig.placeholders() {
        let shown = match (fact_value(fig, rows, name, 0), fig.facts.get(name)) {
            (Ok(v), Some(f)) => format!(
                "{}{}{}",
                // A count (passes, bytes) reads as one.
                if v.fract() == 0.0 {
                    format!("{v:.0}")
                } else {
                    num(v)
                },
                if f.percent { " %" } else { "" },
                f.unit.as_deref().unwrap_or("")
            ),
            _ => "?".into(),
        };
        text = text.replacen(&format!("{{{name}}}"), &shown, 1);
    }
    Some(text)
}

/// What two rows' GPU times are made of (their slowest pass and its share of the frame).
fn measured(rule: &Rule, ro: &Rec, rb: &Rec) -> String {
    if !rule.column().ends_with("_ms_median") && rule.pass.is_none() {
        return String::new();
    }
    let one = |r: &Rec| -> Option<String> {
        let (pass, ms, share) = crate::bounds::slowest_pass(r)?;
        Some(format!(
            "{}: {} {} of {} ms ({} %)",
            r.get(cols::METHOD),
            pass,
            num(ms),
            num(r.f(cols::GPU_MS_MEDIAN)?),
            (100.0 * share).round()
        ))
    };
    match (one(ro), one(rb)) {
        (Some(a), Some(b)) => format!("ours {a}; baseline {b}"),
        _ => String::new(),
    }
}

/// A figure's rows: its own, then one per variant.
fn lines(runs: &Runs, bands: &Bands, fig: &Figure) -> Vec<Line> {
    let paper = match (fig.value, &fig.against, &fig.claim) {
        (Some(v), Some(a), _) => format!("{} {} vs {}", num(v), fig.metric, a),
        (Some(v), None, Some(c)) => format!("{} {}: {}", num(v), fig.metric, c),
        (Some(v), None, None) => format!("{} {}", num(v), fig.metric),
        (None, _, Some(c)) => c.clone(),
        _ => fig.metric.clone(),
    };
    let s = &fig.setup;
    let setup = format!(
        "{}{}, {}{}{}",
        s.gpu,
        s.resolution
            .map(|r| format!(", {}×{}", r[0], r[1]))
            .unwrap_or_default(),
        s.scene,
        s.triangles
            .map(|t| format!(" ({t} triangles)"))
            .unwrap_or_default(),
        s.layers
            .as_ref()
            .map(|l| format!(", {l}"))
            .unwrap_or_default()
    );
    let rows = named_rows(runs, fig);
    let (kind, ours, verdict, why) = if !fig.reproducible {
        (
            Kind::NotReproducible,
            "—".to_string(),
            format!("not reproducible: {}", fig.reason.as_deref().unwrap_or("")),
            String::new(),
        )
    } else if let (Some(n), Some(rule)) = (&fig.needs, &fig.holds) {
        let why = why_text(fig, &rows)
            .map(|w| format!(" Measured in mfx's variant: {w}"))
            .unwrap_or_default();
        (
            Kind::NotBuilt,
            "—".to_string(),
            format!("not built ({})", rule.describe(fig.ratio)),
            format!("needs {}: {}{why}", n.variant, n.why),
        )
    } else if let Some(rule) = &fig.holds {
        let o = rule_points(runs, bands, rule, fig.ratio, &fig.points());
        let (kind, cell, word) = kind_of(&o);
        let verdict = match kind {
            Kind::Ruled(_) => format!("{word} ({})", rule.describe(fig.ratio)),
            _ => word,
        };
        let mut why = match (fig.ours.as_ref(), fig.baseline.as_ref()) {
            (Some(_), Some(_)) if matches!(kind, Kind::Ruled(_)) => rows
                .get("ours")
                .zip(rows.get("baseline"))
                .map(|(a, b)| measured(rule, a, b))
                .unwrap_or_default(),
            _ => String::new(),
        };
        if kind != Kind::Ruled(Verdict::Holds) {
            if let Some(w) = why_text(fig, &rows) {
                why = if why.is_empty() {
                    format!("why: {w}")
                } else {
                    format!("{why}. Why: {w}")
                };
            }
        }
        (kind, cell, verdict, why)
    } else {
        (
            Kind::NotMeasured,
            "—".into(),
            "no rule declared".into(),
            String::new(),
        )
    };
    let mut out = vec![Line {
        cells: [
            fig.row.to_string(),
            format!("{} {} ({})", fig.table, fig.section, fig.id),
            setup,
            paper,
            fig.ratio.map(num).unwrap_or_else(|| "—".into()),
            ours,
            verdict,
            why,
        ],
        kind: Some(kind),
    }];
    for v in &fig.variants {
        let Some(rule) = v.holds.as_ref().or(fig.holds.as_ref()) else {
            continue;
        };
        let o = rule_points(runs, bands, rule, fig.ratio, &v.points());
        let (kind, cell, word) = kind_of(&o);
        let verdict = match kind {
            Kind::Ruled(_) => format!("{word} ({})", rule.describe(fig.ratio)),
            _ => word,
        };
        let ours_row = rows.get(&format!("{}:ours", v.name));
        let measured = match (ours_row, rows.get(&format!("{}:baseline", v.name))) {
            (Some(a), Some(b)) if matches!(kind, Kind::Ruled(_)) => measured(rule, a, b),
            _ => String::new(),
        };
        out.push(Line {
            cells: [
                fig.row.to_string(),
                format!("↳ {} variant '{}': {}", fig.id, v.name, v.what),
                String::new(),
                String::new(),
                String::new(),
                cell,
                format!("mfx's variant {verdict}"),
                measured,
            ],
            kind: None,
        });
    }
    out
}

/// One source's table: its heading, its papers file's name, and its lines.
pub(crate) struct Table {
    pub(crate) heading: String,
    pub(crate) name: String,
    pub(crate) lines: Vec<Line>,
}

/// The columns of every table.
pub(crate) const HEADER: [&str; 8] = [
    "row",
    "figure",
    "setup",
    "paper",
    "paper ratio",
    "ours",
    "verdict",
    "measured: slowest pass (ours; baseline), and why ours differs",
];

/// The note under the heading.
pub(crate) const NOTE: &str = "r = baseline ÷ ours of the rule's column (for times, ours' speed-up), with its 95 % interval; the rule is declared in scenarios/papers/*.toml. An effect within a point's noise band (mfx compare's SAME band: calibrated, else ±2 %) is no measurable effect, never a hold; a hold needs the whole interval to pass the rule; a sampled metric whose rows carry no interval is not a hold; an order holds only whole. A figure whose faithful setup mfx does not build yet is 'not built' and says what it needs; mfx's own variants follow it (↳) and are not counted.";

/// Every source's table, or none when no row of `runs` is from a suite a papers file points to.
pub(crate) fn tables(runs: &Runs, bands: &Bands) -> Vec<Table> {
    let files = papers::builtin();
    let suites: BTreeSet<&str> = files
        .iter()
        .flat_map(|(_, f)| f.figures.iter())
        .flat_map(|f| {
            f.named_points()
                .into_iter()
                .map(|(_, p)| p.suite.as_str())
                .collect::<Vec<_>>()
        })
        .collect();
    if !runs
        .rows
        .iter()
        .any(|r| suites.contains(r.get(cols::SUITE)))
    {
        return Vec::new();
    }
    files
        .iter()
        .map(|(name, f)| Table {
            heading: format!(
                "{} — {} ({})",
                f.source.title, f.source.authors, f.source.venue
            ),
            name: name.to_string(),
            lines: f
                .figures
                .iter()
                .flat_map(|fig| lines(runs, bands, fig))
                .collect(),
        })
        .collect()
}

/// The count of figures per verdict (figures' own rows only, never their variants).
fn tally_of(tables: &[Table]) -> BTreeMap<Kind, usize> {
    let mut t = BTreeMap::new();
    for k in tables.iter().flat_map(|t| &t.lines).filter_map(|l| l.kind) {
        *t.entry(k).or_insert(0) += 1;
    }
    t
}

/// The tally as one sentence ("67 figures: 5 hold, …").
fn tally_text(t: &BTreeMap<Kind, usize>) -> String {
    let total: usize = t.values().sum();
    let parts: Vec<String> = t.iter().map(|(k, n)| format!("{n} {}", k.word())).collect();
    format!("{total} figures: {}.", parts.join(", "))
}

/// The verdict counts of a run's Reproduction tables (empty when it has none).
pub fn tally(runs: &Runs) -> BTreeMap<Kind, usize> {
    tally_of(&tables(runs, &Bands::fixed()))
}

/// The section's HTML with the fixed band, or "" (see [`section_with`]).
pub fn section(runs: &Runs) -> String {
    section_with(runs, &Bands::fixed())
}

/// The section's HTML, or "" when no row of `runs` is from a suite a papers file points to.
pub fn section_with(runs: &Runs, bands: &Bands) -> String {
    let tables = tables(runs, bands);
    if tables.is_empty() {
        return String::new();
    }
    let mut h = format!(
        "<h2 id=\"reproduction\">Reproduction: the sources' published figures beside ours</h2><p class=\"note\">{}</p><p>{}</p>",
        esc(NOTE),
        esc(&tally_text(&tally_of(&tables)))
    );
    for t in &tables {
        let _ = write!(
            h,
            "<h3>{}</h3><table class=\"repro\" id=\"repro-{}\"><tr>",
            esc(&t.heading),
            esc(&t.name)
        );
        for c in HEADER {
            let _ = write!(h, "<th>{}</th>", esc(c));
        }
        h.push_str("</tr>");
        for l in &t.lines {
            h.push_str(if l.kind.is_some() {
                "<tr>"
            } else {
                "<tr class=\"variant\">"
            });
            for c in &l.cells {
                let _ = write!(h, "<td>{}</td>", esc(c));
            }
            h.push_str("</tr>");
        }
        h.push_str("</table>");
    }
    h
}

/// The markdown with the fixed band, or "" (see [`markdown_with`]).
pub fn markdown(runs: &Runs) -> String {
    markdown_with(runs, &Bands::fixed())
}

/// The same tables as markdown (`reproduction.md` beside the report, for a RUN.md), or "".
pub fn markdown_with(runs: &Runs, bands: &Bands) -> String {
    let tables = tables(runs, bands);
    if tables.is_empty() {
        return String::new();
    }
    let cell = |c: &str| c.replace('|', "\\|").replace('\n', " ");
    let mut m = format!(
        "### Reproduction: the sources' published figures beside ours\n\n{NOTE}\n\n{}\n",
        tally_text(&tally_of(&tables))
    );
    for t in &tables {
        let _ = write!(m, "\n#### {}\n\n| {} |\n|", t.heading, HEADER.join(" | "));
        m.push_str(&"---|".repeat(HEADER.len()));
        m.push('\n');
        for l in &t.lines {
            let row: Vec<String> = l.cells.iter().map(|c| cell(c)).collect();
            let _ = writeln!(m, "| {} |", row.join(" | "));
        }
    }
    m
}

#[cfg(test)]
mod tests;
