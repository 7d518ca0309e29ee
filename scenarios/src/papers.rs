//! The sources' published figures as data (`scenarios/papers/<source>.toml`, issue 30): each
//! figure with its source, setup, published value and implied ratio, the suite points that
//! measure it, and the rule by which ours "holds"; or `reproducible = false` with the reason.
//! Parsed strictly (an unknown key is an error); what the points name (suite, method, scene,
//! axis values) is checked against the suites by `bench_core::papers`.

use std::collections::BTreeMap;

use serde::Deserialize;

/// The papers files, embedded so the report and `mfx check` need no working directory.
pub const BUILTIN: &[(&str, &str)] = &[
    (
        "liu-bdp-gpupro",
        include_str!("../papers/liu-bdp-gpupro.toml"),
    ),
    ("bavoil-2007", include_str!("../papers/bavoil-2007.toml")),
    (
        "lightprepass-gpupro",
        include_str!("../papers/lightprepass-gpupro.toml"),
    ),
    (
        "splitsecond-geg2",
        include_str!("../papers/splitsecond-geg2.toml"),
    ),
    ("bf3-dice", include_str!("../papers/bf3-dice.toml")),
];

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PapersFile {
    pub source: Source,
    #[serde(rename = "figure", default)]
    pub figures: Vec<Figure>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Source {
    pub title: String,
    pub authors: String,
    /// Where it was published (book, chapter, venue, year).
    pub venue: String,
    /// The copy in ../shared/sources/.
    pub document: String,
}

/// One published number (or claim) and how mfx measures it.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figure {
    /// Unique within the file.
    pub id: String,
    /// The row of ../shared/sources/figures.md A.1 it comes from.
    pub row: u32,
    pub section: String,
    /// Table or figure, e.g. "Table 6.1", "Fig. 1.2".
    pub table: String,
    pub setup: Setup,
    /// What the value measures, e.g. "fps", "ms", "claim".
    pub metric: String,
    /// The published value (none for a claim or an image).
    pub value: Option<f64>,
    /// What the ratio compares against, in the paper's words ("depth peeling, 24 fps").
    pub against: Option<String>,
    /// The ratio the figure implies, as a speed-up or reduction of `value` over `against`.
    pub ratio: Option<f64>,
    /// A claim in the paper's words, where there is no number (or beside it).
    pub claim: Option<String>,
    pub reproducible: bool,
    /// Why not (required when `reproducible = false`), or what differs in our setup.
    pub reason: Option<String>,
    /// The point measuring `value` (required when reproducible).
    pub ours: Option<PointRef>,
    /// The point measuring `against` (required when reproducible).
    pub baseline: Option<PointRef>,
    /// The rule by which ours holds (required when reproducible).
    pub holds: Option<Rule>,
    /// Why ours differs from the paper, as the committed runs measure it (the mechanism, named
    /// by the columns that show it: the report puts it beside the measured passes). Shown only
    /// when the verdict is "differs" or "within noise"; a figure that holds again keeps it
    /// silent.
    pub why_differs: Option<String>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Setup {
    pub gpu: String,
    pub resolution: Option<[u32; 2]>,
    pub scene: String,
    pub triangles: Option<u64>,
    pub layers: Option<String>,
}

/// A row of a suite: the row of runs.csv whose suite, method, scene label, resolution and axis
/// columns equal these.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointRef {
    pub suite: String,
    pub method: String,
    /// The scene's label (`SceneSpec::label`, the runs.csv `scene_label` column).
    pub scene: String,
    pub resolution: [u32; 2],
    #[serde(default)]
    pub axes: BTreeMap<String, toml::Value>,
}

/// How ours is judged: r = baseline[baseline_column] / ours[column] (with a time column, the
/// speed-up of `ours` over `baseline`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rule {
    pub rule: RuleKind,
    /// The runs.csv column compared (default gpu_ms_median).
    pub column: Option<String>,
    /// The baseline's column, where it differs (e.g. the shadows study's reference_ms: the CPU
    /// ray tracer's time in the same row as the GPU's).
    pub baseline_column: Option<String>,
    /// `ratio_above` / `ratio_below`: the bound r must pass.
    pub threshold: Option<f64>,
    /// `ratio_within`: r must lie within [paper ratio / factor, paper ratio × factor].
    pub factor: Option<f64>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RuleKind {
    /// r > threshold: an ordering (ours is faster or smaller than the baseline).
    RatioAbove,
    /// r < threshold: the reverse ordering.
    RatioBelow,
    /// The paper's ratio within a stated factor.
    RatioWithin,
}

impl Rule {
    pub fn column(&self) -> &str {
        self.column.as_deref().unwrap_or("gpu_ms_median")
    }
    pub fn baseline_column(&self) -> &str {
        self.baseline_column.as_deref().unwrap_or(self.column())
    }

    /// Whether a measured ratio `r` holds against the figure's `paper` ratio.
    pub fn holds(&self, r: f64, paper: Option<f64>) -> Option<bool> {
        Some(match self.rule {
            RuleKind::RatioAbove => r > self.threshold?,
            RuleKind::RatioBelow => r < self.threshold?,
            RuleKind::RatioWithin => {
                let (p, f) = (paper?, self.factor?);
                r >= p / f && r <= p * f
            }
        })
    }

    /// The rule in words, for the report ("r > 1", "r within 2× of 10.7").
    pub fn describe(&self, paper: Option<f64>) -> String {
        let t = |x: Option<f64>| x.map(|v| format!("{v}")).unwrap_or_else(|| "?".into());
        match self.rule {
            RuleKind::RatioAbove => format!("r > {}", t(self.threshold)),
            RuleKind::RatioBelow => format!("r < {}", t(self.threshold)),
            RuleKind::RatioWithin => format!("r within {}× of {}", t(self.factor), t(paper)),
        }
    }

    /// What is missing for this rule to be decidable (none when complete).
    pub fn problems(&self, paper: Option<f64>) -> Vec<String> {
        let mut out = Vec::new();
        match self.rule {
            RuleKind::RatioAbove | RuleKind::RatioBelow if self.threshold.is_none() => {
                out.push("needs threshold".into())
            }
            RuleKind::RatioWithin if self.factor.is_none_or(|f| f < 1.0) => {
                out.push("needs factor ≥ 1".into())
            }
            RuleKind::RatioWithin if paper.is_none() => {
                out.push("ratio_within needs the figure's ratio".into())
            }
            _ => {}
        }
        out
    }
}

/// Parses one papers file (`Err`: the TOML or serde message, which names the key).
pub fn parse(text: &str) -> Result<PapersFile, String> {
    toml::from_str(text).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_papers_file_parses_and_an_unknown_key_is_refused() {
        for (name, text) in BUILTIN {
            let f = parse(text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(!f.figures.is_empty(), "{name}");
        }
        let bad = BUILTIN[0]
            .1
            .replacen("[source]\n", "[source]\nauthor = \"x\"\n", 1);
        let e = parse(&bad).unwrap_err();
        assert!(e.contains("unknown field `author`"), "{e}");
    }

    #[test]
    fn rules_decide_on_the_measured_ratio() {
        let r = |rule, threshold, factor| Rule {
            rule,
            column: None,
            baseline_column: None,
            threshold,
            factor,
        };
        assert_eq!(
            r(RuleKind::RatioAbove, Some(1.0), None).holds(1.2, None),
            Some(true)
        );
        assert_eq!(
            r(RuleKind::RatioAbove, Some(1.0), None).holds(0.9, None),
            Some(false)
        );
        assert_eq!(
            r(RuleKind::RatioBelow, Some(1.0), None).holds(0.9, None),
            Some(true)
        );
        let w = r(RuleKind::RatioWithin, None, Some(2.0));
        assert_eq!(w.holds(6.0, Some(10.7)), Some(true));
        assert_eq!(w.holds(5.0, Some(10.7)), Some(false));
        assert_eq!(w.holds(5.0, None), None);
        assert!(!w.problems(None).is_empty());
    }
}
