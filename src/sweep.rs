//! `mfx sweep`: a suite into a run folder that says how it was made (`run.json`), never loses
//! a row (a folder with a `runs.csv` is refused unless `--resume` or `--force`), stops cleanly
//! on SIGINT/SIGTERM after the row in flight, and exits with codes scripts can trust.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use bench_core::manifest::{context_block, write_runs_json, AdapterInfo, RunManifest};
use bench_core::record::{cols, CsvSink, Row, SamplesSink, Sink, Status, SCHEMA_VERSION};
use bench_core::runner::{self, RunOptions};
use bench_core::studies::Group;
use bench_core::Gpu;
use clap::Args;

use crate::{checked_suite, usage, GpuArgs};

#[derive(Args)]
pub struct SweepArgs {
    /// A suite name (`mfx list suites`) or a TOML path.
    pub suite: String,
    /// Output folder (default results/<run_id>/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run shard I of N (e.g. 0/4): every scene group lands in exactly one shard.
    #[arg(long, value_parser = crate::parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// With --shard: balance the shards by each group's time in this earlier run (a run folder,
    /// a folder of shard folders, or a runs table) instead of group index mod N. Give every shard
    /// of a job the same run.
    #[arg(long, value_name = "RUN", requires = "shard")]
    pub balance_from: Option<PathBuf>,
    /// Continue the run in --out: only the points without a row are run, appended.
    #[arg(long, conflicts_with = "force")]
    pub resume: bool,
    /// Start again in an --out that already holds a runs.csv (its run files are replaced).
    #[arg(long)]
    pub force: bool,
    /// Exit 0 even when rows failed (they are listed either way).
    #[arg(long)]
    pub accept_failures: bool,
    /// Skip the report after the sweep.
    #[arg(long)]
    pub no_report: bool,
    /// Save each point's image as OUT/images/<hash>.npy (for cross-backend comparison).
    #[arg(long)]
    pub save_images: bool,
    /// No FLIP (it costs ~0.1 s per 1024² image row on 16 cores; the columns stay empty).
    #[arg(long)]
    pub no_flip: bool,
    /// Keep the method image, ground truth and FLIP map of the N worst rows in OUT/flip/.
    #[arg(long, default_value_t = 8)]
    pub flip_worst: usize,
    /// Save the finished run as a named baseline (results/baselines/NAME).
    #[arg(long)]
    pub save_baseline: Option<String>,
    /// Compare the finished run with a named baseline (as `mfx compare`).
    #[arg(long)]
    pub baseline: Option<String>,
    /// With --baseline: exit 1 when a point is significantly slower by more than this (5%).
    #[arg(long, requires = "baseline")]
    pub fail_on_slower: Option<String>,
    /// Override a `[timing]` key of the suite (and of its `[software]` profile), e.g.
    /// `--timing settle=false --timing max_noise=0.01`; checked like the suite's own keys.
    #[arg(long = "timing", value_name = "KEY=VALUE")]
    pub timing: Vec<String>,
    /// Run only the points whose method, scene (generator or label) or point key matches this
    /// glob (`*`, `?`, `[…]`); repeatable: a point runs when any filter matches. The floors of
    /// a group run with its points (they are the yardstick of x_floor and the speedups).
    #[arg(long, value_name = "GLOB")]
    pub filter: Vec<String>,
    /// Override an axis of the suite's studies, e.g. `--set max_layers=4,8`: replaces that
    /// axis in every study whose methods declare it; checked like the suite's own values.
    #[arg(long = "set", value_name = "AXIS=V1,V2")]
    pub set: Vec<String>,
    /// Print the points the sweep would run (after --filter, --set, --shard) and exit.
    #[arg(long)]
    pub dry_run: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Where named baselines live.
pub fn baselines_root() -> PathBuf {
    PathBuf::from("results").join("baselines")
}

/// `--set AXIS=V1,V2`: replaces the axis in every study whose methods declare it (and in
/// their per-method tables); an axis no study uses is refused. The caller re-checks the suite.
fn apply_sets(suite: &mut scenarios::Suite, sets: &[String]) -> Result<()> {
    for s in sets {
        let (axis, vals) = s
            .split_once('=')
            .ok_or_else(|| usage(format!("--set '{s}': must be AXIS=V1,V2,…")))?;
        let axis = axis.trim();
        let mut values = Vec::new();
        for v in vals.split(',').map(str::trim) {
            if v.is_empty() {
                return Err(usage(format!("--set '{s}': an empty value")));
            }
            values.push(crate::parse_kv(&format!("{axis}={v}"))?.1);
        }
        let mut used = false;
        let mut known = std::collections::BTreeSet::new();
        for spec in &mut suite.studies {
            let declared = spec.methods.iter().any(|m| {
                bench_core::methods::by_name(m).is_some_and(|m| {
                    m.axes().iter().any(|a| {
                        known.insert(a.name().to_string());
                        a.name() == axis
                    })
                })
            });
            if declared || spec.axes.contains_key(axis) {
                spec.axes.insert(axis.to_string(), values.clone());
                for t in spec.method_axes.values_mut() {
                    if let Some(v) = t.get_mut(axis) {
                        *v = values.clone();
                    }
                }
                used = true;
            }
        }
        if !used {
            return Err(usage(format!(
                "--set '{s}': no study of suite '{}' has a method with axis '{axis}' (axes of its methods: {})",
                suite.name,
                known.into_iter().collect::<Vec<_>>().join(", ")
            )));
        }
    }
    let problems = bench_core::check::check_suite(suite);
    if !problems.is_empty() {
        return Err(usage(format!(
            "--set {}: {}",
            sets.join(" --set "),
            scenarios::problem::report(&problems)
        )));
    }
    Ok(())
}

/// `--filter` globs, compiled (a bad pattern is a usage error).
fn filters(globs: &[String]) -> Result<Vec<glob::Pattern>> {
    globs
        .iter()
        .map(|g| glob::Pattern::new(g).map_err(|e| usage(format!("--filter '{g}': {e}"))))
        .collect()
}

/// The groups cut to the points a filter matches (by method, scene generator or label, or
/// point key); groups left with nothing are dropped. No filter keeps everything.
fn filter_groups(groups: Vec<Group>, pats: &[glob::Pattern]) -> Vec<Group> {
    if pats.is_empty() {
        return groups;
    }
    let any = |s: &str| pats.iter().any(|p| p.matches(s));
    groups
        .into_iter()
        .filter_map(|mut g| {
            if any(&g.scene.generator) || any(&g.scene.label()) {
                return Some(g);
            }
            let floor_matches = runner::FLOORS
                .iter()
                .any(|f| any(f) || any(&g.point_key(f, bench_core::axes::Point::empty().given())));
            let keys: Vec<bool> = g
                .points
                .iter()
                .map(|p| any(&p.method) || any(&g.point_key(&p.method, p.given())))
                .collect();
            let mut keep = keys.into_iter();
            g.points.retain(|_| keep.next().unwrap_or(false));
            (floor_matches || !g.points.is_empty()).then_some(g)
        })
        .collect()
}

/// The groups of this sweep on an adapter of this kind: expanded, sharded (by index mod N, or
/// balanced by a previous run's times), filtered; and each shard's estimated seconds when
/// balanced.
fn groups_for(
    suite: &scenarios::Suite,
    software: bool,
    shard: (usize, usize),
    balance: Option<&bench_core::shard::PreviousTimes>,
    pats: &[glob::Pattern],
) -> Result<(Vec<Group>, Vec<f64>)> {
    let groups = runner::expand(suite, software)?;
    let (mine, load) = match balance {
        Some(prev) => bench_core::shard::balanced(groups, shard, prev),
        None => (runner::shard_groups(groups, shard), Vec::new()),
    };
    Ok((filter_groups(mine, pats), load))
}

/// Rows a group still owes: its points and floors without a row in `done`.
fn owed(g: &Group, done: &std::collections::HashSet<String>) -> usize {
    let empty = bench_core::axes::Point::empty();
    g.points
        .iter()
        .filter(|p| !done.contains(&g.point_key(&p.method, p.given())))
        .count()
        + runner::FLOORS
            .iter()
            .filter(|f| !done.contains(&g.point_key(f, empty.given())))
            .count()
}

/// Where the sweep stands, for a log without a terminal: one line per finished group.
struct GroupLines {
    /// Rows owed by each group still to come, in run order.
    owed: Vec<usize>,
    next: usize,
    in_group: usize,
    rows_done: usize,
    rows_total: usize,
    started: std::time::Instant,
    /// Print the lines (no terminal to draw the bar on).
    print: bool,
}

impl GroupLines {
    fn row_done(&mut self) {
        self.rows_done += 1;
        self.in_group += 1;
        while self.next < self.owed.len() && self.in_group >= self.owed[self.next] {
            self.in_group -= self.owed[self.next];
            self.next += 1;
            if self.print {
                let el = self.started.elapsed();
                let left = self.rows_total.saturating_sub(self.rows_done);
                let eta = el.mul_f64(left as f64 / self.rows_done.max(1) as f64);
                eprintln!(
                    "mfx: group {}/{} done: {}/{} rows, elapsed {}, ETA {}",
                    self.next,
                    self.owed.len(),
                    self.rows_done,
                    self.rows_total,
                    indicatif::FormattedDuration(el),
                    indicatif::FormattedDuration(eta)
                );
            }
        }
    }
}

/// Counts and reasons of the rows a sweep writes; the CSV, samples and FLIP sinks behind it.
struct Progress<'a> {
    lines: GroupLines,
    csv: CsvSink,
    samples: SamplesSink,
    flip: mfx_flip::WorstKeeper,
    bar: &'a indicatif::ProgressBar,
    ok: usize,
    failed: Vec<(String, String)>,
    skipped: BTreeMap<String, usize>,
    /// Seconds of the rows' timed work, prepares, judging and fragment references (where the
    /// sweep's wall time went; the rest is scene building, floors' references, I/O).
    spent_s: [f64; 4],
}

impl Sink for Progress<'_> {
    fn point_done(&mut self, row: &Row) -> bench_core::Result<()> {
        self.csv.point_done(row)?;
        self.samples.point_done(row)?;
        let get = |c| row.get(c).unwrap_or("").to_string();
        if let Some(f) = &row.flip {
            self.flip.offer(
                &get(cols::POINT_KEY),
                &get(cols::METHOD),
                &get(cols::SCENE_LABEL),
                &f.result,
                &f.method_rgb8,
                &f.truth_rgb8,
                f.width,
                f.height,
            );
        }
        let ms = |c| {
            row.get(c)
                .and_then(|v| v.parse::<f64>().ok())
                .unwrap_or(0.0)
                / 1e3
        };
        for (acc, c) in self.spent_s.iter_mut().zip([
            cols::MEASURE_MS,
            cols::PREPARE_MS,
            cols::JUDGE_MS,
            cols::FRAGMENT_REFERENCE_MS,
        ]) {
            *acc += ms(c);
        }
        match row.status() {
            Some(Status::Failed) => {
                self.bar.println(format!(
                    "failed: {} — {}",
                    get(cols::POINT_KEY),
                    get(cols::REASON)
                ));
                self.failed.push((get(cols::POINT_KEY), get(cols::REASON)));
            }
            Some(Status::Skipped) => *self.skipped.entry(get(cols::REASON)).or_default() += 1,
            _ => self.ok += 1,
        }
        self.bar
            .set_message(format!("{} {}", get(cols::SCENE_LABEL), get(cols::METHOD)));
        self.bar.inc(1);
        self.lines.row_done();
        Ok(())
    }
}

pub fn sweep(a: &SweepArgs) -> Result<()> {
    // Everything that can be refused is refused before the GPU starts and before any file is
    // touched: the suite, the arguments, an occupied run folder.
    let mut suite = checked_suite(&a.suite)?;
    if !a.timing.is_empty() {
        let over = scenarios::suite::timing_overrides(&a.timing, "mfx sweep")
            .map_err(|e| usage(e.to_string()))?;
        suite.timing = suite.timing.overlay(&over);
        if let Some(sw) = &mut suite.software {
            sw.timing = sw.timing.overlay(&over);
        }
        bench_core::measure::TimingPlan::from_spec(&suite.timing_for(false))
            .map_err(|e| usage(format!("--timing: {e}")))?;
    }
    if !a.set.is_empty() {
        apply_sets(&mut suite, &a.set)?;
    }
    let pats = filters(&a.filter)?;
    let shard = a.shard.unwrap_or((0, 1));
    let balance = a
        .balance_from
        .as_deref()
        .map(bench_core::shard::PreviousTimes::read)
        .transpose()
        .map_err(|e| usage(format!("--balance-from: {e}")))?;
    // The points on either kind of adapter (the `[software]` profile may change resolutions):
    // a filter that matches nothing on both is a typo, refused now.
    let (on_gpu, load_gpu) = groups_for(&suite, false, shard, balance.as_ref(), &pats)
        .map_err(|e| usage(e.to_string()))?;
    let (on_software, load_software) = groups_for(&suite, true, shard, balance.as_ref(), &pats)
        .map_err(|e| usage(e.to_string()))?;
    if !pats.is_empty() && on_gpu.is_empty() && on_software.is_empty() {
        return Err(usage(format!(
            "--filter {}: matches no method, scene or point key of suite '{}'{} (`--dry-run` without --filter lists them)",
            a.filter.join(" --filter "),
            suite.name,
            if shard.1 > 1 { format!(" in shard {}/{}", shard.0, shard.1) } else { String::new() }
        )));
    }
    if a.dry_run {
        print_points(&suite, &on_gpu, &on_software);
        if !load_gpu.is_empty() {
            let fmt = |l: &[f64]| {
                l.iter()
                    .enumerate()
                    .map(|(i, s)| format!("{i}: {s:.0} s"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            println!(
                "shards balanced by {}'s times, estimated seconds per shard on a GPU: {}; on a software adapter: {}",
                a.balance_from.as_deref().unwrap_or(Path::new("?")).display(),
                fmt(&load_gpu),
                fmt(&load_software)
            );
        }
        return Ok(());
    }
    let fail_frac = a
        .fail_on_slower
        .as_deref()
        .map(report::ab::parse_fraction)
        .transpose()
        .map_err(|e| usage(format!("--fail-on-slower: {e}")))?;
    for name in a.save_baseline.iter().chain(&a.baseline) {
        if name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.') {
            return Err(usage(format!(
                "baseline name '{name}' must be a plain name"
            )));
        }
    }
    // The baseline to compare with must exist now, not after the whole sweep.
    if let Some(name) = &a.baseline {
        report::ab::baseline_dir(&baselines_root(), name)
            .map_err(|e| usage(format!("--baseline: {e:#}")))?;
    }
    let stamp = crate::chrono_stamp();
    let mut run_id = if shard.1 > 1 {
        format!("{stamp}-{}-shard{}of{}", suite.name, shard.0, shard.1)
    } else {
        format!("{stamp}-{}", suite.name)
    };
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(&run_id));
    let csv_path = out.join("runs.csv");
    let mut done = std::collections::HashSet::new();
    let mut earlier: Option<RunManifest> = None;
    if csv_path.is_file() {
        if a.resume {
            let cut = bench_core::record::drop_partial_tail(&csv_path)?;
            if cut > 0 {
                eprintln!(
                    "mfx: {}: dropped a half-written last line ({cut} B) left by the interrupted run",
                    csv_path.display()
                );
            }
        }
        let (keys, old_run) = bench_core::record::existing_points(&csv_path)
            .with_context(|| format!("reading {}", csv_path.display()))?;
        if a.resume {
            if let Ok(m) = RunManifest::read(&out) {
                earlier = Some(m.clone());
                if m.suite_sha256 != bench_core::manifest::sha256_hex(&suite.text) {
                    return Err(usage(format!(
                        "{} was run with another suite text ({} from {}); resuming it with {} would mix two suites: use a new --out",
                        out.display(),
                        m.suite_name,
                        m.suite_source,
                        suite.source
                    )));
                }
                if m.limits != a.gpu.limits() {
                    return Err(usage(format!(
                        "{} was run with --limits {}; resuming it with --limits {} would mix two limits profiles: use a new --out",
                        out.display(),
                        m.limits,
                        a.gpu.limits()
                    )));
                }
            }
            let samples = out.join("samples.csv");
            if samples.is_file() {
                bench_core::record::drop_partial_tail(&samples)?;
                bench_core::record::retain_samples(&samples, &keys)?;
            }
            done = keys;
            if let Some(r) = old_run {
                run_id = r;
            }
        } else if !a.force {
            return Err(usage(format!(
                "{} already holds a runs.csv ({} rows): --resume runs only its missing points, --force starts again (replacing it)",
                out.display(),
                keys.len()
            )));
        }
    } else if a.resume {
        return Err(usage(format!(
            "--resume: {} holds no runs.csv to continue",
            out.display()
        )));
    }

    bench_core::interrupt::install()?;
    let gpu = Gpu::new(&a.gpu.options())?;
    let (groups, load) = if gpu.facts.is_software {
        (on_software, load_software)
    } else {
        (on_gpu, load_gpu)
    };
    if groups.is_empty() {
        return Err(usage(format!(
            "--filter {}: matches no point on {} (a {} adapter); see --dry-run",
            a.filter.join(" --filter "),
            gpu.facts.name,
            if gpu.facts.is_software {
                "software"
            } else {
                "GPU"
            }
        )));
    }
    let total = runner::rows_in(&groups);
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    // Studies that write images (shadows) put them beside the CSV.
    std::env::set_var("MFX_OUT_DIR", &out);
    let mut manifest = RunManifest::new(
        std::env::args().collect(),
        &suite.name,
        &suite.source,
        &suite.text,
        AdapterInfo::of(&gpu.adapter.get_info()),
        shard,
    );
    if let Some(old) = &earlier {
        manifest.continue_from(old);
    }
    manifest.software_profile = gpu.facts.is_software && suite.software.is_some();
    manifest.limits = gpu.profile;
    manifest.points_total = total;
    manifest.gpu = bench_core::manifest::GpuIdentity::of(&gpu);
    manifest.shard_balance =
        a.balance_from
            .as_ref()
            .map(|from| bench_core::manifest::ShardBalance {
                from: from.display().to_string(),
                rule: bench_core::shard::RULE.to_string(),
                estimated_s: load.clone(),
            });
    manifest.resumed_points = done.len();
    // The cross-GPU calibration set, before any point (a software adapter's time says nothing
    // of a GPU, and would cost seconds).
    if !gpu.facts.is_software {
        let runs = bench_core::manifest::CALIBRATION_RUNS;
        manifest.calibration =
            gpu.calibration_ms(runs)?
                .map(|canary_ms| bench_core::manifest::GpuCalibration {
                    set: bench_core::manifest::CALIBRATION_SET.into(),
                    canary_ms,
                    runs,
                });
    }
    manifest.write(&out)?;
    eprintln!(
        "mfx: suite '{}' on {} ({}, {}){}: {} groups, {total} rows{} -> {}",
        suite.name,
        gpu.facts.name,
        gpu.facts.backend,
        gpu.facts.device_type,
        if gpu.facts.is_software && suite.software.is_some() {
            " [software profile]"
        } else {
            ""
        },
        groups.len(),
        if done.is_empty() {
            String::new()
        } else {
            format!(
                " ({} already in {}: resumed)",
                done.len(),
                csv_path.display()
            )
        },
        csv_path.display()
    );
    if let Err(why) = &gpu.monitor {
        eprintln!("mfx: no GPU clocks recorded: {why}");
    }
    let bar = indicatif::ProgressBar::new((total - done.len().min(total)) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} [{elapsed} elapsed, ETA {eta}] {msg}",
        )
        .unwrap(),
    );
    // Without a terminal (a log, CI) the bar draws nothing: a line per finished group instead.
    let terminal =
        std::io::IsTerminal::is_terminal(&std::io::stderr()) && std::env::var_os("CI").is_none();
    if !terminal {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let owed_rows: Vec<usize> = groups
        .iter()
        .map(|g| owed(g, &done))
        .filter(|&n| n > 0)
        .collect();
    let resume = !done.is_empty() || a.resume;
    let mut sink = Progress {
        lines: GroupLines {
            rows_total: owed_rows.iter().sum(),
            owed: owed_rows,
            next: 0,
            in_group: 0,
            rows_done: 0,
            started: std::time::Instant::now(),
            print: !terminal,
        },
        csv: if resume {
            CsvSink::append(&csv_path)?
        } else {
            CsvSink::create(&csv_path)?
        },
        samples: SamplesSink::open(&out.join("samples.csv"), resume)?,
        flip: mfx_flip::WorstKeeper::new(if a.no_flip { 0 } else { a.flip_worst }),
        bar: &bar,
        ok: 0,
        failed: Vec::new(),
        skipped: BTreeMap::new(),
        spent_s: [0.0; 4],
    };
    let opts = RunOptions {
        run_id,
        git_rev: runner::git_rev(),
        shard,
        save_images: a.save_images.then(|| out.clone()),
        flip: !a.no_flip,
        done,
        interrupted: Some(bench_core::interrupt::requested),
        row_cells: bench_core::manifest::row_cells(&manifest.gpu, &manifest.job),
    };
    let outcome = runner::run(&gpu, &suite, &groups, &opts, &mut sink);
    bar.finish_and_clear();
    let outcome = match outcome {
        Ok(o) => o,
        Err(e) => {
            manifest.rows_written =
                sink.ok + sink.failed.len() + sink.skipped.values().sum::<usize>();
            manifest.finish(Some(&format!("error: {e}")));
            manifest.write(&out)?;
            return Err(e.into());
        }
    };
    if !a.no_flip && a.flip_worst > 0 && !sink.flip.is_empty() {
        sink.flip.write(&out)?;
    }
    let skipped: usize = sink.skipped.values().sum();
    manifest.rows_written = outcome.written;
    manifest.rows_ok = sink.ok;
    manifest.rows_failed = sink.failed.len();
    manifest.rows_skipped = skipped;
    manifest.finished =
        outcome.interrupted.is_none() && outcome.already_done + outcome.written == total;
    manifest.finish(outcome.interrupted);
    manifest.write(&out)?;
    let clocks = gpu.monitor.as_ref().ok().map(|m| {
        serde_json::Value::Object(
            m.context()
                .into_iter()
                .map(|(k, v)| (k.to_string(), serde_json::Value::String(v)))
                .collect(),
        )
    });
    write_runs_json(&out, &context_block(&manifest, SCHEMA_VERSION, clocks))?;
    // The typed twin: every column as schema declares it, run.json in its metadata.
    let typed = mfx_table::write_runs_parquet(&out)?;
    if !typed.text_fallback.is_empty() {
        eprintln!(
            "mfx: warning: a cell off its column's declared type (a bug to report):\n{}",
            typed.describe()
        );
    }

    // What happened, in words a log keeps (no terminal needed).
    eprintln!(
        "mfx: wrote {} rows ({} ok, {} failed, {skipped} skipped) to {}{}",
        outcome.written,
        sink.ok,
        sink.failed.len(),
        csv_path.display(),
        if outcome.already_done > 0 {
            format!("; {} rows were already there", outcome.already_done)
        } else {
            String::new()
        }
    );
    let [m, p, j, r] = sink.spent_s;
    eprintln!(
        "mfx: time in rows: {m:.1} s timed (warm-up, clock lift, samples), {p:.1} s prepare, {j:.1} s judging, {r:.1} s f64 fragment references"
    );
    for (key, why) in &sink.failed {
        eprintln!("  failed: {key}: {why}");
    }
    for (why, n) in &sink.skipped {
        eprintln!("  skipped ×{n}: {why}");
    }
    if let Some(sig) = outcome.interrupted {
        eprintln!(
            "mfx: interrupted by {sig}: {} of {total} points have a row; resume with:\n  mfx sweep {} --out {} --resume",
            outcome.already_done + outcome.written,
            a.suite,
            out.display()
        );
        std::process::exit(if sig == "SIGTERM" { 143 } else { 130 });
    }
    let runs = report::Runs::load(&csv_path)?;
    eprintln!("\n{}", report::summary_text(&runs));
    if !a.no_report {
        let page =
            report::build(&out, None).with_context(|| format!("report of {}", out.display()))?;
        eprintln!("mfx: report {}", page.display());
    }
    if let Some(name) = &a.save_baseline {
        let dir = report::ab::save_baseline(&out, &baselines_root(), name)?;
        eprintln!("mfx: baseline '{name}' saved in {}", dir.display());
    }
    let mut slower = 0;
    if let Some(name) = &a.baseline {
        let base = report::ab::baseline_dir(&baselines_root(), name)?;
        let cmp = report::ab::compare_runs(&base, &out, &Default::default())?;
        println!("{}", cmp.markdown());
        if let Some(f) = fail_frac {
            slower = cmp.slower_beyond(f).len();
        }
    }
    if !sink.failed.is_empty() && !a.accept_failures {
        bail!(
            "{} of {total} rows failed (listed above; --accept-failures to exit 0)",
            sink.failed.len()
        );
    }
    if slower > 0 {
        bail!("{slower} points are significantly slower than the baseline beyond the limit");
    }
    Ok(())
}

/// `--dry-run`: the points, one line each, as the sweep would run them.
fn print_points(suite: &scenarios::Suite, on_gpu: &[Group], on_software: &[Group]) {
    for g in on_gpu {
        println!("{} {} {}x{}", g.kind, g.scene.label(), g.width, g.height);
        let empty = bench_core::axes::Point::empty();
        for f in runner::FLOORS {
            println!("  {}", g.point_key(f, empty.given()));
        }
        for p in &g.points {
            println!("  {}", g.point_key(&p.method, p.given()));
        }
    }
    println!(
        "dry run: {} groups, {} rows on a GPU{}; nothing was run",
        on_gpu.len(),
        runner::rows_in(on_gpu),
        if suite.software.is_some() {
            format!(
                " ({} groups, {} rows on a software adapter, with the [software] profile)",
                on_software.len(),
                runner::rows_in(on_software)
            )
        } else {
            String::new()
        }
    );
}

/// `mfx compare BASE NEW`.
/// `mfx compare`'s options.
pub struct CompareArgs<'a> {
    pub noise_band: Option<&'a str>,
    pub alpha: Option<f64>,
    pub fail_on_slower: Option<&'a str>,
    pub html: Option<&'a Path>,
    pub band_from: Option<&'a Path>,
    pub scale_new: Option<f64>,
    pub json: bool,
}

/// `mfx calibrate`: A/A runs → calibration file (and its summary on stdout).
pub fn calibrate(
    runs: &[PathBuf],
    out: &Path,
    noise_band: Option<&str>,
    margin: f64,
) -> Result<()> {
    let mut opts = report::ab::AbOptions::default();
    if let Some(b) = noise_band {
        opts.verdict.noise_band =
            report::ab::parse_fraction(b).map_err(|e| usage(format!("--noise-band: {e}")))?;
    }
    let c =
        report::calibrate::calibrate(runs, &opts, margin).map_err(|e| usage(format!("{e:#}")))?;
    print!("{}", c.markdown());
    c.save(out)?;
    eprintln!("mfx: calibration {}", out.display());
    Ok(())
}

pub fn compare(base: &Path, new: &Path, a: CompareArgs) -> Result<()> {
    let CompareArgs {
        noise_band,
        alpha,
        fail_on_slower,
        html,
        band_from,
        scale_new,
        json,
    } = a;
    let mut opts = report::ab::AbOptions::default();
    if let Some(b) = noise_band {
        opts.verdict.noise_band =
            report::ab::parse_fraction(b).map_err(|e| usage(format!("--noise-band: {e}")))?;
    }
    if let Some(f) = band_from {
        opts.calibration = Some(
            report::calibrate::Calibration::load(f)
                .map_err(|e| usage(format!("--band-from: {e:#}")))?,
        );
    }
    if let Some(x) = scale_new {
        if !(x.is_finite() && x > 0.0) {
            return Err(usage(format!("--scale-new {x} must be a positive number")));
        }
        opts.scale_new = x;
    }
    if let Some(a) = alpha {
        if !(a > 0.0 && a < 1.0) {
            return Err(usage(format!("--alpha {a} must be in (0, 1)")));
        }
        opts.verdict.alpha = a;
    }
    let frac = fail_on_slower
        .map(report::ab::parse_fraction)
        .transpose()
        .map_err(|e| usage(format!("--fail-on-slower: {e}")))?;
    let r = report::ab::compare_runs(base, new, &opts).map_err(|e| usage(format!("{e:#}")))?;
    if json {
        println!("{}", serde_json::to_string_pretty(&compare_json(&r))?);
    } else {
        print!("{}", r.markdown());
    }
    // The page is written only where asked: comparing against a committed reference run must
    // not change the tree it reads.
    if let Some(dir) = html {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let page = r.write_html(dir)?;
        eprintln!("mfx: comparison page {}", page.display());
    }
    if let Some(f) = frac {
        let s = r.slower_beyond(f);
        if !s.is_empty() {
            bail!(
                "{} points are significantly slower by more than {:.1} %",
                s.len(),
                f * 100.0
            );
        }
    }
    Ok(())
}

/// `mfx compare --json`: the comparison's points, verdicts and moves as one object (the same
/// content as the Markdown, for scripts).
fn compare_json(r: &report::ab::AbReport) -> serde_json::Value {
    use serde_json::json;
    let side = |s: &report::ab::Side| {
        json!({
            "runs_csv": s.runs_csv.display().to_string(),
            "samples_csv": s.samples_csv.as_ref().map(|p| p.display().to_string()),
            "schema": s.schema,
            "platforms": s.platforms,
            "run_ids": s.run_ids,
            "git_revs": s.git_revs,
        })
    };
    let verdict = |c: &mfx_stats::Comparison| {
        json!({
            "verdict": c.verdict.to_string(),
            "ratio": c.ratio,
            "ratio_ci": [c.ratio_ci.0, c.ratio_ci.1],
            "p": c.p,
            "n_base": c.n_base,
            "n_new": c.n_new,
            "basis": format!("{:?}", c.basis),
            "why": c.why,
        })
    };
    let points: Vec<_> = r
        .points
        .iter()
        .map(|p| {
            json!({
                "point_key": p.key,
                "platform_base": p.platform_base,
                "platform_new": p.platform_new,
                "base_median_ms": p.base_median_ms,
                "new_median_ms": p.new_median_ms,
                "time": verdict(&p.time),
                "cycles": p.cycles.as_ref().map(verdict),
                "base_sm_mhz": p.base_sm_mhz,
                "new_sm_mhz": p.new_sm_mhz,
                "base_noisy": p.base_noisy,
                "new_noisy": p.new_noisy,
            })
        })
        .collect();
    json!({
        "base": side(&r.base),
        "new": side(&r.new),
        "noise_band": r.opts.verdict.noise_band,
        "alpha": r.opts.verdict.alpha,
        "points": points,
        "only_base": r.only_base,
        "only_new": r.only_new,
        "untimed": r.untimed,
        "errors": r.errors.iter().map(|e| json!({
            "point_key": e.key, "column": e.column.name, "base": e.base, "new": e.new,
        })).collect::<Vec<_>>(),
        "status_changes": r.status_changes.iter().map(|c| json!({
            "point_key": c.key, "base": c.base, "new": c.new, "reason": c.reason,
        })).collect::<Vec<_>>(),
    })
}
