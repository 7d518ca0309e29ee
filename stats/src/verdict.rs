//! SAME / FASTER / SLOWER / UNSURE for one point measured in two runs (BASE and NEW).
//!
//! From samples ([`compare_samples`]):
//! - `ratio` = median(NEW) / median(BASE) (> 1: NEW is slower);
//! - `ratio_ci`: percentile-bootstrap 95 % CI of that ratio (each side resampled independently,
//!   [`crate::BOOTSTRAP_RESAMPLES`] times, seeded);
//! - `p`: two-sided Mann–Whitney U p-value of the two sample sets ([`crate::mwu`]).
//!
//! The rule, first match wins (criterion.rs calls a change only when it is significant *and*
//! beyond a noise band; `nvbench_compare` classifies SAME/FAST/SLOW against the noise):
//! 1. either side has fewer than `min_samples` samples → **Same** if every ratio of a NEW sample
//!    to a BASE sample lies within the noise band (equivalence needs no test then), else
//!    **Unsure** (too few to decide: with 4 against 4 the smallest possible exact p is 0.029,
//!    and a bootstrap of 4 values is coarse);
//! 2. `|ratio − 1| ≤ noise_band` → **Same** — also when significant: a 0.5 % shift that the test
//!    can resolve is still not a change worth reporting;
//! 3. `ratio > 1 + noise_band`: **Slower** if `p < alpha` and `ratio_ci.lo > 1`, else **Unsure**;
//! 4. `ratio < 1 − noise_band`: **Faster** if `p < alpha` and `ratio_ci.hi < 1`, else **Unsure**.
//!
//! From summary columns only ([`compare_intervals`], when the raw samples are missing): each
//! side is a median with an interval (the median's CI where written, else min–max). Same rule
//! with "significant" replaced by "the intervals do not overlap" (NEW's low above BASE's high
//! for Slower), `p` = None, and `ratio_ci` the conservative `[new.lo/base.hi, new.hi/base.lo]`;
//! without intervals only Same or Unsure can come out.
//!
//! Cycles: when both sides know their SM clock, compare `time × clock` ([`cycles_k`]) with the
//! same rule — a change in time that vanishes in cycles was the clock, not the code.

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use crate::mwu::mann_whitney_u;
use crate::summary::{median_unsorted, percentile_interval, BOOTSTRAP_RESAMPLES};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum Verdict {
    Same,
    Faster,
    Slower,
    Unsure,
}

impl Verdict {
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Same => "SAME",
            Verdict::Faster => "FASTER",
            Verdict::Slower => "SLOWER",
            Verdict::Unsure => "UNSURE",
        }
    }
    pub const ALL: [Verdict; 4] = [
        Verdict::Same,
        Verdict::Faster,
        Verdict::Slower,
        Verdict::Unsure,
    ];
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VerdictOptions {
    /// Significance level of the Mann–Whitney U test (criterion's default 0.05).
    pub alpha: f64,
    /// Relative change below which a point is SAME (criterion's default noise threshold 2 %).
    pub noise_band: f64,
    /// Samples needed on each side to decide (see rule 1).
    pub min_samples: usize,
    pub resamples: usize,
    pub seed: u64,
}

impl Default for VerdictOptions {
    fn default() -> Self {
        VerdictOptions {
            alpha: 0.05,
            noise_band: 0.02,
            min_samples: 5,
            resamples: BOOTSTRAP_RESAMPLES,
            seed: 0x006d_6678, // "mfx"
        }
    }
}

/// What the verdict was computed from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Basis {
    /// Raw per-sample times (MWU p-value and a bootstrap CI of the ratio).
    Samples,
    /// Summary columns only (medians and their intervals).
    Summary,
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Comparison {
    pub verdict: Verdict,
    /// NEW / BASE of the medians (> 1: slower).
    pub ratio: f64,
    pub ratio_ci: (f64, f64),
    /// Two-sided MWU p-value (None from summary columns, and when sessions decide).
    pub p: Option<f64>,
    pub n_base: usize,
    pub n_new: usize,
    pub basis: Basis,
    /// One line saying why, for the report.
    pub why: String,
}

fn median(v: &[f64]) -> f64 {
    median_unsorted(&mut v.to_vec())
}

/// Rules 2–4 given the ratio, its CI and whether the difference is significant.
fn classify(ratio: f64, ci: (f64, f64), significant: bool, band: f64) -> (Verdict, &'static str) {
    if (ratio - 1.0).abs() <= band {
        (Verdict::Same, "change within the noise band")
    } else if ratio > 1.0 {
        if significant && ci.0 > 1.0 {
            (
                Verdict::Slower,
                "significantly slower, beyond the noise band",
            )
        } else {
            (
                Verdict::Unsure,
                "slower beyond the band but not significant",
            )
        }
    } else if significant && ci.1 < 1.0 {
        (
            Verdict::Faster,
            "significantly faster, beyond the noise band",
        )
    } else {
        (
            Verdict::Unsure,
            "faster beyond the band but not significant",
        )
    }
}

fn unsure(n_base: usize, n_new: usize, basis: Basis, why: String) -> Comparison {
    Comparison {
        verdict: Verdict::Unsure,
        ratio: f64::NAN,
        ratio_ci: (f64::NAN, f64::NAN),
        p: None,
        n_base,
        n_new,
        basis,
        why,
    }
}

/// The verdict from the two sides' raw samples (times in ms, or cycles).
pub fn compare_samples(base: &[f64], new: &[f64], o: &VerdictOptions) -> Comparison {
    let (nb, nn) = (base.len(), new.len());
    if nb == 0 || nn == 0 {
        return unsure(nb, nn, Basis::Samples, "no samples on one side".into());
    }
    let (mb, mn) = (median(base), median(new));
    if mb.is_nan() || mb <= 0.0 {
        return unsure(nb, nn, Basis::Samples, format!("BASE median is {mb}"));
    }
    let ratio = mn / mb;
    let ci = bootstrap_ratio(base, new, o);
    let p = mann_whitney_u(base, new).map(|t| t.p);
    if nb < o.min_samples || nn < o.min_samples {
        // Too few for a test, but not for equivalence: when even the extreme ratios (NEW's
        // min over BASE's max, NEW's max over BASE's min) lie inside the band, no resampling
        // can leave it (a 300 ms point capped at 4 samples a side, all within 0.01 %).
        let lo = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = |v: &[f64]| v.iter().copied().fold(0.0f64, f64::max);
        let extremes = (lo(new) / hi(base), hi(new) / lo(base));
        if extremes.0 >= 1.0 - o.noise_band && extremes.1 <= 1.0 + o.noise_band {
            return Comparison {
                verdict: Verdict::Same,
                ratio,
                ratio_ci: extremes,
                p,
                n_base: nb,
                n_new: nn,
                basis: Basis::Samples,
                why: format!(
                    "{nb} vs {nn} samples, too few for a test, but every ratio of a NEW sample to a BASE sample is within the noise band"
                ),
            };
        }
        return Comparison {
            ratio,
            ratio_ci: ci,
            p,
            ..unsure(
                nb,
                nn,
                Basis::Samples,
                format!("too few samples ({nb} vs {nn}, need {})", o.min_samples),
            )
        };
    }
    let significant = p.is_some_and(|p| p < o.alpha);
    let (verdict, why) = classify(ratio, ci, significant, o.noise_band);
    Comparison {
        verdict,
        ratio,
        ratio_ci: ci,
        p,
        n_base: nb,
        n_new: nn,
        basis: Basis::Samples,
        why: why.into(),
    }
}

/// The verdict from samples grouped by session (`[timing] sessions`: each session prepared
/// afresh, elsewhere in memory). Samples of one session are not independent of each other — on
/// the H200 a k-buffer point sits in one of two or three time states per preparation, up to
/// 9.6 % apart — so when either side has more than one session the session is the unit:
/// - `ratio`: the pooled medians, as [`compare_samples`];
/// - `ratio_ci`: a two-stage bootstrap (sessions resampled with replacement, then each drawn
///   session's samples), so the interval is as wide as the sessions disagree;
/// - significant: that interval excludes 1; `p` is None (the Mann–Whitney U of the pooled
///   samples treats every sample as independent: beside this verdict it would mislead);
/// - rule 1 (too few samples on a side) as in [`compare_samples`], on the pooled samples.
///
/// With one session on each side this is [`compare_samples`] on them.
pub fn compare_sessions(base: &[Vec<f64>], new: &[Vec<f64>], o: &VerdictOptions) -> Comparison {
    let flat = |v: &[Vec<f64>]| v.iter().flatten().copied().collect::<Vec<f64>>();
    let (fb, fnew) = (flat(base), flat(new));
    let nonempty = |v: &[Vec<f64>]| v.iter().filter(|s| !s.is_empty()).count();
    let (sb, sn) = (nonempty(base), nonempty(new));
    let mut c = compare_samples(&fb, &fnew, o);
    if (sb <= 1 && sn <= 1)
        || c.ratio.is_nan()
        || fb.len() < o.min_samples
        || fnew.len() < o.min_samples
    {
        return c;
    }
    let ci = bootstrap_sessions(base, new, o);
    let significant = ci.0 > 1.0 || ci.1 < 1.0;
    let (verdict, why) = classify(c.ratio, ci, significant, o.noise_band);
    c.verdict = verdict;
    c.ratio_ci = ci;
    c.p = None;
    c.why = format!("{why} ({sb} vs {sn} sessions: the CI resamples sessions)");
    c
}

/// Two-stage percentile bootstrap of median(NEW) / median(BASE) over sessions.
fn bootstrap_sessions(base: &[Vec<f64>], new: &[Vec<f64>], o: &VerdictOptions) -> (f64, f64) {
    let mut rng = Pcg64::seed_from_u64(o.seed);
    let keep = |v: &[Vec<f64>]| {
        v.iter()
            .filter(|s| !s.is_empty())
            .cloned()
            .collect::<Vec<_>>()
    };
    let (base, new) = (keep(base), keep(new));
    let mut draw = |side: &[Vec<f64>], out: &mut Vec<f64>| {
        out.clear();
        for _ in 0..side.len() {
            let s = &side[rng.random_range(0..side.len())];
            for _ in 0..s.len() {
                out.push(s[rng.random_range(0..s.len())]);
            }
        }
        median_unsorted(out)
    };
    let (mut bb, mut bn) = (Vec::new(), Vec::new());
    let mut ratios = Vec::with_capacity(o.resamples);
    for _ in 0..o.resamples.max(1) {
        let d = draw(&base, &mut bb);
        let n = draw(&new, &mut bn);
        if d > 0.0 {
            ratios.push(n / d);
        }
    }
    if ratios.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    percentile_interval(&mut ratios)
}

fn bootstrap_ratio(base: &[f64], new: &[f64], o: &VerdictOptions) -> (f64, f64) {
    let mut rng = Pcg64::seed_from_u64(o.seed);
    let (mut bb, mut bn) = (vec![0.0; base.len()], vec![0.0; new.len()]);
    let mut ratios = Vec::with_capacity(o.resamples);
    for _ in 0..o.resamples.max(1) {
        for x in bb.iter_mut() {
            *x = base[rng.random_range(0..base.len())];
        }
        for x in bn.iter_mut() {
            *x = new[rng.random_range(0..new.len())];
        }
        let d = median_unsorted(&mut bb);
        if d > 0.0 {
            ratios.push(median_unsorted(&mut bn) / d);
        }
    }
    if ratios.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    percentile_interval(&mut ratios)
}

/// Two frame-time modes in one side's samples: the relative distance between the medians of
/// the two groups either side of the widest split of the sorted samples, when each group holds
/// at least `min_frac` of them (and 3), the groups' medians lie `min_sep` or more apart and the
/// split itself is an empty stretch of at least a third of that. `None`: one mode, or too few
/// samples (under 6) to tell. The H200's compute A-buffer on quads(32) has frames at 1.61–1.62
/// and at 1.70–1.71 ms within one session (0.055): its median sits in whichever mode holds
/// more frames, so two runs of one build can differ by the whole gap.
pub fn mode_gap(samples: &[f64], min_frac: f64, min_sep: f64) -> Option<f64> {
    modes(samples, min_frac, min_sep).map(|m| m.gap)
}

/// Two frame-time modes of one side ([`modes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Modes {
    /// Medians of the faster and the slower group.
    pub low: f64,
    pub high: f64,
    /// `(high − low) / median of all`.
    pub gap: f64,
    /// A sample belongs to the slower mode when above this (the middle of the empty stretch).
    pub split: f64,
}

/// The two modes behind [`mode_gap`], when there are two.
pub fn modes(samples: &[f64], min_frac: f64, min_sep: f64) -> Option<Modes> {
    let mut xs: Vec<f64> = samples.iter().copied().filter(|x| x.is_finite()).collect();
    let n = xs.len();
    if n < 6 {
        return None;
    }
    xs.sort_by(f64::total_cmp);
    let m = median_of(&xs);
    if m <= 0.0 {
        return None;
    }
    let lo = ((min_frac * n as f64).ceil() as usize).max(3);
    let mut best: Option<Modes> = None;
    // Split after index i: [0, i] and [i + 1, n).
    for i in lo.saturating_sub(1)..n.saturating_sub(lo) {
        let (a, b) = xs.split_at(i + 1);
        let (low, high) = (median_of(a), median_of(b));
        let sep = (high - low) / m;
        let gap = (xs[i + 1] - xs[i]) / m;
        if sep >= min_sep && gap >= min_sep / 3.0 && best.is_none_or(|s| sep > s.gap) {
            best = Some(Modes {
                low,
                high,
                gap: sep,
                split: 0.5 * (xs[i] + xs[i + 1]),
            });
        }
    }
    best
}

/// Defaults of [`mode_gap`] for a verdict: each mode a fifth of the samples, 1.5 % apart (below
/// the 2 % band, so a gap that can flip a verdict is always seen).
pub const MODE_MIN_FRAC: f64 = 0.2;
pub const MODE_MIN_SEP: f64 = 0.015;

/// How [`compare_matched`] reached its verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Matching {
    /// Both sides show two modes of the same gap: low compared with low, high with high.
    Modes,
    /// Both sides hold an odd number (≥ 3) of sessions: the median session of each compared.
    MedianSession,
    /// Otherwise: [`compare_sessions`] (one session a side: [`compare_samples`]).
    Sessions,
}

impl Matching {
    pub fn as_str(self) -> &'static str {
        match self {
            Matching::Modes => "mode-matched",
            Matching::MedianSession => "median session",
            Matching::Sessions => "sessions resampled",
        }
    }
}

/// A verdict from per-session samples, and what the hold-back rules need to know about the
/// samples it compared.
#[derive(Clone, Debug, PartialEq)]
pub struct Matched {
    pub comparison: Comparison,
    pub matching: Matching,
    /// Two frame-time modes behind the samples compared, per side (None after mode matching:
    /// resolved; for the median session: its own, or the side's where they alternate within
    /// its sessions).
    pub base_modes: Option<Modes>,
    pub new_modes: Option<Modes>,
    /// Median of the samples compared, per side (NEW as given, e.g. scaled).
    pub base_median: f64,
    pub new_median: f64,
}

/// The session whose median is the median of the side's session medians, when the side holds
/// an odd number (≥ 3) of non-empty sessions.
pub fn median_session(sessions: &[Vec<f64>]) -> Option<&[f64]> {
    let mut s: Vec<(f64, &Vec<f64>)> = sessions
        .iter()
        .filter(|v| !v.is_empty())
        .map(|v| (median(v), v))
        .collect();
    if s.len() < 3 || s.len().is_multiple_of(2) {
        return None;
    }
    s.sort_by(|a, b| a.0.total_cmp(&b.0));
    Some(s[s.len() / 2].1)
}

/// The verdict between two sides' per-session samples, each compared with what it can be
/// told apart from (first match wins):
///
/// 1. **Mode-matched.** Both sides' pooled samples show two modes ([`modes`], the verdict
///    defaults) whose gaps agree within the noise band: the fast mode of NEW is compared with
///    the fast mode of BASE and the slow with the slow ([`compare_samples`] on each), and the
///    point is SLOWER / FASTER / SAME only when both modes say so, else UNSURE; `ratio` is the
///    geometric mean of the two mode ratios, `ratio_ci` the hull of their CIs. Why: which mode a
///    frame (or a whole session) falls in is a state the build does not choose — its share
///    moves between runs of one build and drags a pooled median across the gap — while a change
///    of the code moves both modes. Compared mode with mode, a run of one build matches itself
///    whatever the shares, and a 5 % change stays 5 % in each mode.
/// 2. **Median session.** Both sides hold an odd number (≥ 3) of sessions, and their median
///    sessions `min_samples` or more samples each: the side's median
///    session (its session medians' median, [`median_session`]) against the other's, by
///    [`compare_samples`]. Why: a session is prepared afresh and lands in one memory state for
///    all its samples (on the H200 a k-buffer session can sit 4–10 % above its twins), so the
///    session is the unit of a state and the samples are the unit of noise within one. The
///    median session cannot be moved by a minority of sessions in another state (one of three),
///    and within a state its samples are independent enough for the test. The two-stage
///    bootstrap of [`compare_sessions`] instead draws the odd session twice in a quarter of its
///    resamples, so a point with one odd session of three can never be called at 5 %.
/// 3. Otherwise [`compare_sessions`].
///
/// What a state-mix can still do (a majority of NEW's sessions in BASE's minority state; three
/// states spread over three sessions) is left to the caller's band and hold-back rules, which
/// see the modes of the samples actually compared (`base_modes`, `new_modes`).
pub fn compare_matched(base: &[Vec<f64>], new: &[Vec<f64>], o: &VerdictOptions) -> Matched {
    let flat = |v: &[Vec<f64>]| v.iter().flatten().copied().collect::<Vec<f64>>();
    let (fb, fnew) = (flat(base), flat(new));
    let two = |v: &[f64]| modes(v, MODE_MIN_FRAC, MODE_MIN_SEP);
    if let (Some(mb), Some(mn)) = (two(&fb), two(&fnew)) {
        if (mb.gap - mn.gap).abs() <= o.noise_band {
            let split = |v: &[f64], m: &Modes| -> (Vec<f64>, Vec<f64>) {
                v.iter().partition(|x| **x <= m.split)
            };
            let ((bl, bh), (nl, nh)) = (split(&fb, &mb), split(&fnew, &mn));
            let (lo, hi) = (compare_samples(&bl, &nl, o), compare_samples(&bh, &nh, o));
            let verdict = if lo.verdict == hi.verdict {
                lo.verdict
            } else {
                Verdict::Unsure
            };
            let p = match (lo.p, hi.p) {
                (Some(a), Some(b)) => Some(a.max(b)),
                _ => None,
            };
            let why = format!(
                "mode-matched (two modes on both sides, {:.1} % and {:.1} % apart): fast mode \
                 {:.3} {}, slow mode {:.3} {}{}",
                mb.gap * 100.0,
                mn.gap * 100.0,
                lo.ratio,
                lo.verdict,
                hi.ratio,
                hi.verdict,
                match verdict {
                    // Name the undecided mode's reason (e.g. "not significant").
                    Verdict::Unsure => format!(
                        " (the modes disagree: {})",
                        if lo.verdict == Verdict::Unsure || hi.verdict != Verdict::Unsure {
                            &lo.why
                        } else {
                            &hi.why
                        }
                    ),
                    _ => String::new(),
                }
            );
            return Matched {
                comparison: Comparison {
                    verdict,
                    ratio: (lo.ratio * hi.ratio).sqrt(),
                    ratio_ci: (
                        lo.ratio_ci.0.min(hi.ratio_ci.0),
                        lo.ratio_ci.1.max(hi.ratio_ci.1),
                    ),
                    p,
                    n_base: fb.len(),
                    n_new: fnew.len(),
                    basis: Basis::Samples,
                    why,
                },
                matching: Matching::Modes,
                base_modes: None,
                new_modes: None,
                base_median: median(&fb),
                new_median: median(&fnew),
            };
        }
    }
    // A median session too short for a test within it (a 300 ms point capped at 4 samples a
    // session) leaves the decision to the sessions resampled.
    let long = |s: &&[f64]| s.len() >= o.min_samples;
    if let (Some(sb), Some(sn)) = (
        median_session(base).filter(long),
        median_session(new).filter(long),
    ) {
        let mut c = compare_samples(sb, sn, o);
        let count = |v: &[Vec<f64>]| v.iter().filter(|s| !s.is_empty()).count();
        c.why = format!(
            "{} (median session of {} vs {})",
            c.why,
            count(base),
            count(new)
        );
        // Modes for the hold-back: the median session's own, else the side's pooled ones
        // when they alternate frame by frame (some session holds both), not when whole
        // sessions sit in different states (what the median session already sets aside).
        let frame_modes = |side: &[Vec<f64>], med: &[f64], flat: &[f64]| {
            two(med).or_else(|| {
                side.iter()
                    .any(|v| two(v).is_some())
                    .then(|| two(flat))
                    .flatten()
            })
        };
        return Matched {
            comparison: c,
            matching: Matching::MedianSession,
            base_modes: frame_modes(base, sb, &fb),
            new_modes: frame_modes(new, sn, &fnew),
            base_median: median(sb),
            new_median: median(sn),
        };
    }
    Matched {
        comparison: compare_sessions(base, new, o),
        matching: Matching::Sessions,
        base_modes: two(&fb),
        new_modes: two(&fnew),
        base_median: median(&fb),
        new_median: median(&fnew),
    }
}

fn median_of(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    }
}

/// Holds back a FASTER / SLOWER verdict that the point's own instability could explain: when
/// `|ratio − 1|` is within `wide` (the band widened by a mode gap or a noisy session spread of
/// either side; infinite: whatever the ratio), the verdict becomes **Unsure** and `why` says which instability. A verdict is
/// then never more confident than the runs it compares.
pub fn hold_back(mut c: Comparison, wide: f64, why: &str) -> Comparison {
    if matches!(c.verdict, Verdict::Faster | Verdict::Slower) && (c.ratio - 1.0).abs() <= wide {
        let dir = if c.verdict == Verdict::Slower {
            "slower"
        } else {
            "faster"
        };
        c.why = if wide.is_finite() {
            format!(
                "{dir} beyond the band, but within ±{:.1} %: {why}",
                wide * 100.0
            )
        } else {
            format!("{dir} beyond the band, but {why}")
        };
        c.verdict = Verdict::Unsure;
    }
    c
}

/// A side known only by its summary columns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub median: f64,
    /// The median's CI, or min–max where no CI was written; None when neither is.
    pub range: Option<(f64, f64)>,
    /// Samples behind the summary (the `samples` or `reps` column), when known.
    pub n: usize,
}

/// The verdict from summary columns only (see the module notes).
pub fn compare_intervals(base: Interval, new: Interval, o: &VerdictOptions) -> Comparison {
    let (nb, nn) = (base.n, new.n);
    if base.median.is_nan() || base.median <= 0.0 {
        return unsure(
            nb,
            nn,
            Basis::Summary,
            format!("BASE median is {}", base.median),
        );
    }
    let ratio = new.median / base.median;
    let (ci, separate) = match (base.range, new.range) {
        (Some((bl, bh)), Some((nl, nh))) => {
            let ci = (
                if bh > 0.0 { nl / bh } else { f64::NAN },
                if bl > 0.0 { nh / bl } else { f64::INFINITY },
            );
            (ci, nl > bh || nh < bl)
        }
        _ => ((f64::NAN, f64::NAN), false),
    };
    let (verdict, why) = classify(ratio, ci, separate, o.noise_band);
    let why = match verdict {
        Verdict::Unsure if base.range.is_none() || new.range.is_none() => {
            "beyond the band, but no interval to judge it (summary columns only)"
        }
        Verdict::Unsure => "beyond the band, but the intervals overlap (summary columns only)",
        _ => why,
    };
    Comparison {
        verdict,
        ratio,
        ratio_ci: ci,
        p: None,
        n_base: nb,
        n_new: nn,
        basis: Basis::Summary,
        why: why.into(),
    }
}

/// Per-sample kilocycles: `ms × MHz = 10³ cycles`. `None` unless every sample has a clock.
pub fn cycles_k(ms: &[f64], mhz: &[Option<f64>]) -> Option<Vec<f64>> {
    if ms.len() != mhz.len() {
        return None;
    }
    ms.iter()
        .zip(mhz)
        .map(|(t, c)| c.filter(|c| c.is_finite() && *c > 0.0).map(|c| t * c))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stop::tests::pseudo;

    fn series(n: usize, scale: f64, noise: f64, offset: usize) -> Vec<f64> {
        (0..n)
            .map(|i| scale * (1.0 + noise * pseudo(i + offset)))
            .collect()
    }

    #[test]
    fn identical_samples_are_same() {
        let a = series(20, 1.0, 0.05, 0);
        let c = compare_samples(&a, &a, &VerdictOptions::default());
        assert_eq!(c.verdict, Verdict::Same, "{c:?}");
        assert_eq!(c.ratio, 1.0);
        assert!(c.p.unwrap() > 0.9);
        // Even very noisy identical samples: the estimate is exactly 1.
        let a = series(20, 1.0, 0.5, 0);
        assert_eq!(
            compare_samples(&a, &a, &VerdictOptions::default()).verdict,
            Verdict::Same
        );
    }

    #[test]
    fn one_and_a_half_times_slower_is_slower_from_five_samples() {
        let a = series(5, 1.0, 0.02, 0);
        let b: Vec<f64> = a.iter().map(|x| x * 1.5).collect();
        let c = compare_samples(&a, &b, &VerdictOptions::default());
        assert_eq!(c.verdict, Verdict::Slower, "{c:?}");
        assert!((c.ratio - 1.5).abs() < 1e-12);
        assert!(c.ratio_ci.0 > 1.0 && c.p.unwrap() < 0.05);
        // And the other way round.
        let c = compare_samples(&b, &a, &VerdictOptions::default());
        assert_eq!(c.verdict, Verdict::Faster, "{c:?}");
    }

    #[test]
    fn tiny_significant_change_within_the_band_is_same() {
        // 0.5 % slower with 0.1 % noise over 30 samples: clearly significant, but inside 2 %.
        let a = series(30, 1.0, 0.001, 0);
        let b = series(30, 1.005, 0.001, 1000);
        let c = compare_samples(&a, &b, &VerdictOptions::default());
        assert!(c.p.unwrap() < 1e-6, "{c:?}");
        assert_eq!(c.verdict, Verdict::Same, "{c:?}");
    }

    #[test]
    fn too_few_samples_are_unsure() {
        let a = series(4, 1.0, 0.01, 0);
        let b: Vec<f64> = a.iter().map(|x| x * 2.0).collect();
        let c = compare_samples(&a, &b, &VerdictOptions::default());
        assert_eq!(c.verdict, Verdict::Unsure);
        assert!(c.why.contains("too few"), "{}", c.why);
        assert!((c.ratio - 2.0).abs() < 1e-12, "ratio still reported");
    }

    #[test]
    fn too_few_samples_are_same_only_when_every_pairwise_ratio_is_in_the_band() {
        // The H200's dual_peel on shells(16, 256) at 1024²: 4 samples of ≈ 299 ms a side.
        let a = [298.91, 298.93, 298.90, 298.92];
        let b = [298.94, 298.90, 298.91, 298.95];
        let c = compare_samples(&a, &b, &VerdictOptions::default());
        assert_eq!(c.verdict, Verdict::Same, "{c:?}");
        assert!(c.why.contains("too few for a test"), "{}", c.why);
        assert!(c.ratio_ci.0 >= 0.98 && c.ratio_ci.1 <= 1.02);
        // One sample 3 % off on one side: an extreme ratio leaves the band → Unsure, not Same.
        let b2 = [298.94, 298.90, 298.91, 307.9];
        let c2 = compare_samples(&a, &b2, &VerdictOptions::default());
        assert_eq!(c2.verdict, Verdict::Unsure, "{c2:?}");
        assert!(c2.why.contains("too few samples"), "{}", c2.why);
    }

    #[test]
    fn a_noisy_shift_that_is_not_significant_is_unsure() {
        // A 5 % slowdown hidden in ±50 % noise with 10 samples: beyond the band, but the ranks
        // interleave, so the test cannot tell.
        let a = series(10, 1.0, 0.5, 0);
        let b: Vec<f64> = a.iter().map(|x| x * 1.05).collect();
        let c = compare_samples(&a, &b, &VerdictOptions::default());
        assert!(c.p.unwrap() > 0.05, "{c:?}");
        assert_eq!(c.verdict, Verdict::Unsure, "{c:?}");
    }

    #[test]
    fn sessions_in_different_states_widen_the_ci_instead_of_calling_a_change() {
        let o = VerdictOptions::default();
        // Three sessions a side, each 20 tight samples at 1.00 or 1.06 (two memory states):
        // BASE in states (1.00, 1.00, 1.06), NEW (1.06, 1.06, 1.00). Pooled, the samples say
        // 6 % slower with p ≈ 0; by sessions, the states overlap and nothing can be called.
        let s = |m: f64, off: usize| series(20, m, 0.002, off);
        let base = vec![s(1.0, 0), s(1.0, 100), s(1.06, 200)];
        let new = vec![s(1.06, 300), s(1.06, 400), s(1.0, 500)];
        let flat = |v: &[Vec<f64>]| v.concat();
        assert_eq!(
            compare_samples(&flat(&base), &flat(&new), &o).verdict,
            Verdict::Slower
        );
        let c = compare_sessions(&base, &new, &o);
        assert_eq!(c.verdict, Verdict::Unsure, "{c:?}");
        assert!(c.ratio_ci.0 <= 1.0 && c.ratio_ci.1 >= 1.05, "{c:?}");
        assert!(c.why.contains("3 vs 3 sessions"), "{}", c.why);
        assert_eq!(c.p, None, "no sample-level p beside a session verdict");
        // Every session of NEW 1.5× slower: still SLOWER by sessions.
        let slow: Vec<Vec<f64>> = base
            .iter()
            .map(|v| v.iter().map(|x| x * 1.5).collect())
            .collect();
        let c = compare_sessions(&base, &slow, &o);
        assert_eq!(c.verdict, Verdict::Slower, "{c:?}");
        assert!(c.ratio_ci.0 > 1.0);
        // A run against itself: SAME, ratio exactly 1.
        let c = compare_sessions(&base, &base, &o);
        assert_eq!((c.verdict, c.ratio), (Verdict::Same, 1.0), "{c:?}");
        // One session a side: exactly compare_samples.
        assert_eq!(
            compare_sessions(&base[..1], &new[..1], &o),
            compare_samples(&base[0], &new[0], &o)
        );
    }

    #[test]
    fn summary_columns_decide_only_when_intervals_separate() {
        let o = VerdictOptions::default();
        let iv = |m: f64, w: f64| Interval {
            median: m,
            range: Some((m * (1.0 - w), m * (1.0 + w))),
            n: 10,
        };
        assert_eq!(
            compare_intervals(iv(1.0, 0.05), iv(1.0, 0.05), &o).verdict,
            Verdict::Same
        );
        let c = compare_intervals(iv(1.0, 0.05), iv(1.5, 0.05), &o);
        assert_eq!(c.verdict, Verdict::Slower, "{c:?}");
        assert_eq!((c.basis, c.p), (Basis::Summary, None));
        assert_eq!(
            compare_intervals(iv(1.5, 0.05), iv(1.0, 0.05), &o).verdict,
            Verdict::Faster
        );
        // Overlapping intervals: a 10 % shift cannot be called.
        assert_eq!(
            compare_intervals(iv(1.0, 0.2), iv(1.1, 0.2), &o).verdict,
            Verdict::Unsure
        );
        // Medians only.
        let bare = |m: f64| Interval {
            median: m,
            range: None,
            n: 3,
        };
        assert_eq!(
            compare_intervals(bare(1.0), bare(1.0), &o).verdict,
            Verdict::Same
        );
        assert_eq!(
            compare_intervals(bare(1.0), bare(1.5), &o).verdict,
            Verdict::Unsure
        );
    }

    #[test]
    fn two_frame_time_modes_are_found_and_one_is_not() {
        // 20 frames at 1.615 ms and 10 at 1.705 (the H200's compute A-buffer, quads(32) 1024²).
        let mut v = series(20, 1.615, 0.002, 0);
        v.extend(series(10, 1.705, 0.002, 50));
        let g = mode_gap(&v, MODE_MIN_FRAC, MODE_MIN_SEP).unwrap();
        assert!((g - 0.055).abs() < 0.005, "{g}");
        // One mode with ±1 % noise: no gap.
        let one = series(30, 1.0, 0.01, 0);
        assert_eq!(mode_gap(&one, MODE_MIN_FRAC, MODE_MIN_SEP), None);
        // A single outlier is not a mode (each mode needs a fifth of the samples).
        let mut out = series(29, 1.0, 0.001, 0);
        out.push(1.3);
        assert_eq!(mode_gap(&out, MODE_MIN_FRAC, MODE_MIN_SEP), None);
        assert_eq!(
            mode_gap(&v[..5], MODE_MIN_FRAC, MODE_MIN_SEP),
            None,
            "too few"
        );
    }

    #[test]
    fn a_change_within_a_mode_gap_is_held_back_and_one_beyond_it_is_not() {
        let a = series(30, 1.0, 0.002, 0);
        let b: Vec<f64> = a.iter().map(|x| x * 1.061).collect();
        let c = compare_samples(&a, &b, &VerdictOptions::default());
        assert_eq!(c.verdict, Verdict::Slower);
        let h = hold_back(c.clone(), 0.075, "BASE has two modes 5.5 % apart");
        assert_eq!(h.verdict, Verdict::Unsure, "{h:?}");
        assert!(h.why.contains("two modes"), "{}", h.why);
        assert_eq!(hold_back(c.clone(), 0.05, "x").verdict, Verdict::Slower);
        let same = compare_samples(&a, &a, &VerdictOptions::default());
        assert_eq!(hold_back(same, 0.5, "x").verdict, Verdict::Same);
    }

    /// Sessions of `n` frames in two modes (1.615 and 1.705 ms, the H200's compute A-buffer on
    /// quads(32) 1024²), `slow[i]` of session i's frames in the slow mode, all × `scale`.
    fn two_mode_sessions(n: usize, slow: &[usize], scale: f64, off: usize) -> Vec<Vec<f64>> {
        slow.iter()
            .enumerate()
            .map(|(s, &k)| {
                let mut v = series(n - k, 1.615 * scale, 0.002, off + 100 * s);
                v.extend(series(k, 1.705 * scale, 0.002, off + 100 * s + 50));
                v
            })
            .collect()
    }

    #[test]
    fn mode_matching_catches_a_five_percent_shift_whatever_the_mode_shares() {
        let o = VerdictOptions::default();
        // BASE mostly fast (10 of 50 slow frames per session), NEW ×1.05 mostly slow: pooled,
        // NEW's median is 11 % up, but its sessions disagree, and the mode mix explains it.
        let base = two_mode_sessions(50, &[10, 12, 40], 1.0, 0);
        let new = two_mode_sessions(50, &[40, 38, 12], 1.05, 1000);
        let m = compare_matched(&base, &new, &o);
        assert_eq!(m.matching, Matching::Modes, "{m:?}");
        assert_eq!(m.comparison.verdict, Verdict::Slower, "{m:?}");
        assert!((m.comparison.ratio - 1.05).abs() < 0.005, "{m:?}");
        assert!(
            m.comparison.why.contains("mode-matched"),
            "{}",
            m.comparison.why
        );
        // ×0.95: FASTER.
        let fast = two_mode_sessions(50, &[40, 38, 12], 0.95, 1000);
        assert_eq!(
            compare_matched(&base, &fast, &o).comparison.verdict,
            Verdict::Faster
        );
    }

    #[test]
    fn an_a_a_pair_whose_frames_flip_modes_is_not_called_slower() {
        let o = VerdictOptions::default();
        // One build twice: BASE's frames mostly in the fast mode, NEW's mostly in the slow.
        let base = two_mode_sessions(50, &[10, 12, 15], 1.0, 0);
        let new = two_mode_sessions(50, &[40, 38, 35], 1.0, 1000);
        // Sessions resampled: the pooled medians differ by the whole gap and every session
        // agrees, so that rule calls it SLOWER (what the fresh machine saw).
        let pooled = compare_sessions(&base, &new, &o);
        assert!(pooled.ratio > 1.05, "{pooled:?}");
        assert_eq!(pooled.verdict, Verdict::Slower, "{pooled:?}");
        let m = compare_matched(&base, &new, &o);
        assert_eq!(m.matching, Matching::Modes);
        assert_eq!(m.comparison.verdict, Verdict::Same, "{m:?}");
        assert!((m.comparison.ratio - 1.0).abs() < 0.005, "{m:?}");
        // NEW entirely in the slow mode (one mode): not matched mode with mode; the median
        // sessions differ by the gap, and the caller sees the modes it compared to hold it back.
        let all_slow = two_mode_sessions(50, &[50, 50, 50], 1.0, 1000);
        let m = compare_matched(&base, &all_slow, &o);
        assert_eq!(m.matching, Matching::MedianSession);
        assert!(m.base_modes.is_some() && m.new_modes.is_none(), "{m:?}");
    }

    #[test]
    fn the_median_session_is_not_moved_by_one_session_in_another_state() {
        let o = VerdictOptions::default();
        // Three tight sessions, BASE's second 9 % up (the H200's k-buffer at 1024², k = 16).
        let s = |m: f64, off: usize| series(10, m, 0.002, off);
        let base = vec![s(6.13, 0), s(6.75, 100), s(6.18, 200)];
        let new = vec![
            s(6.18 * 1.05, 300),
            s(6.18 * 1.05, 400),
            s(6.18 * 1.05, 500),
        ];
        // Sessions resampled: the odd session drawn twice in a quarter of the resamples.
        assert_eq!(compare_sessions(&base, &new, &o).verdict, Verdict::Unsure);
        let m = compare_matched(&base, &new, &o);
        assert_eq!(m.matching, Matching::MedianSession, "{m:?}");
        assert_eq!(m.comparison.verdict, Verdict::Slower, "{m:?}");
        assert!((m.comparison.ratio - 1.05).abs() < 0.005);
        // A/A: NEW's sessions all in the common state, or one of them in the odd one.
        for new in [
            vec![s(6.18, 300), s(6.17, 400), s(6.18, 500)],
            vec![s(6.18, 300), s(6.17, 400), s(6.75, 500)],
        ] {
            let m = compare_matched(&base, &new, &o);
            assert_eq!(m.comparison.verdict, Verdict::Same, "{m:?}");
        }
        // Even session counts: resampled as before.
        assert_eq!(
            compare_matched(&base[..2], &new[..2], &o).matching,
            Matching::Sessions
        );
        assert_eq!(median_session(&base).unwrap()[0], base[2][0]);
        // Median sessions too short for a test (4 samples, a 300 ms point): resampled.
        let short = |m: f64, off: usize| series(4, m, 0.0001, off);
        let (b3, n3) = (
            vec![short(1.0, 0), short(1.0, 10), short(1.0, 20)],
            vec![short(1.05, 30), short(1.05, 40), short(1.05, 50)],
        );
        let m = compare_matched(&b3, &n3, &o);
        assert_eq!(m.matching, Matching::Sessions);
        assert_eq!(m.comparison.verdict, Verdict::Slower, "{m:?}");
    }

    #[test]
    fn cycles_remove_a_clock_change() {
        // NEW ran at 2/3 of the clock and took 1.5× as long: slower in time, same in cycles.
        let t = series(20, 1.0, 0.01, 0);
        let slow: Vec<f64> = t.iter().map(|x| x * 1.5).collect();
        let o = VerdictOptions::default();
        assert_eq!(compare_samples(&t, &slow, &o).verdict, Verdict::Slower);
        let cb = cycles_k(&t, &vec![Some(1980.0); 20]).unwrap();
        let cn = cycles_k(&slow, &vec![Some(1320.0); 20]).unwrap();
        assert_eq!(compare_samples(&cb, &cn, &o).verdict, Verdict::Same);
        assert!(cycles_k(&t, &vec![None; 20]).is_none());
        assert!(cycles_k(&t, &[Some(1.0)]).is_none());
    }
}
