//! GPU timestamps around each pass, and summary statistics (median, min, max, noise).
//!
//! A method asks the timer for `timestamp_writes` per pass with a label; after the frame the
//! harness resolves them (offsets into the resolve buffer are 256-byte aligned chunks) and reads
//! per-pass milliseconds. Deltas use `wrapping_sub` and the queue's timestamp period, and zero
//! deltas are accepted (a pass may be too short to tick).

use crate::gpu::Gpu;
use crate::Result;

/// Queries per frame; each pass takes two.
pub const MAX_TIMED_PASSES: u32 = 1024;

pub struct GpuTimer {
    set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    readback: Option<wgpu::Buffer>,
    labels: Vec<String>,
    period_ns: f64,
    overflowed: bool,
}

impl GpuTimer {
    pub fn new(gpu: &Gpu) -> Self {
        if !gpu.has(wgpu::Features::TIMESTAMP_QUERY) {
            return GpuTimer {
                set: None,
                resolve: None,
                readback: None,
                labels: vec![],
                period_ns: 1.0,
                overflowed: false,
            };
        }
        let count = MAX_TIMED_PASSES * 2;
        let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let size = count as u64 * 8;
        let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamp resolve"),
            size,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamp readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        GpuTimer {
            set: Some(set),
            resolve: Some(resolve),
            readback: Some(readback),
            labels: vec![],
            period_ns: gpu.queue.get_timestamp_period() as f64,
            overflowed: false,
        }
    }

    pub fn enabled(&self) -> bool {
        self.set.is_some()
    }

    /// Starts a new frame: forgets the previous frame's labels.
    pub fn begin_frame(&mut self) {
        self.labels.clear();
        self.overflowed = false;
    }

    fn next(&mut self, label: &str) -> Option<(u32, u32)> {
        self.set.as_ref()?;
        if self.labels.len() as u32 >= MAX_TIMED_PASSES {
            self.overflowed = true;
            return None;
        }
        let i = self.labels.len() as u32;
        self.labels.push(label.to_string());
        Some((2 * i, 2 * i + 1))
    }

    /// One label timed across several passes (kbuffer_rmw's `sort_flush` records a render
    /// pass per 32-triangle batch, tens of thousands a frame, past [`MAX_TIMED_PASSES`]): the
    /// query indices (beginning, end) for the first pass's beginning and the last pass's end
    /// to write through [`GpuTimer::query_set`]. `None` without timestamps or when full.
    pub fn reserve(&mut self, label: &str) -> Option<(u32, u32)> {
        self.next(label)
    }

    /// The frame's timestamp query set (for [`GpuTimer::reserve`]d indices).
    pub fn query_set(&self) -> Option<&wgpu::QuerySet> {
        self.set.as_ref()
    }

    pub fn render_pass(&mut self, label: &str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let (b, e) = self.next(label)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: self.set.as_ref().unwrap(),
            beginning_of_pass_write_index: Some(b),
            end_of_pass_write_index: Some(e),
        })
    }

    pub fn compute_pass(&mut self, label: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let (b, e) = self.next(label)?;
        Some(wgpu::ComputePassTimestampWrites {
            query_set: self.set.as_ref().unwrap(),
            beginning_of_pass_write_index: Some(b),
            end_of_pass_write_index: Some(e),
        })
    }

    /// Resolves and reads this frame's pass times in ms, in pass order. Empty without timestamps.
    pub fn read(&mut self, gpu: &Gpu) -> Result<Vec<(String, f64)>> {
        let ticks = self.read_ticks(gpu)?;
        Ok(self
            .labels
            .iter()
            .zip(ticks.chunks(2))
            .map(|(l, t)| {
                let d = t[1].wrapping_sub(t[0]);
                // A wrapped (negative) delta means the pass was not timed reliably: count it as 0.
                let d = if d > u64::MAX / 2 { 0 } else { d };
                (l.clone(), d as f64 * self.period_ns * 1e-6)
            })
            .collect())
    }

    /// This frame's passes as (label, start ms, end ms) on the GPU clock, relative to the
    /// earliest timestamp of the frame (one queue: comparable across its submissions).
    pub fn read_spans(&mut self, gpu: &Gpu) -> Result<Vec<(String, f64, f64)>> {
        let ticks = self.read_ticks(gpu)?;
        let Some(&t0) = ticks.iter().min() else {
            return Ok(vec![]);
        };
        let ms = |t: u64| t.wrapping_sub(t0) as f64 * self.period_ns * 1e-6;
        Ok(self
            .labels
            .iter()
            .zip(ticks.chunks(2))
            .map(|(l, t)| (l.clone(), ms(t[0]), ms(t[1]).max(ms(t[0]))))
            .collect())
    }

    fn read_ticks(&mut self, gpu: &Gpu) -> Result<Vec<u64>> {
        let (Some(set), Some(resolve), Some(readback)) = (&self.set, &self.resolve, &self.readback)
        else {
            return Ok(vec![]);
        };
        let n = self.labels.len() as u32 * 2;
        if n == 0 {
            return Ok(vec![]);
        }
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.resolve_query_set(set, 0..n, resolve, 0);
        enc.copy_buffer_to_buffer(resolve, 0, readback, 0, n as u64 * 8);
        gpu.queue.submit([enc.finish()]);
        let bytes = gpu.map_read_range(readback, n as u64 * 8)?;
        Ok(bytemuck::pod_collect_to_vec::<u8, u64>(&bytes))
    }
}

/// Summary of repeated measurements.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Stats {
    pub median: f64,
    pub min: f64,
    pub max: f64,
    /// Relative spread: (p90 − p10) / median, 0 for fewer than 3 samples' worth of spread.
    pub rel_noise: f64,
    pub n: usize,
}

impl Stats {
    pub fn of(samples: &[f64]) -> Option<Stats> {
        if samples.is_empty() {
            return None;
        }
        let mut s: Vec<f64> = samples.to_vec();
        s.sort_by(|a, b| a.total_cmp(b));
        let q = |p: f64| s[((s.len() - 1) as f64 * p).round() as usize];
        let median = if s.len() % 2 == 1 {
            s[s.len() / 2]
        } else {
            0.5 * (s[s.len() / 2 - 1] + s[s.len() / 2])
        };
        let rel_noise = if median > 0.0 {
            (q(0.9) - q(0.1)) / median
        } else {
            0.0
        };
        Some(Stats {
            median,
            min: s[0],
            max: s[s.len() - 1],
            rel_noise,
            n: s.len(),
        })
    }
}
