//! Sweep suites as TOML files (`scenarios/suites/<name>.toml`).
//!
//! A suite lists studies; each study has a `kind` (which runner executes it), scenes (arrays in
//! a scene table expand into one scene per combination), methods, and declared `axes` whose
//! cartesian product the runner sweeps. A method ignores axes it does not declare. Example:
//!
//! ```toml
//! name = "smoke"
//! [timing]
//! max_samples = 20
//! resolutions = [[64, 64]]
//! [[study]]
//! kind = "methods"
//! methods = ["depth_peel"]
//! axes = { max_layers = [64] }
//! [[study.scenes]]
//! generator = "quads"
//! depth_complexity = [2, 8]
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use schema::StudyKind;

use crate::{ParamValue, Params, Problem, Result, SceneError, SceneSpec};

/// Built-in suites, embedded so the binary works from any directory (a file on disk wins).
pub const BUILTIN: &[(&str, &str)] = &[
    ("smoke", include_str!("../suites/smoke.toml")),
    ("default", include_str!("../suites/default.toml")),
    ("geometry", include_str!("../suites/geometry.toml")),
    ("geometry-ci", include_str!("../suites/geometry-ci.toml")),
    ("deferred", include_str!("../suites/deferred.toml")),
    ("deferred-ci", include_str!("../suites/deferred-ci.toml")),
    ("prepass", include_str!("../suites/prepass.toml")),
    ("prepass-ci", include_str!("../suites/prepass-ci.toml")),
    ("stability", include_str!("../suites/stability.toml")),
    ("stability_ci", include_str!("../suites/stability_ci.toml")),
    ("effects", include_str!("../suites/effects.toml")),
    ("methods", include_str!("../suites/methods.toml")),
    ("buckets", include_str!("../suites/buckets.toml")),
    ("shadows", include_str!("../suites/shadows.toml")),
    ("shadows-ci", include_str!("../suites/shadows-ci.toml")),
    ("backends", include_str!("../suites/backends.toml")),
    (
        "geometry-models",
        include_str!("../suites/geometry-models.toml"),
    ),
    (
        "shadows-bunny",
        include_str!("../suites/shadows-bunny.toml"),
    ),
    ("continuum", include_str!("../suites/continuum.toml")),
    ("continuum-ci", include_str!("../suites/continuum-ci.toml")),
    ("aa", include_str!("../suites/aa.toml")),
    ("aa-ci", include_str!("../suites/aa-ci.toml")),
    ("views", include_str!("../suites/views.toml")),
    ("views-ci", include_str!("../suites/views-ci.toml")),
    // The sources' own setups (issue 30), one per source; scenarios/papers/*.toml points here.
    (
        "seeds-buckets",
        include_str!("../suites/seeds-buckets.toml"),
    ),
    (
        "seeds-kbuffer",
        include_str!("../suites/seeds-kbuffer.toml"),
    ),
    (
        "seeds-kbuffer-flush",
        include_str!("../suites/seeds-kbuffer-flush.toml"),
    ),
    ("seeds-volume", include_str!("../suites/seeds-volume.toml")),
    (
        "seeds-geometry",
        include_str!("../suites/seeds-geometry.toml"),
    ),
    (
        "seeds-shadows",
        include_str!("../suites/seeds-shadows.toml"),
    ),
    (
        "seeds-deferred",
        include_str!("../suites/seeds-deferred.toml"),
    ),
    (
        "seeds-prepass",
        include_str!("../suites/seeds-prepass.toml"),
    ),
];

#[derive(Clone, Debug)]
pub struct Suite {
    pub name: String,
    pub description: String,
    /// How points are timed (`[timing]`; unset keys take the harness's defaults).
    pub timing: TimingSpec,
    pub resolutions: Vec<(u32, u32)>,
    /// Applied when the adapter is a CPU (software) device, so a GPU-sized suite stays runnable.
    pub software: Option<SoftwareProfile>,
    pub studies: Vec<StudySpec>,
    /// Where the suite came from: its file, or `(built-in) NAME`.
    pub source: String,
    /// The suite's TOML text as read (copied into a run's manifest).
    pub text: String,
}

/// Overrides for software adapters (lavapipe, llvmpipe).
#[derive(Clone, Debug, Default)]
pub struct SoftwareProfile {
    pub resolutions: Option<Vec<(u32, u32)>>,
    /// Scenes above this many triangles become skipped rows on a software adapter.
    pub max_triangles: Option<u64>,
    /// Overrides of `[timing]` on a software adapter (the same keys, in `[software]`).
    pub timing: TimingSpec,
}

#[derive(Clone, Debug)]
pub struct StudySpec {
    /// Position of the `[[study]]` table in the file (for messages).
    pub index: usize,
    pub kind: StudyKind,
    pub methods: Vec<String>,
    /// Whether the table had a `methods` key at all (`methods = []` is an error, not "none").
    pub methods_given: bool,
    pub axes: BTreeMap<String, Vec<ParamValue>>,
    /// Per-method axis overrides (`[study.method_axes.<method>]`): for that method they replace
    /// the study's axes of the same name, so an axis one method reads with values another
    /// method rejects (e.g. the k-buffer's `variant = "heuristics"`) need not split the table.
    pub method_axes: BTreeMap<String, BTreeMap<String, Vec<ParamValue>>>,
    pub scenes: Vec<SceneSpec>,
    /// For each of `scenes`, the index of the `[[study.scenes]]` table it was expanded from.
    pub scene_tables: Vec<usize>,
    pub resolutions: Option<Vec<(u32, u32)>>,
    /// Everything else in the study table, for the study kind to read.
    pub extra: toml::Table,
}

impl Suite {
    /// Loads a suite by file path or by name (`scenarios/suites/<name>.toml`, then built-ins).
    /// A path that exists but is not a readable file is named as such.
    pub fn load(name_or_path: &str) -> Result<Suite> {
        let (text, source) = Suite::read(name_or_path)?;
        Suite::parse(&text, &source)
    }

    /// A suite's text and where it came from (its file, or `(built-in) NAME`).
    pub fn read(name_or_path: &str) -> Result<(String, String)> {
        let p = Path::new(name_or_path);
        let candidates = [
            p.to_path_buf(),
            PathBuf::from(format!("scenarios/suites/{name_or_path}.toml")),
            // Probes of one question (`mfx list suites --all`), run by name like the others.
            PathBuf::from(format!("scenarios/suites/internal/{name_or_path}.toml")),
        ];
        for c in &candidates {
            if c.is_dir() {
                return Err(SceneError::Suite {
                    path: c.display().to_string(),
                    why: "is a directory, not a suite file".into(),
                });
            }
            if c.is_file() {
                let text = std::fs::read_to_string(c).map_err(|e| SceneError::Suite {
                    path: c.display().to_string(),
                    why: e.to_string(),
                })?;
                return Ok((text, c.display().to_string()));
            }
        }
        if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name_or_path) {
            return Ok((text.to_string(), format!("(built-in) {name_or_path}")));
        }
        Err(SceneError::Suite {
            path: name_or_path.into(),
            why: format!(
                "no such file, and not a suite name (built-in: {})",
                BUILTIN
                    .iter()
                    .map(|(n, _)| *n)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
    }

    /// Parses a suite, reporting every structural problem at once (unknown keys at any level,
    /// wrong types, empty arrays, an unknown study kind) as `Err(SceneError::Problems)`. What
    /// depends on the studies' declarations, methods and generators is checked by
    /// `bench_core::check`.
    pub fn parse(text: &str, source: &str) -> Result<Suite> {
        match Suite::parse_partial(text, source) {
            (Some(s), problems) if problems.is_empty() => Ok(s),
            (_, problems) => Err(SceneError::Problems(problems)),
        }
    }

    /// Parses what can be parsed: the suite with each bad value left at its default and each
    /// unreadable study left out (`None` only when the text is not TOML), and every structural
    /// problem. A checker reads the rest of the suite on from here, so one bad key in
    /// `[timing]` does not hide the studies' problems.
    pub fn parse_partial(text: &str, source: &str) -> (Option<Suite>, Vec<Problem>) {
        let mut problems = Vec::new();
        let suite = parse_into(text, source, &mut problems);
        (suite, problems)
    }

    /// The timing a study runs with on this adapter kind: `[timing]`, then `[software]`'s
    /// overrides on a software adapter.
    pub fn timing_for(&self, software: bool) -> TimingSpec {
        match (&self.software, software) {
            (Some(sw), true) => self.timing.overlay(&sw.timing),
            _ => self.timing.clone(),
        }
    }

    /// Resolutions a study runs at (its own, else the suite's, else the software override).
    pub fn study_resolutions(&self, study: &StudySpec, software: bool) -> Vec<(u32, u32)> {
        if software {
            if let Some(r) = self.software.as_ref().and_then(|s| s.resolutions.clone()) {
                return r;
            }
        }
        study
            .resolutions
            .clone()
            .unwrap_or_else(|| self.resolutions.clone())
    }
}

/// The largest width or height a suite or `mfx render` accepts, in pixels (wgpu's
/// `max_texture_dimension_2d` on the GPUs measured here; larger targets fail to allocate).
pub const MAX_SIDE: u32 = 16384;

/// Keys a suite may have at the top level.
pub const TOP_KEYS: &[&str] = &[
    "name",
    "description",
    "timing",
    "resolutions",
    "software",
    "study",
];
/// Keys of the `[software]` table.
pub const SOFTWARE_KEYS: &[&str] = &[
    "resolutions",
    "max_triangles",
    "min_samples",
    "max_samples",
    "max_noise",
    "min_time_ms",
    "max_time_ms",
    "warmup_frames",
    "warmup_max_frames",
    "interleave",
    "seed",
    "clock_lift_ms",
    "sessions",
    "canary_max_ratio",
    "settle",
    "cold",
];
/// Keys of the `[timing]` table (also accepted in `[software]`, as overrides).
pub const TIMING_KEYS: &[&str] = &[
    "min_samples",
    "max_samples",
    "max_noise",
    "min_time_ms",
    "max_time_ms",
    "warmup_frames",
    "warmup_max_frames",
    "interleave",
    "seed",
    "clock_lift_ms",
    "sessions",
    "canary_max_ratio",
    "settle",
    "cold",
];

/// How the points of a suite are timed: each unset key takes the harness's default
/// (`bench_core::measure::TimingPlan`, documented in results/README.md).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimingSpec {
    /// Samples before the noise target may end a point.
    pub min_samples: Option<u32>,
    /// Samples at most.
    pub max_samples: Option<u32>,
    /// Target half-width of the median's 95 % CI, relative to the median.
    pub max_noise: Option<f64>,
    /// Summed measured time before the target may end a point.
    pub min_time_ms: Option<f64>,
    /// Wall time at most per point.
    pub max_time_ms: Option<f64>,
    /// Warm-up frames at least (then until steady).
    pub warmup_frames: Option<u32>,
    /// Warm-up frames at most.
    pub warmup_max_frames: Option<u32>,
    /// Sample a group's points interleaved in a seeded random order.
    pub interleave: Option<bool>,
    /// Busy GPU work allowed per point, before its warm-up, to lift an SM clock the driver has
    /// lowered back to the adapter's maximum (0: never).
    pub clock_lift_ms: Option<f64>,
    /// Seed of the bootstrap and of the interleaved order.
    pub seed: Option<u64>,
    /// Independent sessions per point (each prepared afresh), the CI widened to cover them.
    pub sessions: Option<u32>,
    /// A sample is discarded when the canary kernel timed right after it ran this many times
    /// slower than the fastest canary of the run (0: no canary).
    pub canary_max_ratio: Option<f64>,
    /// Wait for the GPU to finish and free what earlier points dropped before each point is
    /// prepared (default false).
    pub settle: Option<bool>,
    /// Flush the L2 before each timed sample (nvbench's cold mode; default false).
    pub cold: Option<bool>,
}

impl TimingSpec {
    /// `self` with every key `over` sets replaced.
    pub fn overlay(&self, over: &TimingSpec) -> TimingSpec {
        TimingSpec {
            min_samples: over.min_samples.or(self.min_samples),
            max_samples: over.max_samples.or(self.max_samples),
            max_noise: over.max_noise.or(self.max_noise),
            min_time_ms: over.min_time_ms.or(self.min_time_ms),
            max_time_ms: over.max_time_ms.or(self.max_time_ms),
            warmup_frames: over.warmup_frames.or(self.warmup_frames),
            warmup_max_frames: over.warmup_max_frames.or(self.warmup_max_frames),
            interleave: over.interleave.or(self.interleave),
            seed: over.seed.or(self.seed),
            clock_lift_ms: over.clock_lift_ms.or(self.clock_lift_ms),
            sessions: over.sessions.or(self.sessions),
            canary_max_ratio: over.canary_max_ratio.or(self.canary_max_ratio),
            settle: over.settle.or(self.settle),
            cold: over.cold.or(self.cold),
        }
    }
}
/// Keys every `[[study]]` table may have; a study kind declares its own options besides these.
pub const STUDY_KEYS: &[&str] = &[
    "kind",
    "methods",
    "axes",
    "method_axes",
    "scenes",
    "resolutions",
];

/// Collects the problems of one table as it is read.
struct Ctx<'a> {
    file: &'a str,
    problems: &'a mut Vec<Problem>,
}

impl Ctx<'_> {
    fn push(&mut self, table: &str, key: &str, msg: impl Into<String>) -> &mut Problem {
        self.problems.push(Problem::new(self.file, table, key, msg));
        self.problems.last_mut().expect("just pushed")
    }

    fn unknown_keys(&mut self, t: &toml::Table, table: &str, known: &[&str]) {
        for (k, v) in t.iter().filter(|(k, _)| !known.contains(&k.as_str())) {
            let v = v.to_string();
            let p = self.push(table, k, "unknown key");
            p.known = known.iter().map(|s| s.to_string()).collect();
            p.value = Some(v);
        }
    }

    fn string(&mut self, t: &toml::Table, table: &str, k: &str) -> Option<String> {
        match t.get(k) {
            None => None,
            Some(toml::Value::String(s)) => Some(s.clone()),
            Some(v) => {
                let v = v.to_string();
                self.push(table, k, "must be a string").value = Some(v);
                None
            }
        }
    }

    fn int(&mut self, t: &toml::Table, table: &str, k: &str, min: i64, max: i64) -> Option<i64> {
        match t.get(k) {
            None => None,
            Some(toml::Value::Integer(i)) if (min..=max).contains(i) => Some(*i),
            Some(v) => {
                let v = v.to_string();
                self.push(table, k, format!("must be an integer in {min}..={max}"))
                    .value = Some(v);
                None
            }
        }
    }

    fn resolutions(&mut self, t: &toml::Table, table: &str) -> Option<Vec<(u32, u32)>> {
        let v = t.get("resolutions")?;
        match resolutions(v) {
            Ok(r) if !r.is_empty() => Some(r),
            Ok(_) => {
                self.push(table, "resolutions", "is empty: nothing would run");
                None
            }
            Err(why) => {
                self.push(table, "resolutions", why.to_string()).value = Some(v.to_string());
                None
            }
        }
    }
}

fn parse_into(text: &str, source: &str, problems: &mut Vec<Problem>) -> Option<Suite> {
    let mut cx = Ctx {
        file: source,
        problems,
    };
    let table: toml::Table = match text.parse() {
        Ok(t) => t,
        Err(e) => {
            cx.push("top level", "", format!("not valid TOML: {e}"));
            return None;
        }
    };
    let top = "top level";
    cx.unknown_keys(&table, top, TOP_KEYS);
    let mut suite = Suite {
        name: cx
            .string(&table, top, "name")
            .unwrap_or_else(|| "unnamed".into()),
        description: cx.string(&table, top, "description").unwrap_or_default(),
        timing: TimingSpec::default(),
        resolutions: cx
            .resolutions(&table, top)
            .unwrap_or_else(|| vec![(256, 256)]),
        software: None,
        studies: Vec::new(),
        source: source.into(),
        text: text.into(),
    };
    if let Some(sw) = table.get("software") {
        match sw.as_table() {
            None => {
                cx.push(top, "software", "must be a table ([software])");
            }
            Some(t) => {
                let tn = "[software]";
                cx.unknown_keys(t, tn, SOFTWARE_KEYS);
                suite.software = Some(SoftwareProfile {
                    resolutions: cx.resolutions(t, tn),
                    max_triangles: cx
                        .int(t, tn, "max_triangles", 1, i64::MAX)
                        .map(|i| i as u64),
                    timing: timing_spec(&mut cx, t, tn),
                });
            }
        }
    }
    match table.get("timing") {
        None => {}
        Some(toml::Value::Table(t)) => {
            cx.unknown_keys(t, "[timing]", TIMING_KEYS);
            suite.timing = timing_spec(&mut cx, t, "[timing]");
        }
        Some(_) => {
            cx.push(top, "timing", "must be a table ([timing])");
        }
    }
    for (old, new) in [("reps", "max_samples"), ("warmup", "warmup_frames")] {
        for (t, tn) in [
            (Some(&table), top),
            (
                table.get("software").and_then(|v| v.as_table()),
                "[software]",
            ),
        ] {
            if let Some(p) = t.and_then(|t| t.get(old)).map(|v| v.to_string()) {
                // The fixed repetitions became a stopping rule: say where the knob went.
                if let Some(last) = cx
                    .problems
                    .iter_mut()
                    .rev()
                    .find(|x| x.table == tn && x.key == old)
                {
                    last.message = format!(
                        "was replaced by a stopping rule: use [timing] {new} (and min_samples, max_noise, max_time_ms)"
                    );
                    last.value = Some(p);
                }
            }
        }
    }
    match table.get("study") {
        Some(toml::Value::Array(a)) if !a.is_empty() => {
            for (i, s) in a.iter().enumerate() {
                match s.as_table() {
                    None => {
                        cx.push(&format!("study {i}"), "", "is not a table ([[study]])");
                    }
                    Some(t) => {
                        if let Some(spec) = parse_study(&mut cx, i, t) {
                            suite.studies.push(spec);
                        }
                    }
                }
            }
        }
        Some(toml::Value::Array(_)) | None => {
            cx.push(
                top,
                "study",
                "no [[study]] tables: a suite must declare at least one study",
            );
        }
        Some(_) => {
            cx.push(top, "study", "must be an array of tables ([[study]])");
        }
    }
    Some(suite)
}

/// The timing keys of a table (`[timing]`, or the overrides in `[software]`).
/// `[timing]` keys given as `KEY=VALUE` (values in TOML syntax, e.g. `settle=false`,
/// `max_noise=0.01`), checked as a suite's `[timing]` is: an unknown key or a bad value is an
/// error naming every problem, before any GPU work (`mfx sweep --timing`).
pub fn timing_overrides(pairs: &[String], source: &str) -> Result<TimingSpec> {
    let mut problems = Vec::new();
    let tn = "--timing";
    let mut table = toml::Table::new();
    for pair in pairs {
        match pair.split_once('=') {
            Some((k, v)) => match format!("v = {}", v.trim()).parse::<toml::Table>() {
                Ok(mut t) => {
                    table.insert(k.trim().to_string(), t.remove("v").expect("parsed key"));
                }
                Err(_) => {
                    problems.push(Problem::new(source, tn, k.trim(), "not a TOML value").value(v))
                }
            },
            None => problems.push(Problem::new(source, tn, pair, "must be KEY=VALUE")),
        }
    }
    let mut cx = Ctx {
        file: source,
        problems: &mut problems,
    };
    cx.unknown_keys(&table, tn, TIMING_KEYS);
    let spec = timing_spec(&mut cx, &table, tn);
    if problems.is_empty() {
        Ok(spec)
    } else {
        Err(SceneError::Problems(problems))
    }
}

fn timing_spec(cx: &mut Ctx<'_>, t: &toml::Table, tn: &str) -> TimingSpec {
    let int = |cx: &mut Ctx<'_>, k: &str, min: i64, max: i64| cx.int(t, tn, k, min, max);
    let float = |cx: &mut Ctx<'_>, k: &str, min: f64, max: f64| match t.get(k) {
        None => None,
        Some(v) => match v.as_float().or_else(|| v.as_integer().map(|i| i as f64)) {
            Some(x) if x.is_finite() && (min..=max).contains(&x) => Some(x),
            _ => {
                cx.push(tn, k, format!("must be a number in [{min}, {max}]"))
                    .value = Some(v.to_string());
                None
            }
        },
    };
    let boolean = |cx: &mut Ctx<'_>, k: &str| match t.get(k) {
        None => None,
        Some(toml::Value::Boolean(b)) => Some(*b),
        Some(v) => {
            cx.push(tn, k, "must be true or false").value = Some(v.to_string());
            None
        }
    };
    let interleave = boolean(cx, "interleave");
    let settle = boolean(cx, "settle");
    let cold = boolean(cx, "cold");
    let spec = TimingSpec {
        min_samples: int(cx, "min_samples", 1, 1_000_000).map(|i| i as u32),
        max_samples: int(cx, "max_samples", 1, 1_000_000).map(|i| i as u32),
        max_noise: float(cx, "max_noise", 0.0, 1.0),
        min_time_ms: float(cx, "min_time_ms", 0.0, 3.6e6),
        max_time_ms: float(cx, "max_time_ms", 1.0, 3.6e6),
        warmup_frames: int(cx, "warmup_frames", 0, 100_000).map(|i| i as u32),
        warmup_max_frames: int(cx, "warmup_max_frames", 0, 100_000).map(|i| i as u32),
        interleave,
        seed: int(cx, "seed", 0, i64::MAX).map(|i| i as u64),
        clock_lift_ms: float(cx, "clock_lift_ms", 0.0, 60_000.0),
        sessions: int(cx, "sessions", 1, 100).map(|i| i as u32),
        canary_max_ratio: float(cx, "canary_max_ratio", 0.0, 100.0),
        settle,
        cold,
    };
    if let Some(r) = spec.canary_max_ratio {
        if r > 0.0 && r <= 1.0 {
            cx.push(
                tn,
                "canary_max_ratio",
                "must be 0 (no canary) or above 1: a ratio to the fastest canary of the run",
            )
            .value = Some(r.to_string());
        }
    }
    if let (Some(a), Some(b)) = (spec.min_samples, spec.max_samples) {
        if a > b {
            cx.push(tn, "min_samples", format!("is above max_samples ({b})"))
                .value = Some(a.to_string());
        }
    }
    spec
}

/// What is wrong with a `resolutions` value (the caller names the file and table).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ResolutionsError {
    #[error("must be an array of [width, height]")]
    NotAnArray,
    #[error("each resolution must be [width, height]")]
    NotAPair,
    #[error("width must be an integer")]
    Width,
    #[error("height must be an integer")]
    Height,
    #[error("resolution {width}x{height} out of range 1..={max}")]
    OutOfRange { width: i64, height: i64, max: i64 },
}

fn resolutions(v: &toml::Value) -> std::result::Result<Vec<(u32, u32)>, ResolutionsError> {
    let arr = v.as_array().ok_or(ResolutionsError::NotAnArray)?;
    arr.iter()
        .map(|r| {
            let wh = r
                .as_array()
                .filter(|a| a.len() == 2)
                .ok_or(ResolutionsError::NotAPair)?;
            let w = wh[0].as_integer().ok_or(ResolutionsError::Width)?;
            let h = wh[1].as_integer().ok_or(ResolutionsError::Height)?;
            let max = MAX_SIDE as i64;
            if !(1..=max).contains(&w) || !(1..=max).contains(&h) {
                return Err(ResolutionsError::OutOfRange {
                    width: w,
                    height: h,
                    max,
                });
            }
            Ok((w as u32, h as u32))
        })
        .collect()
}

/// Why a value cannot be swept: sweep values are a scalar or a non-empty array of scalars.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SweepValuesError {
    #[error("is an empty array: nothing to sweep")]
    Empty,
    #[error("arrays must hold scalars")]
    NotScalars,
    #[error("must be a scalar or an array of scalars")]
    NotAScalar,
}

/// A scalar or a non-empty array of scalars, as sweep values.
fn values(v: &toml::Value) -> std::result::Result<Vec<ParamValue>, SweepValuesError> {
    match v {
        toml::Value::Array(a) if a.is_empty() => Err(SweepValuesError::Empty),
        toml::Value::Array(a) => a
            .iter()
            .map(|x| ParamValue::from_toml(x).ok_or(SweepValuesError::NotScalars))
            .collect(),
        other => Ok(vec![
            ParamValue::from_toml(other).ok_or(SweepValuesError::NotAScalar)?
        ]),
    }
}

/// The study's table name in problems: `study 2 (methods)`.
pub fn study_table(index: usize, kind: impl std::fmt::Display) -> String {
    format!("study {index} ({kind})")
}

fn parse_study(cx: &mut Ctx<'_>, index: usize, t: &toml::Table) -> Option<StudySpec> {
    let here0 = format!("study {index}");
    let text = match cx.string(t, &here0, "kind") {
        Some(k) => k,
        None => {
            if t.get("kind").is_none() {
                cx.push(&here0, "kind", "missing: every study needs kind = \"...\"");
            }
            return None;
        }
    };
    // The kind is read once, here: a misspelt one is a problem naming the file and the value,
    // and the rest of the table is still read so that its problems are reported with it.
    let kind = match text.parse::<StudyKind>() {
        Ok(k) => Some(k),
        Err(_) => {
            let p = cx.push(&here0, "kind", "unknown study kind");
            p.value = Some(text.clone());
            p.known = StudyKind::ALL.iter().map(|k| k.to_string()).collect();
            None
        }
    };
    let here = study_table(index, &text);
    let methods = match t.get("methods") {
        None => None,
        Some(toml::Value::Array(a)) => {
            let mut v = Vec::new();
            for m in a {
                match m.as_str() {
                    Some(s) => v.push(s.to_string()),
                    None => {
                        cx.push(&here, "methods", "must hold strings (method names)")
                            .value = Some(m.to_string());
                    }
                }
            }
            Some(v)
        }
        Some(v) => {
            cx.push(&here, "methods", "must be an array of method names")
                .value = Some(v.to_string());
            None
        }
    };
    let mut axes = BTreeMap::new();
    if let Some(a) = t.get("axes") {
        match a.as_table() {
            Some(at) => axes = parse_axes(cx, &format!("{here} › axes"), at),
            None => {
                cx.push(&here, "axes", "must be a table: axes = { name = [values] }");
            }
        }
    }
    let mut method_axes = BTreeMap::new();
    if let Some(m) = t.get("method_axes") {
        match m.as_table() {
            None => {
                cx.push(
                    &here,
                    "method_axes",
                    "must be a table of method = { axis = [values] }",
                );
            }
            Some(mt) => {
                for (name, v) in mt {
                    let tn = format!("{here} › method_axes.{name}");
                    if !methods.as_ref().is_some_and(|ms| ms.contains(name)) {
                        cx.push(
                            &here,
                            &format!("method_axes.{name}"),
                            "names a method that is not in this study's methods",
                        )
                        .known = methods.clone().unwrap_or_default();
                    }
                    match v.as_table() {
                        Some(at) => {
                            method_axes.insert(name.clone(), parse_axes(cx, &tn, at));
                        }
                        None => {
                            cx.push(
                                &here,
                                &format!("method_axes.{name}"),
                                "must be a table of axes",
                            );
                        }
                    }
                }
            }
        }
    }
    let mut scenes = Vec::new();
    let mut scene_tables = Vec::new();
    match t.get("scenes") {
        None => {}
        Some(toml::Value::Array(arr)) => {
            for (j, sc) in arr.iter().enumerate() {
                let Some(st) = sc.as_table() else {
                    cx.push(
                        &here,
                        "scenes",
                        format!("scene {j} is not a table ([[study.scenes]])"),
                    );
                    continue;
                };
                let mut st = st.clone();
                let generator = match st.remove("generator") {
                    Some(toml::Value::String(g)) => g,
                    Some(v) => {
                        cx.push(
                            &format!("{here} › scene {j}"),
                            "generator",
                            "must be a string",
                        )
                        .value = Some(v.to_string());
                        continue;
                    }
                    None => {
                        cx.push(
                            &format!("{here} › scene {j}"),
                            "generator",
                            "missing: each scene needs generator = \"name\"",
                        );
                        continue;
                    }
                };
                let tn = format!("{here} › scene {j} ({generator})");
                let mut ok = true;
                for (k, v) in &st {
                    if let Err(why) = values(v) {
                        cx.push(&tn, k, why.to_string()).value = Some(v.to_string());
                        ok = false;
                    }
                }
                if !ok {
                    continue;
                }
                for params in expand_product(&st).unwrap_or_default() {
                    scenes.push(SceneSpec::new(&generator, params));
                    scene_tables.push(j);
                }
            }
        }
        Some(_) => {
            cx.push(
                &here,
                "scenes",
                "must be an array of tables ([[study.scenes]])",
            );
        }
    }
    let resolutions = cx.resolutions(t, &here);
    let mut extra = t.clone();
    for k in STUDY_KEYS {
        extra.remove(*k);
    }
    Some(StudySpec {
        index,
        kind: kind?,
        methods: methods.clone().unwrap_or_default(),
        methods_given: methods.is_some(),
        axes,
        method_axes,
        scenes,
        scene_tables,
        resolutions,
        extra,
    })
}

fn parse_axes(
    cx: &mut Ctx<'_>,
    table: &str,
    at: &toml::Table,
) -> BTreeMap<String, Vec<ParamValue>> {
    let mut axes = BTreeMap::new();
    for (k, v) in at {
        match values(v) {
            Ok(vals) => {
                axes.insert(k.clone(), vals);
            }
            Err(why) => {
                cx.push(table, k, why.to_string()).value = Some(v.to_string());
            }
        }
    }
    axes
}

/// A key of a table that [`expand_product`] cannot expand.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ProductError {
    #[error("'{0}': arrays must hold scalars")]
    NotScalars(String),
    #[error("'{0}' must be a scalar or array")]
    NotAScalar(String),
    #[error("'{0}' is an empty array: nothing to sweep")]
    Empty(String),
}

/// Expands a table whose values may be arrays into the cartesian product of scalar tables.
pub fn expand_product(t: &toml::Table) -> std::result::Result<Vec<Params>, ProductError> {
    let mut out = vec![Params::new()];
    for (k, v) in t {
        let values: Vec<ParamValue> =
            match v {
                toml::Value::Array(a) => a
                    .iter()
                    .map(|x| {
                        ParamValue::from_toml(x).ok_or_else(|| ProductError::NotScalars(k.clone()))
                    })
                    .collect::<std::result::Result<_, _>>()?,
                other => vec![ParamValue::from_toml(other)
                    .ok_or_else(|| ProductError::NotAScalar(k.clone()))?],
            };
        if values.is_empty() {
            return Err(ProductError::Empty(k.clone()));
        }
        out = out
            .into_iter()
            .flat_map(|p| values.iter().map(move |v| p.clone().with(k, v.clone())))
            .collect();
    }
    Ok(out)
}

/// The study's axes as `method` sees them: its `method_axes` entries replace the shared ones.
pub fn axes_for_method(spec: &StudySpec, method: &str) -> BTreeMap<String, Vec<ParamValue>> {
    let mut axes = spec.axes.clone();
    if let Some(over) = spec.method_axes.get(method) {
        for (k, v) in over {
            axes.insert(k.clone(), v.clone());
        }
    }
    axes
}

/// Cartesian product of the named axes (only those present in `axes`), in key order.
pub fn axis_product(axes: &BTreeMap<String, Vec<ParamValue>>, names: &[&str]) -> Vec<Params> {
    let mut out = vec![Params::new()];
    for name in names {
        if let Some(vals) = axes.get(*name) {
            out = out
                .into_iter()
                .flat_map(|p| vals.iter().map(move |v| p.clone().with(name, v.clone())))
                .collect();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_misspelt_study_kind_names_the_file_and_the_value_and_the_rest_is_still_read() {
        let text =
            "[[study]]\nkind = \"method\"\naxes = 3\n[[study.scenes]]\ngenerator = \"quads\"\n";
        let (suite, problems) = Suite::parse_partial(text, "suites/typo.toml");
        assert!(suite.expect("valid TOML").studies.is_empty());
        let all = crate::problem::report(&problems);
        let kind = problems
            .iter()
            .find(|p| p.key == "kind")
            .unwrap_or_else(|| panic!("no kind problem in:\n{all}"))
            .to_string();
        for want in [
            "suites/typo.toml",
            "'kind' = method",
            "unknown study kind",
            "methods",
        ] {
            assert!(kind.contains(want), "{want:?} not in {kind:?}");
        }
        // The table's other problems are reported with it, not hidden behind the kind.
        assert!(problems.iter().any(|p| p.key == "axes"), "{all}");
    }

    #[test]
    fn every_study_kind_parses_from_its_csv_spelling() {
        for k in StudyKind::ALL {
            let text =
                format!("[[study]]\nkind = \"{k}\"\n[[study.scenes]]\ngenerator = \"quads\"\n");
            let suite = Suite::parse(&text, "t").unwrap_or_else(|e| panic!("{k}: {e}"));
            assert_eq!(suite.studies[0].kind, k);
            assert_eq!(suite.studies[0].kind.to_string(), k.name());
        }
    }
}
