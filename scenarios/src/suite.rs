//! Sweep suites as TOML files (`scenarios/suites/<name>.toml`).
//!
//! A suite lists studies; each study has a `kind` (which runner executes it), scenes (arrays in
//! a scene table expand into one scene per combination), methods, and declared `axes` whose
//! cartesian product the runner sweeps. A method ignores axes it does not declare. Example:
//!
//! ```toml
//! name = "smoke"
//! reps = 5
//! warmup = 2
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

use crate::{ParamValue, Params, Result, SceneError, SceneSpec};

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
];

#[derive(Clone, Debug)]
pub struct Suite {
    pub name: String,
    pub description: String,
    pub reps: u32,
    pub warmup: u32,
    pub resolutions: Vec<(u32, u32)>,
    /// Applied when the adapter is a CPU (software) device, so a GPU-sized suite stays runnable.
    pub software: Option<SoftwareProfile>,
    pub studies: Vec<StudySpec>,
    pub source: String,
}

/// Overrides for software adapters (lavapipe, llvmpipe).
#[derive(Clone, Debug, Default)]
pub struct SoftwareProfile {
    pub resolutions: Option<Vec<(u32, u32)>>,
    /// Scenes above this many triangles become skipped rows on a software adapter.
    pub max_triangles: Option<u64>,
    pub reps: Option<u32>,
}

#[derive(Clone, Debug)]
pub struct StudySpec {
    pub kind: String,
    pub methods: Vec<String>,
    pub axes: BTreeMap<String, Vec<ParamValue>>,
    /// Per-method axis overrides (`[study.method_axes.<method>]`): for that method they replace
    /// the study's axes of the same name, so an axis one method reads with values another
    /// method rejects (e.g. the k-buffer's `variant = "heuristics"`) need not split the table.
    pub method_axes: BTreeMap<String, BTreeMap<String, Vec<ParamValue>>>,
    pub scenes: Vec<SceneSpec>,
    pub resolutions: Option<Vec<(u32, u32)>>,
    /// Everything else in the study table, for the study kind to read.
    pub extra: toml::Table,
}

impl Suite {
    /// Loads a suite by file path or by name (`scenarios/suites/<name>.toml`, then built-ins).
    pub fn load(name_or_path: &str) -> Result<Suite> {
        let p = Path::new(name_or_path);
        let candidates = [
            p.to_path_buf(),
            PathBuf::from(format!("scenarios/suites/{name_or_path}.toml")),
        ];
        for c in &candidates {
            if c.is_file() {
                let text = std::fs::read_to_string(c).map_err(|e| SceneError::Suite {
                    path: c.display().to_string(),
                    why: e.to_string(),
                })?;
                return Suite::parse(&text, &c.display().to_string());
            }
        }
        if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name_or_path) {
            return Suite::parse(text, &format!("(built-in) {name_or_path}"));
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

    pub fn parse(text: &str, source: &str) -> Result<Suite> {
        let err = |why: String| SceneError::Suite {
            path: source.into(),
            why,
        };
        let table: toml::Table = text
            .parse()
            .map_err(|e| err(format!("not valid TOML: {e}")))?;
        let mut suite = Suite {
            name: get_str(&table, "name")
                .map_err(&err)?
                .unwrap_or_else(|| "unnamed".into()),
            description: get_str(&table, "description")
                .map_err(&err)?
                .unwrap_or_default(),
            reps: get_int(&table, "reps", 10, 1, 100_000).map_err(&err)? as u32,
            warmup: get_int(&table, "warmup", 3, 0, 100_000).map_err(&err)? as u32,
            resolutions: match table.get("resolutions") {
                Some(v) => resolutions(v).map_err(&err)?,
                None => vec![(256, 256)],
            },
            software: None,
            studies: Vec::new(),
            source: source.into(),
        };
        if let Some(sw) = table.get("software") {
            let t = sw
                .as_table()
                .ok_or_else(|| err("[software] must be a table".into()))?;
            suite.software = Some(SoftwareProfile {
                resolutions: t
                    .get("resolutions")
                    .map(resolutions)
                    .transpose()
                    .map_err(&err)?,
                max_triangles: t
                    .get("max_triangles")
                    .and_then(|v| v.as_integer().map(|i| i as u64)),
                reps: t.get("reps").and_then(|v| v.as_integer()).map(|i| i as u32),
            });
        }
        let studies = match table.get("study") {
            Some(toml::Value::Array(a)) => a.clone(),
            Some(_) => return Err(err("[[study]] must be an array of tables".into())),
            None => {
                return Err(err(
                    "no [[study]] tables: a suite must declare at least one study".into(),
                ))
            }
        };
        for (i, s) in studies.iter().enumerate() {
            let t = s
                .as_table()
                .ok_or_else(|| err(format!("study {i} is not a table")))?;
            suite
                .studies
                .push(parse_study(t).map_err(|why| err(format!("study {i}: {why}")))?);
        }
        if let Some(k) = table.keys().find(|k| {
            ![
                "name",
                "description",
                "reps",
                "warmup",
                "resolutions",
                "software",
                "study",
            ]
            .contains(&k.as_str())
        }) {
            return Err(err(format!("unknown top-level key '{k}'")));
        }
        Ok(suite)
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

fn get_str(t: &toml::Table, k: &str) -> std::result::Result<Option<String>, String> {
    match t.get(k) {
        None => Ok(None),
        Some(toml::Value::String(s)) => Ok(Some(s.clone())),
        Some(_) => Err(format!("'{k}' must be a string")),
    }
}

fn get_int(
    t: &toml::Table,
    k: &str,
    default: i64,
    min: i64,
    max: i64,
) -> std::result::Result<i64, String> {
    let v = match t.get(k) {
        None => default,
        Some(toml::Value::Integer(i)) => *i,
        Some(_) => return Err(format!("'{k}' must be an integer")),
    };
    if v < min || v > max {
        return Err(format!("'{k}' = {v} is out of range {min}..={max}"));
    }
    Ok(v)
}

fn resolutions(v: &toml::Value) -> std::result::Result<Vec<(u32, u32)>, String> {
    let arr = v
        .as_array()
        .ok_or("resolutions must be an array of [width, height]")?;
    arr.iter()
        .map(|r| {
            let wh = r
                .as_array()
                .filter(|a| a.len() == 2)
                .ok_or("each resolution must be [width, height]")?;
            let w = wh[0].as_integer().ok_or("width must be an integer")?;
            let h = wh[1].as_integer().ok_or("height must be an integer")?;
            if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
                return Err(format!("resolution {w}x{h} out of range 1..=16384"));
            }
            Ok((w as u32, h as u32))
        })
        .collect()
}

/// Expands a table whose values may be arrays into the cartesian product of scalar tables.
pub fn expand_product(t: &toml::Table) -> std::result::Result<Vec<Params>, String> {
    let mut out = vec![Params::new()];
    for (k, v) in t {
        let values: Vec<ParamValue> = match v {
            toml::Value::Array(a) => a
                .iter()
                .map(|x| {
                    ParamValue::from_toml(x)
                        .ok_or_else(|| format!("'{k}': arrays must hold scalars"))
                })
                .collect::<std::result::Result<_, _>>()?,
            other => vec![ParamValue::from_toml(other)
                .ok_or_else(|| format!("'{k}' must be a scalar or array"))?],
        };
        if values.is_empty() {
            return Err(format!("'{k}' is an empty array: nothing to sweep"));
        }
        out = out
            .into_iter()
            .flat_map(|p| values.iter().map(move |v| p.clone().with(k, v.clone())))
            .collect();
    }
    Ok(out)
}

fn parse_study(t: &toml::Table) -> std::result::Result<StudySpec, String> {
    let kind = get_str(t, "kind")?.ok_or("missing 'kind'")?;
    let methods = match t.get("methods") {
        None => Vec::new(),
        Some(toml::Value::Array(a)) => a
            .iter()
            .map(|m| {
                m.as_str()
                    .map(str::to_string)
                    .ok_or("methods must be strings")
            })
            .collect::<std::result::Result<_, _>>()?,
        Some(_) => return Err("'methods' must be an array of strings".into()),
    };
    let axes = match t.get("axes") {
        None => BTreeMap::new(),
        Some(a) => parse_axes(a.as_table().ok_or("'axes' must be a table")?)?,
    };
    let mut method_axes = BTreeMap::new();
    if let Some(m) = t.get("method_axes") {
        let mt = m
            .as_table()
            .ok_or("'method_axes' must be a table of method = { axis = [...] }")?;
        for (name, v) in mt {
            if !methods.contains(name) {
                return Err(format!(
                    "method_axes.{name}: '{name}' is not in this study's methods ({})",
                    methods.join(", ")
                ));
            }
            let at = v
                .as_table()
                .ok_or_else(|| format!("method_axes.{name} must be a table of axes"))?;
            method_axes.insert(name.clone(), parse_axes(at)?);
        }
    }
    let mut scenes = Vec::new();
    if let Some(s) = t.get("scenes") {
        let arr = s
            .as_array()
            .ok_or("'scenes' must be an array of tables ([[study.scenes]])")?;
        for sc in arr {
            let mut st = sc.as_table().ok_or("each scene must be a table")?.clone();
            let generator = match st.remove("generator") {
                Some(toml::Value::String(g)) => g,
                _ => return Err("each scene needs generator = \"name\"".into()),
            };
            for params in expand_product(&st)? {
                scenes.push(SceneSpec::new(&generator, params));
            }
        }
    }
    let resolutions = t.get("resolutions").map(resolutions).transpose()?;
    let mut extra = t.clone();
    for k in [
        "kind",
        "methods",
        "axes",
        "method_axes",
        "scenes",
        "resolutions",
    ] {
        extra.remove(k);
    }
    Ok(StudySpec {
        kind,
        methods,
        axes,
        method_axes,
        scenes,
        resolutions,
        extra,
    })
}

fn parse_axes(at: &toml::Table) -> std::result::Result<BTreeMap<String, Vec<ParamValue>>, String> {
    let mut axes = BTreeMap::new();
    for (k, v) in at {
        let vals = match v {
            toml::Value::Array(arr) => arr
                .iter()
                .map(|x| {
                    ParamValue::from_toml(x).ok_or_else(|| format!("axis '{k}' must hold scalars"))
                })
                .collect::<std::result::Result<Vec<_>, _>>()?,
            other => vec![ParamValue::from_toml(other)
                .ok_or_else(|| format!("axis '{k}' must be scalar or array"))?],
        };
        if vals.is_empty() {
            return Err(format!("axis '{k}' is empty"));
        }
        axes.insert(k.clone(), vals);
    }
    Ok(axes)
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
