//! The run folder's self-description: `run.json` (what ran, from which commit and suite text, on
//! which device, how far it got) and `runs.json`, the JSON twin of `runs.csv` with a context block.
//! Both are written atomically (a temporary file renamed over the old one), so a reader or a
//! killed run never sees half a file.

use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use sha2::{Digest, Sha256};

use crate::record::cols;
use crate::{CoreError, Result};

/// File names inside a run folder.
pub const MANIFEST_FILE: &str = "run.json";
pub const RUNS_JSON_FILE: &str = "runs.json";
pub const RUNS_CSV_FILE: &str = "runs.csv";

/// The device, as the CSV's adapter columns spell it, plus its PCI bus id.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AdapterInfo {
    pub name: String,
    /// Lower-case wgpu backend (`vulkan`, `gl`, …), as in the `backend` column.
    pub backend: String,
    /// Lower-case wgpu device type (`discretegpu`, `cpu`, …), as in `device_type`.
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    /// Empty where the backend does not report it.
    pub pci_bus_id: String,
}

impl AdapterInfo {
    pub fn of(info: &wgpu::AdapterInfo) -> Self {
        AdapterInfo {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend).to_lowercase(),
            device_type: format!("{:?}", info.device_type).to_lowercase(),
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
            pci_bus_id: info.device_pci_bus_id.clone(),
        }
    }
}

/// Which physical GPU ran the points: NVML's identity where NVML has the device, else what
/// wgpu's adapter info says (`run.json`'s `gpu`; its `uuid`, `serial` and `pci_bus_id` are also
/// row columns, so a merge of shards from several GPUs says which row ran where).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GpuIdentity {
    /// `GPU-…` from NVML; empty without it.
    pub uuid: String,
    /// The board serial from NVML; empty where NVML has none.
    pub serial: String,
    /// domain:bus:device.function: NVML's, else wgpu's; empty where neither says.
    pub pci_bus_id: String,
    /// PCI vendor and device ids from wgpu's adapter info (0 where the backend gives none).
    pub vendor_id: u32,
    pub device_id: u32,
    /// `nvml` or `wgpu adapter info (…why not NVML)`.
    pub source: String,
    /// How the processes holding the GPU are read for `gpu_shared`, and what the first read
    /// saw of this process (see `clocks::other_processes`).
    pub process_list: String,
}

impl GpuIdentity {
    /// The identity of `gpu`'s device, and one read of its process list.
    pub fn of(gpu: &crate::gpu::Gpu) -> Self {
        let info = gpu.adapter.get_info();
        let mut id = GpuIdentity {
            pci_bus_id: info.device_pci_bus_id.clone(),
            vendor_id: info.vendor,
            device_id: info.device,
            ..Default::default()
        };
        match &gpu.monitor {
            Ok(m) => {
                id.uuid = m.uuid().to_string();
                id.serial = m.serial().to_string();
                if !m.bus_id().is_empty() {
                    id.pci_bus_id = m.bus_id().to_string();
                }
                id.source = "nvml".into();
            }
            Err(why) => id.source = format!("wgpu adapter info ({why})"),
        }
        let own = crate::clocks::own_pids();
        let pids = match (&gpu.process_list, &gpu.monitor) {
            (Some(l), _) => l
                .pids()
                .map(|p| ("a given list", p))
                .map_err(|e| e.to_string()),
            (None, Ok(m)) => crate::clocks::ProcessList::pids(m)
                .map(|p| ("nvml", p))
                .map_err(|e| e.to_string()),
            (None, Err(why)) => Err(why.to_string()),
        };
        id.process_list = match pids {
            Err(why) => format!("none: {why} (gpu_other_processes stays empty)"),
            Ok((src, p)) if p.iter().any(|x| own.contains(x)) => format!(
                "{src}: this process is listed (pid {:?}); {} other(s) at the start",
                own,
                crate::clocks::other_processes(&p, &own)
            ),
            Ok((src, p)) if !p.is_empty() => format!(
                "{src}: this process is not listed by its own ids {own:?} (the list has another pid namespace's): one listed process is taken for it; {} other(s) at the start",
                crate::clocks::other_processes(&p, &own)
            ),
            Ok((src, _)) => format!(
                "{src}: no process listed at the start, this one neither (a list that hides this process may hide one other)"
            ),
        };
        id
    }
}

/// The batch job a run ran in (`run.json`'s `job`; also row columns): Slurm's environment
/// variables, empty outside Slurm.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JobInfo {
    pub slurm_job_id: String,
    pub slurm_array_job_id: String,
    pub slurm_array_task_id: String,
    /// `SLURM_JOB_NODELIST`: the node(s) of the job.
    pub slurm_job_nodelist: String,
}

impl JobInfo {
    /// From this process's environment.
    pub fn from_env() -> Self {
        Self::from_vars(|k| std::env::var(k).ok())
    }
    /// From any variable lookup (tests).
    pub fn from_vars(var: impl Fn(&str) -> Option<String>) -> Self {
        let v = |k: &str| var(k).unwrap_or_default().trim().to_string();
        JobInfo {
            slurm_job_id: v("SLURM_JOB_ID"),
            slurm_array_job_id: v("SLURM_ARRAY_JOB_ID"),
            slurm_array_task_id: v("SLURM_ARRAY_TASK_ID"),
            slurm_job_nodelist: v("SLURM_JOB_NODELIST"),
        }
    }
}

/// The cells every row of a run carries from its GPU identity and job (`RunOptions::row_cells`).
pub fn row_cells(gpu: &GpuIdentity, job: &JobInfo) -> Vec<(schema::Col, String)> {
    vec![
        (cols::GPU_UUID, gpu.uuid.clone()),
        (cols::GPU_SERIAL, gpu.serial.clone()),
        (cols::PCI_BUS_ID, gpu.pci_bus_id.clone()),
        (cols::SLURM_JOB_ID, job.slurm_job_id.clone()),
        (cols::SLURM_ARRAY_JOB_ID, job.slurm_array_job_id.clone()),
        (cols::SLURM_ARRAY_TASK_ID, job.slurm_array_task_id.clone()),
    ]
}

/// How `--shard I/N` chose this shard's groups (`run.json`'s `shard_balance`; absent: index
/// mod N).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ShardBalance {
    /// The run whose times balanced the shards (`--balance-from`), as given.
    pub from: String,
    /// The rule, in words.
    pub rule: String,
    /// Estimated seconds of each shard's groups, shard 0 first.
    pub estimated_s: Vec<f64>,
}

/// A fixed kernel timed on a shard's GPU before its points, so a merge of shards from several
/// GPUs can say how far the GPUs differ (identical GPUs differ by 8 % on average, Sinha et al.,
/// SC'22).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GpuCalibration {
    /// What was timed.
    pub set: String,
    /// Its median GPU time.
    pub canary_ms: f64,
    pub runs: usize,
}

/// What [`GpuCalibration::set`] says of the set this build measures.
pub const CALIBRATION_SET: &str =
    "canary kernel (16 MiB read by 264 workgroups, 2048 FMAs a thread), median of 21 after a clock lift";
/// Runs of the set.
pub const CALIBRATION_RUNS: usize = 21;

/// The machine a run ran on, beyond the adapter: lavapipe's speed is the CPU's, and a driver's
/// behaviour can be the kernel's.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HostInfo {
    /// `model name` of /proc/cpuinfo's first CPU (empty where unreadable).
    pub cpu_model: String,
    /// Logical CPUs this process may use (`std::thread::available_parallelism`).
    pub cpu_cores: usize,
    /// `linux`, `windows`, … and the distribution's PRETTY_NAME where /etc/os-release has one.
    pub os: String,
    /// Kernel release (/proc/sys/kernel/osrelease; empty elsewhere).
    pub kernel: String,
}

impl HostInfo {
    /// This machine, now.
    pub fn here() -> Self {
        let read = |p: &str| std::fs::read_to_string(p).unwrap_or_default();
        let cpu_model = read("/proc/cpuinfo")
            .lines()
            .find_map(|l| {
                let (k, v) = l.split_once(':')?;
                (k.trim() == "model name").then(|| v.trim().to_string())
            })
            .unwrap_or_default();
        let distro = read("/etc/os-release")
            .lines()
            .find_map(|l| l.strip_prefix("PRETTY_NAME="))
            .map(|v| v.trim_matches('"').to_string());
        HostInfo {
            cpu_model,
            cpu_cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(0),
            os: match distro {
                Some(d) => format!("{} ({d})", std::env::consts::OS),
                None => std::env::consts::OS.to_string(),
            },
            kernel: read("/proc/sys/kernel/osrelease").trim().to_string(),
        }
    }
}

/// How the binary was built (fixed at compile time, `build_info`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildInfo {
    /// `rustc --version`.
    pub rustc: String,
    /// wgpu's version from Cargo.lock.
    pub wgpu: String,
    /// Cargo profile and opt-level, e.g. `release (opt-level 3)`: a debug build times slower
    /// CPU work (judging, references), never the GPU's.
    pub profile: String,
}

impl BuildInfo {
    pub fn this() -> Self {
        BuildInfo {
            rustc: crate::build_info::RUSTC.to_string(),
            wgpu: crate::build_info::WGPU.to_string(),
            profile: crate::build_info::PROFILE.to_string(),
        }
    }
}

/// One invocation of `mfx sweep` on a run folder: the first, and one per `--resume`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Call {
    pub command_line: Vec<String>,
    pub git_rev: String,
    pub started_utc: String,
    pub ended_utc: Option<String>,
    pub elapsed_s: Option<f64>,
    /// Rows this call wrote.
    pub rows_written: usize,
    pub interrupted: Option<String>,
}

/// `run.json`: written when the run starts (`finished: false`), rewritten as it ends or is
/// interrupted. Counts are of this run folder's `runs.csv` rows.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunManifest {
    pub mfx_version: String,
    /// `build_info::git_rev()` of the binary that wrote the run.
    pub git_rev: String,
    /// `std::env::args()`, program first.
    pub command_line: Vec<String>,
    pub suite_name: String,
    /// `built-in NAME` or the suite file's path as given.
    pub suite_source: String,
    /// The suite's TOML exactly as read, so the run can be repeated without the file.
    pub suite_text: String,
    /// Lower-case hex SHA-256 of `suite_text`'s UTF-8 bytes.
    pub suite_sha256: String,
    pub adapter: AdapterInfo,
    /// (I, N) of `--shard I/N`; (0, 1) for a whole run.
    pub shard: (usize, usize),
    /// RFC 3339, UTC, seconds.
    pub started_utc: String,
    pub ended_utc: Option<String>,
    /// Wall time from `new` to `finish` (monotonic clock); `None` until finished.
    pub elapsed_s: Option<f64>,
    pub rows_written: usize,
    pub rows_ok: usize,
    pub rows_failed: usize,
    pub rows_skipped: usize,
    /// Points this shard was to measure (resumed ones included).
    pub points_total: usize,
    /// Rows already in `runs.csv` when the run was resumed (kept, not measured again).
    pub resumed_points: usize,
    /// Every point of the shard has a row.
    pub finished: bool,
    /// The signal that stopped the run early (`SIGINT`, `SIGTERM`), if one did.
    pub interrupted: Option<String>,
    /// The cross-GPU calibration set measured on this GPU before its points (absent in runs
    /// before issue 33, and on software adapters).
    #[serde(default)]
    pub calibration: Option<GpuCalibration>,
    /// The adapter's memory roofs measured before the points (`roofs`: a copy kernel in and far
    /// beyond the L2; absent in runs before issue 41 and without timestamp queries).
    #[serde(default)]
    pub roofs: Option<crate::roofs::Roofs>,
    /// The machine of the latest call (absent in run.json files older than this field).
    #[serde(default)]
    pub host: HostInfo,
    /// How the binary of the latest call was built.
    #[serde(default)]
    pub build: BuildInfo,
    /// The suite's `[software]` profile applied (a software adapter and a suite that has one).
    #[serde(default)]
    pub software_profile: bool,
    /// The limits profile the device was requested with (`--limits`; the `limits` column).
    #[serde(default)]
    pub limits: crate::limits::Profile,
    /// Every call on this run folder, oldest first; the last is this one. The top-level
    /// command line, times and counts are the latest call's (counts: of the whole folder).
    #[serde(default)]
    pub calls: Vec<Call>,
    /// The physical GPU of the latest call (absent in run.json files older than this field).
    #[serde(default)]
    pub gpu: GpuIdentity,
    /// The batch job of the latest call (empty outside Slurm).
    #[serde(default)]
    pub job: JobInfo,
    /// How the shard's groups were chosen when `--balance-from` balanced them.
    #[serde(default)]
    pub shard_balance: Option<ShardBalance>,
    #[serde(skip)]
    clock: Option<Instant>,
}

fn now_utc() -> String {
    chrono::Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
}

/// Lower-case hex SHA-256 of `text`.
pub fn sha256_hex(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> CoreError {
    CoreError::Io(format!("{}: {e}", path.display()))
}

/// Writes `bytes` to `dir/name` through `dir/.name.tmp` and a rename: on one file system the
/// rename replaces the old file at once, so a reader sees the old or the new file, never a part.
fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    let tmp = dir.join(format!(".{name}.tmp"));
    let path = dir.join(name);
    let mut f = std::fs::File::create(&tmp).map_err(|e| io_err(&tmp, e))?;
    f.write_all(bytes).map_err(|e| io_err(&tmp, e))?;
    f.sync_all().map_err(|e| io_err(&tmp, e))?;
    drop(f);
    std::fs::rename(&tmp, &path).map_err(|e| io_err(&path, e))
}

impl RunManifest {
    /// A manifest for a run starting now, from this build (`mfx_version`, `git_rev`).
    pub fn new(
        command_line: Vec<String>,
        suite_name: &str,
        suite_source: &str,
        suite_text: &str,
        adapter: AdapterInfo,
        shard: (usize, usize),
    ) -> Self {
        let started = now_utc();
        let call = Call {
            command_line: command_line.clone(),
            git_rev: crate::build_info::git_rev(),
            started_utc: started.clone(),
            ..Call::default()
        };
        RunManifest {
            mfx_version: crate::build_info::VERSION.to_string(),
            git_rev: crate::build_info::git_rev(),
            command_line,
            suite_name: suite_name.to_string(),
            suite_source: suite_source.to_string(),
            suite_text: suite_text.to_string(),
            suite_sha256: sha256_hex(suite_text),
            adapter,
            shard,
            started_utc: started,
            ended_utc: None,
            elapsed_s: None,
            rows_written: 0,
            rows_ok: 0,
            rows_failed: 0,
            rows_skipped: 0,
            points_total: 0,
            resumed_points: 0,
            finished: false,
            interrupted: None,
            calibration: None,
            roofs: None,
            host: HostInfo::here(),
            build: BuildInfo::this(),
            software_profile: false,
            limits: Default::default(),
            calls: vec![call],
            gpu: GpuIdentity::default(),
            job: JobInfo::from_env(),
            shard_balance: None,
            clock: Some(Instant::now()),
        }
    }

    /// A resumed run: the calls of the folder's earlier `run.json` come before this one (an
    /// older file without `calls` counts as one call, from its top-level fields).
    pub fn continue_from(&mut self, old: &RunManifest) {
        let mut calls = if old.calls.is_empty() {
            vec![Call {
                command_line: old.command_line.clone(),
                git_rev: old.git_rev.clone(),
                started_utc: old.started_utc.clone(),
                ended_utc: old.ended_utc.clone(),
                elapsed_s: old.elapsed_s,
                rows_written: old.rows_written,
                interrupted: old.interrupted.clone(),
            }]
        } else {
            old.calls.clone()
        };
        calls.append(&mut self.calls);
        self.calls = calls;
    }

    /// Stamps the end: `ended_utc`, `elapsed_s`, and `interrupted` (the signal, if any).
    /// `finished` is the caller's to set: whether every point has a row.
    pub fn finish(&mut self, interrupted: Option<&str>) {
        self.ended_utc = Some(now_utc());
        self.elapsed_s = self.clock.map(|c| c.elapsed().as_secs_f64());
        self.interrupted = interrupted.map(str::to_string);
        if let Some(c) = self.calls.last_mut() {
            c.ended_utc = self.ended_utc.clone();
            c.elapsed_s = self.elapsed_s;
            c.interrupted = self.interrupted.clone();
            c.rows_written = self.rows_written;
        }
    }

    /// Writes `dir/run.json` atomically.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let json =
            serde_json::to_vec_pretty(self).map_err(|e| CoreError::Io(format!("run.json: {e}")))?;
        write_atomic(dir, MANIFEST_FILE, &json)
    }

    /// Reads `dir/run.json`.
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join(MANIFEST_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| io_err(&path, e))?;
        serde_json::from_str(&text).map_err(|e| io_err(&path, e))
    }
}

/// The context block of `runs.json`: what a reader needs to interpret every row without the
/// rest of the run folder.
pub fn context_block(manifest: &RunManifest, schema_version: u32, clocks: Option<Value>) -> Value {
    let m = manifest;
    let mut c = serde_json::json!({
        "mfx_version": m.mfx_version,
        "git_rev": m.git_rev,
        "schema_version": schema_version,
        "suite": {
            "name": m.suite_name,
            "source": m.suite_source,
            "sha256": m.suite_sha256,
        },
        "adapter": m.adapter,
        "gpu": m.gpu,
        "job": m.job,
        "host": m.host,
        "build": m.build,
        "software_profile": m.software_profile,
        "limits": m.limits,
        "shard": format!("{}/{}", m.shard.0, m.shard.1),
        "started_utc": m.started_utc,
        "ended_utc": m.ended_utc,
        "finished": m.finished,
        "interrupted": m.interrupted,
    });
    if let Some(clocks) = clocks {
        c["clocks"] = clocks;
    }
    c
}

/// Cells of these columns stay strings whatever they look like: identities, where a
/// digits-only git revision or run id read as a number would lose its leading zeros or digits.
pub const TEXT_COLUMNS: &[&str] = &[
    cols::GIT_REV.name,
    cols::RUN_ID.name,
    cols::POINT_KEY.name,
    cols::SCENE_LABEL.name,
    cols::ADAPTER.name,
    cols::DRIVER.name,
    cols::DRIVER_INFO.name,
];

/// How one column's cells become JSON, decided over the whole column so a column never mixes
/// types: all non-empty cells `true`/`false` → booleans; all numbers (or `inf`/`nan`) → numbers,
/// the non-finite ones as strings; anything else → strings.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Bool,
    Number,
    Text,
}

/// An integer with no leading zeros (so `007` stays text) as an exact JSON integer, a finite
/// float as a JSON number; `None` if the cell is not a number, `Some(Err)` if non-finite.
fn number(cell: &str) -> Option<std::result::Result<Value, ()>> {
    let digits = cell.strip_prefix('-').unwrap_or(cell);
    let is_int = !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit());
    if is_int {
        if digits.len() > 1 && digits.starts_with('0') {
            return None;
        }
        if let Ok(i) = cell.parse::<i64>() {
            return Some(Ok(Value::from(i)));
        }
        if let Ok(u) = cell.parse::<u64>() {
            return Some(Ok(Value::from(u)));
        }
    }
    let f = cell.parse::<f64>().ok()?;
    Some(serde_json::Number::from_f64(f).map(Value::Number).ok_or(()))
}

fn cell_value(kind: Kind, cell: &str) -> Value {
    match kind {
        Kind::Bool => Value::Bool(cell == "true"),
        Kind::Number => match number(cell) {
            Some(Ok(v)) => v,
            _ => Value::String(cell.to_string()),
        },
        Kind::Text => Value::String(cell.to_string()),
    }
}

/// Reads `dir/runs.csv` and writes `dir/runs.json` = `{"context": context, "rows": [{column:
/// value, …}, …]}` atomically, rows in CSV order. Empty cells are left out of their row; column
/// types as in [`Kind`] (identity columns in [`TEXT_COLUMNS`] are always strings).
pub fn write_runs_json(dir: &Path, context: &Value) -> Result<()> {
    let path = dir.join(RUNS_CSV_FILE);
    let mut rd = csv::Reader::from_path(&path).map_err(|e| io_err(&path, e))?;
    let headers: Vec<String> = rd
        .headers()
        .map_err(|e| io_err(&path, e))?
        .iter()
        .map(str::to_string)
        .collect();
    let records: Vec<csv::StringRecord> = rd
        .records()
        .collect::<std::result::Result<_, _>>()
        .map_err(|e| io_err(&path, e))?;
    let kinds: Vec<Kind> = headers
        .iter()
        .enumerate()
        .map(|(i, h)| {
            let cells = || {
                records
                    .iter()
                    .filter_map(|r| r.get(i))
                    .filter(|c| !c.is_empty())
            };
            if TEXT_COLUMNS.contains(&h.as_str()) {
                Kind::Text
            } else if cells().all(|c| c == "true" || c == "false") {
                Kind::Bool
            } else if cells().all(|c| number(c).is_some()) {
                Kind::Number
            } else {
                Kind::Text
            }
        })
        .collect();
    let rows: Vec<Value> = records
        .iter()
        .map(|r| {
            let mut row = Map::new();
            for (i, cell) in r.iter().enumerate() {
                if cell.is_empty() {
                    continue;
                }
                let key = headers
                    .get(i)
                    .cloned()
                    .unwrap_or_else(|| format!("column_{i}"));
                let kind = kinds.get(i).copied().unwrap_or(Kind::Text);
                row.insert(key, cell_value(kind, cell));
            }
            Value::Object(row)
        })
        .collect();
    let doc = serde_json::json!({ "context": context, "rows": rows });
    let json = serde_json::to_vec_pretty(&doc)
        .map_err(|e| CoreError::Io(format!("{RUNS_JSON_FILE}: {e}")))?;
    write_atomic(dir, RUNS_JSON_FILE, &json)
}

#[cfg(test)]
mod tests {
    use super::*;

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

    fn temp(name: &str) -> Tmp {
        tmp_dir(&format!("mfx-manifest-{name}"))
    }

    fn sample() -> RunManifest {
        let mut m = RunManifest::new(
            vec!["mfx".into(), "sweep".into(), "smoke".into()],
            "smoke",
            "built-in smoke",
            "name = \"smoke\"\n",
            AdapterInfo {
                name: "llvmpipe".into(),
                backend: "vulkan".into(),
                device_type: "cpu".into(),
                driver: "llvmpipe".into(),
                driver_info: "Mesa 25".into(),
                pci_bus_id: String::new(),
            },
            (1, 4),
        );
        m.rows_written = 7;
        m.rows_ok = 5;
        m.rows_failed = 1;
        m.rows_skipped = 1;
        m.points_total = 9;
        m.resumed_points = 2;
        m
    }

    #[test]
    fn a_resumed_run_keeps_every_call_and_says_where_it_ran() {
        let mut first = sample();
        first.finish(Some("SIGINT"));
        // A run.json from before `calls` existed reads, and counts as one call.
        let mut old: serde_json::Value = serde_json::to_value(&first).unwrap();
        for k in ["calls", "host", "build", "software_profile"] {
            old.as_object_mut().unwrap().remove(k);
        }
        let old: RunManifest = serde_json::from_value(old).unwrap();
        assert!(old.calls.is_empty());
        let mut second = sample();
        second.command_line.push("--resume".into());
        second.calls[0].command_line.push("--resume".into());
        second.continue_from(&old);
        second.rows_written = 2;
        second.finish(None);
        assert_eq!(second.calls.len(), 2);
        assert_eq!(second.calls[0].interrupted.as_deref(), Some("SIGINT"));
        assert_eq!(second.calls[0].rows_written, 7);
        assert_eq!(second.calls[1].rows_written, 2);
        assert!(second.calls[1]
            .command_line
            .contains(&"--resume".to_string()));
        let mut third = sample();
        third.continue_from(&second);
        assert_eq!(third.calls.len(), 3, "a third call keeps both earlier ones");
        assert!(second.host.cpu_cores > 0);
        assert!(
            second.build.rustc.starts_with("rustc "),
            "{}",
            second.build.rustc
        );
        assert_eq!(
            second.build.wgpu.split('.').count(),
            3,
            "{}",
            second.build.wgpu
        );
    }

    #[test]
    fn sha256_of_known_text() {
        // FIPS 180-2 test vector.
        assert_eq!(
            sha256_hex("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn manifest_round_trips() {
        let dir = temp("round-trip");
        let mut m = sample();
        m.finish(Some("SIGINT"));
        m.write(&dir).unwrap();
        let back = RunManifest::read(&dir).unwrap();
        assert_eq!(
            serde_json::to_value(&back).unwrap(),
            serde_json::to_value(&m).unwrap()
        );
        assert_eq!(back.interrupted.as_deref(), Some("SIGINT"));
        assert_eq!(back.shard, (1, 4));
        assert_eq!(back.suite_sha256, sha256_hex("name = \"smoke\"\n"));
        assert_eq!(back.git_rev, crate::build_info::git_rev());
        assert!(back.elapsed_s.unwrap() >= 0.0);
        assert!(back.ended_utc.unwrap().ends_with('Z'));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn manifest_replaced_atomically() {
        let dir = temp("atomic");
        let mut m = sample();
        m.write(&dir).unwrap();
        assert!(!RunManifest::read(&dir).unwrap().finished);
        // A stale temporary from a run killed mid-write does not stop the next write.
        std::fs::write(dir.join(".run.json.tmp"), b"{ half").unwrap();
        m.finished = true;
        m.finish(None);
        m.write(&dir).unwrap();
        let back = RunManifest::read(&dir).unwrap();
        assert!(back.finished && back.interrupted.is_none());
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, vec!["run.json".to_string()], "no temporary left");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn runs_json_types_cells_by_column() {
        let dir = temp("twin");
        std::fs::write(
            dir.join("runs.csv"),
            "point_key,git_rev,status,gpu_ms_median,rmse,samples,order_seed,matches_truth,reason,code\n\
             a|1,123456789012,ok,1.25,inf,30,18446744073709551615,true,,007\n\
             b|2,123456789012,failed,,NaN,-3,0,false,\"out of memory, 2 GiB\",12\n",
        )
        .unwrap();
        let m = sample();
        let ctx = context_block(&m, 7, Some(serde_json::json!({"source": "none: no nvml"})));
        write_runs_json(&dir, &ctx).unwrap();
        let doc: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("runs.json")).unwrap()).unwrap();
        assert_eq!(doc["context"]["schema_version"], 7);
        assert_eq!(doc["context"]["git_rev"], crate::build_info::git_rev());
        assert_eq!(doc["context"]["adapter"]["driver"], "llvmpipe");
        assert_eq!(doc["context"]["shard"], "1/4");
        assert_eq!(doc["context"]["clocks"]["source"], "none: no nvml");
        let rows = doc["rows"].as_array().unwrap();
        assert_eq!(rows.len(), 2);
        let a = &rows[0];
        assert_eq!(a["point_key"], "a|1");
        assert_eq!(a["git_rev"], "123456789012", "identity columns stay text");
        assert_eq!(a["gpu_ms_median"], 1.25);
        assert_eq!(a["rmse"], "inf", "non-finite as strings");
        assert_eq!(a["samples"], 30);
        assert_eq!(a["order_seed"], u64::MAX, "integers exact, not through f64");
        assert_eq!(a["matches_truth"], true);
        assert!(a.get("reason").is_none(), "empty cells left out");
        assert_eq!(
            a["code"], "007",
            "a column with a leading-zero cell stays text"
        );
        let b = &rows[1];
        assert!(b.get("gpu_ms_median").is_none());
        assert_eq!(b["rmse"], "NaN");
        assert_eq!(b["samples"], -3);
        assert_eq!(b["matches_truth"], false);
        assert_eq!(b["reason"], "out of memory, 2 GiB");
        assert_eq!(b["code"], "12");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_job_comes_from_slurm_variables_and_lands_in_every_row_cell() {
        let env = |k: &str| match k {
            "SLURM_JOB_ID" => Some("4711".to_string()),
            "SLURM_ARRAY_JOB_ID" => Some("4700".to_string()),
            "SLURM_ARRAY_TASK_ID" => Some(" 3\n".to_string()),
            _ => None,
        };
        let job = JobInfo::from_vars(env);
        assert_eq!(job.slurm_array_task_id, "3");
        assert_eq!(job.slurm_job_nodelist, "");
        let gpu = GpuIdentity {
            uuid: "GPU-8a1e".into(),
            pci_bus_id: "00000000:19:00.0".into(),
            ..Default::default()
        };
        let cells: std::collections::BTreeMap<&str, String> = row_cells(&gpu, &job)
            .into_iter()
            .map(|(c, v)| (c.name, v))
            .collect();
        assert_eq!(cells["gpu_uuid"], "GPU-8a1e");
        assert_eq!(cells["pci_bus_id"], "00000000:19:00.0");
        assert_eq!(cells["slurm_job_id"], "4711");
        assert_eq!(cells["slurm_array_job_id"], "4700");
        assert_eq!(cells["slurm_array_task_id"], "3");
        assert_eq!(cells["gpu_serial"], "");
        // run.json and runs.json's context carry both; an older run.json without them reads.
        let mut m = sample();
        m.gpu = gpu.clone();
        m.job = job.clone();
        let ctx = context_block(&m, 3, None);
        assert_eq!(ctx["gpu"]["uuid"], "GPU-8a1e");
        assert_eq!(ctx["job"]["slurm_job_id"], "4711");
        let mut old = serde_json::to_value(&m).unwrap();
        for k in ["gpu", "job", "shard_balance"] {
            old.as_object_mut().unwrap().remove(k);
        }
        let old: RunManifest = serde_json::from_value(old).unwrap();
        assert_eq!(old.gpu, GpuIdentity::default());
        assert!(old.shard_balance.is_none());
    }

    #[test]
    fn context_without_clocks_has_no_clocks_key() {
        let ctx = context_block(&sample(), 3, None);
        assert!(ctx.get("clocks").is_none());
        assert_eq!(ctx["suite"]["source"], "built-in smoke");
        assert_eq!(ctx["finished"], false);
    }
}
