//! GPU clocks, temperature, power and throttle reasons during a point, read through NVML
//! (`nvml-wrapper`, which loads `libnvidia-ml.so.1` at run time: a machine without the NVIDIA
//! driver builds and runs the same binary and records `clock_source = none: <reason>`).
//!
//! Read-only: only NVML queries (`nvmlDeviceGet*`) are called, never a setter — mfx never locks,
//! resets or otherwise changes clocks or any GPU setting.
//!
//! Use: [`GpuMonitor::open`] once per run with the wgpu adapter's `device_pci_bus_id`; after
//! each timed sample, [`GpuMonitor::sample`]; feed kept samples to [`PointClocks::push`] and
//! throttled ones (see `mfx_stats::throttle`, reference [`GpuMonitor::reference_sm_mhz`]) to
//! [`PointClocks::push_discarded`]; write [`PointClocks::to_cells`] into the row.

use crate::record::{cols, Col};
use std::collections::BTreeSet;

use nvml_wrapper::bitmasks::device::ThrottleReasons;
use nvml_wrapper::enum_wrappers::device::{Clock, TemperatureSensor};
use nvml_wrapper::error::NvmlError;
use nvml_wrapper::Nvml;

/// Why there is no NVML monitor for the adapter, or why a process list cannot be read: its text
/// is the `clock_source = none: <reason>` cell, word for word.
#[derive(Debug, thiserror::Error)]
pub enum MonitorError {
    /// `libnvidia-ml.so.1` cannot be loaded or initialised (no NVIDIA driver).
    #[error("NVML not available: {0}")]
    Unavailable(NvmlError),
    #[error("NVML device count: {0}")]
    DeviceCount(NvmlError),
    #[error("NVML device {index}: {error}")]
    Device { index: u32, error: NvmlError },
    #[error("adapter PCI bus id '{0}' is not domain:bus:dev.fn")]
    BadBusId(String),
    #[error("no NVML device at PCI bus id {bus_id} (NVML devices: {})", .seen.join(", "))]
    NoDeviceAt { bus_id: String, seen: Vec<String> },
    #[error("NVML lists no devices")]
    NoDevices,
    /// Several NVIDIA devices and no bus id to choose one by: none is guessed.
    #[error("{count} NVML devices and no adapter PCI bus id to choose one ({})", .seen.join(", "))]
    Ambiguous { count: u32, seen: Vec<String> },
    /// Neither of NVML's process lists (compute, graphics) can be read.
    #[error("NVML process lists: compute: {compute}; graphics: {graphics}")]
    ProcessLists {
        compute: NvmlError,
        graphics: NvmlError,
    },
    /// NVML knows no other vendor's GPUs.
    #[error("not an NVIDIA adapter ({name}, vendor {vendor:#06x}): no NVML clocks")]
    NotNvidia { name: String, vendor: u32 },
}

/// NVML's throttle reasons by the names written in `throttle_reasons`.
const REASONS: [(ThrottleReasons, &str); 9] = [
    (ThrottleReasons::GPU_IDLE, "gpu_idle"),
    (
        ThrottleReasons::APPLICATIONS_CLOCKS_SETTING,
        "applications_clocks_setting",
    ),
    (ThrottleReasons::SW_POWER_CAP, "sw_power_cap"),
    (ThrottleReasons::HW_SLOWDOWN, "hw_slowdown"),
    (ThrottleReasons::SYNC_BOOST, "sync_boost"),
    (ThrottleReasons::SW_THERMAL_SLOWDOWN, "sw_thermal_slowdown"),
    (ThrottleReasons::HW_THERMAL_SLOWDOWN, "hw_thermal_slowdown"),
    (
        ThrottleReasons::HW_POWER_BRAKE_SLOWDOWN,
        "hw_power_brake_slowdown",
    ),
    (
        ThrottleReasons::DISPLAY_CLOCK_SETTING,
        "display_clock_setting",
    ),
];

/// Reasons that mean the clock was held *below* what the workload asked for (power, thermal,
/// hardware protection): a point that saw one is flagged `throttled`. The others are not
/// slowdowns: `gpu_idle` (set whenever no work is queued — true right after each frame, which
/// is when the monitor reads, so it is not recorded), `applications_clocks_setting` (running at
/// the configured application clock), `sync_boost`, `display_clock_setting`.
pub const SLOWDOWN_REASONS: [&str; 5] = [
    "sw_power_cap",
    "hw_slowdown",
    "sw_thermal_slowdown",
    "hw_thermal_slowdown",
    "hw_power_brake_slowdown",
];

/// One reading, taken right after a timed sample. A query the device does not support gives
/// `None`, never 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MonitorSample {
    pub sm_mhz: Option<f64>,
    pub mem_mhz: Option<f64>,
    pub temp_c: Option<f64>,
    pub power_w: Option<f64>,
    pub throttle_reasons: Vec<&'static str>,
    /// Processes other than this one holding the GPU ([`other_processes`]); `None` without a
    /// process list or when it could not be read.
    pub other_processes: Option<u32>,
}

impl MonitorSample {
    /// Whether any slowdown reason ([`SLOWDOWN_REASONS`]) was active.
    pub fn slowdown(&self) -> bool {
        self.throttle_reasons
            .iter()
            .any(|r| SLOWDOWN_REASONS.contains(r))
    }
}

/// A PCI address as (domain, bus, device, function). wgpu writes `0000:00:06.0`, NVML
/// `00000000:00:06.0`; both parse to the same tuple. Case-insensitive hex.
pub fn parse_pci_bus_id(s: &str) -> Option<(u32, u32, u32, u32)> {
    let s = s.trim();
    let mut parts = s.split(':');
    let (a, b, c) = (parts.next()?, parts.next()?, parts.next());
    // "domain:bus:dev.fn", or "bus:dev.fn" with domain 0.
    let (domain, bus, devfn) = match c {
        Some(c) => (a, b, c),
        None => ("0", a, b),
    };
    if parts.next().is_some() {
        return None;
    }
    let (dev, func) = devfn.split_once('.')?;
    let hex = |x: &str| u32::from_str_radix(x, 16).ok();
    Some((hex(domain)?, hex(bus)?, hex(dev)?, hex(func)?))
}

/// Where the processes holding the GPU come from: NVML's lists on an NVIDIA GPU; a test feeds
/// its own (the GPU's process list cannot be faked through NVML).
pub trait ProcessList: Send + Sync {
    /// The ids of every process holding the GPU now (this one included, where listed).
    fn pids(&self) -> Result<Vec<u32>, MonitorError>;
}

/// A fixed list (tests): every read returns `pids`.
#[derive(Clone, Debug)]
pub struct FixedProcesses(pub Vec<u32>);

impl ProcessList for FixedProcesses {
    fn pids(&self) -> Result<Vec<u32>, MonitorError> {
        Ok(self.0.clone())
    }
}

/// This process's ids: `std::process::id()` and, where `/proc/self/status` has an `NSpid`
/// line, its id in every pid namespace it can see.
pub fn own_pids() -> Vec<u32> {
    static OWN: std::sync::OnceLock<Vec<u32>> = std::sync::OnceLock::new();
    OWN.get_or_init(read_own_pids).clone()
}

fn read_own_pids() -> Vec<u32> {
    let mut own = vec![std::process::id()];
    if let Ok(status) = std::fs::read_to_string("/proc/self/status") {
        if let Some(line) = status.lines().find_map(|l| l.strip_prefix("NSpid:")) {
            own.extend(
                line.split_whitespace()
                    .filter_map(|p| p.parse::<u32>().ok()),
            );
        }
    }
    own.sort_unstable();
    own.dedup();
    own
}

/// How many processes other than this one `pids` (a GPU's process list) holds. Where none of
/// `own` is listed, NVML reports ids of another pid namespace (this process runs in a
/// container and NVML lists host pids), so one listed process is taken for this one and the
/// others are the rest; a list that does not show this process at all misses at most one other.
pub fn other_processes(pids: &[u32], own: &[u32]) -> u32 {
    let mut listed = pids.to_vec();
    listed.sort_unstable();
    listed.dedup();
    let others = listed.iter().filter(|p| !own.contains(p)).count();
    if others == listed.len() {
        others.saturating_sub(1) as u32
    } else {
        others as u32
    }
}

/// An open NVML device.
pub struct GpuMonitor {
    nvml: Nvml,
    index: u32,
    name: String,
    bus_id: String,
    driver: String,
    /// `GPU-…` (empty where NVML gives none).
    uuid: String,
    /// The board serial (empty where NVML gives none).
    serial: String,
    default_sm_mhz: Option<f64>,
    max_sm_mhz: Option<f64>,
    /// Peak memory bandwidth in bytes/s ([`peak_bandwidth`]).
    peak_bandwidth: Option<f64>,
}

/// Peak memory bandwidth in bytes/s from NVML's memory bus width (bits) and maximum memory
/// clock (MHz): width / 8 × clock × 2, two transfers per clock (DDR; NVML's HBM clock counts
/// the same way: an H200's 6144-bit bus at 3201 MHz gives 4.92 TB/s, its data sheet's 4.8).
pub fn peak_bandwidth(bus_width_bits: u32, max_mem_mhz: u32) -> Option<f64> {
    (bus_width_bits > 0 && max_mem_mhz > 0)
        .then(|| bus_width_bits as f64 / 8.0 * max_mem_mhz as f64 * 1e6 * 2.0)
}

impl std::fmt::Debug for GpuMonitor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuMonitor")
            .field("index", &self.index)
            .field("name", &self.name)
            .field("bus_id", &self.bus_id)
            .finish()
    }
}

impl GpuMonitor {
    /// Opens the NVML device at `pci_bus_id` (the wgpu adapter's `device_pci_bus_id`; pass
    /// `None` when it is empty). Without a bus id the single NVIDIA device is used; with
    /// several, none is guessed. Every failure is a readable reason for `clock_source`.
    pub fn open(pci_bus_id: Option<&str>) -> Result<GpuMonitor, MonitorError> {
        let nvml = Nvml::init().map_err(MonitorError::Unavailable)?;
        let count = nvml.device_count().map_err(MonitorError::DeviceCount)?;
        let want = match pci_bus_id.filter(|s| !s.trim().is_empty()) {
            Some(s) => {
                Some(parse_pci_bus_id(s).ok_or_else(|| MonitorError::BadBusId(s.to_string()))?)
            }
            None => None,
        };
        let mut seen = Vec::new();
        let mut found = None;
        for i in 0..count {
            let d = nvml
                .device_by_index(i)
                .map_err(|error| MonitorError::Device { index: i, error })?;
            let bus = d.pci_info().map(|p| p.bus_id).unwrap_or_default();
            let hit = match want {
                Some(w) => parse_pci_bus_id(&bus) == Some(w),
                None => count == 1,
            };
            if hit {
                found = Some((i, bus.clone()));
            }
            seen.push(bus);
        }
        let Some((index, bus_id)) = found else {
            return Err(match pci_bus_id {
                Some(s) if want.is_some() => MonitorError::NoDeviceAt {
                    bus_id: s.to_string(),
                    seen,
                },
                _ if count == 0 => MonitorError::NoDevices,
                _ => MonitorError::Ambiguous { count, seen },
            });
        };
        let d = nvml
            .device_by_index(index)
            .map_err(|error| MonitorError::Device { index, error })?;
        let name = d.name().unwrap_or_default();
        let uuid = d.uuid().unwrap_or_default();
        let serial = d.serial().unwrap_or_default();
        let default_sm_mhz = d.default_applications_clock(Clock::SM).ok().map(f64::from);
        let max_sm_mhz = d.max_clock_info(Clock::SM).ok().map(f64::from);
        let peak_bandwidth = match (d.memory_bus_width(), d.max_clock_info(Clock::Memory)) {
            (Ok(w), Ok(mhz)) => peak_bandwidth(w, mhz),
            _ => None,
        };
        let driver = nvml.sys_driver_version().unwrap_or_default();
        Ok(GpuMonitor {
            nvml,
            index,
            name,
            bus_id,
            driver,
            uuid,
            serial,
            default_sm_mhz,
            max_sm_mhz,
            peak_bandwidth,
        })
    }

    /// Reads the current clocks, temperature, power and throttle reasons.
    pub fn sample(&self) -> MonitorSample {
        let Ok(d) = self.nvml.device_by_index(self.index) else {
            return MonitorSample::default();
        };
        let reasons = d
            .current_throttle_reasons()
            .map(|r| {
                REASONS
                    .iter()
                    .filter(|(f, _)| r.contains(*f))
                    .map(|(_, n)| *n)
                    .collect()
            })
            .unwrap_or_default();
        MonitorSample {
            sm_mhz: d.clock_info(Clock::SM).ok().map(f64::from),
            mem_mhz: d.clock_info(Clock::Memory).ok().map(f64::from),
            temp_c: d.temperature(TemperatureSensor::Gpu).ok().map(f64::from),
            power_w: d.power_usage().ok().map(|mw| mw as f64 / 1000.0),
            throttle_reasons: reasons,
            other_processes: None,
        }
    }

    /// The GPU's UUID (`GPU-…`; empty where NVML gives none).
    pub fn uuid(&self) -> &str {
        &self.uuid
    }
    /// The board serial (empty where NVML gives none).
    pub fn serial(&self) -> &str {
        &self.serial
    }

    /// The default SM clock (NVML's default application clock), the throttle rule's reference.
    pub fn default_sm_mhz(&self) -> Option<f64> {
        self.default_sm_mhz
    }
    pub fn max_sm_mhz(&self) -> Option<f64> {
        self.max_sm_mhz
    }
    /// Peak memory bandwidth in bytes/s, where NVML gives the bus width and memory clock.
    pub fn peak_bandwidth(&self) -> Option<f64> {
        self.peak_bandwidth
    }
    /// The throttle rule's reference: the default SM clock, else the maximum.
    pub fn reference_sm_mhz(&self) -> Option<f64> {
        self.default_sm_mhz.or(self.max_sm_mhz)
    }
    pub fn name(&self) -> &str {
        &self.name
    }
    pub fn bus_id(&self) -> &str {
        &self.bus_id
    }
    /// For the JSON context block: device name, bus id, driver and reference clocks.
    pub fn context(&self) -> Vec<(&'static str, String)> {
        let f = |v: Option<f64>| v.map(|x| format!("{x}")).unwrap_or_default();
        vec![
            ("nvml_device", self.name.clone()),
            ("nvml_pci_bus_id", self.bus_id.clone()),
            ("nvml_driver_version", self.driver.clone()),
            ("gpu_uuid", self.uuid.clone()),
            ("gpu_serial", self.serial.clone()),
            ("sm_clock_mhz_default", f(self.default_sm_mhz)),
            ("sm_clock_mhz_max", f(self.max_sm_mhz)),
            ("peak_bandwidth_bytes_per_s", f(self.peak_bandwidth)),
        ]
    }
}

/// NVML's compute and graphics process lists of the device (a Vulkan process is listed as
/// graphics, a CUDA one as compute); one list that cannot be read is left out, both is an error.
impl ProcessList for GpuMonitor {
    fn pids(&self) -> Result<Vec<u32>, MonitorError> {
        let d = self
            .nvml
            .device_by_index(self.index)
            .map_err(|error| MonitorError::Device {
                index: self.index,
                error,
            })?;
        match (
            d.running_compute_processes(),
            d.running_graphics_processes(),
        ) {
            (Err(compute), Err(graphics)) => Err(MonitorError::ProcessLists { compute, graphics }),
            (c, g) => Ok(c.into_iter().chain(g).flatten().map(|p| p.pid).collect()),
        }
    }
}

/// Where a point's clock readings come from (the `clock_source` cell).
#[derive(Clone, Debug, PartialEq)]
enum ClockSource {
    Nvml,
    /// No monitor: the reason.
    Unavailable(String),
}

/// Accumulates the readings of one point.
#[derive(Clone, Debug, PartialEq)]
pub struct PointClocks {
    source: ClockSource,
    sm: Vec<f64>,
    mem_sum: f64,
    mem_n: usize,
    temp_max: Option<f64>,
    power_sum: f64,
    power_n: usize,
    reasons: BTreeSet<&'static str>,
    /// The most other processes seen at once (`None`: no process list read).
    others_max: Option<u32>,
}

impl PointClocks {
    /// For a point measured with a monitor.
    pub fn nvml() -> PointClocks {
        PointClocks::with_source(ClockSource::Nvml)
    }
    /// For a point measured without one (`clock_source = none: <reason>`).
    pub fn unavailable(reason: impl Into<String>) -> PointClocks {
        PointClocks::with_source(ClockSource::Unavailable(reason.into()))
    }
    /// From `GpuMonitor::open`'s result.
    pub fn for_monitor(m: &Result<GpuMonitor, MonitorError>) -> PointClocks {
        match m {
            Ok(_) => PointClocks::nvml(),
            Err(e) => PointClocks::unavailable(e.to_string()),
        }
    }
    fn with_source(source: ClockSource) -> PointClocks {
        PointClocks {
            source,
            sm: Vec::new(),
            mem_sum: 0.0,
            mem_n: 0,
            temp_max: None,
            power_sum: 0.0,
            power_n: 0,
            reasons: BTreeSet::new(),
            others_max: None,
        }
    }

    /// A kept sample's reading: counts in every mean.
    pub fn push(&mut self, s: &MonitorSample) {
        if let Some(c) = s.sm_mhz {
            self.sm.push(c);
        }
        if let Some(m) = s.mem_mhz {
            self.mem_sum += m;
            self.mem_n += 1;
        }
        if let Some(p) = s.power_w {
            self.power_sum += p;
            self.power_n += 1;
        }
        self.push_discarded(s);
    }

    /// Folds another part of the same point (a later session) into this one.
    pub fn merge(&mut self, other: PointClocks) {
        self.sm.extend(other.sm);
        self.mem_sum += other.mem_sum;
        self.mem_n += other.mem_n;
        self.temp_max = match (self.temp_max, other.temp_max) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
        self.power_sum += other.power_sum;
        self.power_n += other.power_n;
        self.reasons.extend(other.reasons);
        self.others_max = self.others_max.max(other.others_max);
    }

    /// A discarded (throttled) sample's reading: only its reasons, temperature and other
    /// processes count (the point was still measured while they held the GPU).
    pub fn push_discarded(&mut self, s: &MonitorSample) {
        self.others_max = self.others_max.max(s.other_processes);
        if let Some(t) = s.temp_c {
            self.temp_max = Some(self.temp_max.map_or(t, |m| m.max(t)));
        }
        self.reasons.extend(
            s.throttle_reasons
                .iter()
                .copied()
                .filter(|r| *r != "gpu_idle"),
        );
    }

    pub fn sm_mean(&self) -> Option<f64> {
        (!self.sm.is_empty()).then(|| self.sm.iter().sum::<f64>() / self.sm.len() as f64)
    }
    /// Whether another process held the GPU during a reading (→ flag `gpu_shared`).
    pub fn gpu_shared(&self) -> bool {
        self.others_max.is_some_and(|n| n > 0)
    }
    /// Whether any reading saw a slowdown reason (→ flag `throttled`).
    pub fn slowdown(&self) -> bool {
        self.reasons.iter().any(|r| SLOWDOWN_REASONS.contains(r))
    }

    /// The row's cells, by the column names of the CSV contract.
    pub fn to_cells(&self) -> Vec<(Col, String)> {
        let mhz = |v: Option<f64>| v.map(|x| format!("{x:.1}")).unwrap_or_default();
        let sm_min = self.sm.iter().copied().reduce(f64::min);
        let sm_max = self.sm.iter().copied().reduce(f64::max);
        let mem = (self.mem_n > 0).then(|| self.mem_sum / self.mem_n as f64);
        let power = (self.power_n > 0).then(|| self.power_sum / self.power_n as f64);
        let source = match &self.source {
            ClockSource::Nvml if self.sm.is_empty() => {
                "none: NVML gave no SM clock reading".to_string()
            }
            ClockSource::Nvml => "nvml".to_string(),
            ClockSource::Unavailable(e) => format!("none: {e}"),
        };
        vec![
            (cols::SM_CLOCK_MHZ_MEAN, mhz(self.sm_mean())),
            (cols::SM_CLOCK_MHZ_MIN, mhz(sm_min)),
            (cols::SM_CLOCK_MHZ_MAX, mhz(sm_max)),
            (cols::MEM_CLOCK_MHZ_MEAN, mhz(mem)),
            (
                cols::GPU_TEMP_C_MAX,
                self.temp_max.map(|t| format!("{t}")).unwrap_or_default(),
            ),
            (
                cols::GPU_POWER_W_MEAN,
                power.map(|p| format!("{p:.3}")).unwrap_or_default(),
            ),
            (
                cols::THROTTLE_REASONS,
                self.reasons.iter().copied().collect::<Vec<_>>().join("|"),
            ),
            (cols::CLOCK_SOURCE, source),
            (
                cols::GPU_OTHER_PROCESSES,
                self.others_max.map(|n| n.to_string()).unwrap_or_default(),
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bus_ids_of_wgpu_and_nvml_agree() {
        let w = parse_pci_bus_id("0000:00:06.0");
        assert_eq!(w, Some((0, 0, 6, 0)));
        assert_eq!(parse_pci_bus_id("00000000:00:06.0"), w);
        assert_eq!(
            parse_pci_bus_id("00000001:9A:1f.7"),
            Some((1, 0x9a, 0x1f, 7))
        );
        assert_eq!(parse_pci_bus_id("0001:9a:1F.7"), Some((1, 0x9a, 0x1f, 7)));
        assert_eq!(parse_pci_bus_id("9a:00.0"), Some((0, 0x9a, 0, 0)));
        assert_eq!(parse_pci_bus_id(""), None);
        assert_eq!(parse_pci_bus_id("0000:00:06"), None);
        assert_eq!(parse_pci_bus_id("0:0:0:0.0"), None);
        assert_eq!(parse_pci_bus_id("zz:00.0"), None);
    }

    #[test]
    fn open_without_a_driver_is_a_readable_error_not_a_panic() {
        // On a machine with the NVIDIA driver and one GPU this opens; elsewhere it must say why.
        match GpuMonitor::open(None) {
            Err(e) => assert!(e.to_string().contains("NVML"), "{e}"),
            Ok(m) => {
                let s = m.sample();
                assert!(s.sm_mhz.is_some_and(|c| c > 0.0), "{s:?}");
            }
        }
        // A bus id no machine has is never silently replaced by another device.
        assert!(GpuMonitor::open(Some("ffff:ff:1f.7")).is_err());
    }

    #[test]
    fn point_clocks_accumulate_and_name_the_contract_columns() {
        let mut p = PointClocks::nvml();
        let r = |sm: f64, t: f64, reasons: Vec<&'static str>| MonitorSample {
            sm_mhz: Some(sm),
            mem_mhz: Some(3201.0),
            temp_c: Some(t),
            power_w: Some(300.0),
            throttle_reasons: reasons,
            other_processes: None,
        };
        p.push(&r(1980.0, 40.0, vec!["gpu_idle"]));
        p.push(&r(1950.0, 45.0, vec!["sw_power_cap"]));
        p.push_discarded(&r(900.0, 52.0, vec!["hw_thermal_slowdown"]));
        let cells: std::collections::BTreeMap<&str, String> =
            p.to_cells().into_iter().map(|(c, v)| (c.name, v)).collect();
        assert_eq!(cells["sm_clock_mhz_mean"], "1965.0");
        assert_eq!(cells["sm_clock_mhz_min"], "1950.0");
        assert_eq!(cells["sm_clock_mhz_max"], "1980.0");
        assert_eq!(cells["mem_clock_mhz_mean"], "3201.0");
        assert_eq!(cells["gpu_temp_c_max"], "52");
        assert_eq!(cells["gpu_power_w_mean"], "300.000");
        assert_eq!(
            cells["throttle_reasons"],
            "hw_thermal_slowdown|sw_power_cap"
        );
        assert_eq!(cells["clock_source"], "nvml");
        assert!(p.slowdown());
        assert_eq!(cells.len(), 9);
        assert_eq!(cells["gpu_other_processes"], "", "no process list read");
    }

    #[test]
    fn without_a_monitor_every_cell_is_empty_but_the_reason() {
        let p = PointClocks::for_monitor(&Err(MonitorError::NotNvidia {
            name: "llvmpipe".into(),
            vendor: 0x10005,
        }));
        let cells = p.to_cells();
        for (k, v) in &cells {
            if *k == cols::CLOCK_SOURCE {
                assert_eq!(
                    v,
                    "none: not an NVIDIA adapter (llvmpipe, vendor 0x10005): no NVML clocks"
                );
            } else {
                assert!(v.is_empty(), "{k} = {v}");
            }
        }
        assert!(!p.slowdown());
        assert_eq!(p.sm_mean(), None);
    }

    #[test]
    fn other_processes_leave_this_one_out_also_under_another_pid_namespace() {
        let own = [4242, 17];
        assert_eq!(other_processes(&[], &own), 0);
        assert_eq!(other_processes(&[4242], &own), 0, "only this process");
        assert_eq!(
            other_processes(&[4242, 4242, 900], &own),
            1,
            "listed twice: once"
        );
        assert_eq!(
            other_processes(&[17, 900, 901], &own),
            2,
            "its id in another namespace"
        );
        // NVML lists host pids and this process runs in a container: one is taken for it.
        assert_eq!(other_processes(&[800], &own), 0);
        assert_eq!(other_processes(&[800, 900], &own), 1);
        assert!(own_pids().contains(&std::process::id()));
    }

    #[test]
    fn a_reading_with_another_process_marks_the_point_shared() {
        let mut p = PointClocks::unavailable("no NVML");
        let s = |n| MonitorSample {
            other_processes: n,
            ..Default::default()
        };
        p.push(&s(Some(0)));
        assert!(!p.gpu_shared());
        let mut later = PointClocks::unavailable("no NVML");
        later.push_discarded(&s(Some(2)));
        p.merge(later);
        assert!(p.gpu_shared(), "a discarded sample counts too");
        let cells: std::collections::BTreeMap<&str, String> =
            p.to_cells().into_iter().map(|(c, v)| (c.name, v)).collect();
        assert_eq!(cells["gpu_other_processes"], "2");
    }

    #[test]
    fn peak_bandwidth_is_bus_bytes_times_double_clock() {
        // H200: 6144-bit HBM3e at 3201 MHz → 4.917 TB/s.
        let b = peak_bandwidth(6144, 3201).unwrap();
        assert!((b - 4.917e12).abs() < 1e9, "{b}");
        assert_eq!(peak_bandwidth(0, 3201), None);
        assert_eq!(peak_bandwidth(6144, 0), None);
    }
}
