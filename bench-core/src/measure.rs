//! Timing one [`Timed`] frame on one scene — a multi-fragment method's, a deferred shading
//! path's, a geometry feed's, the light pre-pass's, the shadow mapper's: untimed preparation, a warm-up until frame times and
//! the SM clock are steady, then timed frames until the stopping rule is met (mfx-stats: a
//! target on the 95 % CI of the median, caps on samples and time, a drift check), the SM clock
//! read after every frame where NVML is present (throttled samples discarded: nvbench's 75 %
//! rule), GPU errors caught as typed errors; and the timing columns of a row.

use std::collections::BTreeMap;

use mfx_stats::{
    Decision, Sampler, StopReason, StopRule, Summary, Warmup, WarmupDecision, WarmupRule,
};

use crate::clocks::{MonitorSample, PointClocks};
use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::record::{cols, Col, GpuMsInterval, Row, Sample};
use crate::timed::{FrameStats, Timed};
use crate::timing::GpuTimer;
use crate::{CoreError, Result};
use schema::MIN_SAMPLES_CI95;

/// How a point is timed: warm-up and stopping rules, and the seed of its bootstrap.
#[derive(Clone, Debug, PartialEq)]
pub struct TimingPlan {
    pub warmup: WarmupRule,
    pub stop: StopRule,
    /// Seed of the bootstrap CIs (and of a seeded measurement order, when interleaved).
    pub seed: u64,
    /// Sample the points of a group interleaved in a seeded random order.
    pub interleave: bool,
    /// Busy GPU work allowed per point before its warm-up to lift a lowered SM clock (NVML
    /// adapters only; 0: never). See [`PointTimer::lift_clock`].
    pub clock_lift_ms: f64,
    /// Independent sessions per point (`[timing] sessions`, default 1): each prepares the method
    /// afresh (new buffers and pipelines), lifts the clock, warms up and samples under the same
    /// rule; the samples are pooled and the median's CI widened to cover every session's median
    /// (`session_spread`). Not with `interleave`.
    pub sessions: usize,
    /// A sample is discarded when the canary kernel timed right after it took more than this
    /// many times its baseline (`mfx_stats::canary`; `Some(0)`: no canary). `None`, the
    /// default: [`mfx_stats::CANARY_MAX_RATIO`] on hardware adapters and no canary on a software
    /// one (its timestamps say little); set explicitly, it applies to any adapter.
    pub canary_max_ratio: Option<f64>,
    /// Before each point is prepared, wait until the GPU is idle and what earlier points
    /// dropped is freed (`[timing] settle`, default false), so a point's buffers and targets are
    /// made with the memory of earlier points already given back. See [`Gpu::settle`].
    /// Measured on the H200 (`results/reference/2026-12-02-h200-floors`): the depth-only
    /// floor's history-dependent time did not move with it (1.041 / 1.465 ms settled or not),
    /// so it is off unless asked for.
    pub settle: bool,
    /// `[timing] cold = true` (nvbench's cold mode): before each timed sample the L2 is flushed
    /// by an untimed clear of twice its size ([`Gpu::flush_l2`]), so the frame finds none of
    /// its data cached; its row is read against the DRAM roof (`l2_resident` false).
    pub cold: bool,
}

impl Default for TimingPlan {
    fn default() -> Self {
        TimingPlan {
            warmup: WarmupRule::default(),
            stop: StopRule::default(),
            seed: 1,
            interleave: false,
            clock_lift_ms: CLOCK_LIFT_MS,
            sessions: 1,
            canary_max_ratio: None,
            settle: false,
            cold: false,
        }
    }
}

/// Default of `[timing] clock_lift_ms`.
pub const CLOCK_LIFT_MS: f64 = 500.0;
/// A clock at or above this share of the adapter's maximum SM clock needs no lift.
pub const CLOCK_LIFT_TARGET: f64 = 0.97;

/// A suite's `[timing]` that cannot work, naming the settings.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TimingError {
    #[error(transparent)]
    Stop(#[from] mfx_stats::StopRuleError),
    #[error("sessions > 1 measures each point on its own, one session after another: it cannot be combined with interleave = true")]
    SessionsWithInterleave,
}

impl TimingPlan {
    /// One frame, no warm-up: for a single render (tests, `mfx render`), not for timings.
    pub fn once() -> TimingPlan {
        TimingPlan {
            warmup: WarmupRule {
                min_frames: 0,
                max_frames: 0,
                ..WarmupRule::default()
            },
            stop: StopRule {
                min_samples: 1,
                max_samples: 1,
                max_noise: f64::INFINITY,
                ..StopRule::default()
            },
            seed: 1,
            interleave: false,
            clock_lift_ms: 0.0,
            sessions: 1,
            canary_max_ratio: Some(0.0),
            settle: false,
            cold: false,
        }
    }

    /// The plan a suite's `[timing]` (with `[software]`'s overrides applied) asks for: every
    /// key it leaves unset takes the default. `Err` names a setting that cannot work.
    pub fn from_spec(spec: &scenarios::TimingSpec) -> std::result::Result<TimingPlan, TimingError> {
        let d = TimingPlan::default();
        let mut stop = d.stop.clone();
        let mut warmup = d.warmup.clone();
        if let Some(v) = spec.min_samples {
            stop.min_samples = v as usize;
        }
        if let Some(v) = spec.max_samples {
            stop.max_samples = v as usize;
            // A fixed count (min = max) takes no minimum above it.
            stop.min_samples = stop.min_samples.min(stop.max_samples);
        }
        if let Some(v) = spec.min_samples {
            stop.min_samples = (v as usize).min(stop.max_samples);
        }
        if let Some(v) = spec.max_noise {
            stop.max_noise = v;
        }
        if let Some(v) = spec.min_time_ms {
            stop.min_time_ms = v;
        }
        if let Some(v) = spec.max_time_ms {
            stop.max_time_ms = v;
        }
        if let Some(v) = spec.warmup_frames {
            warmup.min_frames = v as usize;
            warmup.max_frames = warmup.max_frames.max(v as usize);
        }
        if let Some(v) = spec.warmup_max_frames {
            warmup.max_frames = v as usize;
            warmup.min_frames = warmup.min_frames.min(v as usize);
        }
        stop.validate()?;
        if spec.sessions.unwrap_or(1) > 1 && spec.interleave == Some(true) {
            return Err(TimingError::SessionsWithInterleave);
        }
        Ok(TimingPlan {
            warmup,
            stop,
            seed: spec.seed.unwrap_or(d.seed),
            interleave: spec.interleave.unwrap_or(false),
            clock_lift_ms: spec.clock_lift_ms.unwrap_or(d.clock_lift_ms),
            sessions: spec.sessions.map_or(d.sessions, |n| n as usize),
            canary_max_ratio: spec.canary_max_ratio.or(d.canary_max_ratio),
            settle: spec.settle.unwrap_or(d.settle),
            cold: spec.cold.unwrap_or(d.cold),
        })
    }

    /// The one-line description written to each row (`timing_rule`).
    pub fn describe(&self) -> String {
        let s = &self.stop;
        let d = format!(
            "clock lift ≤ {} ms; warm-up {}–{} frames until steady; {}–{} samples, stop at ±{:.2} % (95 % CI of the median), ≤ {} ms; drift check every {}",
            self.clock_lift_ms,
            self.warmup.min_frames,
            self.warmup.max_frames,
            s.min_samples,
            s.max_samples,
            s.max_noise * 100.0,
            s.max_time_ms,
            s.drift_every
        );
        let d = match self.canary_max_ratio {
            None => format!(
                "{d}; a sample whose canary ran over {}× its baseline discarded (hardware adapters)",
                mfx_stats::CANARY_MAX_RATIO
            ),
            Some(r) if r > 1.0 => {
                format!("{d}; a sample whose canary ran over {r}× its baseline discarded")
            }
            Some(_) => d,
        };
        let d = if self.settle {
            format!("{d}; GPU settled before each point")
        } else {
            d
        };
        let d = if self.cold {
            format!("{d}; cold: L2 flushed before each sample (an untimed clear of twice its size)")
        } else {
            d
        };
        if self.sessions > 1 {
            format!(
                "{d}; {} sessions (each prepared afresh, the later ones after a placement pad), CI widened to cover their medians",
                self.sessions
            )
        } else {
            d
        }
    }
}

/// The result of timing one frame kind on one scene, with the prepared frame (a caller that
/// reads a capture back from it does so from `prepared`).
pub struct Measured<T: ?Sized> {
    /// GPU time per frame over the kept samples (None without timestamp queries).
    pub gpu: Option<Summary>,
    /// Wall-clock time per frame over the kept samples.
    pub cpu: Summary,
    /// Median ms per pass label over the kept samples (passes with one label in one frame are
    /// summed).
    pub pass_ms: BTreeMap<String, f64>,
    /// 95 % interval of each pass's median (as the GPU time's: [`median_interval`]), so a claim
    /// about one pass can be ruled with an interval (`pass_ms_ci`).
    pub pass_ci: BTreeMap<String, (f64, f64)>,
    pub frame: FrameStats,
    pub bytes_allocated: u64,
    pub bytes_overhead: Option<u64>,
    /// [`Timed::bytes_moved`] of one frame (`bytes_per_s`).
    pub bytes_moved: u64,
    /// The adapter's peak memory bandwidth in bytes/s (NVML), where known.
    pub peak_bandwidth: Option<f64>,
    /// The adapter's measured memory roofs, where this run measured them ([`Gpu::roofs`]).
    pub roofs: Option<crate::roofs::Roofs>,
    /// The frame's declared working set: its allocations and the scene's geometry.
    pub working_set: u64,
    /// Sampled cold (the L2 flushed before each sample).
    pub cold: bool,
    /// The frame's own parts ([`Timed::parts`]) per kept sample, in sample order.
    pub parts: BTreeMap<Col, Vec<f64>>,
    pub prepared: Box<T>,
    /// Every timed frame in order, discarded ones included (`samples.csv`).
    pub samples: Vec<Sample>,
    pub warmup_frames: usize,
    pub stop_reason: StopReason,
    pub target_reached: bool,
    /// Wall-clock ms of warm-up and samples.
    pub measure_ms: f64,
    /// Wall-clock ms of the method's prepare.
    pub prepare_ms: f64,
    /// `(max − min) / median` of the sessions' medians (`[timing] sessions` > 1).
    pub session_spread: Option<f64>,
    pub clocks: PointClocks,
    /// Samples the canary rule discarded, and the largest canary ratio seen (None: no canary).
    pub canary: Option<(usize, f64)>,
    /// Clock lift before the warm-up: (ms of busy work, SM MHz before, SM MHz after); None when
    /// none was needed or possible.
    pub clock_lift: Option<(f64, f64, f64)>,
}

impl<T: ?Sized> Measured<T> {
    pub fn gpu_median(&self) -> Option<f64> {
        self.gpu.as_ref().map(|s| s.median)
    }
    /// The median of a part the frame reported ([`Timed::parts`]) over the kept samples.
    pub fn part_median(&self, col: Col) -> Option<f64> {
        let mut v = self.parts.get(&col)?.clone();
        v.sort_by(f64::total_cmp);
        (!v.is_empty()).then(|| mfx_stats::median_of_sorted(&v))
    }
    /// Median of wall minus GPU time over the kept samples (`gpu_idle_ms`), with timestamps.
    pub fn idle_median(&self) -> Option<f64> {
        let mut v: Vec<f64> = self
            .samples
            .iter()
            .filter(|s| !s.discarded)
            .filter_map(|s| s.gpu_ms.map(|g| (s.cpu_ms - g).max(0.0)))
            .collect();
        v.sort_by(f64::total_cmp);
        (!v.is_empty()).then(|| mfx_stats::median_of_sorted(&v))
    }
    pub fn discarded(&self) -> usize {
        self.samples.iter().filter(|s| s.discarded).count()
    }
}

fn scope_error(e: Option<wgpu::Error>, what: &str) -> Result<()> {
    match e {
        None => Ok(()),
        Some(wgpu::Error::OutOfMemory { .. }) => Err(CoreError::OutOfMemory(format!(
            "{what}: the GPU ran out of memory"
        ))),
        Some(e) => Err(CoreError::Gpu(format!("{what}: {e}"))),
    }
}

/// What one frame gave: the GPU passes' ms (empty without timestamps), the wall ms, the
/// clocks right after it, and the frame's own parts ([`Timed::parts`]).
type FrameTimes = (Vec<(String, f64)>, f64, MonitorSample, Vec<(Col, f64)>);

/// One frame: encode, submit, wait.
fn one_frame<T: Timed + ?Sized>(
    gpu: &Gpu,
    scene: &GpuScene,
    prepared: &mut T,
    timer: &mut GpuTimer,
    frame: &mut FrameStats,
) -> Result<FrameTimes> {
    timer.begin_frame();
    let t0 = std::time::Instant::now();
    *frame = prepared.frame(gpu, scene, timer)?;
    gpu.wait()?;
    let cpu = t0.elapsed().as_secs_f64() * 1e3;
    let spans = timer.read_spans(gpu)?;
    gpu.check_lost()?;
    let mut clocks = match &gpu.monitor {
        Ok(m) => m.sample(),
        Err(_) => MonitorSample::default(),
    };
    clocks.other_processes = gpu.other_processes();
    let parts = prepared.parts(&spans);
    let passes = spans.into_iter().map(|(l, a, b)| (l, b - a)).collect();
    Ok((passes, cpu, clocks, parts))
}

/// Timed frames of this process so far: each sample's `seq`, the measurement order.
static FRAMES_TIMED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// One point being timed, in stages (so a group's points can be sampled interleaved): prepared,
/// warmed up, sampled one frame at a time, finished into a [`Measured`].
pub struct PointTimer<'g, T: ?Sized> {
    gpu: &'g Gpu,
    scene: &'g GpuScene,
    plan: TimingPlan,
    prepared: Box<T>,
    bytes_allocated: u64,
    bytes_overhead: Option<u64>,
    parts: BTreeMap<Col, Vec<f64>>,
    timer: GpuTimer,
    reference_mhz: Option<f64>,
    clocks: PointClocks,
    frame: FrameStats,
    samples: Vec<Sample>,
    per_label: BTreeMap<String, Vec<f64>>,
    sampler: Sampler,
    warmup_frames: usize,
    /// Wall time spent on this point's warm-up and samples (its own, when interleaved).
    spent_ms: f64,
    /// Wall time of the timed frames alone: what the stopping rule's `max_time_ms` caps (the
    /// clock lift and warm-up before them do not eat the sampling budget).
    sampling_ms: f64,
    prepare_ms: f64,
    stopped: Option<StopReason>,
    clock_lift: Option<(f64, f64, f64)>,
    /// The canary rule's ratio for this adapter (≤ 1: no canary).
    canary_max: f64,
}

/// Runs `f` in validation and out-of-memory error scopes; a captured error names `what`.
pub fn scoped<T>(gpu: &Gpu, what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let r = f();
    scope_error(pollster::block_on(oom.pop()), what)?;
    scope_error(pollster::block_on(validation.pop()), what)?;
    r
}

/// Makes one [`Timed`] frame kind's GPU objects on a scene (called once per session).
pub type Make<'a, T> = &'a dyn Fn(&GpuScene) -> Result<Box<T>>;

impl<'g, T: Timed + ?Sized> PointTimer<'g, T> {
    /// Prepares a frame with `make` (untimed: every GPU object is created here).
    pub fn prepare_with(
        gpu: &'g Gpu,
        scene: &'g GpuScene,
        make: Make<'_, T>,
        plan: &TimingPlan,
    ) -> Result<PointTimer<'g, T>> {
        gpu.check_lost()?;
        if plan.settle {
            gpu.settle()?;
        }
        let t0 = std::time::Instant::now();
        gpu.take_stage_violation();
        let prepared = scoped(gpu, "prepare", || make(scene))?;
        // A layout over a per-stage storage limit wgpu does not check (compatibility mode's).
        if let Some(why) = gpu.take_stage_violation() {
            return Err(CoreError::Limit(why));
        }
        let prepare_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(PointTimer {
            gpu,
            scene,
            plan: plan.clone(),
            bytes_allocated: prepared.bytes_allocated(),
            bytes_overhead: prepared.bytes_overhead(),
            parts: BTreeMap::new(),
            prepared,
            timer: GpuTimer::new(gpu),
            reference_mhz: gpu.monitor.as_ref().ok().and_then(|m| m.reference_sm_mhz()),
            clocks: PointClocks::for_monitor(&gpu.monitor),
            frame: FrameStats::default(),
            samples: Vec::new(),
            per_label: BTreeMap::new(),
            sampler: Sampler::new(plan.stop.clone()),
            warmup_frames: 0,
            spent_ms: 0.0,
            sampling_ms: 0.0,
            prepare_ms,
            stopped: None,
            clock_lift: None,
            canary_max: match plan.canary_max_ratio {
                None if !gpu.facts.is_software => mfx_stats::CANARY_MAX_RATIO,
                None => 0.0,
                Some(r) => r,
            },
        })
    }

    fn canary_on(&self) -> bool {
        self.canary_max > 1.0 && self.timer.enabled()
    }

    /// Lifts an SM clock the driver has lowered. Measured on the H200: within one sweep the SM
    /// clock stepped down from 1980 MHz to 1485–1740 MHz for whole groups of light points (no
    /// throttle reason, 38 °C, 120 W of 700) and back up after the next idle spell, so whole
    /// groups ran up to 1.3× slower in one run than in its twin while their cycles agreed. When
    /// the clock reads under [`CLOCK_LIFT_TARGET`] of the adapter's maximum, busy compute work
    /// (a few ms per dispatch) runs until it is back or `clock_lift_ms` is spent; the point's
    /// warm-up follows. The settings of the GPU are never changed.
    pub fn lift_clock(&mut self) -> Result<()> {
        let Ok(m) = &self.gpu.monitor else {
            return Ok(());
        };
        let (Some(max), true) = (m.max_sm_mhz(), self.plan.clock_lift_ms > 0.0) else {
            return Ok(());
        };
        let target = CLOCK_LIFT_TARGET * max;
        let Some(before) = m.sample().sm_mhz else {
            return Ok(());
        };
        // A slow canary asks for the lift too: the slow state it sees has no clock reading.
        let canary_slow = |me: &Self| -> Result<bool> {
            Ok(me.canary_on()
                && mfx_stats::canary_discard(me.gpu.canary()?.map(|(_, r)| r), me.canary_max))
        };
        if before >= target && !canary_slow(self)? {
            return Ok(());
        }
        let t0 = std::time::Instant::now();
        let mut now = before;
        while t0.elapsed().as_secs_f64() * 1e3 < self.plan.clock_lift_ms {
            self.gpu.spin()?;
            now = m.sample().sm_mhz.unwrap_or(now);
            if now >= target && !canary_slow(self)? {
                break;
            }
        }
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        self.spent_ms += ms;
        self.clock_lift = Some((ms, before, now));
        Ok(())
    }

    /// Untimed frames until frame times (and the SM clock, where read) stop moving.
    pub fn warm_up(&mut self) -> Result<()> {
        if self.plan.warmup.max_frames == 0 {
            return Ok(());
        }
        let mut warmup = Warmup::new(self.plan.warmup.clone());
        let w0 = std::time::Instant::now();
        let (gpu, scene) = (self.gpu, self.scene);
        scoped(gpu, "warm-up", || loop {
            let (passes, cpu, c, _) = one_frame(
                gpu,
                scene,
                self.prepared.as_mut(),
                &mut self.timer,
                &mut self.frame,
            )?;
            let ms = if self.timer.enabled() {
                passes.iter().map(|(_, ms)| ms).sum()
            } else {
                cpu
            };
            let elapsed = w0.elapsed().as_secs_f64() * 1e3;
            if let WarmupDecision::Done(_) = warmup.push(ms, c.sm_mhz, elapsed) {
                return Ok(());
            }
        })?;
        self.warmup_frames = warmup.frames();
        self.spent_ms += w0.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// One timed frame; `Some(reason)` once the stopping rule ends the point.
    pub fn sample(&mut self) -> Result<Option<StopReason>> {
        if let Some(r) = self.stopped {
            return Ok(Some(r));
        }
        if self.plan.cold {
            self.gpu.flush_l2()?;
        }
        let t0 = std::time::Instant::now();
        let (gpu, scene) = (self.gpu, self.scene);
        let (passes, cpu, c, parts) = scoped(gpu, "frame", || {
            one_frame(
                gpu,
                scene,
                self.prepared.as_mut(),
                &mut self.timer,
                &mut self.frame,
            )
        })?;
        let frame_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.spent_ms += frame_ms;
        self.sampling_ms += frame_ms;
        let gpu_ms = self
            .timer
            .enabled()
            .then(|| passes.iter().map(|(_, ms)| ms).sum::<f64>());
        let unix_ms = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64() * 1e3);
        let canary_ratio = if self.canary_on() {
            gpu.canary()?.map(|(_, r)| r)
        } else {
            None
        };
        let discarded = match (c.sm_mhz, self.reference_mhz) {
            (Some(sm), Some(r)) => mfx_stats::discard(sm, r),
            _ => false,
        } || mfx_stats::canary_discard(canary_ratio, self.canary_max);
        self.samples.push(Sample {
            gpu_ms,
            cpu_ms: cpu,
            sm_mhz: c.sm_mhz,
            mem_mhz: c.mem_mhz,
            discarded,
            seq: FRAMES_TIMED.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            canary_ratio,
            unix_ms,
            session: 0,
        });
        let decision = if discarded {
            self.clocks.push_discarded(&c);
            self.sampler.push_discarded(self.sampling_ms)
        } else {
            self.clocks.push(&c);
            for (col, ms) in parts {
                self.parts.entry(col).or_default().push(ms);
            }
            let mut frame_labels: BTreeMap<String, f64> = BTreeMap::new();
            for (l, ms) in passes {
                *frame_labels.entry(l).or_default() += ms;
            }
            for (l, ms) in frame_labels {
                self.per_label.entry(l).or_default().push(ms);
            }
            // The stopping rule watches the GPU time (the wall time without timestamps).
            self.sampler.push(gpu_ms.unwrap_or(cpu), self.sampling_ms)
        };
        if let Decision::Stop(reason) = decision {
            self.stopped = Some(reason);
        }
        Ok(self.stopped)
    }

    /// The point's statistics (after the rule stopped it).
    pub fn finish(self) -> Result<Measured<T>> {
        let stop_reason = self.stopped.unwrap_or(StopReason::MaxSamples);
        let mut kept: Vec<&Sample> = self.samples.iter().filter(|s| !s.discarded).collect();
        // Every sample discarded (a slow state that lasted the whole point): the statistics of
        // all of them rather than none; the row is flagged throttled and the target not reached.
        let all_discarded = kept.is_empty();
        if all_discarded {
            kept = self.samples.iter().collect();
        }
        let canary = self.canary_on().then(|| {
            let n = self
                .samples
                .iter()
                .filter(|s| mfx_stats::canary_discard(s.canary_ratio, self.canary_max))
                .count();
            let max = self
                .samples
                .iter()
                .filter_map(|s| s.canary_ratio)
                .fold(0.0f64, f64::max);
            (n, max)
        });
        let gpu_kept: Vec<f64> = kept.iter().filter_map(|s| s.gpu_ms).collect();
        let cpu_kept: Vec<f64> = kept.iter().map(|s| s.cpu_ms).collect();
        let seed = self.plan.seed;
        let summary = |v: &[f64]| Summary::of(v, seed);
        let median = |v: &[f64]| {
            let mut s = v.to_vec();
            s.sort_by(f64::total_cmp);
            (!s.is_empty()).then(|| mfx_stats::median_of_sorted(&s))
        };
        let cpu = summary(&cpu_kept)
            .or_else(|| summary(&self.samples.iter().map(|s| s.cpu_ms).collect::<Vec<_>>()))
            .ok_or_else(|| CoreError::Gpu("no frame was timed".into()))?;
        let pass_ci = self
            .per_label
            .iter()
            .filter_map(|(l, v)| Some((l.clone(), median_interval(&summary(v)?).1)))
            .collect();
        Ok(Measured {
            gpu: if !kept.is_empty() && gpu_kept.len() == kept.len() {
                summary(&gpu_kept)
            } else {
                None
            },
            cpu,
            pass_ms: self
                .per_label
                .into_iter()
                .map(|(l, v)| (l, median(&v).unwrap_or(0.0)))
                .collect(),
            pass_ci,
            frame: self.frame,
            bytes_allocated: self.bytes_allocated,
            bytes_overhead: self.bytes_overhead,
            bytes_moved: self.prepared.bytes_moved(),
            peak_bandwidth: self
                .gpu
                .monitor
                .as_ref()
                .ok()
                .and_then(|m| m.peak_bandwidth()),
            roofs: self.gpu.measured_roofs().cloned(),
            working_set: self.bytes_allocated + self.scene.bytes,
            cold: self.plan.cold,
            parts: self.parts,
            prepared: self.prepared,
            warmup_frames: self.warmup_frames,
            target_reached: stop_reason == StopReason::TargetReached && !all_discarded,
            stop_reason,
            samples: self.samples,
            measure_ms: self.spent_ms,
            prepare_ms: self.prepare_ms,
            session_spread: None,
            clocks: self.clocks,
            canary,
            clock_lift: self.clock_lift,
        })
    }
}

/// Times any [`Timed`] frame under `plan`: each session prepares it afresh with `make`
/// (untimed), lifts the clock, warms up, then samples frames until the stopping rule ends it
/// (canary, clock and throttle checks on every sample). Every study's rows are timed here.
pub fn measure_timed<T: Timed + ?Sized>(
    gpu: &Gpu,
    scene: &GpuScene,
    make: Make<'_, T>,
    plan: &TimingPlan,
) -> Result<Measured<T>> {
    // Session k > 0 runs elsewhere in memory: a placement pad (a buffer of a seeded size,
    // 1–255 MiB) is allocated first, then the scene's geometry is copied into new buffers and
    // the method prepared on them. Measured on the H200 (results/reference/2026-12-02-h200-
    // floors): small-scene k-buffer points sit in one of two or three time states per process
    // (1.070 or 1.113–1.138 ms), set by where their memory lands; three such sessions showed a
    // spread over 2 % on 11 of 36 of them, so their CI spans the states one run alone hides.
    let session = |k: usize| -> Result<Measured<T>> {
        // The pad lives until the session ends (`_pad`), so nothing reuses its memory before.
        let (_pad, moved) = if k > 0 {
            let pad = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("placement pad"),
                size: placement_pad_mib(plan.seed, k) << 20,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            let moved = scoped(gpu, "relocate the scene", || scene.relocated(gpu))?;
            (Some(pad), Some(moved))
        } else {
            (None, None)
        };
        let scene = moved.as_ref().unwrap_or(scene);
        let mut t = PointTimer::prepare_with(gpu, scene, make, plan)?;
        t.lift_clock()?;
        t.warm_up()?;
        while t.sample()?.is_none() {}
        let mut m = t.finish()?;
        for s in &mut m.samples {
            s.session = k as u32;
        }
        Ok(m)
    };
    let mut m = session(0)?;
    if plan.sessions <= 1 {
        return Ok(m);
    }
    let mut parts = vec![m.gpu_median().unwrap_or(m.cpu.median)];
    for k in 1..plan.sessions {
        // The earlier session's GPU objects are dropped before the next is prepared, as a new
        // run would allocate them.
        drop(m.prepared);
        let next = session(k)?;
        parts.push(next.gpu_median().unwrap_or(next.cpu.median));
        m = combine(
            m.samples,
            m.clocks,
            m.canary,
            (m.measure_ms, m.prepare_ms),
            m.target_reached,
            m.parts,
            next,
        );
    }
    widen_to_sessions(&mut m, &parts, plan);
    Ok(m)
}

/// MiB of session `k`'s placement pad: 1–255, from the plan's seed (splitmix64).
pub fn placement_pad_mib(seed: u64, k: usize) -> u64 {
    let mut z = seed ^ (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    1 + z % 255
}

/// `next` with the earlier sessions' samples, clocks, times, target and parts folded in.
fn combine<T: ?Sized>(
    samples: Vec<Sample>,
    clocks: PointClocks,
    canary: Option<(usize, f64)>,
    (measure_ms, prepare_ms): (f64, f64),
    reached: bool,
    parts: BTreeMap<Col, Vec<f64>>,
    mut next: Measured<T>,
) -> Measured<T> {
    for (col, mut v) in parts {
        let later = next.parts.remove(&col).unwrap_or_default();
        v.extend(later);
        next.parts.insert(col, v);
    }
    let mut all = samples;
    all.append(&mut next.samples);
    next.samples = all;
    let mut c = clocks;
    c.merge(next.clocks);
    next.clocks = c;
    next.canary = match (canary, next.canary) {
        (Some((a, x)), Some((b, y))) => Some((a + b, x.max(y))),
        (a, b) => a.or(b),
    };
    next.measure_ms += measure_ms;
    next.prepare_ms += prepare_ms;
    next.target_reached &= reached;
    next
}

/// The pooled summary of every session's kept samples, its median's CI widened to cover each
/// session's median; `session_medians` kept for `session_spread`. A spread wider than the noise
/// target (as a half-width) means the target was not reached.
fn widen_to_sessions<T: ?Sized>(m: &mut Measured<T>, parts: &[f64], plan: &TimingPlan) {
    let kept: Vec<&Sample> = m.samples.iter().filter(|s| !s.discarded).collect();
    let gpu: Vec<f64> = kept.iter().filter_map(|s| s.gpu_ms).collect();
    let cpu: Vec<f64> = kept.iter().map(|s| s.cpu_ms).collect();
    let widen = |mut s: Summary| {
        let lo = parts.iter().copied().fold(s.median_ci.0, f64::min);
        let hi = parts.iter().copied().fold(s.median_ci.1, f64::max);
        s.median_ci = (lo, hi);
        s.rel_ci = if s.median > 0.0 {
            0.5 * (hi - lo) / s.median
        } else {
            f64::INFINITY
        };
        s
    };
    if !kept.is_empty() && gpu.len() == kept.len() {
        m.gpu = Summary::of(&gpu, plan.seed).map(widen);
    } else if let Some(c) = Summary::of(&cpu, plan.seed) {
        m.cpu = widen(c);
    }
    let (lo, hi) = parts
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    let mid = m.gpu_median().unwrap_or(m.cpu.median);
    let spread = if mid > 0.0 { (hi - lo) / mid } else { 0.0 };
    if 0.5 * spread > plan.stop.max_noise {
        m.target_reached = false;
    }
    m.session_spread = Some(spread);
}

/// Times several points of one group interleaved (`[timing] interleave = true`): all prepared
/// and warmed up first, then sampled in rounds, one frame of every still-active point per round
/// in a seeded order shuffled afresh each round, so drift spreads over all points as noise
/// instead of biasing the ones measured last. Every point's GPU objects are alive at once.
pub fn measure_interleaved<'g, T: Timed + ?Sized>(
    gpu: &'g Gpu,
    scene: &'g GpuScene,
    items: &[Make<'_, T>],
    plan: &TimingPlan,
) -> Vec<Result<Measured<T>>> {
    let mut timers: Vec<Option<Result<PointTimer<'g, T>>>> = items
        .iter()
        .map(|make| {
            Some(
                PointTimer::prepare_with(gpu, scene, *make, plan).and_then(|mut t| {
                    t.warm_up()?;
                    Ok(t)
                }),
            )
        })
        .collect();
    let mut active: Vec<usize> = (0..items.len())
        .filter(|&i| matches!(timers[i], Some(Ok(_))))
        .collect();
    let mut round = 0u64;
    while !active.is_empty() {
        for i in mfx_stats::round_order(&active, round, plan.seed) {
            if let Some(Ok(t)) = &mut timers[i] {
                match t.sample() {
                    Ok(Some(_)) => active.retain(|&a| a != i),
                    Ok(None) => {}
                    Err(e) => {
                        timers[i] = Some(Err(e));
                        active.retain(|&a| a != i);
                    }
                }
            }
        }
        round += 1;
    }
    timers
        .into_iter()
        .map(|t| match t.expect("every point is kept") {
            Ok(t) => t.finish(),
            Err(e) => Err(e),
        })
        .collect()
}

/// `fragments_per_s`: a frame's true fragment total (the CPU reference's) over the row's
/// median GPU time, where both are known.
pub fn set_fragment_rate(row: &mut Row, true_fragments: u64) {
    if let Some(g) = row.get_f(cols::GPU_MS_MEDIAN).filter(|g| *g > 0.0) {
        row.set_f(cols::FRAGMENTS_PER_S, true_fragments as f64 / (g * 1e-3));
    }
}

/// What `gpu_ms_ci_lo/hi` can honestly be for `g`'s sample count: its 95 % interval of the
/// median, or, with fewer than [`MIN_SAMPLES_CI95`] samples (where no distribution-free interval
/// reaches 95 % coverage: [min, max] of 3 samples covers the median 75 % of the time), the
/// range, called so (`gpu_ms_interval = range`).
pub fn median_interval(g: &Summary) -> (GpuMsInterval, (f64, f64)) {
    if g.n >= MIN_SAMPLES_CI95 {
        (GpuMsInterval::Ci95, g.median_ci)
    } else {
        (GpuMsInterval::Range, (g.min, g.max))
    }
}

/// Timing, pass, clock and memory columns of a measured point, and the flags a timing earns:
/// `noisy` (the stopping rule's target was not met) and `throttled` (a sample was discarded
/// or NVML reported a slowdown).
pub fn set_timing<T: ?Sized>(row: &mut Row, m: &Measured<T>, mesh: &scenarios::Mesh) {
    if let Some(g) = &m.gpu {
        let interval = median_interval(g);
        row.set_f(cols::GPU_MS_MEDIAN, g.median)
            .set_f(cols::GPU_MS_MEAN, g.mean)
            .set_f(cols::GPU_MS_MIN, g.min)
            .set_f(cols::GPU_MS_MAX, g.max)
            .set_f(cols::GPU_MS_P50, g.median)
            .set_f(cols::GPU_MS_P95, g.p95)
            .set_f(cols::GPU_MS_P99, g.p99)
            .set_f(cols::GPU_MS_CI_LO, interval.1 .0)
            .set_f(cols::GPU_MS_CI_HI, interval.1 .1)
            .set(cols::GPU_MS_INTERVAL, interval.0)
            .set_f(cols::GPU_MS_MEAN_CI_LO, g.mean_ci.0)
            .set_f(cols::GPU_MS_MEAN_CI_HI, g.mean_ci.1)
            .set_f(cols::GPU_MS_REL_CI, g.rel_ci)
            .set_f(cols::GPU_MS_REL_NOISE, g.rel_noise)
            .set(cols::GPU_MS_OUTLIERS, g.outliers);
        if g.median > 0.0 && m.bytes_moved > 0 {
            let bps = m.bytes_moved as f64 / (g.median * 1e-3);
            row.set_f(cols::BYTES_PER_S, bps);
            // Against the measured roof of the working set; the NVML spec only without one.
            let roof = match &m.roofs {
                Some(r) => {
                    row.set(cols::L2_RESIDENT, !m.cold && r.resident(m.working_set));
                    Some(r.roof(m.working_set, m.cold)).filter(|p| *p > 0.0)
                }
                None => m.peak_bandwidth,
            };
            if m.roofs.is_some() {
                if let Some(r) = roof {
                    row.set_f(cols::ROOF_BYTES_PER_S, r);
                }
            }
            if let Some(peak) = roof.filter(|p| *p > 0.0) {
                row.set_f(cols::PEAK_BANDWIDTH_FRAC, bps / peak);
            }
        }
        if g.median > 0.0 {
            let secs = g.median * 1e-3 / m.frame.geometry_passes.max(1) as f64;
            row.set_f(cols::TRIANGLES_PER_S, mesh.triangle_count() as f64 / secs)
                .set_f(cols::VERTICES_PER_S, mesh.indices.len() as f64 / secs);
        }
        if m.cpu.median > 0.0 {
            row.set_f(cols::GPU_WALL_RATIO, g.median / m.cpu.median);
        }
    }
    row.set_f(cols::CPU_MS_MEDIAN, m.cpu.median)
        .set_f(cols::CPU_MS_MIN, m.cpu.min)
        .set_f(cols::CPU_MS_MAX, m.cpu.max);
    row.set(
        cols::PASS_MS,
        serde_json::to_string(&m.pass_ms).unwrap_or_default(),
    );
    let pass_ci: BTreeMap<&str, [f64; 2]> = m
        .pass_ci
        .iter()
        .map(|(l, (lo, hi))| (l.as_str(), [*lo, *hi]))
        .collect();
    row.set(
        cols::PASS_MS_CI,
        serde_json::to_string(&pass_ci).unwrap_or_default(),
    );
    row.set(cols::SAMPLES, m.samples.len() - m.discarded())
        .set(cols::SAMPLES_DISCARDED, m.discarded())
        .set(cols::WARMUP_FRAMES, m.warmup_frames)
        .set_f(cols::MEASURE_MS, m.measure_ms)
        .set_f(cols::PREPARE_MS, m.prepare_ms)
        .set(cols::TARGET_REACHED, m.target_reached)
        .set(cols::STOP_REASON, m.stop_reason.as_str());
    if let Some(sp) = m.session_spread {
        row.set_f(cols::SESSION_SPREAD, sp);
    }
    if let Some((n, max)) = m.canary {
        row.set(cols::CANARY_DISCARDED, n);
        if max > 0.0 {
            row.set_f(cols::CANARY_RATIO_MAX, max);
        }
    }
    for (col, v) in m.clocks.to_cells() {
        if !v.is_empty() {
            row.set(col, v);
        }
    }
    row.samples = m.samples.clone();
    row.set(cols::GEOMETRY_PASSES, m.frame.geometry_passes)
        .set(cols::BYTES_ALLOCATED, m.bytes_allocated)
        .set(cols::WORKING_SET_BYTES, m.working_set);
    if let Some(o) = m.bytes_overhead {
        row.set(cols::BYTES_OVERHEAD, o);
    }
    if !m.target_reached {
        row.add_flag(crate::record::Flag::Noisy);
    }
    if m.discarded() > 0 || m.clocks.slowdown() {
        row.add_flag(crate::record::Flag::Throttled);
    }
    if m.clocks.gpu_shared() {
        row.add_flag(crate::record::Flag::GpuShared);
    }
    if let Some((ms, before, after)) = m.clock_lift {
        row.set_f(cols::CLOCK_LIFT_MS, ms)
            .set_f(cols::CLOCK_LIFT_FROM_MHZ, before)
            .set_f(cols::CLOCK_LIFT_TO_MHZ, after);
    }
}

/// `timestamps_incomplete`: the GPU time of a frame is under 5 % of its wall-clock time and
/// the gap exceeds 5 ms. For points whose frame is GPU work only (the methods and stability
/// studies), this means the timestamps missed work: lavapipe's compute passes (0.3 ms of GPU
/// time for 172 ms of wall time) trip it; on the committed H100 runs no methods/stability row
/// does (the smallest ratio with a gap over 2 ms is 0.12: occlusion-query round trips of
/// depth peeling).
pub fn timestamps_incomplete(gpu_ms: f64, cpu_ms: f64) -> bool {
    gpu_ms < 0.05 * cpu_ms && cpu_ms - gpu_ms > 5.0
}

#[cfg(test)]
mod interval_tests {
    use super::*;

    #[test]
    fn too_few_samples_give_the_range_called_range_not_a_95_percent_interval() {
        // The software profile's 3 samples: [min, max] covers the median 75 % of the time.
        let three = Summary::of(&[1.52, 1.93, 5.8], 1).unwrap();
        let (kind, (lo, hi)) = median_interval(&three);
        assert_eq!((kind, lo, hi), (GpuMsInterval::Range, 1.52, 5.8));
        // From MIN_SAMPLES_CI95 on, the order-statistic interval exists: it is the CI.
        let six: Vec<f64> = (0..MIN_SAMPLES_CI95).map(|i| 1.0 + i as f64).collect();
        let s = Summary::of(&six, 1).unwrap();
        assert_eq!(median_interval(&s), (GpuMsInterval::Ci95, s.median_ci));
        // The rule agrees with the stopping rule's own interval (stats::median_ci).
        assert!(mfx_stats::median_ci::lower_index(MIN_SAMPLES_CI95).is_some());
        assert!(mfx_stats::median_ci::lower_index(MIN_SAMPLES_CI95 - 1).is_none());
    }

    #[test]
    fn the_timestamps_rule_trips_on_lavapipe_like_gaps_only() {
        assert!(
            timestamps_incomplete(0.30, 172.0),
            "lavapipe compute_abuffer"
        );
        assert!(
            !timestamps_incomplete(0.002, 0.085),
            "a tiny GPU frame: the gap is overhead"
        );
        assert!(
            !timestamps_incomplete(265.0, 924.0),
            "peeling's CPU round trips: 0.29"
        );
        assert!(!timestamps_incomplete(31.9, 33.0));
    }
}
