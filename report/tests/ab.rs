//! `mfx compare` on synthetic run folders written here: self-compare is SAME everywhere, a copy
//! 1.5× slower is SLOWER everywhere (from raw samples and from summary columns alone), mixed
//! schema versions are refused, moved errors are listed, baselines round-trip.

use std::fmt::Write;
use std::path::Path;

use mfx_analysis::ab::{baseline_dir, compare_runs, parse_fraction, save_baseline, AbOptions};
use mfx_stats::{Summary, Verdict};
use report::ab::{markdown, rule_text, write_html};

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
    tmp_dir(&format!("mfx-ab-{name}"))
}

/// Deterministic noise in [−1, 1) (splitmix64 of the index).
fn pseudo(i: u64) -> f64 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    ((z >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

struct Spec<'a> {
    schema: u32,
    adapter: &'a str,
    /// Multiplies every time.
    scale: f64,
    /// SM clock of every sample (None: no clocks recorded).
    clock: Option<f64>,
    /// Adds to every rmse.
    rmse_shift: f64,
    samples: bool,
    /// `[timing] sessions`: one time multiplier per session, N samples each, written with a
    /// `session` column (empty: one session, no such column, as older runs wrote).
    states: &'a [f64],
}

impl Default for Spec<'_> {
    fn default() -> Self {
        Spec {
            schema: 2,
            adapter: "NVIDIA H200",
            scale: 1.0,
            clock: Some(1980.0),
            rmse_shift: 0.0,
            samples: true,
            states: &[],
        }
    }
}

const POINTS: usize = 6;
const N: usize = 20;

/// A run folder: POINTS points, N samples each of 1 % noise around 0.5·(i+1) ms.
fn write_run(dir: &Path, s: &Spec) {
    let mut runs = String::from(
        "schema,run_id,git_rev,point_key,adapter,backend,status,reason,flag,target_reached,\
         samples,gpu_ms_median,gpu_ms_min,gpu_ms_max,gpu_ms_ci_lo,gpu_ms_ci_hi,\
         sm_clock_mhz_mean,rmse,max_abs_err,matches_truth\n",
    );
    let mut samples = String::from(
        "point_key,run_id,adapter,sample,gpu_ms,cpu_ms,sm_clock_mhz,mem_clock_mhz,discarded,order",
    );
    samples += if s.states.is_empty() {
        "\n"
    } else {
        ",session\n"
    };
    let states: &[f64] = if s.states.is_empty() {
        &[1.0]
    } else {
        s.states
    };
    for p in 0..POINTS {
        let key = format!("methods|shells(count=4)|256x256|m{p}|layers=8");
        let base = 0.5 * (p + 1) as f64;
        let t: Vec<f64> = (0..N * states.len())
            .map(|i| s.scale * states[i / N] * base * (1.0 + 0.01 * pseudo((p * 1000 + i) as u64)))
            .collect();
        let m = Summary::of(&t, 1).unwrap();
        let clock = s.clock.map(|c| c.to_string()).unwrap_or_default();
        let _ = writeln!(
            runs,
            "{},r1,abc123,\"{key}\",{},vulkan,ok,,,true,{N},{},{},{},{},{},{clock},{},0.01,true",
            s.schema,
            s.adapter,
            m.median,
            m.min,
            m.max,
            m.median_ci.0,
            m.median_ci.1,
            1e-3 * (p + 1) as f64 + s.rmse_shift,
        );
        for (i, x) in t.iter().enumerate() {
            let session = if s.states.is_empty() {
                String::new()
            } else {
                format!(",{}", i / N)
            };
            let _ = writeln!(
                samples,
                "\"{key}\",r1,{},{i},{x},{},{clock},2619,false,{}{session}",
                s.adapter,
                x + 0.1,
                i * POINTS + p
            );
        }
        // A throttled sample, far off, that must be ignored.
        let _ = writeln!(
            samples,
            "\"{key}\",r1,{},{},{},0,800,2619,true,0{}",
            s.adapter,
            t.len(),
            100.0 * base,
            if s.states.is_empty() { "" } else { ",0" }
        );
    }
    std::fs::write(dir.join("runs.csv"), runs).unwrap();
    if s.samples {
        std::fs::write(dir.join("samples.csv"), samples).unwrap();
    }
}

fn run(name: &str, s: Spec) -> Tmp {
    let d = tmp(name);
    write_run(&d, &s);
    d
}

#[test]
fn a_run_compared_with_itself_is_same_everywhere() {
    let a = run("self", Spec::default());
    let r = compare_runs(&a, &a, &AbOptions::default()).unwrap();
    assert_eq!(r.points.len(), POINTS);
    for p in &r.points {
        assert_eq!(p.time.verdict, Verdict::Same, "{p:?}");
        assert_eq!(p.cycles.as_ref().unwrap().verdict, Verdict::Same);
        assert_eq!(p.time.n_base, N, "the discarded sample is not counted");
    }
    assert!(r.errors.is_empty() && r.status_changes.is_empty());
    assert!(r.slower_beyond(0.0).is_empty());
    let md = markdown(&r);
    assert!(md.contains("SAME 6"), "{md}");
    // Summary columns only (no samples.csv): still SAME.
    let b = run(
        "self-summary",
        Spec {
            samples: false,
            ..Spec::default()
        },
    );
    let r = compare_runs(&b, &b, &AbOptions::default()).unwrap();
    assert!(r.points.iter().all(|p| p.time.verdict == Verdict::Same));
    assert_eq!(r.summary_only(), POINTS);
    assert!(markdown(&r).contains("summary columns only"));
}

#[test]
fn sessions_in_different_states_are_unsure_not_slower_and_a_real_slowdown_stays_slower() {
    // Three sessions a point, each in one of two memory states 6 % apart (the H200's k-buffers):
    // BASE mostly in the fast state, NEW mostly in the slow one.
    let a = run(
        "states-a",
        Spec {
            states: &[1.0, 1.0, 1.06],
            ..Spec::default()
        },
    );
    let b = run(
        "states-b",
        Spec {
            states: &[1.06, 1.06, 1.0],
            ..Spec::default()
        },
    );
    // Pooled, NEW is 6 % slower; both sides show the same two states, so they are compared
    // state with state (fast with fast, slow with slow): SAME.
    let r = compare_runs(&a, &b, &AbOptions::default()).unwrap();
    for p in &r.points {
        assert!(p.new_median_ms / p.base_median_ms > 1.03, "{p:?}");
        assert_eq!(p.time.verdict, Verdict::Same, "{p:?}");
        assert_eq!(p.time.n_base, 3 * N);
        assert!(p.time.why.contains("mode-matched"), "{}", p.time.why);
    }
    assert!(rule_text(&r).contains("resamples sessions"));
    // The same states, every time 1.5× on NEW: SLOWER however the sessions are resampled.
    let c = run(
        "states-c",
        Spec {
            states: &[1.0, 1.0, 1.06],
            scale: 1.5,
            ..Spec::default()
        },
    );
    let r = compare_runs(&a, &c, &AbOptions::default()).unwrap();
    assert!(r.points.iter().all(|p| p.time.verdict == Verdict::Slower));
    // And a run with sessions against itself: SAME.
    let r = compare_runs(&a, &a, &AbOptions::default()).unwrap();
    assert!(r.points.iter().all(|p| p.time.verdict == Verdict::Same));
}

#[test]
fn a_copy_one_and_a_half_times_slower_is_slower_everywhere() {
    let a = run("base", Spec::default());
    let b = run(
        "slow",
        Spec {
            scale: 1.5,
            ..Spec::default()
        },
    );
    let r = compare_runs(&a, &b, &AbOptions::default()).unwrap();
    assert_eq!(r.points.len(), POINTS);
    for p in &r.points {
        assert_eq!(p.time.verdict, Verdict::Slower, "{p:?}");
        assert!((p.time.ratio - 1.5).abs() < 1e-9, "{}", p.time.ratio);
        assert!(p.time.p.unwrap() < 1e-6);
    }
    assert_eq!(r.slower_beyond(parse_fraction("5%").unwrap()).len(), POINTS);
    assert!(r.slower_beyond(0.6).is_empty(), "1.5× is not 60 % slower");
    // And the other way round.
    let r = compare_runs(&b, &a, &AbOptions::default()).unwrap();
    assert!(r.points.iter().all(|p| p.time.verdict == Verdict::Faster));
    // From summary columns alone: the medians' CIs separate.
    let a = run(
        "base-s",
        Spec {
            samples: false,
            ..Spec::default()
        },
    );
    let b = run(
        "slow-s",
        Spec {
            scale: 1.5,
            samples: false,
            ..Spec::default()
        },
    );
    let r = compare_runs(&a, &b, &AbOptions::default()).unwrap();
    for p in &r.points {
        assert_eq!(p.time.verdict, Verdict::Slower, "{p:?}");
        assert_eq!(p.time.p, None);
    }
}

#[test]
fn a_slower_clock_is_slower_in_time_but_same_in_cycles() {
    let a = run("clk-a", Spec::default());
    let b = run(
        "clk-b",
        Spec {
            scale: 1.5,
            clock: Some(1320.0),
            ..Spec::default()
        },
    );
    let r = compare_runs(&a, &b, &AbOptions::default()).unwrap();
    for p in &r.points {
        assert_eq!(p.time.verdict, Verdict::Slower);
        assert_eq!(p.cycles.as_ref().unwrap().verdict, Verdict::Same, "{p:?}");
    }
    // Without clocks there is no cycle verdict.
    let c = run(
        "clk-none",
        Spec {
            clock: None,
            ..Spec::default()
        },
    );
    let r = compare_runs(&a, &c, &AbOptions::default()).unwrap();
    assert!(r.points.iter().all(|p| p.cycles.is_none()));
}

#[test]
fn mixed_schema_versions_are_refused_naming_both() {
    let a = run("schema2", Spec::default());
    let b = run(
        "schema3",
        Spec {
            schema: 3,
            ..Spec::default()
        },
    );
    let e = compare_runs(&a, &b, &AbOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("schema version 2") && e.contains("schema version 3"),
        "{e}"
    );
    assert!(
        e.contains("mfx-ab-") && e.contains("schema2") && e.contains("schema3"),
        "{e}"
    );
}

#[test]
fn moved_errors_are_listed_and_rounding_is_not() {
    let a = run("err-a", Spec::default());
    // +1e-6 on every rmse: f32-rounding scale, under the 1e-4 floor.
    let b = run(
        "err-b",
        Spec {
            rmse_shift: 1e-6,
            ..Spec::default()
        },
    );
    let r = compare_runs(&a, &b, &AbOptions::default()).unwrap();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    // +1e-3: beyond both tolerances for every point (rmse 1e-3..6e-3).
    let c = run(
        "err-c",
        Spec {
            rmse_shift: 1e-3,
            ..Spec::default()
        },
    );
    let r = compare_runs(&a, &c, &AbOptions::default()).unwrap();
    assert_eq!(r.errors.len(), POINTS);
    assert!(r.errors.iter().all(|e| e.column == schema::cols::RMSE));
    assert!(markdown(&r).contains("Errors that moved (6)"));
}

#[test]
fn different_adapters_are_compared_and_named() {
    let a = run("ad-a", Spec::default());
    let b = run(
        "ad-b",
        Spec {
            adapter: "NVIDIA H100 80GB HBM3",
            ..Spec::default()
        },
    );
    let r = compare_runs(&a, &b, &AbOptions::default()).unwrap();
    assert_eq!(r.points.len(), POINTS);
    let md = markdown(&r);
    assert!(md.contains("Different platforms") && md.contains("H100") && md.contains("H200"));
    // The page is written, with one table row per point and the chart.
    let out = tmp("ad-html");
    let page = write_html(&r, &out).unwrap();
    let html = std::fs::read_to_string(page).unwrap();
    assert_eq!(html.matches("<tr><td>").count(), POINTS);
    assert!(html.contains("<svg") && html.contains("<circle"));
}

#[test]
fn points_on_one_side_only_are_listed() {
    let a = run("only-a", Spec::default());
    let b = tmp("only-b");
    write_run(&b, &Spec::default());
    // Drop the last point from NEW's runs.csv.
    let csv = std::fs::read_to_string(b.join("runs.csv")).unwrap();
    let kept: Vec<&str> = csv.lines().take(POINTS).collect();
    std::fs::write(b.join("runs.csv"), kept.join("\n") + "\n").unwrap();
    let r = compare_runs(&a, &b.join("runs.csv"), &AbOptions::default()).unwrap();
    assert_eq!(
        (r.points.len(), r.only_base.len(), r.only_new.len()),
        (POINTS - 1, 1, 0)
    );
    assert!(r.only_base[0].contains("|m5|"));
}

#[test]
fn baselines_round_trip_and_missing_ones_are_named() {
    let a = run("bl-run", Spec::default());
    let root = tmp("bl-root");
    let d = save_baseline(&a, &root, "main-h200").unwrap();
    assert!(d.join("runs.csv").is_file() && d.join("samples.csv").is_file());
    assert_eq!(baseline_dir(&root, "main-h200").unwrap(), d);
    let e = baseline_dir(&root, "nope").unwrap_err().to_string();
    assert!(e.contains("main-h200"), "{e}");
    assert!(save_baseline(&a, &root, "../escape").is_err());
    let r = compare_runs(&d, &a, &AbOptions::default()).unwrap();
    assert!(r.points.iter().all(|p| p.time.verdict == Verdict::Same));
}

#[test]
fn fractions_parse() {
    assert_eq!(parse_fraction("5%").unwrap(), 0.05);
    assert_eq!(parse_fraction(" 5 % ").unwrap(), 0.05);
    assert_eq!(parse_fraction("0.05").unwrap(), 0.05);
    assert!(parse_fraction("five").is_err());
    assert!(parse_fraction("-1%").is_err());
}

#[test]
fn gzipped_samples_are_read_like_plain_ones() {
    // Committed reference runs keep samples.csv.gz: the comparison must still use raw samples.
    use std::io::Write as _;
    let a = run("gz-base", Spec::default());
    let b = run(
        "gz-slow",
        Spec {
            scale: 1.5,
            ..Spec::default()
        },
    );
    let plain = compare_runs(&a, &b, &AbOptions::default()).unwrap();
    for d in [&a, &b] {
        let raw = std::fs::read(d.join("samples.csv")).unwrap();
        let f = std::fs::File::create(d.join("samples.csv.gz")).unwrap();
        let mut z = flate2::write::GzEncoder::new(f, flate2::Compression::default());
        z.write_all(&raw).unwrap();
        z.finish().unwrap();
        std::fs::remove_file(d.join("samples.csv")).unwrap();
    }
    let gz = compare_runs(&a, &b, &AbOptions::default()).unwrap();
    assert!(gz
        .base
        .samples_csv
        .as_ref()
        .unwrap()
        .ends_with("samples.csv.gz"));
    for (p, q) in plain.points.iter().zip(&gz.points) {
        assert_eq!(q.time.verdict, Verdict::Slower);
        assert!(q.time.p.is_some(), "p from raw samples");
        assert_eq!(p.time.ratio, q.time.ratio);
        assert_eq!(p.time.p, q.time.p);
    }
}

#[test]
fn ratios_off_the_scale_are_marked_with_their_value_not_clamped() {
    let a = run("scale-a", Spec::default());
    for (name, scale, text) in [("scale-hi", 7.49, "7.49×"), ("scale-lo", 0.197, "0.197×")] {
        let b = run(
            name,
            Spec {
                scale,
                ..Spec::default()
            },
        );
        let h = compare_runs(&a, &b, &AbOptions::default()).unwrap();
        let h = report::ab::html_page(&h).into_string();
        assert_eq!(h.matches("class=\"offscale\"").count(), POINTS, "{name}");
        assert!(h.contains(text), "{name}: the value is written");
        assert!(!h.contains("<circle"), "{name}: no dot at the edge");
    }
}
