//! A/B comparison of two runs (`mfx compare BASE NEW`): for every point measured in both, the
//! ratio of median GPU times NEW/BASE with its 95 % CI, a Mann–Whitney p-value and a verdict
//! SAME / FASTER / SLOWER / UNSURE (rule: `mfx_stats::verdict`), in time and — where both sides
//! recorded SM clocks — in cycles; plus every point whose error columns or status moved.
//!
//! Inputs are run folders (`runs.csv`, and `samples.csv` beside it when the run wrote raw
//! samples) or `runs.csv` paths. Points are joined by `point_key` (the adapters may differ: the
//! report names both); when a side holds several platforms (a merged CSV) both sides must, and
//! points are joined by `point_key` and platform. Mixed `schema` versions are refused.
//! Without `samples.csv` on a side, verdicts come from the summary columns (the median and its
//! CI, else min–max): UNSURE unless the intervals separate, and the report says so.
//!
//! Kept independent of the chart code: the page is plain HTML with an inline SVG.

use schema::{cols, samples, Col, Flag};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use mfx_stats::{
    compare_intervals, compare_matched, cycles_k, hold_back, modes, Basis, Comparison, Interval,
    Matched, Matching, Modes, Verdict, VerdictOptions, MODE_MIN_FRAC, MODE_MIN_SEP,
};

use crate::bands::{BandSource, Calibration};
use crate::data::{Rec, Runs};

/// Error columns compared, when present on both sides.
pub const ERROR_COLUMNS: [Col; 7] = [
    cols::RMSE,
    cols::MAX_ABS_ERR,
    cols::BAD_PIXEL_FRAC,
    cols::FLIP_MEAN,
    cols::RMSE_VS_K,
    cols::MAX_ABS_ERR_VS_K,
    cols::MATCHES_TRUTH,
];

#[derive(Clone, Debug)]
pub struct AbOptions {
    pub verdict: VerdictOptions,
    /// An error value moved when `|NEW − BASE| > max(err_abs_tol, err_rel_tol·max(|BASE|,|NEW|))`.
    /// 1e-4: a fortieth of an 8-bit display step (1/255), far above f32 rounding (~1e-7), so
    /// cross-adapter rounding is not listed and a visible change always is.
    pub err_abs_tol: f64,
    /// 5 %: a relative change of a visible error worth a look.
    pub err_rel_tol: f64,
    /// Bands measured by `mfx calibrate` (per point, else per class); `verdict.noise_band` is
    /// then the floor under them.
    pub calibration: Option<Calibration>,
    /// Every NEW sample (and summary time) multiplied by this: 1 normally; 1.05 makes the
    /// synthetic "5 % slower" copy that a calibrated compare must still call SLOWER.
    pub scale_new: f64,
}

impl Default for AbOptions {
    fn default() -> Self {
        AbOptions {
            verdict: VerdictOptions::default(),
            err_abs_tol: 1e-4,
            err_rel_tol: 0.05,
            calibration: None,
            scale_new: 1.0,
        }
    }
}

/// One side of the comparison.
#[derive(Clone, Debug)]
pub struct Side {
    pub runs_csv: PathBuf,
    /// `samples.csv` when present.
    pub samples_csv: Option<PathBuf>,
    pub schema: String,
    /// "adapter (backend)" of its rows, first-seen order.
    pub platforms: Vec<String>,
    pub run_ids: Vec<String>,
    pub git_revs: Vec<String>,
    /// The GPU calibration set's median time on this run's GPU (`run.json`: `calibration`,
    /// written by `mfx sweep` before the points; `mfx merge` compares it across shards).
    pub gpu_calibration_ms: Option<f64>,
}

/// One point measured in both runs.
#[derive(Clone, Debug)]
pub struct PointCmp {
    pub key: String,
    pub platform_base: String,
    pub platform_new: String,
    pub base_median_ms: f64,
    pub new_median_ms: f64,
    /// The verdict in time (`ratio` = NEW/BASE median GPU ms).
    pub time: Comparison,
    /// The verdict in cycles (time × SM clock), when both sides know their clock.
    pub cycles: Option<Comparison>,
    pub base_sm_mhz: Option<f64>,
    pub new_sm_mhz: Option<f64>,
    /// The side's row is flagged `noisy` (or `target_reached = false`).
    pub base_noisy: bool,
    pub new_noisy: bool,
    /// The noise band this point was judged with, and where it came from.
    pub band: f64,
    pub band_source: BandSource,
    /// Two frame-time modes on a side ([`mode_gap`]: their relative distance), from samples.
    pub base_modes: Option<f64>,
    pub new_modes: Option<f64>,
}

impl PointCmp {
    /// "band ±3.1 % (calibrated: this point)".
    pub fn band_note(&self) -> String {
        format!(
            "band ±{:.1} % ({})",
            self.band * 100.0,
            match self.band_source {
                BandSource::Point => "calibrated: this point",
                BandSource::Class => "calibrated: its class",
                BandSource::Fixed => "fixed",
            }
        )
    }
}

/// An error column whose value moved beyond the tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrMove {
    pub key: String,
    pub column: Col,
    pub base: String,
    pub new: String,
}

/// A point whose status differs (e.g. ok → failed).
#[derive(Clone, Debug, PartialEq)]
pub struct StatusChange {
    pub key: String,
    pub base: String,
    pub new: String,
    pub reason: String,
}

#[derive(Clone, Debug)]
pub struct AbReport {
    pub base: Side,
    pub new: Side,
    pub opts: AbOptions,
    /// Points timed on both sides, most severe first (SLOWER, FASTER, UNSURE, SAME; by ratio).
    pub points: Vec<PointCmp>,
    pub only_base: Vec<String>,
    pub only_new: Vec<String>,
    /// In both and ok, but without a GPU time on one side.
    pub untimed: Vec<String>,
    pub errors: Vec<ErrMove>,
    pub status_changes: Vec<StatusChange>,
}

fn platform(r: &Rec) -> String {
    format!("{} ({})", r.get(cols::ADAPTER), r.get(cols::BACKEND))
}

fn distinct(rows: &[Rec], f: impl Fn(&Rec) -> String) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in rows {
        let v = f(r);
        if !v.is_empty() && !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

/// `runs.csv` (else `runs.parquet`) of a folder or the path itself, and `samples.csv` (or `samples.csv.gz`) beside it
/// when present.
fn locate(p: &Path) -> Result<(PathBuf, Option<PathBuf>)> {
    let csv = if p.is_dir() {
        mfx_table::in_folder(p)
            .with_context(|| format!("{}: no runs.csv or runs.parquet there", p.display()))?
    } else {
        p.to_path_buf()
    };
    if !csv.is_file() {
        bail!("{}: no runs.csv there", p.display());
    }
    // Committed reference runs keep their raw samples gzipped (samples.csv.gz).
    let samples = ["samples.csv", "samples.csv.gz"]
        .into_iter()
        .map(|n| csv.with_file_name(n))
        .find(|p| p.is_file());
    Ok((csv, samples))
}

/// Per-sample values of one point of one run.
#[derive(Clone, Debug, Default)]
pub(crate) struct PointSamples {
    gpu_ms: Vec<f64>,
    sm_mhz: Vec<Option<f64>>,
    /// `[timing] sessions` session of each sample (0 where the file has no `session` column).
    session: Vec<u32>,
    /// The canary's ratio to its fastest run after each sample, and the sample's wall time
    /// (`unix_ms`), where written: the drift under load ([`crate::calibrate`]).
    pub(crate) canary: Vec<(f64, f64)>,
}

impl PointSamples {
    /// `values` (one per sample) grouped by session, in session order.
    fn by_session(&self, values: &[f64]) -> Vec<Vec<f64>> {
        let n = self.session.iter().max().map_or(0, |&s| s as usize + 1);
        let mut out = vec![Vec::new(); n.max(1)];
        for (v, &s) in values.iter().zip(&self.session) {
            out[s as usize].push(*v);
        }
        out
    }

    /// The median of each non-empty session, in session order.
    fn session_medians(&self) -> Vec<f64> {
        self.by_session(&self.gpu_ms)
            .into_iter()
            .filter_map(crate::bands::median)
            .collect()
    }

    /// How far apart whole sessions sit: max / min − 1 of the session medians, when there are
    /// two or more sessions and none of them alternates between two frame-time modes itself
    /// (such a point's session medians differ by their modes' shares, which mode matching
    /// resolves). `None` otherwise.
    pub(crate) fn state_spread(&self) -> Option<f64> {
        let sessions: Vec<Vec<f64>> = self
            .by_session(&self.gpu_ms)
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect();
        if sessions.len() < 2
            || sessions
                .iter()
                .any(|s| modes(s, MODE_MIN_FRAC, MODE_MIN_SEP).is_some())
        {
            return None;
        }
        let meds: Vec<f64> = sessions
            .into_iter()
            .filter_map(crate::bands::median)
            .collect();
        let lo = meds.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = meds.iter().copied().fold(0.0f64, f64::max);
        (lo > 0.0).then(|| hi / lo - 1.0)
    }
}

/// Kept samples by (run_id, point_key), in sample order.
pub(crate) type SampleMap = HashMap<(String, String), PointSamples>;

pub(crate) fn load_samples(path: &Path) -> Result<SampleMap> {
    let file = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let input: Box<dyn std::io::Read> = if path.extension().is_some_and(|e| e == "gz") {
        Box::new(flate2::read::GzDecoder::new(file))
    } else {
        Box::new(file)
    };
    let mut rdr = csv::Reader::from_reader(input);
    let h: Vec<String> = rdr
        .headers()
        .with_context(|| format!("{}: no header", path.display()))?
        .iter()
        .map(String::from)
        .collect();
    let col = |c: Col| {
        h.iter()
            .position(|n| n == c.name)
            .with_context(|| format!("{}: no '{c}' column", path.display()))
    };
    let (ck, cr, cg) = (
        col(samples::POINT_KEY)?,
        col(samples::RUN_ID)?,
        col(samples::GPU_MS)?,
    );
    let (cs, cd, cn) = (
        h.iter().position(|c| c == samples::SM_CLOCK_MHZ.name),
        h.iter().position(|c| c == samples::DISCARDED.name),
        // Absent before sessions were recorded: every sample is session 0 then.
        h.iter().position(|c| c == samples::SESSION.name),
    );
    let (cc, cu) = (
        h.iter().position(|c| c == samples::CANARY_RATIO.name),
        h.iter().position(|c| c == samples::UNIX_MS.name),
    );
    let mut out: SampleMap = HashMap::new();
    for (i, rec) in rdr.records().enumerate() {
        let rec = rec.with_context(|| format!("{}: row {}", path.display(), i + 2))?;
        let get = |c: usize| rec.get(c).unwrap_or("");
        if cd.is_some_and(|c| get(c) == "true") {
            continue;
        }
        let Ok(ms) = get(cg).parse::<f64>() else {
            continue; // an untimed sample (no timestamps) has an empty gpu_ms
        };
        let e = out
            .entry((get(cr).to_string(), get(ck).to_string()))
            .or_default();
        e.gpu_ms.push(ms);
        e.sm_mhz.push(
            cs.and_then(|c| get(c).parse::<f64>().ok())
                .filter(|c| *c > 0.0),
        );
        e.session
            .push(cn.and_then(|c| get(c).parse::<u32>().ok()).unwrap_or(0));
        let num = |c: Option<usize>| c.and_then(|c| get(c).parse::<f64>().ok());
        if let (Some(r), Some(t)) = (num(cc), num(cu)) {
            e.canary.push((r, t));
        }
    }
    Ok(out)
}

/// `calibration.canary_ms` of the `run.json` beside a runs.csv, where there is one (read as
/// plain JSON: the report does not depend on the GPU crate that writes it).
fn gpu_calibration_ms(csv: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(csv.with_file_name("run.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("calibration")?
        .get("canary_ms")?
        .as_f64()
        .filter(|x| x.is_finite() && *x > 0.0)
}

impl AbReport {
    /// NEW's GPU over BASE's on the GPU calibration set, when both runs recorded it.
    pub fn gpu_ratio(&self) -> Option<f64> {
        Some(self.new.gpu_calibration_ms? / self.base.gpu_calibration_ms?)
    }
}

pub(crate) fn load_side(p: &Path) -> Result<(Side, Runs, Option<SampleMap>)> {
    // A bundle (`mfx bundle`) is read through a temporary folder; the side names the bundle.
    if mfx_table::bundle::is_bundle(p) {
        let opened = mfx_table::bundle::open(p)?;
        let (mut side, runs, samples) = load_side(opened.dir())?;
        side.runs_csv = p.join(side.runs_csv.file_name().unwrap_or_default());
        side.samples_csv = side
            .samples_csv
            .as_deref()
            .and_then(Path::file_name)
            .map(|n| p.join(n));
        return Ok((side, runs, samples));
    }
    let (csv, samples_csv) = locate(p)?;
    let runs = Runs::load(&csv)?;
    let schemas = distinct(&runs.rows, |r| r.get(cols::SCHEMA).to_string());
    if schemas.len() > 1 {
        bail!(
            "{} mixes CSV schema versions {}: compare runs of one version",
            csv.display(),
            schemas.join(", ")
        );
    }
    let samples = match &samples_csv {
        Some(s) => Some(load_samples(s)?),
        None => None,
    };
    let side = Side {
        gpu_calibration_ms: gpu_calibration_ms(&csv),
        runs_csv: csv,
        samples_csv,
        schema: schemas.into_iter().next().unwrap_or_default(),
        platforms: distinct(&runs.rows, platform),
        run_ids: distinct(&runs.rows, |r| r.get(cols::RUN_ID).to_string()),
        git_revs: distinct(&runs.rows, |r| r.get(cols::GIT_REV).to_string()),
    };
    Ok((side, runs, samples))
}

fn noisy(r: &Rec) -> bool {
    r.flag_set().contains(Flag::Noisy) || r.get(cols::TARGET_REACHED) == "false"
}

/// The summary interval of a row: the median's CI where written, else min–max.
fn interval(r: &Rec, scale: f64) -> Option<Interval> {
    let median = r.f(cols::GPU_MS_MEDIAN)?;
    let pair = |a: Col, b: Col| Some((r.f(a)?, r.f(b)?));
    let range = pair(cols::GPU_MS_CI_LO, cols::GPU_MS_CI_HI)
        .or_else(|| pair(cols::GPU_MS_MIN, cols::GPU_MS_MAX));
    let n = r
        .f(cols::SAMPLES)
        // Schema 1 CSVs had a fixed count in `reps` (no longer a column).
        .or_else(|| r.f_name("reps"))
        .map(|x| x as usize)
        .unwrap_or(0);
    Some(Interval {
        median: median * scale,
        range: range.map(|(a, b)| (a * scale, b * scale)),
        n,
    })
}

/// Whether an error value moved beyond the tolerance (text compared where not numbers).
fn error_moved(b: &str, n: &str, o: &AbOptions) -> bool {
    match (b.parse::<f64>(), n.parse::<f64>()) {
        (Ok(x), Ok(y)) if x.is_finite() && y.is_finite() => {
            (y - x).abs() > o.err_abs_tol.max(o.err_rel_tol * x.abs().max(y.abs()))
        }
        _ => b != n,
    }
}

/// Compares two runs (folders or runs.csv paths). See the module notes.
pub fn compare_runs(base: &Path, new: &Path, opts: &AbOptions) -> Result<AbReport> {
    let (bs, br, bsamp) = load_side(base)?;
    let (ns, nr, nsamp) = load_side(new)?;
    if bs.schema != ns.schema {
        bail!(
            "cannot compare {} (schema version {}) with {} (schema version {}): different CSV \
             schema versions; compare runs written by one schema (rerun BASE or NEW)",
            bs.runs_csv.display(),
            bs.schema,
            ns.runs_csv.display(),
            ns.schema
        );
    }
    let dup = |rows: &[Rec]| {
        let mut seen = std::collections::HashSet::new();
        rows.iter().any(|r| !seen.insert(r.get(cols::POINT_KEY)))
    };
    let by_platform = match (dup(&br.rows), dup(&nr.rows)) {
        (false, false) => false,
        (true, true) => true,
        (b, _) => bail!(
            "{} holds several platforms ({}) but {} one ({}): compare one platform with one, \
             or the same set of platforms on both sides",
            if b { &bs.runs_csv } else { &ns.runs_csv }.display(),
            if b { &bs.platforms } else { &ns.platforms }.join("; "),
            if b { &ns.runs_csv } else { &bs.runs_csv }.display(),
            if b { &ns.platforms } else { &bs.platforms }.join("; "),
        ),
    };
    let key = |r: &Rec| {
        if by_platform {
            format!("{} @ {}", r.get(cols::POINT_KEY), platform(r))
        } else {
            r.get(cols::POINT_KEY).to_string()
        }
    };
    let new_by_key: HashMap<String, &Rec> = nr.rows.iter().map(|r| (key(r), r)).collect();
    let base_keys: std::collections::HashSet<String> = br.rows.iter().map(key).collect();
    let o = &opts.verdict;
    let mut rep = AbReport {
        base: bs,
        new: ns,
        opts: opts.clone(),
        points: Vec::new(),
        only_base: Vec::new(),
        only_new: nr
            .rows
            .iter()
            .map(key)
            .filter(|k| !base_keys.contains(k))
            .collect(),
        untimed: Vec::new(),
        errors: Vec::new(),
        status_changes: Vec::new(),
    };
    for b in &br.rows {
        let k = key(b);
        let Some(n) = new_by_key.get(&k).copied() else {
            rep.only_base.push(k);
            continue;
        };
        if b.get(cols::STATUS) != n.get(cols::STATUS) {
            rep.status_changes.push(StatusChange {
                key: k.clone(),
                base: b.get(cols::STATUS).to_string(),
                new: n.get(cols::STATUS).to_string(),
                reason: [b.get(cols::REASON), n.get(cols::REASON)]
                    .iter()
                    .filter(|s| !s.is_empty())
                    .copied()
                    .collect::<Vec<_>>()
                    .join(" → "),
            });
        }
        if !(b.ok() && n.ok()) {
            continue;
        }
        for col in ERROR_COLUMNS {
            let (x, y) = (b.get(col), n.get(col));
            if (!x.is_empty() || !y.is_empty()) && error_moved(x, y, opts) {
                rep.errors.push(ErrMove {
                    key: k.clone(),
                    column: col,
                    base: x.to_string(),
                    new: y.to_string(),
                });
            }
        }
        let (Some(bm), Some(nm)) = (b.f(cols::GPU_MS_MEDIAN), n.f(cols::GPU_MS_MEDIAN)) else {
            rep.untimed.push(k);
            continue;
        };
        let nm = nm * opts.scale_new;
        let (band, band_source) = match &opts.calibration {
            Some(c) => c.band_for(&k, o.noise_band),
            None => (o.noise_band, BandSource::Fixed),
        };
        let o = &VerdictOptions {
            noise_band: band,
            ..o.clone()
        };
        let (bc, nc) = (b.f(cols::SM_CLOCK_MHZ_MEAN), n.f(cols::SM_CLOCK_MHZ_MEAN));
        let pick = |s: &Option<SampleMap>, r: &Rec| {
            s.as_ref()
                .and_then(|m| {
                    m.get(&(
                        r.get(cols::RUN_ID).to_string(),
                        r.get(cols::POINT_KEY).to_string(),
                    ))
                })
                .filter(|p| !p.gpu_ms.is_empty())
                .cloned()
        };
        let scaled = |p: Option<PointSamples>| {
            p.map(|mut p| {
                p.gpu_ms.iter_mut().for_each(|x| *x *= opts.scale_new);
                p
            })
        };
        let (bsm, nsm) = (pick(&bsamp, b), scaled(pick(&nsamp, n)));
        let meds =
            |p: &Option<PointSamples>| p.as_ref().map_or(Vec::new(), |p| p.session_medians());
        let (bsess, nsess) = (meds(&bsm), meds(&nsm));
        let two = |p: &Option<PointSamples>| {
            p.as_ref()
                .and_then(|p| modes(&p.gpu_ms, MODE_MIN_FRAC, MODE_MIN_SEP))
        };
        let (base_modes, new_modes) = (two(&bsm).map(|m| m.gap), two(&nsm).map(|m| m.gap));
        // The hold-back rules below look at the samples the verdict compared (`matched`):
        // modes and medians of those, and whether modes were already matched.
        let mut matched: Option<Matched> = None;
        let (time, cycles) = match (bsm, nsm) {
            (Some(sb), Some(sn)) => {
                let m = compare_matched(&sb.by_session(&sb.gpu_ms), &sn.by_session(&sn.gpu_ms), o);
                let time = m.comparison.clone();
                matched = Some(m);
                // Per-sample clocks where every sample has one, else the row's mean clock.
                let cyc = |s: &PointSamples, mean: Option<f64>| {
                    cycles_k(&s.gpu_ms, &s.sm_mhz)
                        .or_else(|| mean.map(|c| s.gpu_ms.iter().map(|t| t * c).collect()))
                };
                let cycles = match (cyc(&sb, bc), cyc(&sn, nc)) {
                    (Some(x), Some(y)) => {
                        Some(compare_matched(&sb.by_session(&x), &sn.by_session(&y), o).comparison)
                    }
                    _ => None,
                };
                (time, cycles)
            }
            _ => {
                let s = opts.scale_new;
                let (ib, inew) = (interval(b, 1.0).unwrap(), interval(n, s).unwrap());
                let time = compare_intervals(ib, inew, o);
                let cycles = match (bc, nc) {
                    (Some(x), Some(y)) => Some(compare_intervals(
                        interval(b, x).unwrap(),
                        interval(n, y * s).unwrap(),
                        o,
                    )),
                    _ => None,
                };
                (time, cycles)
            }
        };
        // A verdict no more confident than the runs. Two frame-time modes in the samples
        // compared, not matched mode with mode: when a mode of NEW matches a mode of BASE within
        // the band (a side with one mode is its median), the change may be a shift between
        // modes: UNSURE. Noisy on both sides: within the floor plus their session spread,
        // UNSURE — unless the modes were matched, which is what that spread was.
        let (bn, nn) = (noisy(b), noisy(n));
        let spread = |r: &Rec| r.f(cols::SESSION_SPREAD).filter(|x| x.is_finite());
        let mut why = Vec::new();
        let mut inst = 0.0f64;
        let mode_matched = matched
            .as_ref()
            .is_some_and(|m| m.matching == Matching::Modes);
        let (bmodes, nmodes, cbm, cnm) = match &matched {
            Some(m) => (m.base_modes, m.new_modes, m.base_median, m.new_median),
            None => (None, None, bm, nm),
        };
        if let Some(m) = mode_match(bmodes, nmodes, &time, cbm, cnm, band) {
            why.push(m);
            inst = f64::INFINITY;
        }
        // Median sessions judged without this point's own calibration (which has seen its
        // session states): when either median session sits, within the band, in the state of
        // a session of the other side, the majority may have changed state, not the code.
        let by_median = matched
            .as_ref()
            .is_some_and(|m| m.matching == Matching::MedianSession);
        if by_median && band_source != BandSource::Point {
            if let Some(m) = state_match(&bsess, &nsess, cbm, cnm, &time, band) {
                why.push(m);
                inst = f64::INFINITY;
            }
        }
        if bn && nn && !mode_matched {
            let s = spread(b).unwrap_or(0.0).max(spread(n).unwrap_or(0.0));
            if s > 0.0 {
                inst = inst.max(s);
                why.push(format!(
                    "noisy on both sides (session spread up to {:.1} %)",
                    s * 100.0
                ));
            }
        }
        let (time, cycles) = if inst > 0.0 {
            let wide = band.max(opts.verdict.noise_band + inst);
            let why = why.join("; ");
            (
                hold_back(time, wide, &why),
                cycles.map(|c| hold_back(c, wide, &why)),
            )
        } else {
            (time, cycles)
        };
        rep.points.push(PointCmp {
            key: k,
            platform_base: platform(b),
            platform_new: platform(n),
            base_median_ms: bm,
            new_median_ms: nm,
            time,
            cycles,
            base_sm_mhz: bc,
            new_sm_mhz: nc,
            base_noisy: bn,
            new_noisy: nn,
            band,
            band_source,
            base_modes,
            new_modes,
        });
    }
    let rank = |v: Verdict| match v {
        Verdict::Slower => 0,
        Verdict::Faster => 1,
        Verdict::Unsure => 2,
        Verdict::Same => 3,
    };
    rep.points.sort_by(|a, b| {
        rank(a.time.verdict)
            .cmp(&rank(b.time.verdict))
            .then(b.time.ratio.total_cmp(&a.time.ratio))
    });
    Ok(rep)
}

/// Why a FASTER / SLOWER may be a shift between two frame-time modes (see `compare_runs`), or
/// None. A side with one mode is its median (`bm`, `nm`: the pooled medians, NEW scaled).
fn mode_match(
    b: Option<Modes>,
    n: Option<Modes>,
    c: &Comparison,
    bm: f64,
    nm: f64,
    band: f64,
) -> Option<String> {
    if !matches!(c.verdict, Verdict::Faster | Verdict::Slower) || (b.is_none() && n.is_none()) {
        return None;
    }
    let pts = |m: Option<Modes>, med: f64| match m {
        Some(m) => vec![m.low, m.high],
        None => vec![med],
    };
    let pairs: Vec<(f64, f64)> = match (b, n) {
        (Some(x), Some(y)) => vec![(x.low, y.low), (x.high, y.high)],
        _ => {
            let (pb, pn) = (pts(b, bm), pts(n, nm));
            pb.iter()
                .flat_map(|x| pn.iter().map(move |y| (*x, *y)))
                .collect()
        }
    };
    let (x, y) = pairs
        .into_iter()
        .filter(|(x, _)| *x > 0.0)
        .find(|(x, y)| (y / x - 1.0).abs() <= band)?;
    let gap = b.or(n).map_or(0.0, |m| m.gap);
    Some(format!(
        "two frame-time modes ({:.1} % apart): NEW's {} ms matches BASE's {} ms within the band, so the change may be a shift between modes",
        gap * 100.0,
        fmt_ms(y),
        fmt_ms(x)
    ))
}

/// Why a FASTER / SLOWER between median sessions may be a change of session state (see
/// `compare_runs`), or None: a side's median session (`bm`, `nm`) within the band of one of
/// the other side's sessions.
fn state_match(
    base: &[f64],
    new: &[f64],
    bm: f64,
    nm: f64,
    c: &Comparison,
    band: f64,
) -> Option<String> {
    if !matches!(c.verdict, Verdict::Faster | Verdict::Slower) {
        return None;
    }
    let near = |x: f64, y: f64| x > 0.0 && (y / x - 1.0).abs() <= band;
    if let Some(x) = base.iter().find(|x| near(**x, nm)) {
        return Some(format!(
            "NEW's median session ({} ms) sits in the state of a BASE session ({} ms): the \
             sessions may have changed state (no calibration of this point says how often)",
            fmt_ms(nm),
            fmt_ms(*x)
        ));
    }
    new.iter().find(|y| near(bm, **y)).map(|y| {
        format!(
            "BASE's median session ({} ms) sits in the state of a NEW session ({} ms): the \
             sessions may have changed state (no calibration of this point says how often)",
            fmt_ms(bm),
            fmt_ms(*y)
        )
    })
}

/// "5%", "5 %" or "0.05" → 0.05 (for `--fail-on-slower`).
pub fn parse_fraction(s: &str) -> Result<f64> {
    let t = s.trim();
    let v = match t.strip_suffix('%') {
        Some(p) => p.trim().parse::<f64>().map(|x| x / 100.0),
        None => t.parse::<f64>(),
    }
    .with_context(|| format!("'{s}' is not a fraction like 5% or 0.05"))?;
    if !(0.0..10.0).contains(&v) {
        bail!("'{s}': expected a fraction between 0 and 10 (0 %–1000 %)");
    }
    Ok(v)
}

fn fmt_ms(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.1}")
    } else if v >= 0.01 {
        format!("{v:.4}")
    } else {
        format!("{v:.3e}")
    }
}

fn fmt_ratio(c: &Comparison) -> String {
    let (lo, hi) = c.ratio_ci;
    if lo.is_finite() && hi.is_finite() {
        format!("{:.3} [{lo:.3}, {hi:.3}]", c.ratio)
    } else if c.ratio.is_finite() {
        format!("{:.3}", c.ratio)
    } else {
        "–".into()
    }
}

fn fmt_p(c: &Comparison) -> String {
    match c.p {
        Some(p) if p < 1e-4 => format!("{p:.1e}"),
        Some(p) => format!("{p:.4}"),
        None => "–".into(),
    }
}

impl AbReport {
    /// Points per time verdict (every verdict present, zero or not).
    pub fn counts(&self) -> BTreeMap<Verdict, usize> {
        let mut m: BTreeMap<Verdict, usize> = Verdict::ALL.iter().map(|v| (*v, 0)).collect();
        for p in &self.points {
            *m.entry(p.time.verdict).or_default() += 1;
        }
        m
    }

    pub fn cycle_counts(&self) -> BTreeMap<Verdict, usize> {
        let mut m: BTreeMap<Verdict, usize> = BTreeMap::new();
        for c in self.points.iter().filter_map(|p| p.cycles.as_ref()) {
            *m.entry(c.verdict).or_default() += 1;
        }
        m
    }

    /// The point with the largest NEW/BASE ratio, and the one with the smallest.
    pub fn extremes(&self) -> Option<(&PointCmp, &PointCmp)> {
        let ok = || self.points.iter().filter(|p| p.time.ratio.is_finite());
        let hi = ok().max_by(|a, b| a.time.ratio.total_cmp(&b.time.ratio))?;
        let lo = ok().min_by(|a, b| a.time.ratio.total_cmp(&b.time.ratio))?;
        Some((hi, lo))
    }

    /// Points SLOWER in time whose ratio exceeds `1 + frac` (for `--fail-on-slower`).
    pub fn slower_beyond(&self, frac: f64) -> Vec<&PointCmp> {
        self.points
            .iter()
            .filter(|p| p.time.verdict == Verdict::Slower && p.time.ratio > 1.0 + frac)
            .collect()
    }

    /// Points whose verdict came from summary columns only.
    pub fn summary_only(&self) -> usize {
        self.points
            .iter()
            .filter(|p| p.time.basis == Basis::Summary)
            .count()
    }

    fn side_line(s: &Side) -> String {
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
    pub fn rule_text(&self) -> String {
        let o = &self.opts.verdict;
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
            self.opts.err_abs_tol,
            self.opts.err_rel_tol * 100.0,
            self.band_text()
        )
    }

    /// How the bands were set, and the hold-back rule (part of [`Self::rule_text`]).
    fn band_text(&self) -> String {
        let floor = self.opts.verdict.noise_band * 100.0;
        let mut t = match &self.opts.calibration {
            Some(c) => {
                let n = |s: BandSource| self.points.iter().filter(|p| p.band_source == s).count();
                let mut bands: Vec<f64> = self.points.iter().map(|p| p.band).collect();
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
        if self.opts.scale_new != 1.0 {
            let _ = write!(
                t,
                " SYNTHETIC: every NEW time was multiplied by {} (--scale-new).",
                self.opts.scale_new
            );
        }
        t
    }

    fn headline(&self) -> Vec<String> {
        let mut v = Vec::new();
        let c = self.counts();
        v.push(format!(
            "{} points compared ({} only in BASE, {} only in NEW, {} without GPU time): {}",
            self.points.len(),
            self.only_base.len(),
            self.only_new.len(),
            self.untimed.len(),
            c.iter()
                .map(|(k, n)| format!("{k} {n}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        let cc = self.cycle_counts();
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
        if let Some((hi, lo)) = self.extremes() {
            v.push(format!(
                "Largest ratio {:.3} ({}), smallest {:.3} ({})",
                hi.time.ratio, hi.key, lo.time.ratio, lo.key
            ));
        }
        let s = self.summary_only();
        if s > 0 {
            v.push(format!(
                "{s} of {} verdicts are from summary columns only (no raw samples on a side): \
                 mostly UNSURE unless the intervals separate",
                self.points.len()
            ));
        }
        if self.base.platforms != self.new.platforms {
            v.push(format!(
                "Different platforms: BASE {} vs NEW {}",
                self.base.platforms.join("; "),
                self.new.platforms.join("; ")
            ));
        }
        if let Some(g) = self.gpu_ratio() {
            let within = self
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
    pub fn markdown(&self) -> String {
        let md = |s: &str| s.replace('|', "\\|");
        let mut m = String::new();
        let _ = writeln!(m, "# mfx compare\n");
        let _ = writeln!(m, "- BASE: {}", md(&Self::side_line(&self.base)));
        let _ = writeln!(m, "- NEW: {}", md(&Self::side_line(&self.new)));
        for l in self.headline() {
            let _ = writeln!(m, "- {}", md(&l));
        }
        let _ = writeln!(m, "\n{}\n", self.rule_text());
        let _ = writeln!(
            m,
            "| point | BASE ms | NEW ms | NEW/BASE [95 % CI] | p | time | cycles | note |\n\
             |---|---:|---:|---|---:|---|---|---|"
        );
        for p in &self.points {
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
            if let Some(g) = self.gpu_ratio() {
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
        if !self.errors.is_empty() {
            let _ = writeln!(
                m,
                "\n## Errors that moved ({})\n\n| point | column | BASE | NEW |\n|---|---|---|---|",
                self.errors.len()
            );
            for e in &self.errors {
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
        if !self.status_changes.is_empty() {
            let _ = writeln!(
                m,
                "\n## Status changes ({})\n\n| point | BASE | NEW | reason |\n|---|---|---|---|",
                self.status_changes.len()
            );
            for s in &self.status_changes {
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
            ("Only in BASE", &self.only_base),
            ("Only in NEW", &self.only_new),
            ("Without GPU time", &self.untimed),
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
    pub fn write_html(&self, dir: &Path) -> Result<PathBuf> {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let path = dir.join("compare.html");
        std::fs::write(&path, self.html())
            .with_context(|| format!("writing {}", path.display()))?;
        Ok(path)
    }

    /// The page as a string.
    pub fn html(&self) -> String {
        let mut h = String::new();
        let _ = write!(
            h,
            "<!doctype html><html><head><meta charset=\"utf-8\"><title>mfx compare</title><style>\
             body{{font-family:sans-serif;max-width:1300px;margin:2em auto;color:#222}}\
             table{{border-collapse:collapse;margin:1em 0;font-size:13px}}\
             td,th{{border:1px solid #ccc;padding:3px 7px;text-align:left}}th{{background:#f3f3f3}}\
             td.n{{text-align:right;font-variant-numeric:tabular-nums}}\
             .SLOWER{{color:#b00;font-weight:bold}}.FASTER{{color:#070;font-weight:bold}}\
             .UNSURE{{color:#a60}}.SAME{{color:#555}}</style></head><body><h1>mfx compare</h1><ul>"
        );
        let _ = write!(h, "<li>BASE: {}</li>", esc(&Self::side_line(&self.base)));
        let _ = write!(h, "<li>NEW: {}</li>", esc(&Self::side_line(&self.new)));
        for l in self.headline() {
            let _ = write!(h, "<li>{}</li>", esc(&l));
        }
        let _ = write!(h, "</ul><p>{}</p>", esc(&self.rule_text()));
        h.push_str(&self.svg());
        h.push_str(
            "<h2>Points</h2><table id=\"points\"><tr><th>point</th><th>BASE ms</th><th>NEW ms</th>\
             <th>NEW/BASE [95 % CI]</th><th>p</th><th>time</th><th>BASE MHz</th><th>NEW MHz</th>\
             <th>cycles</th><th>basis</th><th>why</th></tr>",
        );
        let mhz = |v: Option<f64>| v.map(|x| format!("{x:.0}")).unwrap_or_default();
        for p in &self.points {
            let flag = |noisy: bool| if noisy { " (noisy)" } else { "" };
            let _ = write!(
                h,
                "<tr><td>{}</td><td class=\"n\">{}{}</td><td class=\"n\">{}{}</td>\
                 <td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"{v}\">{v}</td>\
                 <td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td><td>{:?}</td><td>{}</td></tr>",
                esc(&p.key),
                fmt_ms(p.base_median_ms),
                flag(p.base_noisy),
                fmt_ms(p.new_median_ms),
                flag(p.new_noisy),
                fmt_ratio(&p.time),
                fmt_p(&p.time),
                mhz(p.base_sm_mhz),
                mhz(p.new_sm_mhz),
                p.cycles
                    .as_ref()
                    .map(|c| format!("{} ({})", c.verdict, fmt_ratio(c)))
                    .unwrap_or_default(),
                p.time.basis,
                esc(&format!("{}; {}", p.time.why, p.band_note())),
                v = p.time.verdict,
            );
        }
        h.push_str("</table>");
        if !self.errors.is_empty() {
            h.push_str(
                "<h2>Errors that moved</h2><table id=\"errors\"><tr><th>point</th><th>column</th>\
                 <th>BASE</th><th>NEW</th></tr>",
            );
            for e in &self.errors {
                let _ = write!(
                    h,
                    "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                    esc(&e.key),
                    e.column,
                    esc(&e.base),
                    esc(&e.new)
                );
            }
            h.push_str("</table>");
        }
        if !self.status_changes.is_empty() {
            h.push_str(
                "<h2>Status changes</h2><table id=\"status\"><tr><th>point</th><th>BASE</th>\
                 <th>NEW</th><th>reason</th></tr>",
            );
            for s in &self.status_changes {
                let _ = write!(
                    h,
                    "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                    esc(&s.key),
                    esc(&s.base),
                    esc(&s.new),
                    esc(&s.reason)
                );
            }
            h.push_str("</table>");
        }
        for (title, keys) in [
            ("Only in BASE", &self.only_base),
            ("Only in NEW", &self.only_new),
            ("Without GPU time", &self.untimed),
        ] {
            if !keys.is_empty() {
                let _ = write!(h, "<h2>{title} ({})</h2><ul>", keys.len());
                for k in keys {
                    let _ = write!(h, "<li>{}</li>", esc(k));
                }
                h.push_str("</ul>");
            }
        }
        h.push_str("</body></html>\n");
        h
    }

    /// One row per point: the ratio (dot, coloured by verdict) and its 95 % CI (bar) on a log
    /// axis, with the noise band shaded.
    fn svg(&self) -> String {
        let pts: Vec<&PointCmp> = self
            .points
            .iter()
            .filter(|p| p.time.ratio.is_finite() && p.time.ratio > 0.0)
            .collect();
        if pts.is_empty() {
            return String::new();
        }
        let band = self.opts.verdict.noise_band;
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
        let mut s = String::new();
        let _ = write!(
            s,
            "<h2>Ratios</h2><svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{height}\" \
             font-family=\"sans-serif\" font-size=\"10\">",
            label_w + plot_w + 20.0
        );
        let _ = write!(
            s,
            "<rect x=\"{:.1}\" y=\"{top}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"#eee\"/>",
            x(1.0 - band),
            x(1.0 + band) - x(1.0 - band),
            row_h * pts.len() as f64
        );
        for t in [0.25f64, 0.5, 0.8, 0.9, 1.0, 1.1, 1.25, 1.5, 2.0, 4.0] {
            if t.ln() >= lo && t.ln() <= hi {
                let _ = write!(
                    s,
                    "<line x1=\"{0:.1}\" x2=\"{0:.1}\" y1=\"{1}\" y2=\"{2:.1}\" stroke=\"{3}\"/>\
                     <text x=\"{0:.1}\" y=\"{4}\" text-anchor=\"middle\">{t}</text>",
                    x(t),
                    top,
                    height - 10.0,
                    if t == 1.0 { "#444" } else { "#ddd" },
                    top - 8.0
                );
            }
        }
        for (i, p) in pts.iter().enumerate() {
            let y = top + row_h * (i as f64 + 0.5);
            let colour = match p.time.verdict {
                Verdict::Slower => "#b00",
                Verdict::Faster => "#070",
                Verdict::Unsure => "#d80",
                Verdict::Same => "#777",
            };
            let label: String = p.key.chars().take(80).collect();
            let _ = write!(
                s,
                "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
                label_w - 6.0,
                y + 3.5,
                esc(&label)
            );
            let (a, b) = p.time.ratio_ci;
            if finite(a) && finite(b) {
                let _ = write!(
                    s,
                    "<line x1=\"{:.1}\" x2=\"{:.1}\" y1=\"{y:.1}\" y2=\"{y:.1}\" stroke=\"{colour}\" \
                     stroke-width=\"2\"/>",
                    x(a),
                    x(b)
                );
            }
            let r = p.time.ratio;
            if (RATIO_MIN..=RATIO_MAX).contains(&r) {
                let _ = write!(
                    s,
                    "<circle cx=\"{:.1}\" cy=\"{y:.1}\" r=\"3.5\" fill=\"{colour}\"><title>{} {}</title></circle>",
                    x(r),
                    esc(&p.key),
                    fmt_ratio(&p.time)
                );
            } else {
                // Off the scale: an arrow at the edge pointing out, and the value written beside
                // it, never a dot drawn at the edge as if it were the value.
                let (tip, dir, anchor) = if r > RATIO_MAX {
                    (x(RATIO_MAX), 1.0, "end")
                } else {
                    (x(RATIO_MIN), -1.0, "start")
                };
                let _ = write!(
                    s,
                    "<path class=\"offscale\" data-value=\"{r}\" d=\"M{:.1},{y:.1} L{:.1},{:.1} L{:.1},{:.1} Z\" fill=\"{colour}\"><title>{} {} (off the scale)</title></path>\
                     <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"{anchor}\" fill=\"{colour}\">{}×</text>",
                    tip,
                    tip - dir * 8.0,
                    y - 4.5,
                    tip - dir * 8.0,
                    y + 4.5,
                    esc(&p.key),
                    fmt_ratio(&p.time),
                    tip - dir * 11.0,
                    y + 3.5,
                    crate::cells::short(Some(r))
                );
            }
        }
        s.push_str("</svg>");
        s
    }
}

/// The ratio chart's scale: ratios outside it are drawn as off-scale arrows with their value.
pub const RATIO_MIN: f64 = 0.25;
pub const RATIO_MAX: f64 = 4.0;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A baseline name usable as one folder name.
fn check_name(name: &str) -> Result<()> {
    if name.is_empty()
        || name.starts_with('.')
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
    {
        bail!("baseline name '{name}': use letters, digits, '-', '_' and '.' (not leading)");
    }
    Ok(())
}

/// Files a baseline keeps from a run folder (those present).
pub const BASELINE_FILES: [&str; 4] = ["runs.csv", "samples.csv", "runs.json", "run.json"];

/// `mfx sweep … --save-baseline NAME`: copies the run's data files into `root/NAME/`
/// (replacing an older baseline of that name); returns that folder.
pub fn save_baseline(run_dir: &Path, root: &Path, name: &str) -> Result<PathBuf> {
    check_name(name)?;
    if !run_dir.join("runs.csv").is_file() {
        bail!("{}: no runs.csv to save as baseline", run_dir.display());
    }
    let dest = root.join(name);
    if dest.exists() {
        std::fs::remove_dir_all(&dest)
            .with_context(|| format!("replacing baseline {}", dest.display()))?;
    }
    std::fs::create_dir_all(&dest).with_context(|| format!("creating {}", dest.display()))?;
    for f in BASELINE_FILES {
        let src = run_dir.join(f);
        if src.is_file() {
            std::fs::copy(&src, dest.join(f))
                .with_context(|| format!("copying {} to {}", src.display(), dest.display()))?;
        }
    }
    Ok(dest)
}

/// `--baseline NAME`: the folder of a saved baseline, or an error listing those that exist.
pub fn baseline_dir(root: &Path, name: &str) -> Result<PathBuf> {
    check_name(name)?;
    let d = root.join(name);
    if d.join("runs.csv").is_file() {
        return Ok(d);
    }
    let mut have: Vec<String> = std::fs::read_dir(root)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter(|e| e.path().join("runs.csv").is_file())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    have.sort();
    bail!(
        "no baseline '{name}' in {} (saved baselines: {})",
        root.display(),
        if have.is_empty() {
            "none".to_string()
        } else {
            have.join(", ")
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gpu_calibration_is_read_from_run_json_where_written() {
        let d = std::env::temp_dir().join(format!("mfx-ab-gpucal-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let csv = d.join("runs.csv");
        assert_eq!(gpu_calibration_ms(&csv), None, "no run.json");
        std::fs::write(d.join("run.json"), r#"{"calibration": null}"#).unwrap();
        assert_eq!(
            gpu_calibration_ms(&csv),
            None,
            "run.json without a calibration"
        );
        std::fs::write(
            d.join("run.json"),
            r#"{"calibration": {"set": "canary", "canary_ms": 0.125, "runs": 21}}"#,
        )
        .unwrap();
        assert_eq!(gpu_calibration_ms(&csv), Some(0.125));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
