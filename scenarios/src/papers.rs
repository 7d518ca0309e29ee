//! The sources' published figures as data (`scenarios/papers/<source>.toml`, issues 30 and 45):
//! each figure with its source, setup, published value and implied ratio, the suite points that
//! measure it, and the rule by which ours "holds"; or `reproducible = false` with the reason.
//!
//! A figure is ruled on its **faithful** points (`ours`/`baseline`, or an `order` of points): the
//! source's setup as its text describes it. Where mfx does not build that setup yet, `needs` says
//! what is missing and why, and the figure's verdict is "not built"; mfx's own choices are named
//! `variant`s, ruled by the same rule and shown beside the faithful verdict, never instead of it.
//!
//! A rule can fail ([`Rule::problems`] refuses one that accepts r = 1, rows with no effect), and
//! [`judge`] never calls an effect inside the noise band a hold. `why_differs` states the measured
//! reason with `{name}` placeholders filled from the rows (`facts`), so a number it states is the
//! rows' number. Parsed strictly (an unknown key is an error); what the points name (suite,
//! method, scene, axis values) is checked against the suites by `bench_core::papers`.

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
    /// The point measuring `value` (with `baseline`, a two-point figure).
    pub ours: Option<PointRef>,
    /// The point measuring `against`.
    pub baseline: Option<PointRef>,
    /// An ordering claim ("BDP > BDP2 > ADP > DP"): the points from the first of the claim to
    /// the last; each must beat the next by the rule (r = next ÷ previous of the rule's column).
    pub order: Option<Vec<PointRef>>,
    /// The rule by which the faithful points (and every variant) hold.
    pub holds: Option<Rule>,
    /// The faithful setup is not built yet: what it needs. The verdict is then "not built"; the
    /// variants show what mfx measures today.
    pub needs: Option<Needs>,
    /// mfx's own choices, ruled beside the faithful verdict (never counted as it).
    #[serde(rename = "variant", default)]
    pub variants: Vec<Variant>,
    /// Why ours differs from the paper, as the rows measure it: `{name}` placeholders are
    /// filled from `facts`, so every number it states is a number of the rows. Shown when the
    /// verdict is not a hold.
    pub why_differs: Option<String>,
    /// The numbers `why_differs` states, each read from a row of this figure.
    #[serde(default)]
    pub facts: BTreeMap<String, Fact>,
}

impl Figure {
    /// The faithful points in rule order: `[ours, baseline]` or the `order`.
    pub fn points(&self) -> Vec<&PointRef> {
        points_of(&self.ours, &self.baseline, &self.order)
    }

    /// Every named row of the figure (`ours`, `baseline`, `order1`…, `<variant>:ours`…) and its
    /// point: what a fact's `row` may name.
    pub fn named_points(&self) -> Vec<(String, &PointRef)> {
        let mut out = named(
            "",
            self.ours.as_ref(),
            self.baseline.as_ref(),
            self.order.as_deref(),
        );
        for v in &self.variants {
            out.extend(named(
                &format!("{}:", v.name),
                v.ours.as_ref(),
                v.baseline.as_ref(),
                v.order.as_deref(),
            ));
        }
        out
    }

    /// The placeholders of `why_differs` (`{name}`), in order.
    pub fn placeholders(&self) -> Vec<&str> {
        placeholders(self.why_differs.as_deref().unwrap_or(""))
    }
}

fn points_of<'a>(
    ours: &'a Option<PointRef>,
    baseline: &'a Option<PointRef>,
    order: &'a Option<Vec<PointRef>>,
) -> Vec<&'a PointRef> {
    match order {
        Some(o) => o.iter().collect(),
        None => ours.iter().chain(baseline.iter()).collect(),
    }
}

fn named<'a>(
    prefix: &str,
    ours: Option<&'a PointRef>,
    baseline: Option<&'a PointRef>,
    order: Option<&'a [PointRef]>,
) -> Vec<(String, &'a PointRef)> {
    let mut out = Vec::new();
    if let Some(p) = ours {
        out.push((format!("{prefix}ours"), p));
    }
    if let Some(p) = baseline {
        out.push((format!("{prefix}baseline"), p));
    }
    for (i, p) in order.unwrap_or(&[]).iter().enumerate() {
        out.push((format!("{prefix}order{}", i + 1), p));
    }
    out
}

/// `{name}` placeholders of a text, in order.
pub fn placeholders(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find('{') {
        let Some(j) = rest[i..].find('}') else { break };
        out.push(&rest[i + 1..i + j]);
        rest = &rest[i + j + 1..];
    }
    out
}

/// What the faithful setup needs that mfx does not build yet.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Needs {
    /// The variant to build, as it will be named (an axis value, a pass, a suite point).
    pub variant: String,
    /// Why today's implementation is not the source's: the cause (mfx's choice), not the
    /// hardware.
    pub why: String,
    /// The items of issue 45's "Differences that are mfx's choices" (1–11) it is.
    #[serde(default)]
    pub items: Vec<u32>,
}

/// One of mfx's own setups of a figure, ruled beside the faithful verdict.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// Short name (unique in the figure; a fact names its rows `<name>:ours`, …).
    pub name: String,
    /// How it departs from the source, in one line.
    pub what: String,
    pub ours: Option<PointRef>,
    pub baseline: Option<PointRef>,
    pub order: Option<Vec<PointRef>>,
    /// The rule, where it is not the figure's (e.g. another column).
    pub holds: Option<Rule>,
}

impl Variant {
    pub fn points(&self) -> Vec<&PointRef> {
        points_of(&self.ours, &self.baseline, &self.order)
    }
}

/// A number `why_differs` states: `column` (or `pass`, from `pass_ms`) of the named row,
/// divided by `per` (a column of the same row) and by the fact `over` (another fact's value).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fact {
    /// `ours`, `baseline`, `order1`…, or `<variant>:ours`… ([`Figure::named_points`]).
    pub row: String,
    pub column: Option<String>,
    pub pass: Option<String>,
    /// A column of the same row to divide by (e.g. `geometry_passes`: per pass).
    pub per: Option<String>,
    /// Another fact of the figure: this one is divided by its value (a ratio between rows).
    pub over: Option<String>,
    /// Shown ×100 with " %".
    #[serde(default)]
    pub percent: bool,
    /// Appended after the number (" ms", "×").
    pub unit: Option<String>,
    /// What the text's words assume of the number ("dominates": at least 50 %); the test on
    /// the committed run checks it.
    pub at_least: Option<f64>,
    pub at_most: Option<f64>,
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
/// columns equal these. It must name enough axes to match one point (`mfx check`).
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
/// speed-up of `ours` over `baseline`); for an `order`, r = next / previous of each neighbour.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rule {
    pub rule: RuleKind,
    /// The runs.csv column compared (default gpu_ms_median).
    pub column: Option<String>,
    /// The baseline's column, where it differs (two columns of one row: a share).
    pub baseline_column: Option<String>,
    /// Compare this pass of `pass_ms` instead of a column (a claim about one pass).
    pub pass: Option<String>,
    /// The baseline's pass, where it differs from `pass`.
    pub baseline_pass: Option<String>,
    /// `ratio_above` / `ratio_below` / `order`: the bound r must pass (`order`: default 1).
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
    /// Each point of `order` beats the next: r = next ÷ previous > threshold (default 1).
    Order,
}

impl Rule {
    pub fn column(&self) -> &str {
        self.column.as_deref().unwrap_or("gpu_ms_median")
    }
    pub fn baseline_column(&self) -> &str {
        self.baseline_column.as_deref().unwrap_or(self.column())
    }
    pub fn baseline_pass(&self) -> Option<&str> {
        self.baseline_pass.as_deref().or(self.pass.as_deref())
    }

    fn threshold(&self) -> Option<f64> {
        match self.rule {
            RuleKind::Order => Some(self.threshold.unwrap_or(1.0)),
            _ => self.threshold,
        }
    }

    /// Whether a ratio `r` passes the rule's bound against the figure's `paper` ratio (the
    /// bound alone: [`judge`] adds the noise band and the interval).
    pub fn accepts(&self, r: f64, paper: Option<f64>) -> Option<bool> {
        Some(match self.rule {
            RuleKind::RatioAbove | RuleKind::Order => r > self.threshold()?,
            RuleKind::RatioBelow => r < self.threshold?,
            RuleKind::RatioWithin => {
                let (p, f) = (paper?, self.factor?);
                r >= p / f && r <= p * f
            }
        })
    }

    /// The direction of the effect the rule claims: above 1 (+1), below (−1), for the example
    /// a test builds.
    pub fn direction(&self, paper: Option<f64>) -> f64 {
        match self.rule {
            RuleKind::RatioAbove | RuleKind::Order => 1.0,
            RuleKind::RatioBelow => -1.0,
            RuleKind::RatioWithin => match paper {
                Some(p) if p < 1.0 => -1.0,
                _ => 1.0,
            },
        }
    }

    /// The rule in words, for the report ("r > 1", "r within 2× of 10.7").
    pub fn describe(&self, paper: Option<f64>) -> String {
        let t = |x: Option<f64>| x.map(|v| format!("{v}")).unwrap_or_else(|| "?".into());
        let what = match (&self.pass, self.baseline_pass()) {
            (Some(p), Some(b)) if p == b => format!(" of pass {p}"),
            (Some(p), Some(b)) => format!(" of passes {p} / {b}"),
            _ => String::new(),
        };
        match self.rule {
            RuleKind::RatioAbove => format!("r{what} > {}", t(self.threshold)),
            RuleKind::RatioBelow => format!("r{what} < {}", t(self.threshold)),
            RuleKind::RatioWithin => format!("r{what} within {}× of {}", t(self.factor), t(paper)),
            RuleKind::Order => format!("each r{what} > {}, in order", t(self.threshold())),
        }
    }

    /// What is missing for this rule to be decidable, and a rule that cannot fail: one that
    /// accepts r = 1 (rows with no effect).
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
            RuleKind::Order if self.factor.is_some() => {
                out.push("order takes a threshold, not a factor".into())
            }
            _ => {}
        }
        if out.is_empty() && self.accepts(1.0, paper) == Some(true) {
            out.push(format!(
                "'{}' holds on rows with no effect (r = 1): it cannot fail",
                self.describe(paper)
            ));
        }
        if self.baseline_pass.is_some() && self.pass.is_none() {
            out.push("baseline_pass without pass".into());
        }
        if self.pass.is_some() && self.column.is_some() {
            out.push("pass and column: a rule compares one or the other".into());
        }
        out
    }
}

/// A verdict on one ratio (or each neighbour of an order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    /// The whole interval passes the rule, and the effect is beyond the noise band.
    Holds,
    /// The whole interval fails the rule.
    Differs,
    /// |r − 1| within the noise band: the paper's effect, measured, is not there.
    NoEffect,
    /// The interval straddles the rule's bound.
    WithinNoise,
    /// A sampled metric whose row has no interval: its median passes the rule, which is not a
    /// hold.
    NoInterval,
}

impl Verdict {
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Differs => "differs",
            Verdict::NoEffect => "differs (no measurable effect)",
            Verdict::WithinNoise => "within noise",
            Verdict::NoInterval => "no interval (the median passes; not a hold)",
        }
    }
}

/// What one measured ratio says: `r` its value, `interval` its 95 % interval (`Some((r, r))` for
/// an exact metric; `None` for a sampled one whose row has none), `band` the point's noise band
/// (`mfx compare`'s SAME band: calibrated or ±2 %). A ratio within the band of 1 is no
/// measurable effect, whatever the rule (never a hold); a hold needs the whole interval to pass.
pub fn judge(
    rule: &Rule,
    paper: Option<f64>,
    r: f64,
    interval: Option<(f64, f64)>,
    band: f64,
) -> Option<Verdict> {
    if !r.is_finite() {
        return None;
    }
    if (r - 1.0).abs() <= band {
        return Some(Verdict::NoEffect);
    }
    let Some((lo, hi)) = interval else {
        return Some(match rule.accepts(r, paper)? {
            true => Verdict::NoInterval,
            false => Verdict::Differs,
        });
    };
    // A ratio_within interval around the paper's range: the ends pass and fail on both sides.
    let (a, b) = (rule.accepts(lo, paper)?, rule.accepts(hi, paper)?);
    let outside_within = match (rule.rule, paper, rule.factor) {
        (RuleKind::RatioWithin, Some(p), Some(f)) => hi < p / f || lo > p * f,
        _ => !a && !b,
    };
    Some(if a && b {
        Verdict::Holds
    } else if outside_within {
        Verdict::Differs
    } else {
        Verdict::WithinNoise
    })
}

/// An order's verdict from its neighbours': a hold needs every neighbour to hold; any neighbour
/// that differs (or has no effect) makes the whole ordering differ, unless none has an effect;
/// else the weakest one.
pub fn judge_order(each: &[Verdict]) -> Option<Verdict> {
    if each.is_empty() {
        return None;
    }
    for v in [Verdict::Holds, Verdict::NoEffect] {
        if each.iter().all(|x| *x == v) {
            return Some(v);
        }
    }
    for v in [Verdict::Differs, Verdict::NoEffect] {
        if each.contains(&v) {
            return Some(Verdict::Differs);
        }
    }
    each.iter().copied().find(|v| *v != Verdict::Holds)
}

/// Parses one papers file (`Err`: the TOML or serde message, which names the key).
pub fn parse(text: &str) -> Result<PapersFile, toml::de::Error> {
    toml::from_str(text)
}

/// Every built-in papers file, parsed (a file that does not parse is left out: `mfx check` and
/// the tests say why).
pub fn builtin() -> Vec<(&'static str, PapersFile)> {
    BUILTIN
        .iter()
        .filter_map(|(n, t)| parse(t).ok().map(|f| (*n, f)))
        .collect()
}

/// Numerals standing alone in a text (not part of a word such as "RGBA32F", "H200" or
/// "32-triangle"): what `why_differs` may state only through a placeholder, unless the figure's
/// own published fields contain it.
pub fn bare_numbers(text: &str) -> Vec<String> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let glued = |c: Option<&char>| c.is_some_and(|c| c.is_alphanumeric() || *c == '_');
    while i < chars.len() {
        if chars[i].is_ascii_digit() && !glued(i.checked_sub(1).and_then(|j| chars.get(j))) {
            let start = i;
            while i < chars.len()
                && (chars[i].is_ascii_digit() || chars[i] == '.' || chars[i] == ',')
            {
                i += 1;
            }
            let mut num: String = chars[start..i].iter().collect();
            while num.ends_with(['.', ',']) {
                num.pop();
            }
            // "32-triangle", "4×4", "§5.3": a configuration word or a reference, not a figure.
            let next = chars.get(i);
            let prev = start.checked_sub(1).and_then(|j| chars.get(j));
            let word = glued(next)
                || (next == Some(&'-') && glued(chars.get(i + 1)))
                || (next == Some(&'×') && chars.get(i + 1).is_some_and(|c| c.is_ascii_digit()))
                || prev == Some(&'×')
                || prev == Some(&'§');
            if !word {
                out.push(num);
            }
        } else {
            i += 1;
        }
    }
    out
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
        let e = parse(&bad).unwrap_err().to_string();
        assert!(e.contains("unknown field `author`"), "{e}");
    }

    fn rule(kind: RuleKind, threshold: Option<f64>, factor: Option<f64>) -> Rule {
        Rule {
            rule: kind,
            column: None,
            baseline_column: None,
            pass: None,
            baseline_pass: None,
            threshold,
            factor,
        }
    }

    #[test]
    fn rules_decide_on_the_measured_ratio() {
        let above = rule(RuleKind::RatioAbove, Some(1.0), None);
        assert_eq!(above.accepts(1.2, None), Some(true));
        assert_eq!(above.accepts(0.9, None), Some(false));
        let below = rule(RuleKind::RatioBelow, Some(1.0), None);
        assert_eq!(below.accepts(0.9, None), Some(true));
        let w = rule(RuleKind::RatioWithin, None, Some(2.0));
        assert_eq!(w.accepts(6.0, Some(10.7)), Some(true));
        assert_eq!(w.accepts(5.0, Some(10.7)), Some(false));
        assert_eq!(w.accepts(5.0, None), None);
        assert!(!w.problems(None).is_empty());
    }

    #[test]
    fn a_rule_that_holds_on_no_effect_is_refused() {
        // Table 3.2's cache order within 1.5× of 1.19 accepts r = 1: no effect would hold.
        let w = rule(RuleKind::RatioWithin, None, Some(1.5));
        assert!(w.problems(Some(1.191))[0].contains("cannot fail"));
        assert!(w.problems(Some(3.0)).is_empty());
        // r > 0.9 (the old latency rule) holds at 1; r > 1 does not.
        let p = rule(RuleKind::RatioAbove, Some(0.9), None).problems(None);
        assert!(p[0].contains("cannot fail"), "{p:?}");
        assert!(rule(RuleKind::RatioAbove, Some(1.0), None)
            .problems(None)
            .is_empty());
        assert!(
            rule(RuleKind::RatioBelow, Some(1.1), None).problems(None)[0].contains("cannot fail")
        );
    }

    #[test]
    fn an_effect_inside_the_band_is_no_effect_and_a_hold_needs_the_whole_interval() {
        let above = rule(RuleKind::RatioAbove, Some(1.0), None);
        // Table 3.4's r = 1.002 with a tight interval: no measurable effect, not a hold.
        assert_eq!(
            judge(&above, None, 1.002, Some((1.001, 1.003)), 0.02),
            Some(Verdict::NoEffect)
        );
        assert_eq!(
            judge(&above, None, 1.3, Some((1.25, 1.35)), 0.02),
            Some(Verdict::Holds)
        );
        assert_eq!(
            judge(&above, None, 1.05, Some((0.98, 1.12)), 0.02),
            Some(Verdict::WithinNoise)
        );
        assert_eq!(
            judge(&above, None, 0.7, Some((0.69, 0.71)), 0.02),
            Some(Verdict::Differs)
        );
        // A calibrated band of 5 %: 1.04 is no effect there.
        assert_eq!(
            judge(&above, None, 1.04, Some((1.035, 1.045)), 0.05),
            Some(Verdict::NoEffect)
        );
        // No interval on a sampled metric: its median passing is not a hold; failing differs.
        assert_eq!(
            judge(&above, None, 1.3, None, 0.02),
            Some(Verdict::NoInterval)
        );
        assert_eq!(judge(&above, None, 0.5, None, 0.02), Some(Verdict::Differs));
        let w = rule(RuleKind::RatioWithin, None, Some(2.0));
        assert_eq!(
            judge(&w, Some(10.7), 3.42, Some((3.40, 3.44)), 0.02),
            Some(Verdict::Differs)
        );
        assert_eq!(
            judge(&w, Some(10.7), 5.4, Some((5.2, 5.6)), 0.02),
            Some(Verdict::WithinNoise)
        );
    }

    #[test]
    fn an_order_holds_only_whole() {
        use Verdict::*;
        assert_eq!(judge_order(&[Holds, Holds, Holds]), Some(Holds));
        assert_eq!(judge_order(&[Holds, Differs, Holds]), Some(Differs));
        assert_eq!(judge_order(&[Holds, NoEffect]), Some(Differs));
        assert_eq!(judge_order(&[NoEffect, NoEffect]), Some(NoEffect));
        assert_eq!(judge_order(&[Holds, WithinNoise]), Some(WithinNoise));
        assert_eq!(judge_order(&[]), None);
    }

    /// The numerals of a text as numbers ("1,000" is 1000; "RGBA32F" gives 32).
    fn numbers(text: &str) -> Vec<f64> {
        let mut out = Vec::new();
        let mut cur = String::new();
        for c in text.chars().chain(std::iter::once(' ')) {
            if c.is_ascii_digit() || (!cur.is_empty() && (c == '.' || c == ',')) {
                cur.push(c);
            } else if !cur.is_empty() {
                let t = cur.trim_end_matches(['.', ',']).replace(',', "");
                out.extend(t.parse::<f64>().ok());
                cur.clear();
            }
        }
        out
    }

    #[test]
    fn every_published_value_of_the_sources_has_an_entry() {
        // Transcribed from the four documents in ../shared/sources/ (tables and numbers in the
        // text): each must be the value, ratio, comparison, claim or setup of some figure of its
        // source's papers file, reproduced or with the reason it is not.
        let published: &[(&str, &[f64])] = &[
            // Liu et al. Figs. 1.2 and 1.3 (fps).
            (
                "liu-bdp-gpupro",
                &[256.0, 128.0, 106.0, 24.0, 212.0, 183.0, 20.0],
            ),
            // Bavoil: Table 3.1 (four GPUs × four modes).
            (
                "bavoil-2007",
                &[
                    0.80, 24.54, 21.07, 15.54, 7.10, 9.45, 8.31, 4.40, 7.73, 4.56, 48.4, 90.5,
                    3.36, 7.43, 17.5, 54.8,
                ],
            ),
            // Table 3.2, Table 3.3.
            (
                "bavoil-2007",
                &[
                    110.0, 119.0, 131.0, 144.0, 97.4, 107.0, 116.0, 127.0, 158.0, 161.0, 1.01,
                    10.1, 10.8, 2.56, 0.35,
                ],
            ),
            // Table 3.4 (7800 GTX then X800).
            (
                "bavoil-2007",
                &[
                    397.0, 207.0, 253.0, 41.0, 311.0, 228.0, 322.0, 237.0, 205.0, 252.0, 259.0,
                    256.0, 5.1, 4.9, 257.0, 244.0, 243.0, 193.0, 5.4,
                ],
            ),
            // Table 6.1 (MP, SP, SPwH on the Dragon, Powerplant, Lucy).
            (
                "bavoil-2007",
                &[
                    41.4, 10.3, 139.0, 3.1, 2.6, 5.1, 1.3, 20.1, 0.2, 0.4, 0.1, 1.7,
                ],
            ),
            // The text: Fig. 3.1's 1M-vertex cliff and the X800's crash above 2M, the Lucy 28M
            // crash unbatched, Fig. 3.2's 500–1,000 batches, Fig. 5.5's 4.1 and 1.2 fps at 289
            // and 1089 samples, Fig. 5.8's 5.9 fps against 17 min, §5.5.1's 2×, Fig. 5.6's 441.
            (
                "bavoil-2007",
                &[
                    1e6, 2e6, 28e6, 500.0, 1000.0, 4.1, 1.2, 289.0, 1089.0, 5.9, 17.0, 2.0, 441.0,
                ],
            ),
            // Tovey & McAuley: six SPEs, 256 KB of local store, a 128-byte release value.
            ("lightprepass-gpupro", &[6.0, 256.0, 128.0]),
            // Split/Second: 128 raw IDs into 32 shaders, QUAD's 4 and RECT's 3 indices,
            // 321×181 tile vertices at 1280×720.
            (
                "splitsecond-geg2",
                &[128.0, 32.0, 4.0, 3.0, 321.0, 181.0, 1280.0, 720.0],
            ),
            // BF3: geometry pass 6–10 ms, copy 1.3 ms, 40 ms over 5 SPUs, culling 1–4 ms for
            // 1000+ lights, diffuse-only 2×, LUT 21 cycles, 1–6 SPUs, reload 10 s.
            (
                "bf3-dice",
                &[6.0, 10.0, 1.3, 40.0, 5.0, 1.0, 4.0, 1000.0, 2.0, 21.0],
            ),
        ];
        for (name, values) in published {
            let text = BUILTIN.iter().find(|(n, _)| n == name).unwrap().1;
            let f = parse(text).unwrap();
            let mut found: Vec<f64> = Vec::new();
            for fig in &f.figures {
                found.extend(fig.value);
                found.extend(fig.ratio);
                let s = &fig.setup;
                for t in [
                    fig.against.as_deref(),
                    fig.claim.as_deref(),
                    Some(s.scene.as_str()),
                    s.layers.as_deref(),
                    Some(s.gpu.as_str()),
                ] {
                    found.extend(numbers(t.unwrap_or("")));
                }
                found.extend(s.resolution.iter().flatten().map(|x| *x as f64));
            }
            for v in *values {
                assert!(
                    found
                        .iter()
                        .any(|x| (x - v).abs() <= 1e-9 * v.abs().max(1.0)),
                    "{name}: {v} has no entry"
                );
            }
        }
    }

    #[test]
    fn bare_numbers_are_numerals_outside_words() {
        assert_eq!(
            bare_numbers("16 passes at about 1 ms, 8 RGBA32F targets on the H200"),
            ["16", "1", "8"]
        );
        assert!(bare_numbers("32-triangle batches, 4×4 quads, §5.3.2, {route_ms} ms").is_empty());
        assert_eq!(bare_numbers("1.7× for 3.8×, 2.5 %."), ["1.7", "3.8", "2.5"]);
        assert_eq!(placeholders("a {x} b {y_z}."), ["x", "y_z"]);
    }
}
