//! Timing one prepared method on one scene: untimed preparation, warm-up, timed frames, GPU
//! errors caught as typed errors; and the timing columns of a row.

use std::collections::BTreeMap;

use crate::axes::Point;

use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::method::{FrameStats, Method, Prepared};
use crate::record::{cols, Row};
use crate::timing::{GpuTimer, Stats};
use crate::{CoreError, Result};

/// The result of timing one method on one scene.
pub struct Measured {
    pub gpu_ms: Option<Stats>,
    pub cpu_ms: Stats,
    /// Median ms per pass label (passes with the same label in one frame are summed).
    pub pass_ms: BTreeMap<String, f64>,
    pub frame: FrameStats,
    pub bytes_allocated: u64,
    pub prepared: Box<dyn Prepared>,
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

/// Prepares `method` (untimed), runs `warmup` frames, then `reps` timed frames.
pub fn measure(
    gpu: &Gpu,
    scene: &GpuScene,
    method: &dyn Method,
    point: &Point,
    warmup: u32,
    reps: u32,
) -> Result<Measured> {
    gpu.check_lost()?;
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let prepared = method.prepare(gpu, scene, point);
    scope_error(pollster::block_on(oom.pop()), "prepare")?;
    scope_error(pollster::block_on(validation.pop()), "prepare")?;
    let mut prepared = prepared?;
    let bytes_allocated = prepared.bytes_allocated();

    let mut timer = GpuTimer::new(gpu);
    let mut gpu_samples = Vec::new();
    let mut cpu_samples = Vec::new();
    let mut per_label: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut frame = FrameStats::default();
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let mut run = || -> Result<()> {
        for rep in 0..warmup + reps {
            timer.begin_frame();
            let t0 = std::time::Instant::now();
            frame = prepared.frame(gpu, scene, &mut timer)?;
            gpu.wait()?;
            let cpu = t0.elapsed().as_secs_f64() * 1e3;
            let passes = timer.read(gpu)?;
            gpu.check_lost()?;
            if rep >= warmup {
                cpu_samples.push(cpu);
                if timer.enabled() {
                    gpu_samples.push(passes.iter().map(|(_, ms)| ms).sum());
                    let mut frame_labels: BTreeMap<String, f64> = BTreeMap::new();
                    for (l, ms) in passes {
                        *frame_labels.entry(l).or_default() += ms;
                    }
                    for (l, ms) in frame_labels {
                        per_label.entry(l).or_default().push(ms);
                    }
                }
            }
        }
        Ok(())
    };
    let res = run();
    scope_error(pollster::block_on(oom.pop()), "frame")?;
    scope_error(pollster::block_on(validation.pop()), "frame")?;
    res?;
    Ok(Measured {
        gpu_ms: Stats::of(&gpu_samples),
        cpu_ms: Stats::of(&cpu_samples).unwrap_or_default(),
        pass_ms: per_label
            .into_iter()
            .map(|(l, v)| (l, Stats::of(&v).map(|s| s.median).unwrap_or(0.0)))
            .collect(),
        frame,
        bytes_allocated,
        prepared,
    })
}

/// Timing, pass and memory columns of a measured point.
pub fn set_timing(row: &mut Row, m: &Measured, mesh: &scenarios::Mesh) {
    if let Some(g) = m.gpu_ms {
        row.set_f(cols::GPU_MS_MEDIAN, g.median)
            .set_f(cols::GPU_MS_MIN, g.min)
            .set_f(cols::GPU_MS_MAX, g.max)
            .set_f(cols::GPU_MS_REL_NOISE, g.rel_noise);
        if g.median > 0.0 {
            let secs = g.median * 1e-3 / m.frame.geometry_passes.max(1) as f64;
            row.set_f(cols::TRIANGLES_PER_S, mesh.triangle_count() as f64 / secs)
                .set_f(cols::VERTICES_PER_S, mesh.indices.len() as f64 / secs);
        }
    }
    row.set_f(cols::CPU_MS_MEDIAN, m.cpu_ms.median)
        .set_f(cols::CPU_MS_MIN, m.cpu_ms.min)
        .set_f(cols::CPU_MS_MAX, m.cpu_ms.max);
    row.set(
        cols::PASS_MS,
        serde_json::to_string(&m.pass_ms).unwrap_or_default(),
    );
    row.set(cols::GEOMETRY_PASSES, m.frame.geometry_passes)
        .set(cols::BYTES_ALLOCATED, m.bytes_allocated);
}
