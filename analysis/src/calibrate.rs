//! A/A calibration (`mfx calibrate RUN1 RUN2 [RUN3…]`): two or more runs of one build on one
//! kind of GPU, compared pair by pair with the fixed band, say how often that band raises a
//! false alarm (every FASTER / SLOWER between runs of one build is one), per method family;
//! and how far each point's median moves between runs of one build: its **band**, the
//! largest `|ratio − 1|` over all pairs (times `margin`), never below the floor. A class band
//! (method × scene kind: the largest of its points') covers points the runs did not hold.
//! `mfx compare --band-from FILE` judges each point against its band and prints it.
//!
//! Why per point: on the H200 the medians of 214 of 220 `methods` points stay within 1 % of
//! their twin in another run, while the compute A-buffer's quads(32) points move by up to 5 %
//! (two frame-time modes) and the RMW k-buffer on grass(200000) by 4 % (session states): one
//! band for all either calls those changes or hides a 5 % change everywhere.
//!
//! Session states: each `[timing] sessions` session is prepared afresh and lands in one memory
//! state (on the H200 the RMW k-buffer on grass(200000) at 1024² sits in states 4–7 % apart, and
//! in one run all three sessions sat in a state that another run visited once). A handful of
//! A/A runs may never see such a point's median session change state, so its band is also never
//! below its typical state spread: the median over the runs of max/min − 1 of its session
//! medians (points whose sessions alternate between two frame-time modes within themselves are
//! left out: the compare matches their modes).
//!
//! The drift under load: the canary's ratio to its fastest run climbs from ~1.05 to ~1.08 over
//! the first minute of every committed H200 run, in every run alike, so in runs of one suite
//! (the same point order) each point meets the same drift and it cancels. Dividing each sample
//! by its canary ratio was tried on the four committed `methods` runs with three sessions: it
//! made the medians of A/A pairs agree *less* (median |ln ratio| 0.07 % → 0.2–0.7 %), since the
//! canary (a compute kernel reading 16 MiB) is not slowed the way a raster point is. So the
//! drift is reported per run ([`Drift`]), not divided out.

use std::path::{Path, PathBuf};

use std::collections::BTreeMap;

use anyhow::{bail, Context, Result};
use mfx_stats::Verdict;

use crate::ab::{compare_runs, load_side, AbOptions};
use crate::bands::median;
pub use crate::bands::*;

/// The canary drift of one run folder (None where its samples have no canary column).
fn drift(run: &Path) -> Result<Drift> {
    let (_, _, samples) = load_side(run)?;
    let all: Vec<(f64, f64)> = samples
        .iter()
        .flat_map(|m| m.values())
        .flat_map(|p| p.canary.iter().copied())
        .collect();
    let t0 = all.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
    let pick = |f: &dyn Fn(f64) -> bool| {
        median(
            all.iter()
                .filter(|(_, t)| f(t - t0))
                .map(|(r, _)| *r)
                .collect(),
        )
    };
    Ok(Drift {
        run: run.display().to_string(),
        canary_first_15s: pick(&|dt| dt < 15_000.0),
        canary_after_60s: pick(&|dt| dt >= 60_000.0),
    })
}

/// Calibrates from two or more A/A runs (see the module notes). `opts.verdict.noise_band` is
/// the floor; `opts.calibration` and `opts.scale_new` are ignored.
pub fn calibrate(runs: &[PathBuf], opts: &AbOptions, margin: f64) -> Result<Calibration> {
    if runs.len() < 2 {
        bail!(
            "mfx calibrate needs two or more runs of one build (got {})",
            runs.len()
        );
    }
    if !(margin.is_finite() && margin >= 1.0) {
        bail!("margin {margin} must be 1 or more");
    }
    let opts = AbOptions {
        calibration: None,
        scale_new: 1.0,
        ..opts.clone()
    };
    let floor = opts.verdict.noise_band;
    let mut moved: BTreeMap<String, f64> = BTreeMap::new();
    let mut false_alarms: BTreeMap<String, Alarms> = BTreeMap::new();
    for (i, a) in runs.iter().enumerate() {
        for b in &runs[i + 1..] {
            let rep = compare_runs(a, b, &opts)
                .with_context(|| format!("comparing {} with {}", a.display(), b.display()))?;
            for p in &rep.points {
                let al = false_alarms
                    .entry(family_of(&p.key).to_string())
                    .or_default();
                al.compared += 1;
                match p.time.verdict {
                    Verdict::Same => al.same += 1,
                    Verdict::Faster => al.faster += 1,
                    Verdict::Slower => al.slower += 1,
                    Verdict::Unsure => al.unsure += 1,
                }
                if p.time.ratio.is_finite() && p.time.ratio > 0.0 {
                    let d = p.time.ratio.ln().abs();
                    let e = moved.entry(p.key.clone()).or_insert(0.0);
                    *e = e.max(d);
                }
            }
        }
    }
    // Session states: a point whose sessions, in the typical run (the median over the runs),
    // sit x apart can show its median session in any of those states in the next run, whether
    // or not these runs happened to: its band is at least x.
    let mut spreads: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for r in runs {
        let (_, _, samples) = load_side(r)?;
        for ((_, key), p) in samples.iter().flatten() {
            if let Some(x) = p.state_spread() {
                spreads.entry(key.clone()).or_default().push(x);
            }
        }
    }
    let typical = |k: &str| {
        spreads
            .get(k)
            .filter(|v| v.len() == runs.len())
            .and_then(|v| median(v.clone()))
            .unwrap_or(0.0)
    };
    let points: BTreeMap<String, f64> = moved
        .into_iter()
        .map(|(k, d)| {
            let b = floor.max(margin * d.exp_m1()).max(typical(&k));
            (k, b)
        })
        .collect();
    let mut classes: BTreeMap<String, f64> = BTreeMap::new();
    for (k, b) in &points {
        let e = classes.entry(class_of(k)).or_insert(floor);
        *e = e.max(*b);
    }
    Ok(Calibration {
        format: FORMAT.into(),
        runs: runs.iter().map(|p| p.display().to_string()).collect(),
        floor,
        margin,
        points,
        classes,
        false_alarms,
        drift: runs.iter().map(|r| drift(r)).collect::<Result<_>>()?,
    })
}

#[cfg(test)]
mod tests {
    //! The verdict rule on the committed H200 A/A runs: bands calibrated on one day's runs judge
    //! the other day's pairs, both directions, as they are (A/A) and scaled ×1.05 / ×0.95.
    use super::*;
    use crate::ab::{compare_runs, AbOptions};

    const REPEAT: [(&str, &str); 3] = [
        ("a", "2026-12-03-h200-repeat/start1/methods-a"),
        ("b", "2026-12-03-h200-repeat/start1/methods-b"),
        ("c", "2026-12-03-h200-repeat/start2/methods-c"),
    ];
    const SESSIONS: [(&str, &str); 4] = [
        ("s3a", "2026-12-02-h200-sessions/call1/methods-s3a"),
        ("s3b", "2026-12-02-h200-sessions/call1/methods-s3b"),
        ("s3c", "2026-12-02-h200-sessions/call2/methods-s3c"),
        ("s3d", "2026-12-02-h200-sessions/call2/methods-s3d"),
    ];

    fn path(p: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../results/reference")
            .join(p)
    }

    fn opts(cal: Option<&Calibration>, scale: f64, resamples: usize) -> AbOptions {
        let mut o = AbOptions::default();
        o.verdict.resamples = resamples;
        o.calibration = cal.cloned();
        o.scale_new = scale;
        o
    }

    /// Every ordered pair of `runs` at ×1, ×1.05 and ×0.95: a Markdown table, and each row's
    /// (pair, scale, SAME, FASTER, SLOWER, UNSURE, points).
    #[allow(
        clippy::type_complexity,
        reason = "the table's text and its rows, one tuple per printed column"
    )]
    fn table(
        runs: &[(&str, &str)],
        cal: Option<&Calibration>,
        resamples: usize,
    ) -> (String, Vec<(String, f64, [usize; 5])>) {
        let mut rows = Vec::new();
        let mut md = String::from(
            "| pair | NEW × | SAME | FASTER | SLOWER | UNSURE | of |\n|---|---:|---:|---:|---:|---:|---:|\n",
        );
        for scale in [1.0, 1.05, 0.95] {
            for (i, (na, pa)) in runs.iter().enumerate() {
                for (j, (nb, pb)) in runs.iter().enumerate() {
                    if i == j {
                        continue;
                    }
                    let r =
                        compare_runs(&path(pa), &path(pb), &opts(cal, scale, resamples)).unwrap();
                    let c = r.counts();
                    let v = [
                        c[&Verdict::Same],
                        c[&Verdict::Faster],
                        c[&Verdict::Slower],
                        c[&Verdict::Unsure],
                        r.points.len(),
                    ];
                    md.push_str(&format!(
                        "| {na} → {nb} | {scale} | {} | {} | {} | {} | {} |\n",
                        v[0], v[1], v[2], v[3], v[4]
                    ));
                    for p in r.points.iter().filter(|p| {
                        scale == 1.0 && matches!(p.time.verdict, Verdict::Faster | Verdict::Slower)
                    }) {
                        println!(
                            "{na} → {nb} {}: {} {:.3} {:?} {}",
                            p.key, p.time.verdict, p.time.ratio, p.time.ratio_ci, p.time.why
                        );
                    }
                    rows.push((format!("{na} → {nb}"), scale, v));
                }
            }
        }
        (md, rows)
    }

    fn check(rows: &[(String, f64, [usize; 5])]) {
        for (pair, scale, [same, faster, slower, _, n]) in rows {
            let at = |k: usize| k as f64 / *n as f64 >= 0.95;
            if *scale == 1.0 {
                assert_eq!((faster, slower), (&0, &0), "{pair}: A/A false alarms");
                assert!(at(*same), "{pair}: SAME {same} of {n}");
            } else if *scale > 1.0 {
                assert_eq!(*faster, 0, "{pair} ×{scale}");
                assert!(at(*slower), "{pair} ×{scale}: SLOWER {slower} of {n}");
            } else {
                assert_eq!(*slower, 0, "{pair} ×{scale}");
                assert!(at(*faster), "{pair} ×{scale}: FASTER {faster} of {n}");
            }
        }
    }

    fn runs(v: &[(&str, &str)]) -> Vec<PathBuf> {
        v.iter().map(|(_, p)| path(p)).collect()
    }

    #[test]
    fn bands_from_one_day_judge_the_other_days_pairs_both_ways() {
        let resamples = 300;
        let o = opts(None, 1.0, resamples);
        let dec02 = calibrate(&runs(&SESSIONS), &o, 1.0).unwrap();
        let (md, rows) = table(&REPEAT, Some(&dec02), resamples);
        println!("2026-12-03 pairs, bands from 2026-12-02:\n{md}");
        check(&rows);
        let dec03 = calibrate(&runs(&REPEAT), &o, 1.0).unwrap();
        let (md, rows) = table(&SESSIONS, Some(&dec03), resamples);
        println!("2026-12-02 pairs, bands from 2026-12-03:\n{md}");
        check(&rows);
    }

    /// The tables for RUN.md (default resamples, fixed band and calibrated):
    /// `cargo test -p mfx-analysis --lib verdict_tables -- --ignored --nocapture`. The
    /// calibration's own Markdown is what `mfx calibrate` prints (`report::ab`).
    #[test]
    #[ignore]
    fn verdict_tables() {
        let o = opts(None, 1.0, AbOptions::default().verdict.resamples);
        let r = o.verdict.resamples;
        let dec02 = calibrate(&runs(&SESSIONS), &o, 1.0).unwrap();
        let dec03 = calibrate(&runs(&REPEAT), &o, 1.0).unwrap();
        println!(
            "false alarms per family at the fixed band (2026-12-02 pairs): {:#?}",
            dec02.false_alarms
        );
        println!("## 2026-12-03, fixed band\n{}", table(&REPEAT, None, r).0);
        println!(
            "## 2026-12-03, bands from 2026-12-02\n{}",
            table(&REPEAT, Some(&dec02), r).0
        );
        println!("## 2026-12-02, fixed band\n{}", table(&SESSIONS, None, r).0);
        println!(
            "## 2026-12-02, bands from 2026-12-03\n{}",
            table(&SESSIONS, Some(&dec03), r).0
        );
    }
}
