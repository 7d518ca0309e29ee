//! How cost grows (the `scaling` suite): per method and per sweep — a scene at several
//! resolutions (fragments ∝ pixels at constant geometry), or a family of scenes at one resolution
//! that differ in one parameter (tessellation at constant fragments, depth complexity) — a
//! least-squares fit of GPU time on log-log axes against the variable the sweep moves most
//! (true fragments F or triangles T), its R², the local exponents between neighbouring points,
//! and the rows that leave the linear regime: a local exponent over [`OFF_FIT`] (a bend:
//! occupancy, a cache, the geometry cost taking over), failed or skipped rows (memory, adapter
//! limits) and `overflow` rows (sort capacity). Charts of time against F and against T, those
//! rows hollow. Drawn for runs of a suite named `scaling`: a mix of unrelated scenes (the
//! `methods` suite) has no single law to fit.

use schema::StudyKind;
use schema::{cols, Flag};
use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;

use crate::cells::short;
use crate::charts::{Figure, Pt, Series, XY};
use crate::labels::{parse_scene, scene_name};
use crate::studies::methods::scene_families;
use mfx_analysis::data::{Rec, Runs};

/// A local exponent above this (time growing faster than x^1.5) leaves the linear regime.
pub const OFF_FIT: f64 = 1.5;

/// A fit of log t on log-x variables.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// Intercept, then one exponent per variable.
    pub coef: Vec<f64>,
    pub r2: f64,
    pub n: usize,
}

impl Fit {
    /// The fitted time at the given variables (not logs).
    pub fn predict(&self, x: &[f64]) -> f64 {
        let l: f64 = self.coef[0]
            + self.coef[1..]
                .iter()
                .zip(x)
                .map(|(c, v)| c * v.ln())
                .sum::<f64>();
        l.exp()
    }
}

/// Ordinary least squares of ln y on (1, ln x₁, …, ln x_k) through the normal equations;
/// `None` with fewer points than coefficients + 1, a non-positive value, or a singular system
/// (a variable that does not vary).
pub fn fit_loglog(xs: &[Vec<f64>], ys: &[f64]) -> Option<Fit> {
    let k = xs.first()?.len() + 1;
    let n = ys.len();
    if n != xs.len() || n < k + 1 {
        return None;
    }
    if ys
        .iter()
        .chain(xs.iter().flatten())
        .any(|&v| v.is_nan() || v <= 0.0)
    {
        return None;
    }
    let rows: Vec<Vec<f64>> = xs
        .iter()
        .map(|x| {
            std::iter::once(1.0)
                .chain(x.iter().map(|v| v.ln()))
                .collect()
        })
        .collect();
    let ly: Vec<f64> = ys.iter().map(|y| y.ln()).collect();
    // A = XᵀX | Xᵀy, solved by Gaussian elimination with partial pivoting.
    let mut a = vec![vec![0.0; k + 1]; k];
    for (r, y) in rows.iter().zip(&ly) {
        for i in 0..k {
            for j in 0..k {
                a[i][j] += r[i] * r[j];
            }
            a[i][k] += r[i] * y;
        }
    }
    for c in 0..k {
        let p = (c..k).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[p][c].abs() < 1e-9 * (1.0 + a[c][c].abs()) {
            return None;
        }
        a.swap(c, p);
        let pivot = a[c].clone();
        for (i, row) in a.iter_mut().enumerate() {
            if i != c {
                let f = row[c] / pivot[c];
                for (x, p) in row.iter_mut().zip(&pivot).skip(c) {
                    *x -= f * p;
                }
            }
        }
    }
    let coef: Vec<f64> = (0..k).map(|i| a[i][k] / a[i][i]).collect();
    let mean = ly.iter().sum::<f64>() / n as f64;
    let (mut ss_res, mut ss_tot) = (0.0, 0.0);
    for (r, y) in rows.iter().zip(&ly) {
        let p: f64 = r.iter().zip(&coef).map(|(x, c)| x * c).sum();
        ss_res += (y - p).powi(2);
        ss_tot += (y - mean).powi(2);
    }
    let r2 = if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else {
        1.0
    };
    Some(Fit { coef, r2, n })
}

/// (true fragments, triangles, GPU ms) of a row; fragments from `frags` (floors have none).
fn f_t(r: &Rec, frags: &BTreeMap<String, f64>) -> Option<(f64, f64, f64)> {
    Some((
        r.f(cols::TRUE_FRAGMENTS)
            .or_else(|| frags.get(&scene_res(r)).copied())?,
        r.f(cols::TRIANGLES)?,
        r.trusted_ms()?,
    ))
}

fn scene_res(r: &Rec) -> String {
    format!(
        "{}|{}x{}",
        r.get(cols::SCENE_LABEL),
        r.get(cols::WIDTH),
        r.get(cols::HEIGHT)
    )
}

/// Whether the runs are a `scaling` suite's.
pub fn applies(runs: &Runs) -> bool {
    // A fit needs at least two scene × resolution places: a run filtered to one point (the 4K
    // study alone) has nothing to fit, and its rows read on the methods pages.
    let places: std::collections::BTreeSet<String> = runs
        .rows
        .iter()
        .filter(|r| {
            r.get(cols::SUITE) == "scaling" && r.get(cols::STUDY) == StudyKind::Methods.name()
        })
        .map(scene_res)
        .collect();
    places.len() >= 2
}

/// One sweep of a method: rows where one of F or T varies (a scene at several resolutions, or a
/// family of scenes at one resolution), fitted against the one that varies more.
struct Sweep<'a> {
    name: String,
    rows: Vec<&'a Rec>,
}

fn sweeps<'a>(rows: &[&'a Rec]) -> Vec<Sweep<'a>> {
    let mut out = Vec::new();
    // A scene at several resolutions: fragments ∝ pixels at constant geometry.
    for (label, g) in Runs::group_by(rows.iter().copied(), |r| r.get(cols::SCENE_LABEL).into()) {
        if Runs::distinct(g.iter().copied(), cols::WIDTH).len() >= 3 {
            out.push(Sweep {
                name: format!("resolution, {}", scene_name(&label)),
                rows: g,
            });
        }
    }
    // A family of scenes at one resolution (one parameter swept).
    for (res, g) in Runs::group_by(rows.iter().copied(), |r| {
        format!("{}×{}", r.get(cols::WIDTH), r.get(cols::HEIGHT))
    }) {
        let labels = Runs::distinct(g.iter().copied(), cols::SCENE_LABEL);
        for (family, scenes) in scene_families(&labels) {
            if scenes.len() < 3 {
                continue;
            }
            out.push(Sweep {
                name: format!("{family}, {res}"),
                rows: g
                    .iter()
                    .copied()
                    .filter(|r| scenes.iter().any(|s| s == r.get(cols::SCENE_LABEL)))
                    .collect(),
            });
        }
    }
    // Scenes of one generator at one resolution with about the same triangle count (within
    // ±25 % of their median) but fragments spread at least 4×: depth complexity at constant
    // geometry (nested shells: count up, tessellation down).
    for (key, g) in Runs::group_by(rows.iter().copied(), |r| {
        format!(
            "{}|{}×{}",
            parse_scene(r.get(cols::SCENE_LABEL)).0,
            r.get(cols::WIDTH),
            r.get(cols::HEIGHT)
        )
    }) {
        let mut tris: Vec<f64> = g.iter().filter_map(|r| r.f(cols::TRIANGLES)).collect();
        if tris.is_empty() {
            continue;
        }
        tris.sort_by(f64::total_cmp);
        let mid = tris[tris.len() / 2];
        let near: Vec<&Rec> = g
            .iter()
            .copied()
            .filter(|r| {
                r.f(cols::TRIANGLES)
                    .is_some_and(|t| (t / mid - 1.0).abs() <= 0.25)
            })
            .collect();
        let scenes = Runs::distinct(near.iter().copied(), cols::SCENE_LABEL);
        let f: Vec<f64> = near
            .iter()
            .filter_map(|r| r.f(cols::TRUE_FRAGMENTS))
            .collect();
        let (lo, hi) = f
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        if scenes.len() >= 3 && hi >= 4.0 * lo {
            let (gen, res) = key.split_once('|').unwrap_or((&key, ""));
            let set: Vec<&str> = scenes.iter().map(|s| s.as_str()).collect();
            // Not again if a family above already holds exactly these scenes.
            if !out.iter().any(|s: &Sweep| {
                let mut a = Runs::distinct(s.rows.iter().copied(), cols::SCENE_LABEL);
                a.sort();
                let mut b: Vec<String> = set.iter().map(|s| s.to_string()).collect();
                b.sort();
                a == b
            }) {
                out.push(Sweep {
                    name: format!(
                        "{gen}, depth complexity at ≈ {} triangles, {res}",
                        short(Some(mid))
                    ),
                    rows: near,
                });
            }
        }
    }
    out
}

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let rows: Vec<&Rec> = runs
        .study(StudyKind::Methods)
        .into_iter()
        .filter(|r| r.get(cols::SUITE) == "scaling")
        .collect();
    let frags: BTreeMap<String, f64> = rows
        .iter()
        .filter_map(|r| Some((scene_res(r), r.f(cols::TRUE_FRAGMENTS)?)))
        .collect();
    let methods = Runs::distinct(rows.iter().copied(), cols::METHOD);
    // One line of the fits table per method and sweep.
    let mut lines: Vec<[String; 9]> = Vec::new();
    // Rows out of the linear regime, by (method, scene, resolution): hollow in the charts.
    let mut off_rows: std::collections::BTreeSet<String> = Default::default();
    let row_key = |r: &Rec| format!("{}|{}", r.get(cols::METHOD), scene_res(r));
    for m in &methods {
        let mine: Vec<&Rec> = rows
            .iter()
            .copied()
            .filter(|r| r.get(cols::METHOD) == m)
            .collect();
        for sw in sweeps(&mine) {
            let mut timed: Vec<(&Rec, (f64, f64, f64))> = sw
                .rows
                .iter()
                .filter(|r| r.ok())
                .filter_map(|r| Some((*r, f_t(r, &frags)?)))
                .collect();
            let span = |k: fn(&(f64, f64, f64)) -> f64| {
                timed
                    .iter()
                    .map(|(_, v)| k(v))
                    .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)))
            };
            let (fl, fh) = span(|v| v.0);
            let (tl, th) = span(|v| v.1);
            let by_t = (th / tl) > (fh / fl);
            let x = move |v: &(f64, f64, f64)| if by_t { v.1 } else { v.0 };
            timed.sort_by(|a, b| x(&a.1).total_cmp(&x(&b.1)));
            let fit = fit_loglog(
                &timed.iter().map(|(_, v)| vec![x(v)]).collect::<Vec<_>>(),
                &timed.iter().map(|(_, v)| v.2).collect::<Vec<_>>(),
            );
            // Local exponents between neighbours (distinct x only).
            let mut local = Vec::new();
            let mut out = Vec::new();
            for w in timed.windows(2) {
                let (a, b) = (&w[0].1, &w[1].1);
                if x(b) > x(a) * 1.05 {
                    let e = (b.2 / a.2).ln() / (x(b) / x(a)).ln();
                    local.push(format!("{e:.2}"));
                    // Superlinear growth between these two points: the method has left its
                    // linear regime by the second.
                    if e > OFF_FIT {
                        out.push(format!(
                            "{}: local exponent {e:.2}",
                            scene_name(w[1].0.get(cols::SCENE_LABEL))
                        ));
                        off_rows.insert(row_key(w[1].0));
                    }
                }
            }
            for r in &sw.rows {
                let why = if !r.ok() {
                    Some(format!("{} ({})", r.get(cols::STATUS), r.get(cols::REASON)))
                } else if r.flag_set().contains(Flag::Overflow) {
                    Some(Flag::Overflow.to_string())
                } else {
                    None
                };
                if let Some(w) = why {
                    out.push(format!(
                        "{} {}×{}: {w}",
                        scene_name(r.get(cols::SCENE_LABEL)),
                        r.get(cols::WIDTH),
                        r.get(cols::HEIGHT)
                    ));
                    off_rows.insert(row_key(r));
                }
            }
            let (lo, hi) = if by_t { (tl, th) } else { (fl, fh) };
            lines.push([
                m.clone(),
                sw.name.clone(),
                if by_t { "triangles" } else { "true fragments" }.into(),
                format!("{}–{}", short(Some(lo)), short(Some(hi))),
                timed.len().to_string(),
                fit.as_ref()
                    .map_or("—".into(), |f| format!("{:.2}", f.coef[1])),
                fit.as_ref().map_or("—".into(), |f| format!("{:.3}", f.r2)),
                local.join(", "),
                if out.is_empty() {
                    "none".to_string()
                } else {
                    out.join("; ")
                },
            ]);
        }
    }
    let table = maud::html! {
        table {
            tr {
                th { "method" } th { "sweep" } th { "x" } th { "x range" } th { "timed rows" }
                th { "exponent" } th { "R²" } th { "local exponents (point to point)" }
                th { "out of the linear regime" }
            }
            @for l in &lines { tr { @for c in l { td { (c) } } } }
        }
    };
    let mut by_f = Vec::new();
    let mut by_t = Vec::new();
    for (mi, m) in methods.iter().enumerate() {
        let pts = |k: fn(&(f64, f64, f64)) -> f64| -> Vec<Pt> {
            let mut v: Vec<Pt> = rows
                .iter()
                .filter(|r| r.get(cols::METHOD) == m && r.ok())
                .filter_map(|r| {
                    let v = f_t(r, &frags)?;
                    let (lo, hi) = r.gpu_ci().unzip();
                    let off = off_rows.contains(&row_key(r));
                    Some(Pt::spread(k(&v), v.2, lo, hi).flagged(off))
                })
                .collect();
            v.sort_by(|a, b| a.x.total_cmp(&b.x));
            v
        };
        let series = |points: Vec<Pt>| Series {
            name: m.clone(),
            family: mi,
            color: Some(mi),
            points,
        };
        by_f.push(series(pts(|v| v.0)));
        by_t.push(series(pts(|v| v.1)));
    }
    let mut figs = vec![Figure::html(
        "How cost grows: exponents of GPU time per sweep",
        maud::html! {
            p {
                "Per method and sweep (a scene at several resolutions: fragments ∝ pixels at \
                 constant geometry; a family of scenes at one resolution that differ in one \
                 parameter: tessellation at constant fragments, or depth complexity), a \
                 least-squares fit of ln(GPU ms) against ln x, x the variable the sweep moves \
                 most (triangles or true fragments; floors take the scene's fragments). 1 is \
                 linear. The local exponents between neighbouring points show where growth \
                 bends. Out of the linear regime: a local exponent over " (OFF_FIT) " (the point \
                 it reaches is named), and failed, skipped or overflowing rows (memory, adapter \
                 limits, sort capacity); they are drawn hollow below."
            }
            (table)
        },
    )];
    for (series, x_label, stem, what) in [
        (by_f, "true fragments", "scaling_time_vs_fragments", "F"),
        (by_t, "triangles", "scaling_time_vs_triangles", "T"),
    ] {
        if series.iter().all(|s| s.points.is_empty()) {
            continue;
        }
        let xy = XY {
            title: format!("GPU time vs {x_label}"),
            x_label: x_label.into(),
            y_label: "GPU time per frame [ms]".into(),
            log_x: true,
            log_y: true,
            lines: false,
            series,
            ..Default::default()
        };
        figs.push(xy.draw(
            dir,
            stem,
            &format!(
                "Every timed ok row of the scaling suite, one colour per method, log-log. Points at \
                 one {what} are the other sweeps. Hollow: out of the linear regime (see the table). \
                 Whiskers: 95 % bootstrap CI of the median."
            ),
        )?);
    }
    Ok(figs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_scene_at_one_resolution_has_no_scaling_page() {
        let rec = |scene: &str, w: &str| {
            let mut r = Rec::default();
            for (k, v) in [
                (cols::SUITE, "scaling"),
                (cols::STUDY, "methods"),
                (cols::SCENE_LABEL, scene),
                (cols::WIDTH, w),
                (cols::HEIGHT, w),
            ] {
                r.set(k, v);
            }
            r
        };
        let one = Runs {
            rows: vec![rec("shells(count=8,segments=354)", "3840")],
            ..Default::default()
        };
        assert!(!applies(&one));
        let two = Runs {
            rows: vec![
                rec("shells(count=8,segments=354)", "512"),
                rec("shells(count=8,segments=354)", "1024"),
            ],
            ..Default::default()
        };
        assert!(applies(&two));
    }

    #[test]
    fn a_power_law_is_fitted_exactly_and_a_constant_variable_is_refused() {
        // t = 2e-3 · F^1.0 · T^0.5 on a grid.
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        for f in [1e5, 1e6, 1e7] {
            for t in [1e4f64, 1e5, 1e6] {
                xs.push(vec![f, t]);
                ys.push(2e-3 * f * t.sqrt());
            }
        }
        let fit = fit_loglog(&xs, &ys).unwrap();
        assert!((fit.coef[1] - 1.0).abs() < 1e-9, "{fit:?}");
        assert!((fit.coef[2] - 0.5).abs() < 1e-9, "{fit:?}");
        assert!((fit.r2 - 1.0).abs() < 1e-12);
        assert!((fit.predict(&[1e6, 1e4]) - 2e-3 * 1e6 * 1e2).abs() < 1e-6);
        // T constant: the joint system is singular; F alone still fits.
        let xs2: Vec<Vec<f64>> = [1e5, 1e6, 1e7, 1e8].iter().map(|&f| vec![f, 7.0]).collect();
        let ys2: Vec<f64> = [1e5f64, 1e6, 1e7, 1e8]
            .iter()
            .map(|f| f.powf(0.8))
            .collect();
        assert!(fit_loglog(&xs2, &ys2).is_none());
        let one: Vec<Vec<f64>> = xs2.iter().map(|x| vec![x[0]]).collect();
        assert!((fit_loglog(&one, &ys2).unwrap().coef[1] - 0.8).abs() < 1e-9);
        // Too few points, or a non-positive time.
        assert!(fit_loglog(&one[..2], &ys2[..2]).is_none());
        assert!(fit_loglog(&one, &[1.0, 0.0, 1.0, 1.0]).is_none());
    }
}
