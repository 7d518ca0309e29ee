//! `mfx`: sweep multi-fragment methods on a GPU, log tidy CSV, and report.

mod bundle;
mod sweep;

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use bench_core::{BackendChoice, Gpu, GpuOptions};
use clap::{Args, Parser, Subcommand};
use mfx::STUDIES;
use mfx_multifragment::methods;
use scenarios::{ParamValue, Params, SceneSpec, Suite};
use schema::cols;

#[derive(Parser)]
#[command(
    name = "mfx",
    version,
    about = "GPU multi-fragment rendering benchmark and research harness"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Args, Clone)]
pub(crate) struct GpuArgs {
    /// wgpu backend: vulkan, gl (wgpu's own EGL/GL choice), gles (a GLES 3.x context of our own
    /// through EGL: compute where wgpu alone would take desktop GL 3.3), or any (vulkan + gl).
    #[arg(long, default_value = "vulkan")]
    backend: BackendChoice,
    /// Use the adapter whose name contains this (case-insensitive).
    #[arg(long)]
    adapter: Option<String>,
    /// Use adapter number K of `mfx list adapters` (for one shard per GPU).
    #[arg(long)]
    adapter_index: Option<usize>,
    /// Render targets' memory: pooled (wgpu's shared blocks, the default) or dedicated (a Vulkan
    /// allocation each, as VK_KHR_dedicated_allocation offers for render targets).
    #[arg(long)]
    texture_memory: Option<bench_core::texture_memory::TextureMemory>,
    /// Limits the device is requested with: adapter (its own, the default), webgpu (WebGPU's
    /// default limits: what a browser grants), webgpu-compat (WebGPU's compatibility mode) or
    /// downlevel (a WebGL2-class device). What does not fit is a `skipped` row naming the limit;
    /// k-buffers split their entries to fit.
    #[arg(long, default_value = "adapter")]
    limits: bench_core::limits::Profile,
}

impl GpuArgs {
    /// The `--limits` profile.
    pub(crate) fn limits(&self) -> bench_core::limits::Profile {
        self.limits
    }
    pub(crate) fn options(&self) -> GpuOptions {
        GpuOptions {
            backend: self.backend,
            adapter: self.adapter.clone(),
            adapter_index: self.adapter_index,
            texture_memory: self.texture_memory,
            limits: self.limits,
        }
    }
}

#[derive(Subcommand)]
enum Cmd {
    /// List scenes, methods, studies, suites, adapters or CSV columns.
    List {
        /// scenes | methods | studies | suites | adapters | columns (all when omitted)
        what: Option<String>,
        /// Print one JSON object (a key per list) instead of text.
        #[arg(long)]
        json: bool,
        /// Also list the internal probe suites (scenarios/suites/internal/: one question each,
        /// kept for the runs that answered it).
        #[arg(long)]
        all: bool,
        #[command(flatten)]
        gpu: GpuArgs,
    },
    /// Run a suite (a name in scenarios/suites or a TOML path) and write runs.csv + plots.
    Sweep(sweep::SweepArgs),
    /// Compare two runs point by point (run folders or runs.csv files): ratio of medians with
    /// its CI, SAME / FASTER / SLOWER / UNSURE, and errors that moved. Points are joined by
    /// point_key; two runs with no point in common exit 2 (nothing was compared).
    Compare {
        /// The run compared against: a run folder (its runs.csv, and samples.csv or
        /// samples.csv.gz beside it when there) or a runs.csv path.
        #[arg(value_name = "BASE")]
        base: PathBuf,
        /// The run judged against BASE, in the same forms; ratios are NEW / BASE (> 1: NEW is
        /// slower).
        #[arg(value_name = "NEW")]
        new: PathBuf,
        /// Changes within this band are SAME even when significant (default 2%).
        #[arg(long)]
        noise_band: Option<String>,
        /// Significance level of the Mann–Whitney test (default 0.05).
        #[arg(long)]
        alpha: Option<f64>,
        /// Exit 1 when a point is significantly slower by more than this (e.g. 5%).
        #[arg(long)]
        fail_on_slower: Option<String>,
        /// Write compare.html into this folder (nothing is written without it).
        #[arg(long)]
        html: Option<PathBuf>,
        /// Bands per point from `mfx calibrate` (calibration.json); --noise-band is their floor.
        #[arg(long)]
        band_from: Option<PathBuf>,
        /// Multiply every NEW time by this (a synthetic change: 1.05 must come out SLOWER).
        #[arg(long)]
        scale_new: Option<f64>,
        /// Print the comparison as JSON on stdout instead of Markdown.
        #[arg(long)]
        json: bool,
    },
    /// A/A calibration: compare two or more runs of one build pair by pair; write each point's
    /// band (how far its median moved) and the false-alarm rate per method family.
    Calibrate {
        #[arg(required = true, num_args = 2..)]
        runs: Vec<PathBuf>,
        /// The calibration file to write.
        #[arg(long, default_value = "calibration.json")]
        out: PathBuf,
        /// The floor under every band (default 2%).
        #[arg(long)]
        noise_band: Option<String>,
        /// Each point's band = its largest A/A move × this (default 1).
        #[arg(long, default_value_t = 1.0)]
        margin: f64,
    },
    /// Check suites (names or TOML paths) without a GPU: every problem at once; exit 2 if any.
    Check {
        #[arg(required = true)]
        suites: Vec<String>,
    },
    /// Merge run folders (shards, machines) into one runs.csv; duplicates are reported.
    Merge {
        /// Run folders, folders of run folders (one level down), or runs.csv files.
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        /// Exit with an error when a point appears twice (instead of keeping the first).
        #[arg(long)]
        strict: bool,
    },
    /// Turn a run folder's runs.csv (or runs.parquet) into PNG/SVG plots and an HTML page; a
    /// bundle (`mfx bundle`) is unpacked first, into --out (default: its name without .tar.gz).
    Report {
        dir: PathBuf,
        /// Adapter name (substring) used as the baseline of cross-adapter speedups.
        #[arg(long)]
        baseline: Option<String>,
        /// Where a bundle is unpacked and reported (bundles only).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// One attachable file of a run: runs.parquet, run.json, samples, summary, report (a
    /// .tar.gz that `mfx report` and `mfx compare` read where they read a run folder).
    Bundle {
        run: PathBuf,
        /// The bundle file (default: <run folder name>.mfx.tar.gz here).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Stack every run folder under ROOT into one Parquet file (a `run_folder` column says
    /// which), for history queries in pandas, polars or DuckDB.
    Dataset {
        #[arg(default_value = "results/reference")]
        root: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// Keep folders holding merged_from.txt (merges of runs stored beside them).
        #[arg(long)]
        with_merged: bool,
    },
    /// Render one scene with one method to a PNG (and the CPU reference beside it).
    Render {
        /// Scene generator (`mfx list scenes`: quads, shells, grass, …), its parameters from
        /// --param; or give a model file with --model instead.
        #[arg(long)]
        scene: Option<String>,
        /// Scene parameter, repeatable: --param depth_complexity=8
        #[arg(long = "param")]
        params: Vec<String>,
        /// Render a model file: OBJ, PLY (.ply, .ply.gz) or glTF 2.0 (.gltf, .glb), by its
        /// extension (the `obj` or `gltf` scene generator). `--obj` is the old name.
        #[arg(long, alias = "obj", conflicts_with = "scene")]
        model: Option<PathBuf>,
        /// Method, or a comma-separated list with --reference-out (one image each).
        #[arg(long, default_value = "depth_peel")]
        method: String,
        /// Method axis, repeatable: --axis max_layers=16
        #[arg(long = "axis")]
        axes: Vec<String>,
        /// Width in pixels (default 256, or the --camera-in file's).
        #[arg(long)]
        width: Option<u32>,
        /// Height in pixels (default 256, or the --camera-in file's).
        #[arg(long)]
        height: Option<u32>,
        /// Write the method's image (composited over white) here.
        #[arg(long)]
        png: Option<PathBuf>,
        /// Also write the ground truth here: the composite of every fragment (f64 reference).
        #[arg(long)]
        reference_png: Option<PathBuf>,
        /// Also write the method's own truncated definition here (the k nearest fragments), for
        /// a method that keeps k.
        #[arg(long)]
        reference_k_png: Option<PathBuf>,
        /// Write the camera (row-major clip-from-world matrix, wgpu conventions) as JSON.
        #[arg(long)]
        camera_out: Option<PathBuf>,
        /// Render from the camera in this JSON (as written by --camera-out).
        #[arg(long)]
        camera_in: Option<PathBuf>,
        /// Write ground truth here: depth complexity (uint16 .npy + 16-bit PNG), the reference
        /// composite and each method's image (float32 RGBA .npy + PNG), and camera.json.
        #[arg(long)]
        reference_out: Option<PathBuf>,
        #[command(flatten)]
        gpu: GpuArgs,
    },
    /// Deferred-shading debug views (classification ids, lights per tile, image) as PNGs.
    ShadingViews {
        #[arg(long, default_value = "city")]
        scene: String,
        /// Scene parameter, repeatable: --param lights=1024
        #[arg(long = "param")]
        params: Vec<String>,
        #[arg(long, default_value_t = 1280)]
        width: u32,
        #[arg(long, default_value_t = 720)]
        height: u32,
        #[arg(long, default_value_t = 16)]
        tile_size: u32,
        #[arg(long, default_value_t = 0.0)]
        attenuation_threshold: f64,
        /// Folder for the PNGs (e.g. the run folder).
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        gpu: GpuArgs,
    },
    /// Load model files (OBJ, PLY, .ply.gz, glTF .gltf/.glb) as a scene would and print their triangle and vertex
    /// counts; no GPU. A model a script fetches names the script when it is missing.
    Model {
        /// Model files, e.g. models/dragon_vrip.ply.gz
        #[arg(required = true)]
        paths: Vec<PathBuf>,
    },
}

/// A `--shard` value that is not `I/N` with 0 ≤ I < N.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
pub(crate) enum ShardError {
    #[error("shard must be I/N, e.g. 0/4")]
    NotIOverN,
    #[error("shard index '{0}' is not a number")]
    Index(String),
    #[error("shard count '{0}' is not a number")]
    Count(String),
    #[error("shard {0}/{1}: need 0 <= I < N")]
    OutOfRange(usize, usize),
}

pub(crate) fn parse_shard(s: &str) -> std::result::Result<(usize, usize), ShardError> {
    let (i, n) = s.split_once('/').ok_or(ShardError::NotIOverN)?;
    let i: usize = i.parse().map_err(|_| ShardError::Index(i.to_string()))?;
    let n: usize = n.parse().map_err(|_| ShardError::Count(n.to_string()))?;
    if n == 0 || i >= n {
        return Err(ShardError::OutOfRange(i, n));
    }
    Ok((i, n))
}

/// `k=v` into a typed value: integers, floats, booleans, else strings.
pub(crate) fn parse_kv(s: &str) -> Result<(String, ParamValue)> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| usage(format!("'{s}' is not key=value")))?;
    let val = if let Ok(i) = v.parse::<i64>() {
        ParamValue::Int(i)
    } else if let Ok(x) = v.parse::<f64>() {
        ParamValue::Float(x)
    } else if let Ok(b) = v.parse::<bool>() {
        ParamValue::Bool(b)
    } else {
        ParamValue::Str(v.to_string())
    };
    Ok((k.to_string(), val))
}

/// A bad suite or bad arguments, found before any GPU work: exit code 2, so a script can tell
/// it from a run that failed (1).
#[derive(Debug)]
pub(crate) struct Usage(String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

pub(crate) fn usage(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Usage(msg.into()))
}

/// Loads and checks a suite; every problem at once as a usage error.
pub(crate) fn checked_suite(name: &str) -> Result<Suite> {
    bench_core::check::load(STUDIES, name).map_err(|p| {
        usage(format!(
            "suite '{name}': {} problem{}:\n{}",
            p.len(),
            if p.len() == 1 { "" } else { "s" },
            scenarios::problem::report(&p)
        ))
    })
}

/// EGL (wgpu's GL probe, Mesa's loaders) asks libwayland for a display, which prints
/// "error: XDG_RUNTIME_DIR is invalid or not set" where the variable is missing or relative (ssh,
/// containers, CI) although nothing needs a display. mfx renders offscreen, so it points the
/// variable at the temp directory before any thread or GPU library starts: the probe then finds
/// no socket and says nothing.
fn quiet_egl_runtime_dir() {
    let valid =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_absolute());
    if !valid {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
}

fn main() {
    quiet_egl_runtime_dir();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        eprintln!("mfx: error: {e:#}");
        let code = if e.downcast_ref::<Usage>().is_some() {
            2
        } else {
            1
        };
        std::process::exit(code);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.cmd {
        Cmd::List {
            what,
            gpu,
            json,
            all,
        } => {
            if json {
                list_json(what.as_deref(), &gpu, all)
            } else {
                list(what.as_deref(), &gpu, all)
            }
        }
        Cmd::Sweep(a) => sweep::sweep(&a),
        Cmd::Compare {
            base,
            new,
            noise_band,
            alpha,
            fail_on_slower,
            html,
            band_from,
            scale_new,
            json,
        } => sweep::compare(
            &base,
            &new,
            sweep::CompareArgs {
                noise_band: noise_band.as_deref(),
                alpha,
                fail_on_slower: fail_on_slower.as_deref(),
                html: html.as_deref(),
                band_from: band_from.as_deref(),
                scale_new,
                json,
            },
        ),
        Cmd::Calibrate {
            runs,
            out,
            noise_band,
            margin,
        } => sweep::calibrate(&runs, &out, noise_band.as_deref(), margin),
        Cmd::Check { suites } => {
            let mut bad = 0;
            for name in &suites {
                match bench_core::check::load(STUDIES, name) {
                    Ok(suite) => println!(
                        "ok: {name} ({}): {} studies, {} rows on a GPU, {} on a software adapter{}",
                        suite.source,
                        suite.studies.len(),
                        bench_core::runner::rows_of(STUDIES, &suite, false),
                        bench_core::runner::rows_of(STUDIES, &suite, true),
                        models_line(&suite)
                    ),
                    Err(p) => {
                        bad += 1;
                        println!("{}", scenarios::problem::report(&p));
                    }
                }
            }
            // The papers files point into the suites: checked on every `mfx check`.
            let papers = mfx::papers::check_builtin();
            if papers.is_empty() {
                println!(
                    "ok: papers ({} files in scenarios/papers)",
                    scenarios::papers::BUILTIN.len()
                );
            } else {
                println!("{}", scenarios::problem::report(&papers));
                return Err(usage(format!(
                    "the papers files have {} problems",
                    papers.len()
                )));
            }
            if bad > 0 {
                return Err(usage(format!(
                    "{bad} of {} suites have problems",
                    suites.len()
                )));
            }
            Ok(())
        }
        Cmd::Merge {
            inputs,
            out,
            strict,
        } => {
            let m = bench_core::merge::merge(&inputs, &out)?;
            println!("{}", m.summary());
            if strict && !m.duplicates.is_empty() {
                bail!(
                    "{} duplicate points (--strict); see {}",
                    m.duplicates.len(),
                    out.join("duplicates.csv").display()
                );
            }
            Ok(())
        }
        Cmd::Report { dir, baseline, out } => {
            let page = if mfx_table::bundle::is_bundle(&dir) {
                bundle::report_of_bundle(&dir, out.as_deref(), baseline.as_deref())?
            } else if out.is_some() {
                return Err(usage(format!(
                    "--out is for a bundle; {} is not one (its report goes in its report/)",
                    dir.display()
                )));
            } else {
                report::build(&dir, baseline.as_deref())
                    .with_context(|| format!("report of {}", dir.display()))?
            };
            println!("report: {}", page.display());
            Ok(())
        }
        Cmd::Bundle { run, out } => {
            let file = bundle::bundle(&run, out.as_deref())?;
            println!("bundle: {}", file.display());
            Ok(())
        }
        Cmd::Dataset {
            root,
            out,
            with_merged,
        } => bundle::dataset(&root, &out, with_merged),
        Cmd::Render {
            scene,
            params,
            model,
            method,
            axes,
            width,
            height,
            png,
            reference_png,
            reference_k_png,
            camera_out,
            camera_in,
            reference_out,
            gpu,
        } => {
            let mut p = Params::new();
            for kv in &params {
                let (k, v) = parse_kv(kv)?;
                p.set(&k, v);
            }
            let generator = match (&scene, &model) {
                (_, Some(path)) => {
                    p.set("path", ParamValue::Str(path.display().to_string()));
                    scenarios::model::generator_for(path).to_string()
                }
                (Some(s), None) => s.clone(),
                (None, None) => return Err(usage("give --scene NAME or --model FILE")),
            };
            let mut a = Params::new();
            for kv in &axes {
                let (k, v) = parse_kv(kv)?;
                a.set(&k, v);
            }
            if png.is_none() && camera_out.is_none() && reference_out.is_none() {
                return Err(usage(
                    "nothing to write: give --png, --camera-out and/or --reference-out",
                ));
            }
            render(&RenderJob {
                spec: SceneSpec::new(&generator, p),
                methods: method.split(',').map(|m| m.trim().to_string()).collect(),
                axes: a,
                width,
                height,
                png,
                reference_png,
                reference_k_png,
                camera_out,
                camera_in,
                reference_out,
                gpu,
            })
        }
        Cmd::Model { paths } => {
            for p in &paths {
                // A bad or missing file is bad input (exit 2), named by the loader.
                let m = scenarios::model::load(p).map_err(|e| usage(e.to_string()))?;
                println!(
                    "{}: {} triangles, {} vertices",
                    p.display(),
                    m.triangle_count(),
                    m.vertex_count()
                );
            }
            Ok(())
        }
        Cmd::ShadingViews {
            scene,
            params,
            width,
            height,
            tile_size,
            attenuation_threshold,
            out,
            gpu,
        } => {
            let mut p = Params::new();
            for kv in &params {
                let (k, v) = parse_kv(kv)?;
                p.set(&k, v);
            }
            let scene = SceneSpec::new(&scene, p).build()?;
            let g = Gpu::new(&gpu.options())?;
            let (files, legend) = mfx_shading::debug::write_views(
                &g,
                &scene,
                width,
                height,
                tile_size,
                attenuation_threshold,
                &out,
            )?;
            for f in files {
                println!("wrote {}", f.display());
            }
            println!("{legend}");
            Ok(())
        }
    }
}

const LISTS: &[&str] = &[
    "scenes", "methods", "studies", "suites", "adapters", "columns",
];

fn check_list(what: Option<&str>) -> Result<()> {
    match what {
        Some(w) if !LISTS.contains(&w) => {
            Err(usage(format!("unknown list '{w}' ({})", LISTS.join(", "))))
        }
        _ => Ok(()),
    }
}

/// Every suite name: the built-in ones, then the files of scenarios/suites/ that are not
/// built in (a file of a built-in's name wins when loaded, as `Suite::load` says).
fn suite_names(internal: bool) -> Vec<(String, bool)> {
    let mut names: Vec<(String, bool)> = scenarios::suite::BUILTIN
        .iter()
        .map(|(n, _)| (n.to_string(), true))
        .collect();
    let stems = |dir: &str| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .map(|rd| {
                rd.filter_map(|e| e.ok())
                    .filter_map(|e| {
                        let p = e.path();
                        (p.extension()? == "toml")
                            .then(|| p.file_stem()?.to_str().map(str::to_string))?
                    })
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    };
    let mut files = stems("scenarios/suites");
    if internal {
        files.extend(stems("scenarios/suites/internal"));
    }
    for f in files {
        if !names.iter().any(|(n, _)| *n == f) {
            names.push((f, false));
        }
    }
    names
}

/// Adapters of the chosen backend, as `list adapters` prints them.
fn adapter_rows(gpu: &GpuArgs) -> Vec<serde_json::Value> {
    bench_core::gpu::list_adapters(gpu.backend)
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let info = a.get_info();
            let facts = bench_core::gpu::AdapterFacts::of(
                &info,
                a.features() & bench_core::gpu::wanted_features(),
            );
            let l = a.limits();
            serde_json::json!({
                "index": i,
                "name": facts.name,
                "backend": facts.backend,
                "device_type": facts.device_type,
                "driver": facts.driver,
                "driver_info": facts.driver_info,
                "pci_bus_id": info.device_pci_bus_id,
                "features": facts.features,
                "max_color_attachments": l.max_color_attachments,
                "max_color_attachment_bytes_per_sample": l.max_color_attachment_bytes_per_sample,
                "max_storage_buffer_binding_size": l.max_storage_buffer_binding_size,
            })
        })
        .collect()
}

/// `mfx list --json`: one object, a key per list asked for.
fn list_json(what: Option<&str>, gpu: &GpuArgs, internal: bool) -> Result<()> {
    use serde_json::json;
    check_list(what)?;
    let is = |w: &str| what.is_none() || what == Some(w);
    let mut o = serde_json::Map::new();
    if is("scenes") {
        let v: Vec<_> = scenarios::scenes::GENERATORS
            .iter()
            .map(|g| json!({"name": g, "describe": scenarios::scenes::describe(g)}))
            .collect();
        o.insert("scenes".into(), v.into());
    }
    if is("methods") {
        let v: Vec<_> = methods::all()
            .iter()
            .map(|m| {
                let axes: Vec<_> = m
                    .axes()
                    .iter()
                    .map(|a| json!({"name": a.name(), "summary": a.summary(), "doc": a.doc}))
                    .collect();
                json!({"name": m.name(), "exact": m.exact(), "describe": m.describe(), "axes": axes})
            })
            .collect();
        o.insert("methods".into(), v.into());
    }
    if is("studies") {
        let v: Vec<_> = STUDIES
            .iter()
            .map(|s| json!({"kind": s.kind().name(), "describe": s.describe()}))
            .collect();
        o.insert("studies".into(), v.into());
    }
    if is("suites") {
        let v: Vec<_> = suite_names(internal)
            .into_iter()
            .map(
                |(name, builtin)| match bench_core::check::load(STUDIES, &name) {
                    Ok(suite) => json!({
                        "name": name,
                        "built_in": builtin,
                        "source": suite.source,
                        "description": suite.description,
                        "rows_gpu": bench_core::runner::rows_of(STUDIES, &suite, false),
                        "rows_software": bench_core::runner::rows_of(STUDIES, &suite, true),
                        "models": bench_core::check::models_needed(&suite),
                    }),
                    Err(p) => json!({
                        "name": name,
                        "built_in": builtin,
                        "problems": p.iter().map(|p| p.to_string()).collect::<Vec<_>>(),
                    }),
                },
            )
            .collect();
        o.insert("suites".into(), v.into());
    }
    if is("columns") {
        let v: Vec<_> = schema::all()
            .map(|c| json!({"name": c.name, "doc": c.doc}))
            .collect();
        o.insert("columns".into(), v.into());
        o.insert(
            "schema_version".into(),
            bench_core::record::SCHEMA_VERSION.into(),
        );
    }
    if is("adapters") {
        o.insert("adapters".into(), adapter_rows(gpu).into());
    }
    println!("{}", serde_json::to_string_pretty(&o)?);
    Ok(())
}

fn list(what: Option<&str>, gpu: &GpuArgs, internal: bool) -> Result<()> {
    let all = what.is_none();
    let is = |w: &str| all || what == Some(w);
    check_list(what)?;
    if is("scenes") {
        println!("scenes:");
        for g in scenarios::scenes::GENERATORS {
            println!("  {g:<8} {}", scenarios::scenes::describe(g));
        }
    }
    if is("methods") {
        println!("methods (exact: captures every fragment within capacity):");
        println!(
            "  {:<16} {:<6} what it is (source, passes, bytes per pixel)",
            "method", "exact"
        );
        for m in methods::all() {
            println!("  {:<16} {:<6} {}", m.name(), m.exact(), m.describe());
            for a in m.axes() {
                println!("  {:<16} {:<6}   axis {}: {}", "", "", a.summary(), a.doc);
            }
        }
    }
    if is("studies") {
        println!("studies:");
        for s in STUDIES {
            println!("  {:<10} {}", s.kind().name(), s.describe());
        }
    }
    if is("suites") {
        println!("suites (built in, then files of scenarios/suites/ only; a file scenarios/suites/NAME.toml or any path wins{}):", if internal { "; then the internal probes of scenarios/suites/internal/" } else { "; --all adds the internal probes" });
        for (name, builtin) in suite_names(internal) {
            match Suite::load(&name) {
                Ok(suite) => println!(
                    "  {name:<16} {}{} rows on a GPU, {} on a software adapter{}\n  {:<16} {}",
                    if builtin { "" } else { "(file only) " },
                    bench_core::runner::rows_of(STUDIES, &suite, false),
                    bench_core::runner::rows_of(STUDIES, &suite, true),
                    models_line(&suite),
                    "",
                    suite.description
                ),
                Err(e) => println!("  {name:<16} PROBLEMS: {e}"),
            }
        }
    }
    if what == Some("columns") && std::env::var_os("MFX_COLUMNS_MARKDOWN").is_some() {
        print!("{}", schema::markdown());
        return Ok(());
    }
    if is("columns") {
        println!(
            "CSV columns (schema {}):",
            bench_core::record::SCHEMA_VERSION
        );
        for c in schema::all() {
            println!("  {:<24} {}", c.name, c.doc);
        }
    }
    if is("adapters") {
        println!("adapters ({:?}; index for --adapter-index):", gpu.backend);
        for (i, a) in bench_core::gpu::list_adapters(gpu.backend)
            .iter()
            .enumerate()
        {
            let info = a.get_info();
            let facts = bench_core::gpu::AdapterFacts::of(
                &info,
                a.features() & bench_core::gpu::wanted_features(),
            );
            println!(
                "  [{i}] {} ({}, {}, driver {} {}, pci {})",
                facts.name,
                facts.backend,
                facts.device_type,
                facts.driver,
                facts.driver_info,
                if info.device_pci_bus_id.is_empty() {
                    "-"
                } else {
                    &info.device_pci_bus_id
                }
            );
            println!("      features: {}", facts.features);
            let l = a.limits();
            println!(
                "      max colour attachments: {}, bytes per sample: {}",
                l.max_color_attachments, l.max_color_attachment_bytes_per_sample
            );
        }
    }
    Ok(())
}

/// ", needs models/a.obj, …" for a suite whose scenes read files.
fn models_line(suite: &Suite) -> String {
    let m: Vec<String> = bench_core::check::models_needed(suite)
        .into_iter()
        .map(|p| {
            if std::path::Path::new(&p).is_file() {
                p
            } else if let Some(cmd) = scenarios::obj::fetch_command(&p) {
                format!("{p} (missing here: fetch it with `{cmd}`)")
            } else {
                format!("{p} (missing here: models/README.md says where it comes from)")
            }
        })
        .collect();
    if m.is_empty() {
        String::new()
    } else {
        format!("; needs {}", m.join(", "))
    }
}

/// UTC now as yyyymmdd-hhmmss (a run folder's name).
pub(crate) fn chrono_stamp() -> String {
    chrono::Utc::now().format("%Y%m%d-%H%M%S").to_string()
}

struct RenderJob {
    spec: SceneSpec,
    methods: Vec<String>,
    axes: Params,
    width: Option<u32>,
    height: Option<u32>,
    png: Option<PathBuf>,
    reference_png: Option<PathBuf>,
    reference_k_png: Option<PathBuf>,
    camera_out: Option<PathBuf>,
    camera_in: Option<PathBuf>,
    reference_out: Option<PathBuf>,
    gpu: GpuArgs,
}

/// A render's width or height, checked against the limit suites have
/// (`scenarios::suite::MAX_SIDE`): a usage error naming the option, before any GPU work.
fn check_side(what: &str, side: Option<u32>) -> Result<()> {
    let max = scenarios::suite::MAX_SIDE;
    match side {
        Some(s) if !(1..=max).contains(&s) => Err(usage(format!(
            "{what} {s} is out of range 1..={max} (the largest side a suite accepts)"
        ))),
        _ => Ok(()),
    }
}

/// Bytes a render holds at once, estimated: per pixel the reference's offsets, its f64
/// composite and the f32 images (≈ 128 B), and per fragment one reference fragment, the count
/// scaled up from a probe raster of the same view at 64 pixels across.
fn render_bytes(scene: &scenarios::Scene, w: u32, h: u32) -> u64 {
    const PER_PIXEL: u64 = 128;
    let pixels = w as u64 * h as u64;
    let pw = 64u32.min(w);
    let ph = ((h as u64 * pw as u64) / w.max(1) as u64).clamp(1, 64) as u32;
    let probe = mfx_reference::rasterize(scene, pw, ph).total_fragments() as f64;
    let fragments = probe * pixels as f64 / (pw as f64 * ph as f64);
    let per_fragment = std::mem::size_of::<mfx_reference::RefFragment>() as f64;
    pixels * PER_PIXEL + (fragments * per_fragment) as u64
}

/// The host's available memory (MemAvailable of /proc/meminfo), where the OS says it.
fn host_available_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kb: u64 = info
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    Some(kb * 1024)
}

fn gib(b: u64) -> String {
    format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64)
}

/// A render whose estimate exceeds the host's available memory is a usage error (exit 2) before
/// the reference grows; one over 1 GiB says its estimate first.
fn check_host_memory(estimate: u64, w: u32, h: u32) -> Result<()> {
    if let Some(avail) = host_available_bytes() {
        if estimate > avail {
            return Err(usage(format!(
                "a {w}x{h} render needs about {} (reference fragments and images), more than this host's {} available: render a smaller size",
                gib(estimate),
                gib(avail)
            )));
        }
    }
    if estimate > 1 << 30 {
        eprintln!(
            "mfx: a {w}x{h} render: about {} of memory (estimate)",
            gib(estimate)
        );
    }
    Ok(())
}

/// The adapter's own limits on a render of this size: its largest texture side and its largest
/// buffer (one RGBA f32 image is read back in one buffer).
fn check_adapter_limits(gpu: &Gpu, w: u32, h: u32) -> Result<()> {
    let side = gpu.limits.max_texture_dimension_2d;
    if w > side || h > side {
        return Err(usage(format!(
            "{w}x{h} is over {}'s largest texture side {side}",
            gpu.facts.name
        )));
    }
    let image = w as u64 * h as u64 * 16;
    if image > gpu.limits.max_buffer_size {
        return Err(usage(format!(
            "a {w}x{h} RGBA f32 image is {}, over {}'s largest buffer ({}): render a smaller size",
            gib(image),
            gpu.facts.name,
            gib(gpu.limits.max_buffer_size)
        )));
    }
    Ok(())
}

fn render(job: &RenderJob) -> Result<()> {
    use bench_core::image_io;
    use scenarios::camera::CameraFile;
    // Everything that can be checked without a GPU is, first: the sizes, the scene's parameters
    // and file, the methods, and each method's axes (a misspelt axis is an error, not a silent
    // default).
    for (what, given) in [("--width", job.width), ("--height", job.height)] {
        check_side(what, given)?;
    }
    let scene_problems = job.spec.check();
    if !scene_problems.is_empty() {
        let lines: Vec<String> = scene_problems.iter().map(|e| e.to_string()).collect();
        return Err(usage(format!(
            "scene {}: {}",
            job.spec.label(),
            lines.join("; ")
        )));
    }
    let mut points = Vec::new();
    for method in &job.methods {
        let m = methods::by_name(method).ok_or_else(|| {
            usage(format!(
                "unknown method '{method}' (known: {})",
                methods::all()
                    .iter()
                    .map(|m| m.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })?;
        let point = bench_core::axes::Point::resolve(&m.axes(), &job.axes)
            .map_err(|e| usage(format!("{method}: {}", e.join("; "))))?;
        m.validate(&point)
            .map_err(|e| usage(format!("{method}: {e}")))?;
        points.push(point);
    }
    let mut scene = job.spec.build()?;
    let (mut w, mut h) = (job.width.unwrap_or(256), job.height.unwrap_or(256));
    if let Some(path) = &job.camera_in {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let cam: CameraFile = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a camera JSON", path.display()))?;
        for (what, side) in [("width", cam.width), ("height", cam.height)] {
            check_side(&format!("{}: {what}", path.display()), Some(side))?;
        }
        cam.apply(&mut scene.camera)
            .map_err(|why| anyhow::anyhow!("{}: {why}", path.display()))?;
        // The matrix holds the aspect ratio: a different size would stretch the image.
        for (given, file, what) in [
            (job.width, cam.width, "width"),
            (job.height, cam.height, "height"),
        ] {
            if given.is_some_and(|g| g != file) {
                return Err(usage(format!(
                    "--{what} {} differs from {}'s {what} {file}: the camera matrix is made for its own size",
                    given.unwrap_or(0),
                    path.display()
                )));
            }
        }
        (w, h) = (cam.width, cam.height);
    }
    let world_from_object = if job.spec.generator == "obj" {
        scenarios::obj::world_from_file(&job.spec)?
    } else {
        Vec::new()
    };
    let cam_file = CameraFile::of(&scene.camera, w, h, &world_from_object);
    let cam_json = serde_json::to_string_pretty(&cam_file)?;
    if let Some(p) = &job.camera_out {
        if let Some(parent) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating {}", parent.display()))?;
        }
        std::fs::write(p, &cam_json).with_context(|| format!("writing {}", p.display()))?;
        println!("camera -> {}", p.display());
    }
    if job.methods.len() > 1 && (job.png.is_some() || job.reference_png.is_some()) {
        return Err(usage(
            "--png and --reference-png take one method; use --reference-out DIR for several",
        ));
    }
    let need_gpu = job.png.is_some() || job.reference_out.is_some();
    // A big render is refused before it grows: its bytes estimated from a small probe raster,
    // against the host's memory and (below, once the adapter is open) the adapter's limits.
    let estimate = render_bytes(&scene, w, h);
    check_host_memory(estimate, w, h)?;
    let gpu = if need_gpu {
        let gpu = Gpu::new(&job.gpu.options())?;
        check_adapter_limits(&gpu, w, h)?;
        Some(gpu)
    } else {
        None
    };
    let lists = Some(mfx_reference::rasterize(&scene, w, h));
    if lists.as_ref().is_some_and(|l| l.total_fragments() == 0) {
        // Not an error (an empty view is a valid question), but never silent: every image of
        // it is the background, and every method "matches" it.
        eprintln!(
            "mfx: warning: scene {} covers no pixel at {w}x{h} from this camera: every image is the background",
            job.spec.label()
        );
    }
    if let (Some(dir), Some(lists)) = (&job.reference_out, &lists) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        std::fs::write(dir.join("camera.json"), &cam_json)?;
        let dc = lists.depth_complexity();
        let max = lists.max_depth_complexity();
        if max > u16::MAX as u32 {
            bail!("depth complexity {max} does not fit uint16: render a smaller scene");
        }
        let dc16: Vec<u16> = dc.iter().map(|&d| d as u16).collect();
        image_io::write_npy(
            &dir.join("depth_complexity.npy"),
            &[h as u64, w as u64],
            &dc16,
        )?;
        image_io::write_png16(&dir.join("depth_complexity.png"), w, h, &dc16)?;
        let reference: Vec<[f32; 4]> = lists
            .composite()
            .iter()
            .map(|p| p.map(|c| c as f32))
            .collect();
        image_io::write_npy_rgba(&dir.join("reference.npy"), w, h, &reference)?;
        image_io::write_png(
            &dir.join("reference.png"),
            w,
            h,
            &reference,
            [1.0, 1.0, 1.0],
        )?;
        println!(
            "reference -> {}: depth complexity max {max}, {} fragments",
            dir.display(),
            lists.total_fragments()
        );
    }
    let Some(gpu) = gpu else {
        return Ok(());
    };
    let gscene = bench_core::gpu_scene::GpuScene::upload(&gpu, &scene, w, h);
    for (method, point) in job.methods.iter().zip(&points) {
        let m = methods::get(method);
        if let Err(why) = methods::supports(m.as_ref(), &gpu, point) {
            if job.methods.len() == 1 {
                bail!("{method} cannot run here: {why}");
            }
            println!("{method}: skipped ({why})");
            continue;
        }
        // A short timing (a few warm frames, a few samples): enough to say what one frame
        // costs; sweeps time properly.
        let plan = bench_core::measure::TimingPlan::from_spec(&scenarios::TimingSpec {
            min_samples: Some(5),
            max_samples: Some(5),
            warmup_frames: Some(2),
            warmup_max_frames: Some(2),
            ..Default::default()
        })
        .expect("a valid plan");
        let mut measured =
            mfx_multifragment::method::measure(&gpu, &gscene, m.as_ref(), point, &plan)?;
        let mut cap = measured.prepared.readback(&gpu, &gscene)?;
        let img = cap
            .image
            .clone()
            .with_context(|| format!("{method} produces no image"))?;
        if let Some(png) = &job.png {
            image_io::write_png(png, w, h, &img, [1.0, 1.0, 1.0])?;
            println!(
                "{}: {} on {} at {w}x{h} -> {}",
                gpu.facts.name,
                method,
                job.spec.label(),
                png.display()
            );
        }
        if let Some(dir) = &job.reference_out {
            image_io::write_npy_rgba(&dir.join(format!("{method}.npy")), w, h, &img)?;
            image_io::write_png(
                &dir.join(format!("{method}.png")),
                w,
                h,
                &img,
                [1.0, 1.0, 1.0],
            )?;
        }
        let lists = lists
            .as_ref()
            .expect("the reference is rasterised for every render");
        measured.prepared.judge(&mut cap, lists);
        let folds = mfx_multifragment::effects::AXES
            .iter()
            .all(|e| m.axes().iter().any(|a| a.name() == e.name()));
        let effect = if folds {
            mfx_multifragment::effects::EffectConfig::from_point(point)
                .map_err(|e| usage(e.to_string()))?
        } else {
            mfx_multifragment::effects::EffectConfig::default()
        };
        let j = mfx_multifragment::judge::judge(
            &cap,
            lists,
            mfx_multifragment::judge::Context {
                scene: &scene,
                effect: &effect,
                exact: m.exact(),
                flip: true,
                truths: None,
            },
        )
        .map_err(|e| anyhow::anyhow!("{method}: {e}"))?;
        let truth = effect.reference(&scene, lists, methods::Expected::All);
        let to32 =
            |v: &[[f64; 4]]| -> Vec<[f32; 4]> { v.iter().map(|p| p.map(|c| c as f32)).collect() };
        if let Some(r) = &job.reference_png {
            image_io::write_png(r, w, h, &to32(&truth), [1.0, 1.0, 1.0])?;
            println!("ground truth (every fragment) -> {}", r.display());
        }
        if let (Some(r), methods::Expected::FirstK(k)) = (&job.reference_k_png, cap.expected) {
            let own = effect.reference(&scene, lists, methods::Expected::FirstK(k));
            image_io::write_png(r, w, h, &to32(&own), [1.0, 1.0, 1.0])?;
            println!(
                "its own definition ({k} nearest fragments) -> {}",
                r.display()
            );
        }
        let capacity = match cap.expected {
            methods::Expected::All => "every fragment".to_string(),
            methods::Expected::FirstK(k) => format!("{k} nearest per pixel"),
        };
        let mut row = bench_core::record::Row::new();
        j.write(&mut row);
        println!(
            "{method} on {} at {w}x{h}: GPU {} ms (wall {:.3} ms); keeps {capacity}; layers captured max {}; overflow in {:.2} % of pixels; flags: {}",
            gpu.facts.name,
            measured
                .gpu_median()
                .map(|g| format!("{g:.3}"))
                .unwrap_or_else(|| "— (no timestamps)".into()),
            measured.cpu.median,
            j.layers_captured_max
                .map(|n| n.to_string())
                .unwrap_or_else(|| "?".into()),
            100.0 * j.overflow_rate,
            row.get(cols::FLAG).filter(|f| !f.is_empty()).unwrap_or("none"),
        );
        if let Some(e) = &j.truth {
            println!(
                "  vs the ground truth (every fragment): rmse {:.3e}, max abs {:.3e}, bad pixels {:.4} %{}{}",
                e.rmse,
                e.max_abs,
                100.0 * e.bad_pixel_frac,
                j.flip
                    .as_ref()
                    .map(|f| format!(", FLIP mean {:.4} (p99 {:.4})", f.result.mean, f.result.p99))
                    .unwrap_or_default(),
                if j.matches_truth == Some(true) { " — matches" } else { "" }
            );
        }
        if let Some(e) = &j.vs_k {
            println!(
                "  vs its own definition ({capacity}): rmse {:.3e}, max abs {:.3e}, bad pixels {:.4} %",
                e.rmse,
                e.max_abs,
                100.0 * e.bad_pixel_frac
            );
        }
    }
    Ok(())
}
