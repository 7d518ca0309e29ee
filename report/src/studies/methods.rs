//! Figures of the `methods` study. Per scene and resolution: error vs GPU time as a Pareto front
//! (RMSE vs the ground truth by default; FLIP mean as a second front when the CSV has it), error
//! vs memory, time vs memory, and a table of every configuration. Across scenes: GPU time vs
//! depth complexity (one chart per family of scenes that differ in one parameter), the hazard,
//! overflow and collision rates, the speedup over classic depth peeling and the multiple of the
//! depth-only floor.

use schema::cols;
use schema::StudyKind;
use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;
use maud::{html, Markup};

use crate::cells::{exact_cell, short, time_cell};
use crate::charts::{Bars, Figure, Named, Pt, Series, MARKERS, XY};
use crate::labels::{config_key, file_safe, parse_scene, scene_name, scene_names, ConfigLabels};
use crate::pareto;
use crate::points::{ci_caption_rows, time_pt};
use mfx_analysis::data::{resolution, Rec, Runs};

/// Colour (configuration) and marker (method family) of every configuration of a set of rows,
/// fixed across a report's charts so a configuration looks the same everywhere.
#[derive(Clone, Debug, Default)]
pub struct Styles {
    colors: BTreeMap<String, usize>,
    families: BTreeMap<String, usize>,
}

impl Styles {
    /// Every configuration gets its own (colour, marker) pair from the declared tables
    /// (`charts::PALETTE` × the markers): the marker names the method, the colour is the next
    /// one not yet drawn with that marker, so two series look alike only past 32 configurations
    /// of the same marker.
    pub fn new<'a>(rows: impl IntoIterator<Item = &'a Rec>) -> Styles {
        let mut s = Styles::default();
        let mut next: BTreeMap<usize, usize> = BTreeMap::new();
        for r in rows {
            let n = s.families.len();
            let fam = *s
                .families
                .entry(r.get(cols::METHOD).to_string())
                .or_insert(n);
            let key = config_key(r);
            if let std::collections::btree_map::Entry::Vacant(e) = s.colors.entry(key) {
                // Each marker starts at its first method's own colour, so one-configuration
                // methods still differ in colour as well as marker.
                let c = next.entry(fam % MARKERS).or_insert(fam);
                e.insert(*c);
                *c += 1;
            }
        }
        s
    }
    pub fn color(&self, r: &Rec) -> usize {
        self.colors.get(&config_key(r)).copied().unwrap_or(0)
    }
    pub fn family(&self, r: &Rec) -> usize {
        self.families.get(r.get(cols::METHOD)).copied().unwrap_or(0)
    }
}

/// One series per configuration (named by `labels`), styled by `styles`, points sorted by x.
pub fn config_series(
    rows: &[&Rec],
    labels: &ConfigLabels,
    styles: &Styles,
    pt: impl Fn(&Rec) -> Option<Pt>,
) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for r in rows {
        let Some(p) = pt(r) else { continue };
        let name = labels.get(r);
        match out.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(p),
            None => out.push(Series {
                name,
                family: styles.family(r),
                color: Some(styles.color(r)),
                points: vec![p],
            }),
        }
    }
    for s in &mut out {
        s.points.sort_by(|a, b| a.x.total_cmp(&b.x));
    }
    out
}

/// The rows of one scene at one resolution whose front is drawn; the front's members by key.
struct Fronts {
    time: Vec<String>,
    memory: Vec<String>,
}

/// The non-dominated rows of `rows` for (x, y) = `xy(r)`.
fn front_of(rows: &[&Rec], xy: impl Fn(&Rec) -> Option<(f64, f64)>) -> Vec<usize> {
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| xy(r).unwrap_or((f64::NAN, f64::NAN)))
        .collect();
    pareto::front(&pts)
}

fn named(
    rows: &[&Rec],
    idx: &[usize],
    labels: &ConfigLabels,
    xy: impl Fn(&Rec) -> Option<(f64, f64)>,
) -> Vec<Named> {
    idx.iter()
        .filter_map(|&i| {
            let (x, y) = xy(rows[i])?;
            Some(Named {
                x,
                y,
                text: labels.get(rows[i]),
            })
        })
        .collect()
}

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let all: Vec<&Rec> = runs
        .study(StudyKind::Methods)
        .into_iter()
        .filter(|r| r.ok())
        .collect();
    let methods: Vec<&Rec> = all.iter().copied().filter(|r| !r.is_floor()).collect();
    let styles = Styles::new(methods.iter().copied());
    let mut figs = Vec::new();
    for (res, at_res) in Runs::group_by(methods.iter().copied(), resolution) {
        // Errors of different effects are different quantities: one front per scene and effect.
        let effects = Runs::distinct(at_res.iter().copied(), cols::EFFECT).len() > 1;
        for (key, g) in Runs::group_by(at_res.iter().copied(), |r| {
            let e = if effects { r.get(cols::EFFECT) } else { "" };
            format!("{}\u{0}{e}", r.get(cols::SCENE_LABEL))
        }) {
            let (label, effect) = key.split_once('\u{0}').unwrap_or((&key, ""));
            let floors: Vec<&Rec> = all
                .iter()
                .copied()
                .filter(|r| {
                    r.is_floor() && r.get(cols::SCENE_LABEL) == label && resolution(r) == res
                })
                .collect();
            scene_figures(
                runs, label, effect, &res, &g, &floors, &styles, dir, &mut figs,
            )?;
        }
        time_vs_complexity(&at_res, &res, &styles, dir, &mut figs)?;
        rates(&at_res, &res, &styles, dir, &mut figs)?;
        ratio_bars(&at_res, &res, dir, &mut figs)?;
    }
    Ok(figs)
}

#[allow(
    clippy::too_many_arguments,
    reason = "one scene's figures: its rows, floors, labels, styles and output folder"
)]
fn scene_figures(
    runs: &Runs,
    label: &str,
    effect: &str,
    res: &str,
    g: &[&Rec],
    floors: &[&Rec],
    styles: &Styles,
    dir: &Path,
    figs: &mut Vec<Figure>,
) -> Result<()> {
    // Every chart of this scene draws these rows: its caption says what their whiskers are.
    let ci = ci_caption_rows(g);
    let ci = ci.as_str();
    let name = if effect.is_empty() {
        scene_name(label)
    } else {
        format!("{}, {effect}", scene_name(label))
    };
    let stem = file_safe(&format!("{label}_{effect}_{res}"));
    let labels = ConfigLabels::new(g.iter().copied());
    let configs = Runs::distinct_by(g, config_key);
    if configs.len() < 2 {
        figs.push(Figure::note(
            format!("{name}, {res}"),
            format!(
                "one configuration only ({}): no front, memory or time chart to draw; its numbers are in the table below.",
                g.first().map(|r| labels.get(r)).unwrap_or_default()
            ),
        ));
        figs.push(Figure::html(
            format!("Configurations — {name}, {res}"),
            scene_table(
                runs,
                g,
                floors,
                &labels,
                &Fronts {
                    time: vec![],
                    memory: vec![],
                },
                &name,
                res,
            ),
        ));
        return Ok(());
    }
    let fixed = labels.fixed_note();
    let vlines: Vec<(f64, String)> = floors
        .iter()
        .filter_map(|r| {
            let ms = r.trusted_ms()?;
            Some((ms, format!("{} {}", r.get(cols::METHOD), short(Some(ms)))))
        })
        .collect();
    let timed: Vec<&Rec> = g.iter().copied().filter(|r| r.time_trusted()).collect();
    let time_err = |r: &Rec| Some((r.trusted_ms()?, r.f(cols::RMSE)?));
    let mem_err = |r: &Rec| Some((r.bytes_per_pixel()?, r.f(cols::RMSE)?));
    let mem_time = |r: &Rec| Some((r.bytes_per_pixel()?, r.trusted_ms()?));
    // On the fronts an exact configuration's error is 0: its RMSE is f32 rounding, and ranking
    // exact methods by rounding noise would put a slower one on the front.
    let judged = |r: &Rec, e: f64| {
        if r.exact_result() == Some(true) {
            0.0
        } else {
            e
        }
    };
    let f_time = front_of(&timed, |r| time_err(r).map(|(t, e)| (t, judged(r, e))));
    let f_mem = front_of(g, |r| mem_err(r).map(|(m, e)| (m, judged(r, e))));
    let fronts = Fronts {
        time: f_time.iter().map(|&i| config_key(timed[i])).collect(),
        memory: f_mem.iter().map(|&i| config_key(g[i])).collect(),
    };
    let x_ci = |r: &Rec, y: f64| {
        let (lo, hi) = r.gpu_ci().unzip();
        Some(Pt {
            x: r.trusted_ms()?,
            y,
            xlo: lo,
            xhi: hi,
            flagged: r.flagged(),
            ..Default::default()
        })
    };
    let excluded = g.len() - timed.len();
    let untimed_note = if excluded > 0 {
        format!(" {excluded} point(s) whose GPU timestamps miss part of the frame are left out (their time is not the frame's).")
    } else {
        String::new()
    };
    // 1. RMSE vs time, the default front.
    let xy = XY {
        title: format!("Error vs GPU time — {name}, {res}"),
        x_label: "GPU time per frame [ms]".into(),
        y_label: "RMSE vs ground truth".into(),
        log_x: true,
        log_y: true,
        series: config_series(g, &labels, styles, |r| x_ci(r, r.f(cols::RMSE)?)),
        front: named(&timed, &f_time, &labels, time_err),
        front_name: "Pareto front (RMSE, time)".into(),
        vlines: vlines.clone(),
        zero_label: "exact (0)".into(),
        ..Default::default()
    };
    figs.push(xy.draw(
        dir,
        &format!("methods_pareto_time_{stem}"),
        &format!(
            "One point per configuration; the dashed line joins the configurations no other beats on both time and error (the Pareto front), each named. \
             Exact configurations ({}) count as error 0 on the front. Zero error is drawn in the band under the log axis, not clamped. Hollow: flagged. Dashed verticals: the floors of the same scene. \
             Horizontal whiskers: {} {fixed}{untimed_note}",
            runs.exactness_rule(),
            ci.trim_start_matches("Whiskers: ")
        ),
    )?);
    // 2. FLIP mean vs time, when measured.
    if g.iter().any(|r| r.f(cols::FLIP_MEAN).is_some()) {
        let flip_time = |r: &Rec| Some((r.trusted_ms()?, r.f(cols::FLIP_MEAN)?));
        let f = front_of(&timed, flip_time);
        let xy = XY {
            title: format!("FLIP vs GPU time — {name}, {res}"),
            x_label: "GPU time per frame [ms]".into(),
            y_label: "mean FLIP vs ground truth".into(),
            log_x: true,
            log_y: true,
            series: config_series(g, &labels, styles, |r| x_ci(r, r.f(cols::FLIP_MEAN)?)),
            front: named(&timed, &f, &labels, flip_time),
            front_name: "Pareto front (FLIP mean, time)".into(),
            vlines: vlines.clone(),
            zero_label: "identical (0)".into(),
            ..Default::default()
        };
        figs.push(xy.draw(
            dir,
            &format!("methods_pareto_flip_{stem}"),
            &format!("The same configurations judged by NVIDIA's FLIP (mean over the image, LDR over white), a perceptual difference. {fixed}"),
        )?);
    }
    // 3. RMSE vs memory, 4. time vs memory.
    if g.iter().any(|r| r.bytes_per_pixel().is_some()) {
        let xy = XY {
            title: format!("Error vs memory — {name}, {res}"),
            x_label: "bytes allocated per pixel".into(),
            y_label: "RMSE vs ground truth".into(),
            log_x: true,
            log_y: true,
            series: config_series(g, &labels, styles, |r| {
                Some(Pt::new(r.bytes_per_pixel()?, r.f(cols::RMSE)?).flagged(r.flagged()))
            }),
            front: named(g, &f_mem, &labels, mem_err),
            front_name: "Pareto front (RMSE, memory)".into(),
            zero_label: "exact (0)".into(),
            ..Default::default()
        };
        figs.push(xy.draw(
            dir,
            &format!("methods_pareto_memory_{stem}"),
            &format!("Memory = every buffer and texture the method allocates (scene buffers excluded), per pixel of the target. Exact configurations count as error 0 on the front. {fixed}"),
        )?);
        let f = front_of(&timed, mem_time);
        let xy = XY {
            title: format!("GPU time vs memory — {name}, {res}"),
            x_label: "bytes allocated per pixel".into(),
            y_label: "GPU time per frame [ms]".into(),
            log_x: true,
            log_y: true,
            series: config_series(g, &labels, styles, |r| time_pt(r, r.bytes_per_pixel()?)),
            front: named(&timed, &f, &labels, mem_time),
            front_name: "Pareto front (time, memory)".into(),
            ..Default::default()
        };
        figs.push(xy.draw(
            dir,
            &format!("methods_time_vs_memory_{stem}"),
            &format!("{ci} {fixed}"),
        )?);
    } else {
        figs.push(Figure::note(
            format!("Memory — {name}, {res}"),
            "not drawn: this CSV has no bytes_allocated or bytes_per_pixel (memory not measured).",
        ));
    }
    figs.push(Figure::html(
        format!("Configurations — {name}, {res}"),
        scene_table(runs, g, floors, &labels, &fronts, &name, res),
    ));
    Ok(())
}

/// The per-scene table: every configuration with its time, floor multiple, memory, errors, flag
/// and whether it is on the fronts. Sorted by time.
fn scene_table(
    runs: &Runs,
    g: &[&Rec],
    floors: &[&Rec],
    labels: &ConfigLabels,
    fronts: &Fronts,
    name: &str,
    res: &str,
) -> Markup {
    let flip = runs.has(cols::FLIP_MEAN) || g.iter().any(|r| r.f(cols::FLIP_MEAN).is_some());
    let mut rows: Vec<&Rec> = g.to_vec();
    rows.sort_by(|a, b| {
        a.f(cols::GPU_MS_MEDIAN)
            .unwrap_or(f64::INFINITY)
            .total_cmp(&b.f(cols::GPU_MS_MEDIAN).unwrap_or(f64::INFINITY))
    });
    let on_front = |r: &Rec| {
        let k = config_key(r);
        let mut on = String::new();
        if fronts.time.contains(&k) {
            on.push('T');
        }
        if fronts.memory.contains(&k) {
            on.push('M');
        }
        on
    };
    let config = |r: &Rec| {
        let label = labels.get(r);
        label
            .strip_prefix(r.get(cols::METHOD))
            .unwrap_or(&label)
            .trim()
            .to_string()
    };
    html! {
        table.scene {
            caption {
                (name) " at " (res) ": every configuration, fastest first. Front: on the Pareto \
                 front of RMSE vs time (T) and of RMSE vs memory (M). " (runs.exactness_rule())
            }
            tr {
                th { "method" } th { "configuration" } th { "GPU ms [95 % CI] or (range, n)" }
                th { "× floor_depth" } th { "bytes/px" } th { "RMSE" }
                @if flip { th { "FLIP mean" } th { "FLIP p99" } }
                th { "exact" } th { "flag" } th { "front" }
            }
            @for r in floors {
                tr.floor {
                    td { (r.get(cols::METHOD)) } td { "(floor)" } td { (time_cell(r)) } td {}
                    td { (short(r.bytes_per_pixel())) } td {}
                    @if flip { td {} td {} }
                    td {} td { (r.get(cols::FLAG)) } td {}
                }
            }
            @for r in &rows {
                tr class=[r.flagged().then_some("flagged")] {
                    td { (r.get(cols::METHOD)) }
                    td { (config(r)) }
                    td { (time_cell(r)) }
                    td { (short(r.f(cols::X_FLOOR).filter(|_| r.time_trusted()))) }
                    td { (short(r.bytes_per_pixel())) }
                    td { (short(r.f(cols::RMSE))) }
                    @if flip {
                        td { (short(r.f(cols::FLIP_MEAN))) }
                        td { (short(r.f(cols::FLIP_P99))) }
                    }
                    td { (exact_cell(r)) }
                    td { (r.flags().join(", ")) }
                    td { (on_front(r)) }
                }
            }
        }
        @if !flip { p.note { "FLIP: not measured in this CSV (no flip_mean column)." } }
    }
}

/// Scenes that differ from each other in one parameter only form a family; GPU time against
/// the true depth complexity is drawn per family with at least two scenes, lines joining one
/// configuration's points (never across different meshes or tessellations).
fn time_vs_complexity(
    at_res: &[&Rec],
    res: &str,
    styles: &Styles,
    dir: &Path,
    figs: &mut Vec<Figure>,
) -> Result<()> {
    let labels_all = Runs::distinct(at_res.iter().copied(), cols::SCENE_LABEL);
    for (family, scenes) in scene_families(&labels_all) {
        if scenes.len() < 2 {
            continue;
        }
        let g: Vec<&Rec> = at_res
            .iter()
            .copied()
            .filter(|r| scenes.iter().any(|s| s == r.get(cols::SCENE_LABEL)))
            .collect();
        let title = format!("GPU time vs depth complexity — {family}, {res}");
        let dcs = Runs::distinct(g.iter().copied(), cols::DEPTH_COMPLEXITY_MAX);
        if dcs.len() < 2 {
            figs.push(Figure::note(
                title,
                format!(
                    "not drawn: every scene of the family has the same true depth complexity ({}); their times are in the scene tables.",
                    dcs.join(", ")
                ),
            ));
            continue;
        }
        let labels = ConfigLabels::new(g.iter().copied());
        let all = config_series(&g, &labels, styles, |r| {
            time_pt(r, r.f(cols::DEPTH_COMPLEXITY_MAX)?)
        });
        let ci = ci_caption_rows(&g);
        let caption = format!(
            "Scenes: {}. x: the scene's true maximum depth complexity (CPU reference). {ci} {}",
            scene_names(&scenes).join("; "),
            labels.fixed_note()
        );
        // Up to six lines read in one panel; more become one panel per method (small
        // multiples on one shared scale), the other methods' lines in grey behind.
        if all.len() <= 6 {
            let xy = XY {
                title,
                x_label: "true max fragments per pixel".into(),
                y_label: "GPU time per frame [ms]".into(),
                log_x: true,
                log_y: true,
                lines: true,
                series: all,
                ..Default::default()
            };
            figs.push(xy.draw(
                dir,
                &format!("methods_time_vs_complexity_{}_{res}", file_safe(&family)),
                &caption,
            )?);
            continue;
        }
        let methods = Runs::distinct(g.iter().copied(), cols::METHOD);
        for m in &methods {
            let mine: Vec<&Rec> = g
                .iter()
                .copied()
                .filter(|r| r.get(cols::METHOD) == m)
                .collect();
            let (series, others): (Vec<Series>, Vec<Series>) = all
                .iter()
                .cloned()
                .partition(|s| mine.iter().any(|r| labels.get(r) == s.name));
            let xy = XY {
                title: format!("GPU time vs depth complexity — {m}; {family}, {res}"),
                x_label: "true max fragments per pixel".into(),
                y_label: "GPU time per frame [ms]".into(),
                log_x: true,
                log_y: true,
                lines: true,
                series,
                context: others.into_iter().map(|s| s.points).collect(),
                context_name: "other methods (their own panels)".into(),
                ..Default::default()
            };
            figs.push(xy.draw(
                dir,
                &format!(
                    "methods_time_vs_complexity_{}_{}_{res}",
                    file_safe(&family),
                    file_safe(m)
                ),
                &format!(
                    "One panel per method ({} panels on the same axes); {caption}",
                    methods.len()
                ),
            )?);
        }
    }
    Ok(())
}

/// Groups scene labels into families: same generator, same mesh, and every parameter equal but
/// one (the one that varies most). Returns (family name, its scene labels).
pub fn scene_families(labels: &[String]) -> Vec<(String, Vec<String>)> {
    let mut by_gen: Vec<(String, Vec<&String>)> = Vec::new();
    for l in labels {
        let g = parse_scene(l).0;
        match by_gen.iter_mut().find(|(n, _)| *n == g) {
            Some((_, v)) => v.push(l),
            None => by_gen.push((g, vec![l])),
        }
    }
    let mut out = Vec::new();
    for (g, ls) in by_gen {
        // The parameter with the most distinct values is the one a family sweeps.
        let mut counts: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for l in &ls {
            for (k, v) in parse_scene(l).1 {
                let e = counts.entry(k).or_default();
                if !e.contains(&v) {
                    e.push(v);
                }
            }
        }
        // A mesh path is what a family holds fixed; of equal counts the first name wins.
        let swept = counts
            .iter()
            .filter(|(k, v)| v.len() > 1 && !matches!(k.as_str(), "path" | "mesh" | "file"))
            .max_by(|a, b| a.1.len().cmp(&b.1.len()).then(b.0.cmp(a.0)))
            .map(|(k, _)| k.clone());
        let mut fams: Vec<(String, Vec<String>)> = Vec::new();
        for l in &ls {
            let rest: Vec<String> = parse_scene(l)
                .1
                .into_iter()
                .filter(|(k, _)| Some(k) != swept.as_ref())
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            let name = scene_name(&format!("{g}({})", rest.join(",")));
            let name = match &swept {
                Some(s) => format!("{name}, {s} swept"),
                None => name,
            };
            match fams.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => v.push((*l).clone()),
                None => fams.push((name, vec![(*l).clone()])),
            }
        }
        out.extend(fams);
    }
    out
}

/// Hazard, overflow and collision rates against depth complexity, one point per scene and
/// configuration; a rate that is zero everywhere is one line instead of an empty chart.
fn rates(
    at_res: &[&Rec],
    res: &str,
    styles: &Styles,
    dir: &Path,
    figs: &mut Vec<Figure>,
) -> Result<()> {
    for (col, what) in [
        (
            cols::HAZARD_RATE,
            "pixels whose captured set is not the true k nearest (read-modify-write hazards)",
        ),
        (
            cols::OVERFLOW_RATE,
            "pixels whose fragments exceeded the method's capacity",
        ),
        (
            cols::COLLISION_RATE,
            "true fragments merged or lost by bucket collisions",
        ),
    ] {
        let g: Vec<&Rec> = at_res
            .iter()
            .copied()
            .filter(|r| r.f(col).is_some())
            .collect();
        if g.is_empty() {
            continue;
        }
        let title = format!("{col} vs depth complexity — {res}");
        if g.iter().all(|r| r.f(col) == Some(0.0)) {
            let methods = Runs::distinct(g.iter().copied(), cols::METHOD);
            figs.push(Figure::note(
                title,
                format!(
                    "not drawn: {col} is 0 at all {} points ({}).",
                    g.len(),
                    methods.join(", ")
                ),
            ));
            continue;
        }
        let labels = ConfigLabels::new(g.iter().copied());
        let xy = XY {
            title,
            x_label: "true max fragments per pixel".into(),
            y_label: format!("{col} (fraction)"),
            log_x: true,
            log_y: false,
            series: config_series(&g, &labels, styles, |r| {
                Some(Pt::new(r.f(cols::DEPTH_COMPLEXITY_MAX)?, r.f(col)?).flagged(r.flagged()))
            }),
            ..Default::default()
        };
        figs.push(xy.draw(
            dir,
            &format!("methods_{col}_{res}"),
            &format!(
                "Fraction of {what}; one point per scene and configuration. {}",
                labels.fixed_note()
            ),
        )?);
    }
    Ok(())
}

/// Speedup over depth peeling and multiple of the floor: one row per configuration, one dot or
/// bar per scene.
fn ratio_bars(at_res: &[&Rec], res: &str, dir: &Path, figs: &mut Vec<Figure>) -> Result<()> {
    let scenes = Runs::distinct(at_res.iter().copied(), cols::SCENE_LABEL);
    let names = scene_names(&scenes);
    let labels = ConfigLabels::new(at_res.iter().copied());
    for (col, title, ylab, stem, skip) in [
        (
            cols::SPEEDUP_VS_DEPTH_PEEL,
            "Speedup over classic depth peeling",
            "depth_peel GPU time / configuration's (×)",
            "methods_speedup",
            Some("depth_peel"),
        ),
        (
            cols::X_FLOOR,
            "Multiple of the depth-only floor",
            "GPU time / floor_depth GPU time (×)",
            "methods_x_floor",
            None,
        ),
    ] {
        let rows: Vec<&Rec> = at_res
            .iter()
            .copied()
            .filter(|r| r.f(col).is_some() && r.time_trusted() && Some(r.get(cols::METHOD)) != skip)
            .collect();
        let dropped = dropped_from_ratio(at_res, col, skip, &labels);
        let title = format!("{title} — {res}");
        if rows.is_empty() {
            if at_res.iter().any(|r| r.f(col).is_some()) {
                figs.push(Figure::note(
                    title,
                    format!(
                        "not drawn: only {} ran, a comparison with itself.",
                        skip.unwrap_or("one method")
                    ),
                ));
            }
            continue;
        }
        let mut configs: Vec<(String, String)> = Vec::new();
        for r in &rows {
            let k = config_key(r);
            if !configs.iter().any(|(c, _)| *c == k) {
                configs.push((k, labels.get(r)));
            }
        }
        let series = scenes
            .iter()
            .zip(&names)
            .map(|(s, n)| {
                let vals = configs
                    .iter()
                    .map(|(k, _)| {
                        rows.iter()
                            .find(|r| r.get(cols::SCENE_LABEL) == s && config_key(r) == *k)
                            .and_then(|r| Some(Pt::new(0.0, r.f(col)?).flagged(r.flagged())))
                    })
                    .collect();
                (n.clone(), vals)
            })
            .filter(|(_, v): &(String, Vec<Option<Pt>>)| v.iter().any(|p| p.is_some()))
            .collect();
        let bars = Bars {
            title,
            y_label: ylab.into(),
            log_y: true,
            categories: configs.into_iter().map(|(_, l)| l).collect(),
            series,
            reference: Some(1.0),
        };
        figs.push(bars.draw(
            dir,
            &format!("{stem}_{res}"),
            &format!(
                "Same scene, resolution and run; the vertical line marks 1×. {}{dropped}",
                labels.fixed_note()
            ),
        )?);
    }
    Ok(())
}

/// The caption's sentence naming the rows a ratio chart leaves out, and why: " Left out: a
/// (2 scenes), b: no trusted GPU time (…)." (empty when none is).
fn dropped_from_ratio(
    at_res: &[&Rec],
    col: schema::Col,
    skip: Option<&str>,
    labels: &ConfigLabels,
) -> String {
    let mut why: Vec<(String, Vec<String>)> = Vec::new();
    for r in at_res {
        if Some(r.get(cols::METHOD)) == skip || (r.f(col).is_some() && r.time_trusted()) {
            continue;
        }
        let reason = if !r.time_trusted() {
            mfx_analysis::verdict::untrusted_reason(r).to_string()
        } else if r.trusted_ms().is_none() {
            "no GPU time".to_string()
        } else {
            format!("no {col} (its scene has no trusted reference time)")
        };
        let name = format!(
            "{} on {}",
            labels.get(r),
            scene_name(r.get(cols::SCENE_LABEL))
        );
        match why.iter_mut().find(|(w, _)| *w == reason) {
            Some((_, v)) => v.push(name),
            None => why.push((reason, vec![name])),
        }
    }
    why.iter()
        .map(|(w, names)| format!(" Left out ({}): {}: {w}.", names.len(), names.join("; ")))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_configuration_has_its_own_colour_and_marker() {
        // 17 methods with 1–4 configurations each (more than 32 configurations, more methods
        // than markers): today's depth_peel and bdp2 were both blue circles.
        let mut rows = Vec::new();
        for m in 0..17 {
            for k in 0..=(m % 4) {
                let mut r = Rec::default();
                r.set(cols::METHOD, format!("m{m}"));
                r.set(cols::POINT_KEY, format!("methods|s|64x64|m{m}|layers={k}"));
                rows.push(r);
            }
        }
        let st = Styles::new(rows.iter());
        let mut seen = std::collections::BTreeSet::new();
        for r in &rows {
            let pair = (
                crate::charts::PALETTE[st.color(r) % crate::charts::PALETTE.len()],
                st.family(r) % MARKERS,
            );
            assert!(
                seen.insert(pair),
                "{} shares {pair:?}",
                r.get(cols::POINT_KEY)
            );
        }
        assert!(seen.len() > crate::charts::PALETTE.len());
    }

    /// Two scenes measured with different sample counts, the compute A-buffer untimed on one,
    /// and overflow rates of 0 at one depth complexity.
    fn two_scenes() -> (tempfile::TempDir, Runs) {
        let header = "schema,run_id,study,scene_label,width,height,method,point_key,adapter,backend,status,gpu_ms_median,gpu_ms_ci_lo,gpu_ms_ci_hi,samples,gpu_ms_interval,gpu_time_trusted,x_floor,rmse,matches_truth,exact,depth_complexity_max,overflow_rate,bytes_per_pixel,flag";
        let mut rows = Vec::new();
        for (scene, n, dc) in [
            ("quads(depth_complexity=8)", 3, 8),
            ("quads(depth_complexity=32)", 2, 32),
        ] {
            let key = |m: &str| format!("\"methods|{scene}|64x64|{m}|\"");
            rows.push(format!("3,r,methods,\"{scene}\",64,64,floor_depth,{},G,vulkan,ok,0.1,0.09,0.11,{n},range,true,,,,,{dc},,,", key("floor_depth")));
            for (i, m) in ["depth_peel", "linked_list", "kbuffer_rmw", "bdp"]
                .iter()
                .enumerate()
            {
                let ms = 1.0 + i as f64;
                let over = if *m == "kbuffer_rmw" && dc == 32 {
                    "0.2"
                } else {
                    "0"
                };
                rows.push(format!(
                    "3,r,methods,\"{scene}\",64,64,{m},{},G,vulkan,ok,{ms},{},{},{n},range,true,{},3e-8,true,true,{dc},{over},{},",
                    key(m), ms * 0.9, ms * 1.1, ms / 0.1, 16 * (i + 1)
                ));
            }
            if dc == 8 {
                rows.push(format!("3,r,methods,\"{scene}\",64,64,compute_abuffer,{},G,vulkan,ok,0.05,0.04,0.06,{n},range,false,,3e-8,true,true,{dc},0,8,timestamps_incomplete", key("compute_abuffer")));
            }
        }
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("runs.csv");
        std::fs::write(&p, format!("{header}\n{}\n", rows.join("\n"))).unwrap();
        let runs = Runs::load(&p).unwrap();
        (d, runs)
    }

    #[test]
    fn each_caption_describes_its_own_chart() {
        let (d, runs) = two_scenes();
        let figs = figures(&runs, d.path()).unwrap();
        let cap = |stem: &str| {
            figs.iter()
                .find(|f| f.stem.starts_with(stem))
                .unwrap_or_else(|| {
                    panic!(
                        "no {stem}: {:?}",
                        figs.iter().map(|f| &f.stem).collect::<Vec<_>>()
                    )
                })
                .caption
                .clone()
        };
        let p8 = cap("methods_pareto_time_quads_depth_complexity_8");
        assert!(
            p8.contains("range (n = 3)") && !p8.contains("n = 2"),
            "{p8}"
        );
        assert!(p8.contains("1 point(s) whose GPU timestamps miss"), "{p8}");
        let p32 = cap("methods_pareto_time_quads_depth_complexity_32");
        assert!(
            p32.contains("range (n = 2)") && !p32.contains("n = 3"),
            "{p32}"
        );
        // Nothing is left out of the second scene's chart, and its caption says nothing of it.
        assert!(
            !p32.contains("left out") && !p32.contains("miss part"),
            "{p32}"
        );
        // The × floor chart names the point it drops and why.
        let xf = cap("methods_x_floor");
        assert!(
            xf.contains("Left out (1): compute_abuffer on quads")
                && xf.contains("GPU timestamps miss part of the frame"),
            "{xf}"
        );
    }

    #[test]
    fn zero_rates_stay_on_the_zero_line() {
        let (d, runs) = two_scenes();
        let figs = figures(&runs, d.path()).unwrap();
        let f = figs
            .iter()
            .find(|f| f.stem.starts_with("methods_overflow_rate"))
            .expect("an overflow chart");
        let l: crate::charts::Layout = serde_json::from_str(
            &std::fs::read_to_string(d.path().join(format!("{}.layout.json", f.stem))).unwrap(),
        )
        .unwrap();
        // Every marker but the one overflowing sits at y = 0: one pixel row for all of them.
        let mut ys: Vec<i64> = l
            .marks
            .iter()
            .map(|m| (m.rect.y + m.rect.h / 2.0).round() as i64)
            .collect();
        ys.sort_unstable();
        ys.dedup();
        assert_eq!(ys.len(), 2, "zero markers moved off their line: {ys:?}");
        assert_eq!(crate::charts::layout::check(&l), Ok(()));
    }

    #[test]
    fn families_never_join_different_meshes() {
        let l: Vec<String> = [
            "quads(depth_complexity=8)",
            "quads(depth_complexity=32)",
            "shells(count=16,segments=256)",
            "shells(count=4,segments=16)",
            "obj(instances=4,path=m/a.obj)",
            "obj(instances=16,path=m/a.obj)",
            "obj(instances=4,path=m/b.obj)",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let f = scene_families(&l);
        let sizes: Vec<(String, usize)> = f.iter().map(|(n, v)| (n.clone(), v.len())).collect();
        assert_eq!(
            sizes,
            [
                ("quads, depth_complexity swept".to_string(), 2),
                ("shells (segments=256), count swept".to_string(), 1),
                ("shells (segments=16), count swept".to_string(), 1),
                ("obj a, instances swept".to_string(), 2),
                ("obj b, instances swept".to_string(), 1),
            ]
        );
    }
}
