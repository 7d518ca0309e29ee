//! Memory roofs measured on the adapter (issue 41 goal 7): what a copy kernel moves per second
//! with its working set inside the last-level cache (L2) and far beyond it, measured once per
//! run (`mfx sweep` records them in run.json, `roofs`), so that each row's declared traffic is
//! read against the roof of its own working set (`roof_bytes_per_s`, `l2_resident`) rather than
//! against the memory's spec: on the H200 most rows of a sweep declare working sets under its
//! 50 MB L2, where the spec's HBM bandwidth is not the bound.
//!
//! The kernel copies a buffer into another (vec4 loads and stores, grid-stride, every SM busy);
//! a point's bandwidth is (bytes read + bytes written) / its median GPU time over
//! [`TIMED_RUNS`] dispatches after [`WARM_RUNS`] untimed ones (so a working set that fits the L2
//! is in it). Sizes come from the adapter where its L2 is known ([`known_l2`]: half the L2, and
//! the largest working set the bindings allow, ≥ 16× it on the GPUs listed), else from a sweep
//! of powers of two (1 MiB up), whose knee gives the L2's size (the largest working set still
//! at or above the geometric mean of the two roofs). Nothing here is asserted: the figures are
//! the adapter's, recorded as measured.
//!
//! Below `gpu` (it takes the device, not a `Gpu`), so that `Gpu` can cache them.

use serde::{Deserialize, Serialize};

use crate::{CoreError, Result};

/// Untimed dispatches before the timed ones of each size.
pub const WARM_RUNS: usize = 2;
/// Timed dispatches of each size (their median is the point's time).
pub const TIMED_RUNS: usize = 5;
/// Largest working set measured on a hardware adapter, and on a software one (its time is the
/// CPU's: the sweep only has to run).
const MAX_WORKING_SET: u64 = 1 << 30;
const MAX_WORKING_SET_SOFTWARE: u64 = 16 << 20;
const MIN_WORKING_SET: u64 = 1 << 20;

/// One working set measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoofPoint {
    /// Bytes of both buffers (read and written once per dispatch).
    pub working_set_bytes: u64,
    pub bytes_per_s: f64,
}

/// The adapter's measured roofs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Roofs {
    /// What was timed.
    pub kernel: String,
    /// The L2's size in bytes, and where it comes from: `adapter table (NAME)` or `sweep knee`.
    pub l2_bytes: u64,
    pub l2_source: String,
    /// Copy bandwidth with the working set inside the L2 (the fastest point at or under half of
    /// it), bytes read + written per second.
    pub l2_bytes_per_s: f64,
    /// Copy bandwidth far beyond the L2 (the largest working set measured).
    pub dram_bytes_per_s: f64,
    /// Every point measured, smallest first.
    pub points: Vec<RoofPoint>,
}

impl Roofs {
    /// Whether a frame touching `working_set` bytes (warm, between frames) can be served from
    /// the L2: all of it fits.
    pub fn resident(&self, working_set: u64) -> bool {
        working_set <= self.l2_bytes
    }

    /// The roof a frame of `working_set` bytes is read against: the L2's where it is resident
    /// (and `cold` is off), the DRAM's otherwise.
    pub fn roof(&self, working_set: u64, cold: bool) -> f64 {
        if !cold && self.resident(working_set) {
            self.l2_bytes_per_s
        } else {
            self.dram_bytes_per_s
        }
    }
}

/// The L2 of adapters whose size is published (NVIDIA's data sheets: H100 and H200 50 MB,
/// A100 40 MB), by a name the adapter reports; None elsewhere (the sweep finds it).
pub fn known_l2(adapter_name: &str) -> Option<u64> {
    const MB: u64 = 1 << 20;
    let n = adapter_name.to_ascii_uppercase();
    if n.contains("H100") || n.contains("H200") {
        Some(50 * MB)
    } else if n.contains("A100") {
        Some(40 * MB)
    } else {
        None
    }
}

/// Bytes a dispatch moves at least: a small working set is copied over again (`REPS` times)
/// within the dispatch, so launch and timestamp overhead stay small beside it.
const MIN_BYTES_PER_DISPATCH: u64 = 64 << 20;

// Each pass stores values that differ from the last (`+ r`), and a store may alias the source
// (two bindings), so no copy is folded away.
const COPY_WGSL: &str = "
override REPS: u32 = 1u;
@group(0) @binding(0) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> dst: array<vec4<f32>>;
@compute @workgroup_size(WG)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let n = arrayLength(&dst);
    let stride = nw.x * WG;
    for (var r = 0u; r < REPS; r = r + 1u) {
        for (var i = id.x; i < n; i = i + stride) {
            dst[i] = src[i] + vec4<f32>(f32(r));
        }
    }
}";

/// The kernel's words in run.json.
pub const KERNEL: &str = "copy of one buffer into another (vec4, grid-stride, up to 65535 workgroups of 256 threads or the device's most; a working set under 64 MiB copied over again within the dispatch to move 64 MiB), median of 5 timed dispatches after 2";

/// What measuring needs of the device: `roofs` is below `gpu` (which caches the result).
pub struct Device<'a> {
    pub device: &'a wgpu::Device,
    pub queue: &'a wgpu::Queue,
    pub adapter_name: &'a str,
    pub software: bool,
    /// The largest storage binding and buffer.
    pub max_binding: u64,
    pub timestamps: bool,
}

/// Measures the roofs; None without timestamp queries (nothing to time the copies with).
pub fn measure(d: &Device<'_>) -> Result<Option<Roofs>> {
    if !d.timestamps {
        return Ok(None);
    }
    let cap = if d.software {
        MAX_WORKING_SET_SOFTWARE
    } else {
        MAX_WORKING_SET
    };
    // Two buffers of half the working set each, every one within one binding.
    let largest = cap.min(2 * d.max_binding).max(MIN_WORKING_SET);
    let largest = 1u64 << (63 - largest.leading_zeros());
    let known = known_l2(d.adapter_name);
    let sizes: Vec<u64> = match known {
        Some(l2) => vec![(l2 / 2).min(largest), largest],
        None => (0..)
            .map(|k| MIN_WORKING_SET << k)
            .take_while(|&w| w <= largest)
            .collect(),
    };
    let kernel = CopyKernel::new(d);
    let mut points = Vec::with_capacity(sizes.len());
    for w in sizes {
        let reps = MIN_BYTES_PER_DISPATCH.div_ceil(w).max(1);
        let ms = kernel.time(d, w, reps as u32)?;
        let moved = (w * reps) as f64;
        points.push(RoofPoint {
            working_set_bytes: w,
            bytes_per_s: if ms > 0.0 { moved / (ms * 1e-3) } else { 0.0 },
        });
    }
    Ok(Some(summarise(points, known, d.adapter_name)))
}

/// The roofs of measured `points`: the L2's from the fastest point within half the L2 (known, or
/// the sweep's knee), the DRAM's from the largest.
pub fn summarise(points: Vec<RoofPoint>, known: Option<u64>, adapter: &str) -> Roofs {
    let peak = points.iter().map(|p| p.bytes_per_s).fold(0.0, f64::max);
    let dram = points.last().map_or(0.0, |p| p.bytes_per_s);
    let (l2_bytes, l2_source) = match known {
        Some(l2) => (l2, format!("adapter table ({adapter})")),
        None => {
            // The largest working set still at or above the geometric mean of the two roofs.
            let mid = (peak * dram).sqrt();
            let knee = points
                .iter()
                .filter(|p| p.bytes_per_s >= mid)
                .map(|p| p.working_set_bytes)
                .max()
                .unwrap_or(0);
            (knee, "sweep knee".to_string())
        }
    };
    let l2 = points
        .iter()
        .filter(|p| p.working_set_bytes <= l2_bytes.max(MIN_WORKING_SET))
        .map(|p| p.bytes_per_s)
        .fold(0.0, f64::max);
    Roofs {
        kernel: KERNEL.into(),
        l2_bytes,
        l2_source,
        l2_bytes_per_s: if l2 > 0.0 { l2 } else { peak },
        dram_bytes_per_s: dram,
        points,
    }
}

/// The copy kernel's module with two timestamps per timed dispatch.
struct CopyKernel {
    module: wgpu::ShaderModule,
    /// Threads a workgroup: 256, or the device's most where fewer.
    wg: u32,
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
}

impl CopyKernel {
    fn new(d: &Device<'_>) -> CopyKernel {
        let l = d.device.limits();
        let wg = 256
            .min(l.max_compute_invocations_per_workgroup)
            .min(l.max_compute_workgroup_size_x)
            .max(1);
        let src = format!("const WG: u32 = {wg}u;\n{COPY_WGSL}");
        let module = d.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("roof copy"),
            source: wgpu::ShaderSource::Wgsl(src.into()),
        });
        let n = 2 * TIMED_RUNS as u32;
        let set = d.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("roof copy"),
            ty: wgpu::QueryType::Timestamp,
            count: n,
        });
        let buf = |label, usage| {
            d.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: n as u64 * 8,
                usage,
                mapped_at_creation: false,
            })
        };
        CopyKernel {
            module,
            wg,
            set,
            resolve: buf(
                "roof resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            read: buf(
                "roof read-back",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
        }
    }

    /// The median GPU ms of copying `working_set / 2` bytes `reps` times over.
    fn time(&self, d: &Device<'_>, working_set: u64, reps: u32) -> Result<f64> {
        let half = working_set / 2;
        let constants = [("REPS", reps as f64)];
        let pipeline = d
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("roof copy"),
                layout: None,
                module: &self.module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            });
        let mk = |label| {
            d.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: half,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let (src, dst) = (mk("roof source"), mk("roof destination"));
        let bind = d.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("roof copy"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: src.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: dst.as_entire_binding(),
                },
            ],
        });
        let groups = (half / 16).div_ceil(self.wg as u64).clamp(1, 65_535) as u32;
        let mut enc = d.device.create_command_encoder(&Default::default());
        for j in 0..WARM_RUNS + TIMED_RUNS {
            let timed = j.checked_sub(WARM_RUNS).map(|k| k as u32);
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("roof copy"),
                timestamp_writes: timed.map(|k| wgpu::ComputePassTimestampWrites {
                    query_set: &self.set,
                    beginning_of_pass_write_index: Some(2 * k),
                    end_of_pass_write_index: Some(2 * k + 1),
                }),
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(groups, 1, 1);
        }
        let n = 2 * TIMED_RUNS as u32;
        enc.resolve_query_set(&self.set, 0..n, &self.resolve, 0);
        enc.copy_buffer_to_buffer(&self.resolve, 0, &self.read, 0, n as u64 * 8);
        d.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        self.read
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                let _ = tx.send(r);
            });
        d.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| CoreError::Gpu(format!("roofs: poll failed: {e}")))?;
        rx.recv()
            .map_err(|_| CoreError::Gpu("roofs: map callback dropped".into()))?
            .map_err(|e| CoreError::Gpu(format!("roofs: map failed: {e}")))?;
        let t: Vec<u64> = {
            let view = self
                .read
                .slice(..)
                .get_mapped_range()
                .map_err(|e| CoreError::Gpu(format!("roofs: mapped range: {e}")))?;
            bytemuck::pod_collect_to_vec(&view)
        };
        self.read.unmap();
        let period = d.queue.get_timestamp_period() as f64 * 1e-6;
        let mut ms: Vec<f64> = t
            .chunks_exact(2)
            .map(|p| p[1].wrapping_sub(p[0]))
            .filter(|&ticks| ticks < u64::MAX / 2)
            .map(|ticks| ticks as f64 * period)
            .collect();
        ms.sort_by(f64::total_cmp);
        Ok(ms.get(ms.len() / 2).copied().unwrap_or(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(mib: u64, gbps: f64) -> RoofPoint {
        RoofPoint {
            working_set_bytes: mib << 20,
            bytes_per_s: gbps * 1e9,
        }
    }

    #[test]
    fn a_sweep_finds_the_knee_and_a_known_l2_takes_its_size() {
        // Fast to 32 MiB, slow from 128 MiB: the knee is the last point above √(9000 · 3000).
        let pts = vec![
            p(1, 6000.0),
            p(8, 9000.0),
            p(32, 8500.0),
            p(128, 3200.0),
            p(512, 3000.0),
        ];
        let r = summarise(pts.clone(), None, "some GPU");
        assert_eq!(r.l2_bytes, 32 << 20);
        assert_eq!((r.l2_bytes_per_s, r.dram_bytes_per_s), (9000e9, 3000e9));
        assert!(r.resident(32 << 20) && !r.resident((32 << 20) + 1));
        assert_eq!(r.roof(1 << 20, false), 9000e9);
        assert_eq!(r.roof(1 << 20, true), 3000e9, "cold: the L2 was flushed");
        assert_eq!(r.roof(1 << 30, false), 3000e9);
        let k = summarise(pts, known_l2("NVIDIA H200"), "NVIDIA H200");
        assert_eq!(k.l2_bytes, 50 << 20);
        assert!(k.l2_source.contains("H200"));
        assert_eq!(known_l2("llvmpipe (LLVM 19)"), None);
    }
}
