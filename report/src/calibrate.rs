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
    let points: BTreeMap<String, f64> = moved
        .into_iter()
        .map(|(k, d)| (k, floor.max(margin * d.exp_m1())))
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
