//! `mfx sweep`: a suite into a run folder that says how it was made (`run.json`), never loses
//! a row (a folder with a `runs.csv` is refused unless `--resume` or `--force`), stops cleanly
//! on SIGINT/SIGTERM after the row in flight, and exits with codes scripts can trust.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use bench_core::manifest::{context_block, write_runs_json, AdapterInfo, RunManifest};
use bench_core::record::{cols, CsvSink, Row, SamplesSink, Sink, Status, SCHEMA_VERSION};
use bench_core::runner::{self, RunOptions};
use bench_core::study::Group;
use bench_core::Gpu;
use clap::Args;
use mfx::STUDIES;

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

/// `--set AXIS=V1,V2`: replaces the axis for every method that reads it, among the methods
/// `--filter` selects (the filter comes first: `--filter 'kbuffer_*' --set layers=8,16` touches
/// the k-buffers only). A method that declares the axis but reads it at none of its points
/// (`layers` of the linked list's counted pool) is left alone; an axis no selected method reads
/// is refused. The caller re-checks the suite.
fn apply_sets(suite: &mut scenarios::Suite, sets: &[String], pats: &[glob::Pattern]) -> Result<()> {
    // (study index, method) of every point the filter keeps, on either kind of adapter.
    let selected: Option<std::collections::BTreeSet<(usize, String)>> = if pats.is_empty() {
        None
    } else {
        let mut keep = std::collections::BTreeSet::new();
        for software in [false, true] {
            let groups =
                runner::expand(STUDIES, suite, software).map_err(|e| usage(e.to_string()))?;
            for g in filter_groups(groups, pats) {
                for p in &g.points {
                    keep.insert((g.study_index, p.method.clone()));
                }
            }
        }
        Some(keep)
    };
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
        let mut unread = Vec::new();
        for (si, spec) in suite.studies.iter_mut().enumerate() {
            let Some(study) = bench_core::study::by_kind(STUDIES, spec.kind) else {
                continue;
            };
            let points = bench_core::study::points(study, spec).unwrap_or_default();
            let chosen = |m: &str| {
                selected
                    .as_ref()
                    .is_none_or(|k| k.contains(&(si, m.to_string())))
            };
            let mut targets = Vec::new();
            for p in &points {
                let Some(a) = study
                    .axes(&p.method)
                    .into_iter()
                    .inspect(|a| {
                        known.insert(a.name().to_string());
                    })
                    .find(|a| a.name() == axis)
                else {
                    continue;
                };
                if !chosen(&p.method) || targets.contains(&p.method) {
                    continue;
                }
                match a.ignored_at(&p.point) {
                    None => targets.push(p.method.clone()),
                    Some(with) => unread.push(format!("{} ({with})", p.method)),
                }
            }
            for m in targets {
                unread.retain(|u| !u.starts_with(&format!("{m} (")));
                if spec.methods_given {
                    spec.method_axes
                        .entry(m)
                        .or_default()
                        .insert(axis.to_string(), values.clone());
                } else {
                    // A study of one implicit method: its axes are the study's.
                    spec.axes.insert(axis.to_string(), values.clone());
                }
                used = true;
            }
            // The study's own value of the axis, now replaced for every method that read it,
            // would name configurations that do not differ for the rest: it goes.
            if spec.method_axes.values().any(|o| o.contains_key(axis))
                && spec.axes.contains_key(axis)
            {
                let points = bench_core::study::points(study, spec).unwrap_or_default();
                let still_read = points.iter().any(|p| {
                    !spec
                        .method_axes
                        .get(&p.method)
                        .is_some_and(|o| o.contains_key(axis))
                        && study
                            .axes(&p.method)
                            .iter()
                            .any(|a| a.name() == axis && a.ignored_at(&p.point).is_none())
                });
                if !still_read {
                    spec.axes.remove(axis);
                }
            }
        }
        if !used {
            unread.sort();
            unread.dedup();
            return Err(usage(format!(
                "--set '{s}': no {}method of suite '{}' reads axis '{axis}'{} (axes of its methods: {})",
                if selected.is_some() { "selected " } else { "" },
                suite.name,
                if unread.is_empty() {
                    String::new()
                } else {
                    format!("; declared but unread by {}", unread.join(", "))
                },
                known.into_iter().collect::<Vec<_>>().join(", ")
            )));
        }
    }
    let problems = bench_core::check::check_suite(STUDIES, suite);
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
            let floor_matches = runner::FLOORS.iter().any(|f| {
                any(f.name())
                    || any(&g.point_key(f.name(), bench_core::axes::Point::empty().given()))
            });
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
    let groups = runner::expand(STUDIES, suite, software)?;
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
            .filter(|f| !done.contains(&g.point_key(f.name(), empty.given())))
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

/// `mfx sweep`, in its steps: everything that can be refused is refused before the GPU starts
/// and before any file is touched (the suite, the arguments, an occupied run folder); then the
/// GPU, the run record, the rows, and what the run says at its end.
pub fn sweep(a: &SweepArgs) -> Result<()> {
    let suite = suite_of(a)?;
    let plan = plan_points(a, &suite)?;
    if a.dry_run {
        print_points(&suite, &plan.on_gpu, &plan.on_software);
        print_balance(a, &plan);
        return Ok(());
    }
    let fail_frac = check_baseline_args(a)?;
    let mut folder = open_run_folder(a, &suite, plan.shard)?;

    bench_core::interrupt::install()?;
    let gpu = Gpu::new(&a.gpu.options())?;
    let (groups, load) = groups_on(a, &gpu, plan)?;
    let total = runner::rows_in(&groups);
    std::fs::create_dir_all(&folder.out)
        .with_context(|| format!("creating {}", folder.out.display()))?;
    // Studies that write images (shadows) put them beside the CSV.
    std::env::set_var("MFX_OUT_DIR", &folder.out);
    let mut manifest = start_manifest(a, &gpu, &suite, &folder, total, &load)?;
    announce(&gpu, &suite, &groups, total, &folder);

    let bar = progress_bar((total - folder.done.len().min(total)) as u64);
    let mut sink = Progress::open(a, &folder, &groups, &bar)?;
    let opts = RunOptions {
        run_id: folder.run_id.clone(),
        git_rev: runner::git_rev(),
        shard: folder.shard,
        save_images: a.save_images.then(|| folder.out.clone()),
        flip: !a.no_flip,
        done: std::mem::take(&mut folder.done),
        interrupted: Some(bench_core::interrupt::requested),
        row_cells: bench_core::manifest::row_cells(&manifest.gpu, &manifest.job),
    };
    let outcome = runner::run(&gpu, STUDIES, &suite, &groups, &opts, &mut sink);
    bar.finish_and_clear();
    let outcome = match outcome {
        Ok(o) => o,
        Err(e) => {
            manifest.rows_written =
                sink.ok + sink.failed.len() + sink.skipped.values().sum::<usize>();
            manifest.finish(Some(&format!("error: {e}")));
            manifest.write(&folder.out)?;
            return Err(e.into());
        }
    };
    if !a.no_flip && a.flip_worst > 0 && !sink.flip.is_empty() {
        sink.flip.write(&folder.out)?;
    }
    finish_manifest(&gpu, &mut manifest, &sink, &outcome, total, &folder.out)?;
    print_outcome(&sink, &outcome, &folder.csv_path);
    if let Some(sig) = outcome.interrupted {
        eprintln!(
            "mfx: interrupted by {sig}: {} of {total} points have a row; resume with:\n  mfx sweep {} --out {} --resume",
            outcome.already_done + outcome.written,
            a.suite,
            folder.out.display()
        );
        std::process::exit(if sig == "SIGTERM" { 143 } else { 130 });
    }
    after_run(a, &folder.out, fail_frac, &sink, total)
}

/// The suite as checked, with `--timing` and `--set` applied and checked again.
fn suite_of(a: &SweepArgs) -> Result<scenarios::Suite> {
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
    // The filter first: `--set` touches only the methods it selects.
    if !a.set.is_empty() {
        let pats = filters(&a.filter)?;
        apply_sets(&mut suite, &a.set, &pats)?;
    }
    Ok(suite)
}

/// The points of this sweep on either kind of adapter.
struct PointPlan {
    shard: (usize, usize),
    on_gpu: Vec<Group>,
    on_software: Vec<Group>,
    /// Estimated seconds per shard when balanced by a previous run (else empty).
    load_gpu: Vec<f64>,
    load_software: Vec<f64>,
}

/// The points on either kind of adapter (the `[software]` profile may change resolutions): a
/// filter that matches nothing on both is a typo, refused now.
fn plan_points(a: &SweepArgs, suite: &scenarios::Suite) -> Result<PointPlan> {
    let pats = filters(&a.filter)?;
    let shard = a.shard.unwrap_or((0, 1));
    let balance = a
        .balance_from
        .as_deref()
        .map(bench_core::shard::PreviousTimes::read)
        .transpose()
        .map_err(|e| usage(format!("--balance-from: {e}")))?;
    let (on_gpu, load_gpu) = groups_for(suite, false, shard, balance.as_ref(), &pats)
        .map_err(|e| usage(e.to_string()))?;
    let (on_software, load_software) = groups_for(suite, true, shard, balance.as_ref(), &pats)
        .map_err(|e| usage(e.to_string()))?;
    if !pats.is_empty() && on_gpu.is_empty() && on_software.is_empty() {
        return Err(usage(format!(
            "--filter {}: matches no method, scene or point key of suite '{}'{} (`--dry-run` without --filter lists them)",
            a.filter.join(" --filter "),
            suite.name,
            if shard.1 > 1 { format!(" in shard {}/{}", shard.0, shard.1) } else { String::new() }
        )));
    }
    Ok(PointPlan {
        shard,
        on_gpu,
        on_software,
        load_gpu,
        load_software,
    })
}

/// The estimated seconds per shard of a balanced sharding (`--balance-from`), for `--dry-run`.
fn print_balance(a: &SweepArgs, plan: &PointPlan) {
    if plan.load_gpu.is_empty() {
        return;
    }
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
        fmt(&plan.load_gpu),
        fmt(&plan.load_software)
    );
}

/// `--fail-on-slower`, `--save-baseline` and `--baseline`, checked now (the baseline to
/// compare with must exist now, not after the whole sweep); the fraction of `--fail-on-slower`.
fn check_baseline_args(a: &SweepArgs) -> Result<Option<f64>> {
    let fail_frac = a
        .fail_on_slower
        .as_deref()
        .map(mfx_analysis::ab::parse_fraction)
        .transpose()
        .map_err(|e| usage(format!("--fail-on-slower: {e}")))?;
    for name in a.save_baseline.iter().chain(&a.baseline) {
        if name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.') {
            return Err(usage(format!(
                "baseline name '{name}' must be a plain name"
            )));
        }
    }
    if let Some(name) = &a.baseline {
        mfx_analysis::ab::baseline_dir(&baselines_root(), name)
            .map_err(|e| usage(format!("--baseline: {e:#}")))?;
    }
    Ok(fail_frac)
}

/// Where the rows go, and what an earlier run there already holds.
struct RunFolder {
    out: PathBuf,
    csv_path: PathBuf,
    run_id: String,
    shard: (usize, usize),
    /// Point keys that already have a row (`--resume`).
    done: std::collections::HashSet<String>,
    /// The run record of the run being resumed.
    earlier: Option<RunManifest>,
    /// Rows are appended (`--resume`, or points already done).
    resume: bool,
}

/// The run folder: a new one, or with `--resume` the interrupted run's (same suite text and
/// limits; a half-written last line dropped), or with `--force` a replaced one. A folder that
/// holds a runs.csv is refused otherwise.
fn open_run_folder(
    a: &SweepArgs,
    suite: &scenarios::Suite,
    shard: (usize, usize),
) -> Result<RunFolder> {
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
    let resume = !done.is_empty() || a.resume;
    Ok(RunFolder {
        out,
        csv_path,
        run_id,
        shard,
        done,
        earlier,
        resume,
    })
}

/// The groups this adapter runs (a software adapter takes the `[software]` profile's), and
/// the estimated seconds per shard where balanced; none is a filter that matches nothing here.
fn groups_on(a: &SweepArgs, gpu: &Gpu, plan: PointPlan) -> Result<(Vec<Group>, Vec<f64>)> {
    let (groups, load) = if gpu.facts.is_software {
        (plan.on_software, plan.load_software)
    } else {
        (plan.on_gpu, plan.load_gpu)
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
    Ok((groups, load))
}

/// The run record, written before any point: the command, the suite, the adapter, and (on a
/// GPU) the cross-GPU calibration set's time.
fn start_manifest(
    a: &SweepArgs,
    gpu: &Gpu,
    suite: &scenarios::Suite,
    folder: &RunFolder,
    total: usize,
    load: &[f64],
) -> Result<RunManifest> {
    let mut manifest = RunManifest::new(
        std::env::args().collect(),
        &suite.name,
        &suite.source,
        &suite.text,
        AdapterInfo::of(&gpu.adapter.get_info()),
        folder.shard,
    );
    if let Some(old) = &folder.earlier {
        manifest.continue_from(old);
    }
    manifest.software_profile = gpu.facts.is_software && suite.software.is_some();
    manifest.limits = gpu.profile;
    manifest.points_total = total;
    manifest.gpu = bench_core::manifest::GpuIdentity::of(gpu);
    manifest.shard_balance =
        a.balance_from
            .as_ref()
            .map(|from| bench_core::manifest::ShardBalance {
                from: from.display().to_string(),
                rule: bench_core::shard::RULE.to_string(),
                estimated_s: load.to_vec(),
            });
    manifest.resumed_points = folder.done.len();
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
    // The memory roofs every row is read against (`roof_bytes_per_s`), before any point: on a
    // software adapter too (its sweep is small), so every run records them.
    manifest.roofs = gpu.roofs().cloned();
    manifest.write(&folder.out)?;
    Ok(manifest)
}

/// The line that says what runs where.
fn announce(
    gpu: &Gpu,
    suite: &scenarios::Suite,
    groups: &[Group],
    total: usize,
    folder: &RunFolder,
) {
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
        if folder.done.is_empty() {
            String::new()
        } else {
            format!(
                " ({} already in {}: resumed)",
                folder.done.len(),
                folder.csv_path.display()
            )
        },
        folder.csv_path.display()
    );
    if let Err(why) = &gpu.monitor {
        eprintln!("mfx: no GPU clocks recorded: {why}");
    }
}

/// Whether stderr is a terminal to draw the bar on (not under CI).
fn terminal() -> bool {
    std::io::IsTerminal::is_terminal(&std::io::stderr()) && std::env::var_os("CI").is_none()
}

/// The progress bar; without a terminal (a log, CI) it draws nothing (`GroupLines` prints a
/// line per finished group instead).
fn progress_bar(len: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} [{elapsed} elapsed, ETA {eta}] {msg}",
        )
        .unwrap(),
    );
    if !terminal() {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    bar
}

impl<'a> Progress<'a> {
    /// The sinks of a run folder: runs.csv and samples.csv (appended when resuming), the FLIP
    /// keeper, and the per-group lines.
    fn open(
        a: &SweepArgs,
        folder: &RunFolder,
        groups: &[Group],
        bar: &'a indicatif::ProgressBar,
    ) -> Result<Progress<'a>> {
        let owed_rows: Vec<usize> = groups
            .iter()
            .map(|g| owed(g, &folder.done))
            .filter(|&n| n > 0)
            .collect();
        Ok(Progress {
            lines: GroupLines {
                rows_total: owed_rows.iter().sum(),
                owed: owed_rows,
                next: 0,
                in_group: 0,
                rows_done: 0,
                started: std::time::Instant::now(),
                print: !terminal(),
            },
            csv: if folder.resume {
                CsvSink::append(&folder.csv_path)?
            } else {
                CsvSink::create(&folder.csv_path)?
            },
            samples: SamplesSink::open(&folder.out.join("samples.csv"), folder.resume)?,
            flip: mfx_flip::WorstKeeper::new(if a.no_flip { 0 } else { a.flip_worst }),
            bar,
            ok: 0,
            failed: Vec::new(),
            skipped: BTreeMap::new(),
            spent_s: [0.0; 4],
        })
    }
}

/// The run record's counts and end, and runs.json (the context block with the GPU's clocks).
fn finish_manifest(
    gpu: &Gpu,
    manifest: &mut RunManifest,
    sink: &Progress,
    outcome: &runner::RunOutcome,
    total: usize,
    out: &Path,
) -> Result<()> {
    manifest.rows_written = outcome.written;
    manifest.rows_ok = sink.ok;
    manifest.rows_failed = sink.failed.len();
    manifest.rows_skipped = sink.skipped.values().sum();
    manifest.finished =
        outcome.interrupted.is_none() && outcome.already_done + outcome.written == total;
    manifest.finish(outcome.interrupted);
    manifest.write(out)?;
    let clocks = gpu.monitor.as_ref().ok().map(|m| {
        serde_json::Value::Object(
            m.context()
                .into_iter()
                .map(|(k, v)| (k.to_string(), serde_json::Value::String(v)))
                .collect(),
        )
    });
    write_runs_json(out, &context_block(manifest, SCHEMA_VERSION, clocks))?;
    // The typed twin: every column as schema declares it, run.json in its metadata.
    let typed = mfx_table::write_runs_parquet(out)?;
    if !typed.text_fallback.is_empty() {
        eprintln!(
            "mfx: warning: a cell off its column's declared type (a bug to report):\n{}",
            typed.describe()
        );
    }
    Ok(())
}

/// What happened, in words a log keeps (no terminal needed).
fn print_outcome(sink: &Progress, outcome: &runner::RunOutcome, csv_path: &Path) {
    let skipped: usize = sink.skipped.values().sum();
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
}

/// The summary, the report, the baseline saved or compared with, and the exit code: failed
/// rows (unless `--accept-failures`) and points slower than `--fail-on-slower` are errors.
fn after_run(
    a: &SweepArgs,
    out: &Path,
    fail_frac: Option<f64>,
    sink: &Progress,
    total: usize,
) -> Result<()> {
    let runs = report::Runs::load(&out.join("runs.csv"))?;
    eprintln!("\n{}", report::summary_text(&runs));
    if !a.no_report {
        let page =
            report::build(out, None).with_context(|| format!("report of {}", out.display()))?;
        eprintln!("mfx: report {}", page.display());
    }
    if let Some(name) = &a.save_baseline {
        let dir = mfx_analysis::ab::save_baseline(out, &baselines_root(), name)?;
        eprintln!("mfx: baseline '{name}' saved in {}", dir.display());
    }
    let mut slower = 0;
    if let Some(name) = &a.baseline {
        let base = mfx_analysis::ab::baseline_dir(&baselines_root(), name)?;
        let cmp = mfx_analysis::ab::compare_runs(&base, out, &Default::default())?;
        no_common_point(&cmp).map_err(|e| anyhow::anyhow!("--baseline {name}: {e}"))?;
        println!("{}", report::ab::markdown(&cmp));
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
            println!("  {}", g.point_key(f.name(), empty.given()));
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
    let mut opts = mfx_analysis::ab::AbOptions::default();
    if let Some(b) = noise_band {
        opts.verdict.noise_band =
            mfx_analysis::ab::parse_fraction(b).map_err(|e| usage(format!("--noise-band: {e}")))?;
    }
    let c = mfx_analysis::calibrate::calibrate(runs, &opts, margin)
        .map_err(|e| usage(format!("{e:#}")))?;
    print!("{}", report::ab::calibration_markdown(&c));
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
    let mut opts = mfx_analysis::ab::AbOptions::default();
    if let Some(b) = noise_band {
        opts.verdict.noise_band =
            mfx_analysis::ab::parse_fraction(b).map_err(|e| usage(format!("--noise-band: {e}")))?;
    }
    if let Some(f) = band_from {
        opts.calibration = Some(
            mfx_analysis::calibrate::Calibration::load(f)
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
        .map(mfx_analysis::ab::parse_fraction)
        .transpose()
        .map_err(|e| usage(format!("--fail-on-slower: {e}")))?;
    let r =
        mfx_analysis::ab::compare_runs(base, new, &opts).map_err(|e| usage(format!("{e:#}")))?;
    no_common_point(&r).map_err(|e| usage(e.to_string()))?;
    if json {
        println!("{}", serde_json::to_string_pretty(&compare_json(&r))?);
    } else {
        print!("{}", report::ab::markdown(&r));
    }
    // The page is written only where asked: comparing against a committed reference run must
    // not change the tree it reads.
    if let Some(dir) = html {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let page = report::ab::write_html(&r, dir)?;
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

/// Two runs that share no point compared nothing: an error naming both sides' sizes and a key
/// of each (a different suite, resolution or schema of keys), never an empty SAME.
fn no_common_point(r: &mfx_analysis::ab::AbReport) -> std::result::Result<(), NoCommonPoint> {
    if r.common > 0 {
        return Ok(());
    }
    let first = |v: &[String]| v.first().cloned().unwrap_or_else(|| "none".into());
    Err(NoCommonPoint {
        base: r.base.runs_csv.clone(),
        new: r.new.runs_csv.clone(),
        base_points: r.only_base.len(),
        base_example: first(&r.only_base),
        new_points: r.only_new.len(),
        new_example: first(&r.only_new),
    })
}

/// Two runs with no point in common: both files, their sizes and a key of each.
#[derive(Debug, thiserror::Error)]
#[error(
    "{} and {} have no point in common (points are joined by point_key): nothing to compare. \
     BASE has {base_points} points (e.g. {base_example}), NEW {new_points} (e.g. {new_example})",
    base.display(),
    new.display()
)]
struct NoCommonPoint {
    base: std::path::PathBuf,
    new: std::path::PathBuf,
    base_points: usize,
    base_example: String,
    new_points: usize,
    new_example: String,
}

/// `mfx compare --json`: the comparison's points, verdicts and moves as one object (the same
/// content as the Markdown, for scripts).
fn compare_json(r: &mfx_analysis::ab::AbReport) -> serde_json::Value {
    use serde_json::json;
    let side = |s: &mfx_analysis::ab::Side| {
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
