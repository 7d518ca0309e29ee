//! Whole reports, read as a reader would: every chart's layout passes `layout::check`, the page
//! carries the summary `summary_text` writes, FLIP columns and images show when measured, and
//! every committed reference CSV still renders.

use std::path::Path;

use report::charts::{layout, Layout};
use schema::{Flag, FlagSet};

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
fn tmp(name: &str) -> Tmp {
    tmp_dir(&format!("mfx-report-{name}"))
}

/// Every `*.layout.json` under `dir`, checked; returns how many there were.
fn check_layouts(dir: &Path) -> usize {
    let mut n = 0;
    let mut bad = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.to_string_lossy().ends_with(".layout.json") {
                let l: Layout =
                    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
                if let Err(e) = layout::check(&l) {
                    bad.extend(e);
                }
                n += 1;
            }
        }
    }
    assert!(bad.is_empty(), "{}: {bad:#?}", dir.display());
    n
}

const HEADER: &str = "schema,run_id,suite,study,scene,scene_label,width,height,method,point_key,adapter,backend,device_type,status,reason,gpu_ms_median,gpu_ms_ci_lo,gpu_ms_ci_hi,x_floor,rmse,bad_pixel_frac,matches_truth,flag,flip_mean,flip_p99,bytes_allocated,bytes_per_pixel,depth_complexity_max,overflow_rate";

#[allow(clippy::too_many_arguments, reason = "one CSV row, every cell named")]
fn row(
    scene: &str,
    method: &str,
    axes: &str,
    ms: f64,
    rmse: &str,
    exact: bool,
    flag: &str,
    flip: &str,
    bpp: f64,
) -> String {
    let key = format!("methods|{scene}|64x64|{method}|{axes}");
    format!(
        "1,r,custom,methods,obj,\"{scene}\",64,64,{method},\"{key}\",lavapipe,vulkan,cpu,ok,,{ms},{},{},{},{rmse},0,{exact},{flag},{flip},{flip},{},{bpp},8,0",
        ms * 0.95,
        ms * 1.05,
        ms / 0.1,
        bpp * 4096.0
    )
}

#[test]
fn a_custom_suite_report_reads_well() {
    let d = tmp("custom");
    let mut rows = Vec::new();
    for mesh in [
        "/home/someone/models/holes-a.obj",
        "/home/someone/models/holes-b.obj",
    ] {
        let scene = format!("obj(instances=4,path={mesh})");
        let key = format!("methods|{scene}|64x64|floor_depth|");
        rows.push(format!(
            "1,r,custom,methods,obj,\"{scene}\",64,64,floor_depth,\"{key}\",lavapipe,vulkan,cpu,ok,,0.1,0.09,0.11,,,,,,,,4096,16,8,"
        ));
        rows.push(row(
            &scene,
            "depth_peel",
            "max_layers=64",
            3.0,
            "0",
            true,
            "",
            "0",
            120.0,
        ));
        rows.push(row(
            &scene,
            "linked_list",
            "layers=8",
            1.0,
            "0",
            true,
            "",
            "0",
            300.0,
        ));
        rows.push(row(
            &scene,
            "linked_list",
            "layers=4",
            0.8,
            "2e-3",
            false,
            &FlagSet::of(&[Flag::Overflow, Flag::Noisy]).to_string(),
            "0.05",
            160.0,
        ));
        rows.push(row(
            &scene, "wboit", "", 0.3, "3e-2", false, "", "0.2", 24.0,
        ));
    }
    rows.push("1,r,custom,methods,obj,x,64,64,bdp,methods|x|64x64|bdp|,lavapipe,vulkan,cpu,skipped,needs 8 colour attachments,,,,,,,,,,,,,,".into());
    std::fs::write(
        d.join("runs.csv"),
        format!("{HEADER}\n{}\n", rows.join("\n")),
    )
    .unwrap();
    let page = report::build(&d, None).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    let charts = check_layouts(&d.join("report"));
    assert!(charts >= 8, "{charts} charts");
    // Mesh stems name the scenes; no label is cut to a shared prefix.
    assert!(
        html.contains("obj holes-a") && html.contains("obj holes-b"),
        "mesh stems"
    );
    assert!(!html.contains('…'), "a label was cut");
    // The page's verdict and summary_text say the same: the winner's cell is on the page.
    let runs = report::Runs::load(&d.join("runs.csv")).unwrap();
    let text = report::summary_text(&runs);
    assert!(
        text.contains(
            "Fastest exact (by construction): linked_list layers=8 at 1 [0.95, 1.05] ms, 10× floor_depth"
        ),
        "{text}"
    );
    assert!(text.contains("RMSE ≤ 1e-2: linked_list layers=4"), "{text}");
    assert!(text.contains("needs 8 colour attachments"), "{text}");
    assert!(html.contains("id=\"summary\"") && !html.contains("<pre"));
    assert!(
        html.contains("linked_list layers=8 at 1 [0.95, 1.05] ms"),
        "verdict cell"
    );
    // FLIP columns are shown; the run has no FLIP images, which the page says in one line.
    assert!(html.contains("<th>FLIP mean</th>") && html.contains("has no FLIP images"));
    // The flagged point is listed; the exact points are in the zero band, not clamped.
    assert!(html.contains("id=\"flagged\"") && html.contains("overflow, noisy"));
    let l: Layout = serde_json::from_str(
        &std::fs::read_to_string(
            std::fs::read_dir(d.join("report"))
                .unwrap()
                .map(|e| e.unwrap().path())
                .find(|p| {
                    p.to_string_lossy().contains("methods_pareto_time_")
                        && p.to_string_lossy().ends_with(".layout.json")
                })
                .unwrap(),
        )
        .unwrap(),
    )
    .unwrap();
    assert!(l.zero_band > 0.0 && l.y.range[0] > 1e-4, "{l:?}");
    // A rate that is zero everywhere is one line, not an empty chart.
    assert!(html.contains("overflow_rate is 0 at all"), "overflow note");
}

#[test]
fn every_committed_reference_csv_still_renders() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../results/reference");
    let mut csvs = Vec::new();
    let mut stack = vec![root];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() && !p.ends_with("report") && !p.ends_with("images") {
                stack.push(p);
            } else if p.file_name().is_some_and(|n| n == "runs.csv") {
                csvs.push(p);
            }
        }
    }
    assert!(csvs.len() >= 10, "{csvs:?}");
    for (i, csv) in csvs.iter().enumerate() {
        let d = tmp(&format!("ref{i}"));
        std::fs::copy(csv, d.join("runs.csv")).unwrap();
        report::build(&d, None).unwrap_or_else(|e| panic!("{}: {e:#}", csv.display()));
        check_layouts(&d.join("report"));
    }
}

#[test]
fn a_merged_limits_run_shows_the_split_s_cost_against_the_adapter_s_row() {
    // `default` and `default --limits webgpu` merged: two platforms for the charts, one table
    // that reads both (the split row beside the unsplit one of the same point).
    let d = tmp("limits");
    let h = format!("{HEADER},limits,split");
    let key = "methods|q|64x64|kbuffer_atomic|layers=16";
    let r = |limits: &str, split: &str, ms: f64| {
        format!(
            "1,r,default,methods,quads,q,64,64,kbuffer_atomic,\"{key}\",H200,vulkan,discretegpu,ok,,{ms},{},{},,0,0,true,,,,4096,1,2,0,{limits},{split}",
            ms * 0.99,
            ms * 1.01
        )
    };
    let rows = [r("adapter", "", 2.0), r("webgpu", "bindings:2", 2.04)];
    std::fs::write(d.join("runs.csv"), format!("{h}\n{}\n", rows.join("\n"))).unwrap();
    let page = report::build(&d, None).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("×1.020 of unsplit"), "{html}");
    assert!(html.contains("H200 (vulkan, webgpu limits)"), "{html}");
}

#[test]
fn a_views_run_draws_flicker_against_time_and_error_and_popping_along_the_path() {
    let d = tmp("views");
    let header = "schema,run_id,suite,study,scene,scene_label,width,height,method,point_key,adapter,backend,device_type,status,gpu_ms_median,gpu_ms_path_p99,rmse,exact,layers,camera_path,pop_epsilon,flicker_mean,popping_mean,path_series";
    let scene = "shells(camera_path=orbit,path_views=4)";
    // One exact row (no flicker, no popping: drawn in the zero band) and a k-buffer whose
    // tail pops at view 2.
    let series = |rmse: [f64; 4], popping: [f64; 3]| {
        format!(
            "\"{{\"\"gpu_ms\"\":[1,1,1,1],\"\"rmse\"\":{rmse:?},\"\"flip\"\":[null,null,null,null],\"\"flicker\"\":[null,0,0,0],\"\"popping\"\":[null,{},{},{}],\"\"changed\"\":[null,0.5,0.5,0.5],\"\"exact\"\":[true,true,true,true]}}\"",
            popping[0], popping[1], popping[2]
        )
    };
    let rows = [
        format!(
            "1,r,views,views,shells,\"{scene}\",64,64,depth_peel,\"views|{scene}|64x64|depth_peel|\",lavapipe,vulkan,cpu,ok,2.0,2.5,0,true,,orbit,0.01,0,0,{}",
            series([0.0; 4], [0.0; 3])
        ),
        format!(
            "1,r,views,views,shells,\"{scene}\",64,64,kbuffer_atomic,\"views|{scene}|64x64|kbuffer_atomic|layers=2\",lavapipe,vulkan,cpu,ok,1.0,1.4,0.01,false,2,orbit,0.01,0.002,0.05,{}",
            series([0.01, 0.012, 0.03, 0.011], [0.0, 0.15, 0.01])
        ),
    ];
    std::fs::write(
        d.join("runs.csv"),
        format!("{header}\n{}\n", rows.join("\n")),
    )
    .unwrap();
    let page = report::build(&d, None).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("Views that move"), "the views section");
    check_layouts(&d.join("report"));
    let names: Vec<String> = std::fs::read_dir(d.join("report"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("views_") && n.ends_with(".png"))
        .collect();
    for kind in ["_flicker.png", "_error.png", "_popping.png"] {
        assert!(
            names.iter().any(|n| n.ends_with(kind)),
            "no {kind} in {names:?}"
        );
    }
}

/// The image and chart paths a committed run's RUN.md (or any Markdown under
/// results/reference, or README.md) names, in a link or a code span: `report/<chart>` is redrawn by
/// `mfx report` (charts are not committed), so the run's report is built in a temp copy and the
/// chart must be there; any other path must be in the tree.
#[test]
fn every_image_a_committed_doc_names_resolves() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut docs = vec![root.join("README.md")];
    let mut stack = vec![root.join("results/reference")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "md") {
                docs.push(p);
            }
        }
    }
    let is_image = |s: &str| {
        [".png", ".svg", ".pdf", ".jpg"]
            .iter()
            .any(|x| s.ends_with(x))
    };
    let (mut in_tree, mut redrawn, mut bad) = (0, 0, Vec::new());
    for doc in &docs {
        let text = std::fs::read_to_string(doc).unwrap();
        // Code spans (odd pieces between backticks) and link targets `](…)` / `src="…"`.
        let mut paths: Vec<&str> = text.split('`').skip(1).step_by(2).collect();
        for open in ["](", "src=\""] {
            paths.extend(
                text.split(open)
                    .skip(1)
                    .filter_map(|s| s.split([')', '"', ' ']).next()),
            );
        }
        // A path (it has a folder), not a pattern (`p*-…`, `0-…-512x512`) nor a web address.
        paths.retain(|p| {
            is_image(p)
                && p.contains('/')
                && !p.contains(['*', '…', '<', ' '])
                && !p.contains("://")
        });
        if paths.is_empty() {
            continue;
        }
        let dir = doc.parent().unwrap();
        let mut report: Option<Tmp> = None;
        for p in paths {
            if let Some(chart) = p.strip_prefix("report/") {
                let out = report.get_or_insert_with(|| {
                    let t = tmp("cited");
                    for f in ["runs.csv", "run.json"] {
                        if dir.join(f).is_file() {
                            std::fs::copy(dir.join(f), t.join(f)).unwrap();
                        }
                    }
                    report::build(&t, None).unwrap_or_else(|e| panic!("{}: {e:#}", doc.display()));
                    t
                });
                redrawn += 1;
                if !out.join("report").join(chart).is_file() {
                    // The charts it does draw of the same kind, to name the new one.
                    let kind = chart.split('_').next().unwrap_or(chart);
                    let ext = Path::new(chart).extension().unwrap_or_default();
                    let drawn: Vec<String> = std::fs::read_dir(out.join("report"))
                        .unwrap()
                        .map(|e| e.unwrap().path())
                        .filter(|f| f.extension() == Some(ext))
                        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
                        .filter(|n| n.starts_with(kind))
                        .collect();
                    bad.push(format!(
                        "{}: {p} is not drawn by mfx report (it draws {drawn:?})",
                        doc.display()
                    ));
                }
            } else {
                in_tree += 1;
                if !dir.join(p).is_file() && !root.join(p).is_file() {
                    bad.push(format!("{}: {p}", doc.display()));
                }
            }
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
    // The reference runs cite charts (redrawn) today; a doc that cites none is fine, but the
    // scan must have found what is there.
    assert!(
        redrawn + in_tree >= 2,
        "{redrawn} redrawn, {in_tree} in the tree"
    );
}
