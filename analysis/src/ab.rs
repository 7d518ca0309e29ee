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
//! Typed results only: `report::ab` writes them as Markdown and as a page.

use schema::{cols, samples, Col, Flag};
use std::collections::{BTreeMap, HashMap};
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
    /// Points (keys) present on both sides, whatever their status.
    pub common: usize,
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

/// `runs.csv` (else `runs.parquet`) of a folder or the path itself, and `samples.csv` (or
/// `samples.csv.gz`) beside it when present.
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
        common: 0,
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
        rep.common += 1;
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

/// A time in ms, 4 decimals below 100 ms (e notation below 0.01).
pub fn fmt_ms(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.1}")
    } else if v >= 0.01 {
        format!("{v:.4}")
    } else {
        format!("{v:.3e}")
    }
}

/// "1.023 [1.010, 1.035]", the ratio alone, or "–".
pub fn fmt_ratio(c: &Comparison) -> String {
    let (lo, hi) = c.ratio_ci;
    if lo.is_finite() && hi.is_finite() {
        format!("{:.3} [{lo:.3}, {hi:.3}]", c.ratio)
    } else if c.ratio.is_finite() {
        format!("{:.3}", c.ratio)
    } else {
        "–".into()
    }
}

/// The Mann–Whitney p-value, or "–".
pub fn fmt_p(c: &Comparison) -> String {
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
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
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
    }
}
