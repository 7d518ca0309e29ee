//! Cross-adapter and cross-backend comparison, drawn when a CSV (usually `mfx merge`d from
//! several machines) holds more than one platform (adapter × backend): GPU time per method and
//! scene per platform (grouped bars, log scale), each platform's speedup over a baseline
//! platform (`mfx report --baseline NAME`), and how closely the same point's images agree across
//! platforms (max and RMS difference of the saved images, `mfx sweep --save-images`).
//!
//! Points are matched by `point_key` (study|scene|resolution|method|axes), so two platforms are
//! compared only on exactly the same scene, resolution and configuration.

use schema::cols;
use schema::StudyKind;
use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use maud::{html, Markup};

use crate::charts::{Bars, Figure, Pt};
use crate::labels::{file_safe, scene_name, ConfigLabels};
use mfx_analysis::data::{platform, platforms, resolution, Rec, Runs};

/// What the comparison adds to the page.
pub struct Comparison {
    pub figures: Vec<Figure>,
    /// Tables (speedups, image agreement).
    pub html: Markup,
    /// The largest max-abs image difference between platforms, with its point and platforms.
    pub worst_image_diff: Option<(f64, String, String, String)>,
}

/// The baseline platform: the first whose "adapter (backend)" contains `name` (case-insensitive),
/// or by default the first CPU adapter (lavapipe/llvmpipe), else the first platform.
pub fn baseline(runs: &Runs, name: Option<&str>) -> Result<String> {
    let all = platforms(runs);
    match name {
        Some(n) => all
            .iter()
            .find(|p| p.to_lowercase().contains(&n.to_lowercase()))
            .cloned()
            .with_context(|| {
                format!(
                    "--baseline '{n}' matches no adapter in the CSV (adapters: {})",
                    all.join("; ")
                )
            }),
        None => Ok(runs
            .rows
            .iter()
            .find(|r| r.get(cols::DEVICE_TYPE) == "cpu")
            .map(platform)
            .or_else(|| all.first().cloned())
            .unwrap_or_default()),
    }
}

fn num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 0.01 {
        format!("{v:.3}")
    } else {
        format!("{v:.2e}")
    }
}

/// A CSV number cell, shortened like `num`; text that is not a number is kept.
fn cell(s: &str) -> String {
    s.parse::<f64>().map(num).unwrap_or_else(|_| s.to_string())
}

fn geomean(v: &[f64]) -> Option<f64> {
    let v: Vec<f64> = v
        .iter()
        .copied()
        .filter(|x| *x > 0.0 && x.is_finite())
        .collect();
    (!v.is_empty()).then(|| (v.iter().map(|x| x.ln()).sum::<f64>() / v.len() as f64).exp())
}

/// Max and RMS difference over all channels of two premultiplied RGBA images.
pub fn image_diff(a: &[f32], b: &[f32]) -> Option<(f64, f64)> {
    if a.len() != b.len() || a.is_empty() {
        return None;
    }
    let (mut max, mut sq) = (0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        let d = (*x as f64 - *y as f64).abs();
        // A NaN on one side is the largest possible disagreement, never hidden.
        let d = if d.is_nan() { f64::INFINITY } else { d };
        max = max.max(d);
        sq += d * d;
    }
    Some((max, (sq / a.len() as f64).sqrt()))
}

fn read_image(path: &Path) -> Result<(Vec<u64>, Vec<f32>)> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let npy = npyz::NpyFile::new(&bytes[..]).with_context(|| format!("{}", path.display()))?;
    let shape = npy.shape().to_vec();
    let v: Vec<f32> = npy
        .into_vec()
        .with_context(|| format!("{}: not float32", path.display()))?;
    Ok((shape, v))
}

/// The ok rows by point key and platform, and the keys in first-seen order: points are
/// compared only on exactly the same scene, resolution and configuration.
struct Points<'a> {
    by_point: BTreeMap<&'a str, BTreeMap<String, &'a Rec>>,
    order: Vec<&'a str>,
}

/// Every ok row, timed or not: a platform without GPU timestamps (GLES) has no time to chart
/// or divide, but its images still agree or not with the others'. The time charts and the
/// speed-ups read `trusted_ms` themselves.
fn points(runs: &Runs) -> Points<'_> {
    let mut by_point: BTreeMap<&str, BTreeMap<String, &Rec>> = BTreeMap::new();
    let mut order: Vec<&str> = Vec::new();
    for r in runs.rows.iter().filter(|r| r.ok()) {
        let k = r.get(cols::POINT_KEY);
        if !by_point.contains_key(k) {
            order.push(k);
        }
        by_point
            .entry(k)
            .or_default()
            .entry(platform(r))
            .or_insert(r);
    }
    Points { by_point, order }
}

/// Step 1, time per configuration: one chart per scene × resolution, one bar per platform
/// (points measured on at least two platforms only: only they say anything about platforms).
fn time_charts(
    pts: &Points,
    plats: &[String],
    labels: &ConfigLabels,
    out: &Path,
) -> Result<Vec<Figure>> {
    let mut scenes: Vec<(String, String)> = Vec::new();
    for k in &pts.order {
        let r = pts.by_point[k].values().next().expect("non-empty");
        let s = (r.get(cols::SCENE_LABEL).to_string(), resolution(r));
        if !scenes.contains(&s) {
            scenes.push(s);
        }
    }
    let mut figures = Vec::new();
    for (label, res) in &scenes {
        let here: Vec<&str> = pts
            .order
            .iter()
            .copied()
            .filter(|k| {
                let r = pts.by_point[k].values().next().expect("non-empty");
                r.get(cols::SCENE_LABEL) == label
                    && resolution(r) == *res
                    && pts.by_point[k].len() >= 2
            })
            .collect();
        if here.is_empty() {
            continue;
        }
        let categories: Vec<String> = here
            .iter()
            .map(|k| {
                let r = pts.by_point[k].values().next().expect("non-empty");
                let study = r.get(cols::STUDY);
                let c = labels.get(r);
                if study == StudyKind::Methods.name() || c.starts_with("floor_") {
                    c
                } else {
                    format!("{study}: {c}")
                }
            })
            .collect();
        let series = plats
            .iter()
            .map(|p| {
                let v = here
                    .iter()
                    .map(|k| {
                        pts.by_point[k]
                            .get(p)
                            .and_then(|r| crate::points::time_pt(r, 0.0))
                    })
                    .collect();
                (p.clone(), v)
            })
            .collect();
        let drawn: Vec<&Rec> = here
            .iter()
            .flat_map(|k| pts.by_point[k].values().copied())
            .collect();
        let bars = Bars {
            title: format!("GPU time per platform — {}, {res}", scene_name(label)),
            y_label: "GPU time per frame [ms]".into(),
            log_y: true,
            categories,
            series,
            reference: None,
        };
        figures.push(bars.draw(
            out,
            &format!("compare_time_{}_{res}", file_safe(label)),
            &format!(
                "Median GPU time per frame of each configuration on each platform. {} \
                 floor_depth/floor_opaque are the rasterisation floors of the same scene.",
                crate::points::ci_caption_rows(&drawn)
            ),
        )?);
    }
    Ok(figures)
}

/// Per configuration, per platform other than the baseline: baseline ms / platform ms on each
/// scene measured (trusted times) on both.
struct Speedups {
    base: String,
    others: Vec<String>,
    /// Configurations in first-seen order.
    configs: Vec<String>,
    speed: BTreeMap<String, BTreeMap<String, Vec<f64>>>,
}

impl Speedups {
    fn of(&self, config: &str, platform: &str) -> Option<&Vec<f64>> {
        self.speed.get(config)?.get(platform)
    }
}

fn min_max(s: &[f64]) -> (f64, f64) {
    (
        s.iter().copied().fold(f64::INFINITY, f64::min),
        s.iter().copied().fold(0.0, f64::max),
    )
}

/// Step 2, speed-ups over the baseline platform.
fn speedups(pts: &Points, plats: &[String], base: &str, labels: &ConfigLabels) -> Speedups {
    let others: Vec<String> = plats.iter().filter(|p| *p != base).cloned().collect();
    let mut configs: Vec<String> = Vec::new();
    let mut speed: BTreeMap<String, BTreeMap<String, Vec<f64>>> = BTreeMap::new();
    for k in &pts.order {
        let per = &pts.by_point[k];
        let Some(b) = per.get(base).and_then(|r| r.trusted_ms()) else {
            continue;
        };
        let c = labels.get(per.values().next().expect("non-empty"));
        for p in &others {
            if let Some(t) = per.get(p).and_then(|r| r.trusted_ms()) {
                if t > 0.0 && b > 0.0 {
                    if !configs.contains(&c) {
                        configs.push(c.clone());
                    }
                    speed
                        .entry(c.clone())
                        .or_default()
                        .entry(p.clone())
                        .or_default()
                        .push(b / t);
                }
            }
        }
    }
    Speedups {
        base: base.to_string(),
        others,
        configs,
        speed,
    }
}

/// The speed-up chart: per configuration the geometric mean over scenes, whiskers the smallest
/// and largest scene.
fn speedup_chart(s: &Speedups, out: &Path) -> Result<Figure> {
    let series = s
        .others
        .iter()
        .map(|p| {
            let v = s
                .configs
                .iter()
                .map(|c| {
                    let v = s.of(c, p)?;
                    let (lo, hi) = min_max(v);
                    Some(Pt::spread(0.0, geomean(v)?, Some(lo), Some(hi)))
                })
                .collect();
            (p.clone(), v)
        })
        .collect();
    let bars = Bars {
        title: format!("Speedup over {}", s.base),
        y_label: "baseline GPU time / platform GPU time (×)".into(),
        log_y: true,
        categories: s.configs.clone(),
        series,
        reference: Some(1.0),
    };
    bars.draw(
        out,
        "compare_speedup",
        &format!(
            "Per configuration: geometric mean over the scenes measured on both of \
             (GPU time on {}) / (GPU time on the platform); whiskers: the smallest and \
             largest scene. Above 1 is faster than the baseline.",
            s.base
        ),
    )
}

fn speedup_table(s: &Speedups) -> Markup {
    html! {
        h3 { "Speedup over " (s.base) }
        table id="speedup" {
            tr {
                th { "configuration" }
                @for p in &s.others { th { (p) " (geomean, min–max, scenes)" } }
            }
            @for c in &s.configs {
                tr {
                    td { (c) }
                    @for p in &s.others {
                        td {
                            @if let Some(v) = s.of(c, p) {
                                @let (lo, hi) = min_max(v);
                                (geomean(v).map(num).unwrap_or_default()) "× ("
                                (num(lo)) "–" (num(hi)) ", " (v.len()) ")"
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Two platforms' images of one point, and how far apart they are.
#[derive(Clone, Debug)]
pub struct ImagePair {
    pub max: f64,
    pub rms: f64,
    pub key: String,
    pub a: String,
    pub b: String,
    /// Each image's own RMSE vs the f64 reference (as written in its row).
    pub rmse_a: String,
    pub rmse_b: String,
}

/// Step 3, image agreement: every pair of platforms' saved images of one point, largest
/// difference first; images that could not be compared, with why.
struct Agreement {
    pairs: Vec<ImagePair>,
    problems: Vec<String>,
    /// Points with images on two or more platforms.
    with_images: usize,
}

fn image_agreement(pts: &Points, run_dir: &Path) -> Agreement {
    let mut ag = Agreement {
        pairs: Vec::new(),
        problems: Vec::new(),
        with_images: 0,
    };
    for k in &pts.order {
        let imgs: Vec<(&String, &Rec)> = pts.by_point[k]
            .iter()
            .filter(|(_, r)| !r.get(cols::IMAGE_FILE).is_empty())
            .map(|(p, r)| (p, *r))
            .collect();
        if imgs.len() < 2 {
            continue;
        }
        ag.with_images += 1;
        let mut loaded = Vec::new();
        for (p, r) in &imgs {
            match read_image(&run_dir.join(r.get(cols::IMAGE_FILE))) {
                Ok(img) => loaded.push((*p, *r, img)),
                Err(e) => ag.problems.push(format!("{p}: {e:#}")),
            }
        }
        for i in 0..loaded.len() {
            for j in i + 1..loaded.len() {
                let (pa, ra, (sa, a)) = &loaded[i];
                let (pb, rb, (sb, b)) = &loaded[j];
                if sa != sb {
                    ag.problems.push(format!(
                        "{k}: image shapes differ ({sa:?} on {pa}, {sb:?} on {pb})"
                    ));
                    continue;
                }
                if let Some((max, rms)) = image_diff(a, b) {
                    ag.pairs.push(ImagePair {
                        max,
                        rms,
                        key: k.to_string(),
                        a: (*pa).clone(),
                        b: (*pb).clone(),
                        rmse_a: ra.get(cols::RMSE).to_string(),
                        rmse_b: rb.get(cols::RMSE).to_string(),
                    });
                }
            }
        }
    }
    ag.pairs.sort_by(|x, y| {
        y.max
            .partial_cmp(&x.max)
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    ag
}

fn agreement_table(ag: &Agreement) -> Markup {
    html! {
        h3 { "Image agreement across platforms" }
        @if ag.pairs.is_empty() {
            p {
                "No point has saved images on two platforms (run the sweeps with "
                code { "mfx sweep --save-images" } " and merge the folders)."
            }
        } @else {
            p {
                (ag.with_images) " points have images on two or more platforms. Difference of the \
                 premultiplied RGBA images over all pixels and channels (the same point should give \
                 the same image on every platform; each image's own RMSE vs the f64 CPU reference is \
                 beside it). Largest first."
            }
            table id="agreement" {
                tr {
                    th { "point" } th { "platform A" } th { "platform B" } th { "max abs diff" }
                    th { "RMS diff" } th { "RMSE A vs ref" } th { "RMSE B vs ref" }
                }
                @for x in &ag.pairs {
                    tr {
                        td { (x.key) } td { (x.a) } td { (x.b) } td { (num(x.max)) }
                        td { (num(x.rms)) } td { (cell(&x.rmse_a)) } td { (cell(&x.rmse_b)) }
                    }
                }
            }
        }
        @if !ag.problems.is_empty() {
            p.failed { "Images that could not be compared (" (ag.problems.len()) "):" }
            ul { @for p in &ag.problems { li { (p) } } }
        }
    }
}

/// The comparison of a run folder's rows, or `None` when they hold one platform only.
pub fn compare(
    runs: &Runs,
    run_dir: &Path,
    out: &Path,
    baseline_name: Option<&str>,
) -> Result<Option<Comparison>> {
    let plats = platforms(runs);
    if plats.len() < 2 {
        if let Some(n) = baseline_name {
            bail!(
                "--baseline '{n}': the CSV holds one adapter only ({})",
                plats.join("")
            );
        }
        return Ok(None);
    }
    let base = baseline(runs, baseline_name)?;
    let pts = points(runs);
    let labels = ConfigLabels::new(runs.rows.iter().filter(|r| r.ok()));
    let mut figures = time_charts(&pts, &plats, &labels, out)?;
    let speed = speedups(&pts, &plats, &base, &labels);
    if !speed.configs.is_empty() {
        figures.push(speedup_chart(&speed, out)?);
    }
    let ag = image_agreement(&pts, run_dir);
    let page = html! {
        h2 { "Adapters and backends: speedups and image agreement" }
        p {
            (plats.len()) " platforms (adapter, backend): " (plats.join("; "))
            ". Baseline for speedups: " b { (base) }
            @if baseline_name.is_none() {
                " (default: the first CPU adapter; choose with "
                code { "mfx report --baseline NAME" } ")"
            }
            "."
        }
        @if !speed.configs.is_empty() { (speedup_table(&speed)) }
        (agreement_table(&ag))
    };
    let worst_image_diff = ag
        .pairs
        .first()
        .map(|x| (x.max, x.key.clone(), x.a.clone(), x.b.clone()));
    Ok(Some(Comparison {
        figures,
        html: page,
        worst_image_diff,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_npy(path: &Path, px: &[f32]) {
        use npyz::WriterBuilder;
        let mut w = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&[1, (px.len() / 4) as u64, 4])
            .writer(std::fs::File::create(path).unwrap())
            .begin_nd()
            .unwrap();
        w.extend(px.iter().copied()).unwrap();
        w.finish().unwrap();
    }

    const H: &str = "schema,point_key,study,scene,scene_label,width,height,method,max_layers,adapter,backend,device_type,status,gpu_ms_median,gpu_ms_min,gpu_ms_max,rmse,image_file";

    /// A temp folder removed when the test ends, pass or fail (derefs to its path).
    struct Tmp(tempfile::TempDir);
    impl std::ops::Deref for Tmp {
        type Target = std::path::Path;
        fn deref(&self) -> &std::path::Path {
            self.0.path()
        }
    }
    impl AsRef<std::path::Path> for Tmp {
        fn as_ref(&self) -> &std::path::Path {
            self.0.path()
        }
    }
    fn tmp_dir(prefix: &str) -> Tmp {
        Tmp(tempfile::Builder::new()
            .prefix(&format!("{prefix}-"))
            .tempdir()
            .expect("a temp folder"))
    }

    fn setup(name: &str) -> Tmp {
        let d = tmp_dir(&format!("mfx-compare-{name}"));
        std::fs::create_dir_all(d.join("images")).unwrap();
        std::fs::create_dir_all(d.join("report")).unwrap();
        let rows = [
            "1,m|q|2x1|floor_depth|,methods,quads,q,2,1,floor_depth,,GPU,vulkan,discretegpu,ok,0.1,0.1,0.1,,",
            "1,m|q|2x1|floor_depth|,methods,quads,q,2,1,floor_depth,,llvmpipe,vulkan,cpu,ok,1.0,1.0,1.0,,",
            "1,m|q|2x1|depth_peel|max_layers=8,methods,quads,q,2,1,depth_peel,8,GPU,vulkan,discretegpu,ok,0.5,0.4,0.6,0,images/a.npy",
            "1,m|q|2x1|depth_peel|max_layers=8,methods,quads,q,2,1,depth_peel,8,llvmpipe,vulkan,cpu,ok,20,19,21,0,images/b.npy",
            "1,m|q|2x1|depth_peel|max_layers=8,methods,quads,q,2,1,depth_peel,8,llvmpipe,gl,cpu,ok,40,39,41,0,images/c.npy",
            "1,m|q|2x1|depth_peel|max_layers=8,methods,quads,q,2,1,depth_peel,8,GPU,gl,discretegpu,skipped,,,,,",
        ];
        std::fs::write(d.join("runs.csv"), format!("{H}\n{}\n", rows.join("\n"))).unwrap();
        write_npy(
            &d.join("images/a.npy"),
            &[0.5, 0.5, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0],
        );
        write_npy(
            &d.join("images/b.npy"),
            &[0.5, 0.5, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0],
        );
        write_npy(
            &d.join("images/c.npy"),
            &[0.5, 0.5, 0.5, 0.75, 0.0, 0.0, 0.0, 0.0],
        );
        d
    }

    #[test]
    fn compares_platforms_speedups_and_images() {
        let d = setup("platforms");
        let runs = Runs::load(&d.join("runs.csv")).unwrap();
        let c = compare(&runs, &d, &d.join("report"), Some("llvmpipe (vulkan"))
            .unwrap()
            .unwrap();
        // One time chart (one scene) and one speedup chart, both written.
        assert_eq!(c.figures.len(), 2);
        for f in &c.figures {
            assert!(d.join("report").join(format!("{}.png", f.stem)).is_file());
            assert!(d.join("report").join(format!("{}.svg", f.stem)).is_file());
        }
        // GPU over lavapipe: 20 / 0.5 = 40× for depth_peel, 1.0 / 0.1 = 10× for the floor.
        assert!(
            c.html.0.contains("<td>depth_peel</td><td>40.000×"),
            "{}",
            c.html.0
        );
        assert!(
            c.html.0.contains("<td>floor_depth</td><td>10.000×"),
            "{}",
            c.html.0
        );
        // Images: vulkan GPU = vulkan lavapipe exactly; GL differs by 0.25 in one of 8 channels.
        let (max, key, _, _) = c.worst_image_diff.clone().unwrap();
        assert_eq!(max, 0.25);
        assert!(key.contains("depth_peel"));
        assert!(c.html.0.contains("id=\"agreement\""));
        assert_eq!(
            c.html.0.matches("<td>0.250</td><td>0.088</td>").count(),
            2,
            "{}",
            c.html.0
        );
        assert!(
            c.html.0.contains("<td>0</td><td>0</td>"),
            "the identical pair is listed: {}",
            c.html.0
        );
    }

    #[test]
    fn a_platform_without_gpu_time_still_has_its_images_compared() {
        // The H200's GLES rows have no timestamps: they once vanished from image agreement.
        let d = setup("untimed");
        let csv = std::fs::read_to_string(d.join("runs.csv")).unwrap();
        let csv = csv.replace("llvmpipe,gl,cpu,ok,40,39,41,", "llvmpipe,gl,cpu,ok,,,,");
        std::fs::write(d.join("runs.csv"), csv).unwrap();
        let runs = Runs::load(&d.join("runs.csv")).unwrap();
        let c = compare(&runs, &d, &d.join("report"), Some("llvmpipe (vulkan"))
            .unwrap()
            .unwrap();
        assert_eq!(c.worst_image_diff.clone().unwrap().0, 0.25);
        assert_eq!(
            c.html.0.matches("<td>0.250</td><td>0.088</td>").count(),
            2,
            "{}",
            c.html.0
        );
        // It has no speed-up: it was never timed.
        assert!(!c.html.0.contains("<td>0.500×"), "{}", c.html.0);
    }

    #[test]
    fn one_platform_draws_nothing_and_a_bad_baseline_is_an_error() {
        let d = setup("bad");
        let runs = Runs::load(&d.join("runs.csv")).unwrap();
        let e = compare(&runs, &d, &d.join("report"), Some("no such gpu"))
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("'no such gpu'") && e.contains("llvmpipe (gl)"),
            "{e}"
        );
        let mut one = runs.clone();
        one.rows
            .retain(|r| r.get(cols::ADAPTER) == "GPU" && r.get(cols::BACKEND) == "vulkan");
        assert!(compare(&one, &d, &d.join("report"), None)
            .unwrap()
            .is_none());
        // Default baseline: the first CPU adapter.
        assert_eq!(baseline(&runs, None).unwrap(), "llvmpipe (vulkan)");
    }

    #[test]
    fn a_merged_report_names_platforms_and_every_image_exists() {
        let d = setup("page");
        let page = crate::build(&d, None).unwrap();
        let html = std::fs::read_to_string(&page).unwrap();
        for t in ["runs", "speedup", "agreement", "rows", "notok"] {
            assert!(html.contains(&format!("id=\"{t}\"")), "no table {t}");
        }
        // The rows table says which platform each row ran on.
        assert!(html.contains("<td>GPU (vulkan)</td>"), "{html}");
        assert!(html.contains("<td>llvmpipe (gl)</td>"), "{html}");
        // Every image the page shows is on disk (the browser check's precondition).
        let srcs: Vec<&str> = html
            .split("<img src=\"")
            .skip(1)
            .map(|s| &s[..s.find('"').unwrap()])
            .collect();
        assert!(srcs.len() >= 2, "{srcs:?}");
        for s in srcs {
            assert!(page.parent().unwrap().join(s).is_file(), "{s} missing");
        }
    }

    #[test]
    fn nan_is_the_largest_difference() {
        assert_eq!(
            image_diff(&[0.0, f32::NAN], &[0.0, 0.0]).unwrap().0,
            f64::INFINITY
        );
        assert_eq!(image_diff(&[1.0], &[1.0, 2.0]), None);
    }
}
