//! The timestamps rule (measure::timestamps_incomplete) on measurements, not just on numbers: a
//! method whose frame does most of its GPU work outside its timestamped passes (as lavapipe's
//! timestamps once missed 99 % of compute_abuffer's) is caught; the same work timed is not.

use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::gpu_util::{bind_buffers, compute_pipeline, shader, storage_entry, STORAGE_RW};
use bench_core::measure::timestamps_incomplete;
use bench_core::measure::TimingPlan;
use bench_core::timing::GpuTimer;
use bench_core::Result;
use mfx_multifragment::method::measure;
use mfx_multifragment::method::{Capture, FrameStats, Method, Prepared};
use mfx_multifragment::testing::{gpu, point, scene};
use scenarios::{ParamValue, Params};

/// A test-only method: one busy compute dispatch per frame, inside a timed pass or not, and a
/// tiny timed pass beside it.
struct Burn {
    timed: bool,
}

struct BurnPrepared {
    timed: bool,
    pipe: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
}

const KERNEL: &str = "
@group(0) @binding(0) var<storage, read_write> acc: array<f32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var x = acc[id.x];
    for (var i = 0u; i < 20000u; i = i + 1u) {
        x = x * 0.999 + 0.001 * f32(i & 7u);
    }
    acc[id.x] = x;
}";

impl Method for Burn {
    fn name(&self) -> &'static str {
        "burn"
    }
    fn describe(&self) -> &'static str {
        "test only: busy compute work, timed or not"
    }
    fn exact(&self) -> bool {
        false
    }
    fn prepare(
        &self,
        gpu: &Gpu,
        _: &GpuScene,
        _: &bench_core::axes::Point,
    ) -> Result<Box<dyn Prepared>> {
        let module = shader(gpu, "burn", KERNEL);
        let cs = wgpu::ShaderStages::COMPUTE;
        let bgl = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: None,
                entries: &[storage_entry(0, false, cs)],
            });
        let layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(&bgl)],
                immediate_size: 0,
            });
        let pipe = compute_pipeline(gpu, "burn", &layout, &module, "main", &[], false);
        let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 64 * 64 * 4,
            usage: STORAGE_RW,
            mapped_at_creation: false,
        });
        let bind = bind_buffers(gpu, "burn", &bgl, &[&buf]);
        Ok(Box::new(BurnPrepared {
            timed: self.timed,
            pipe,
            bind,
        }))
    }
}

impl bench_core::timed::Timed for BurnPrepared {
    fn frame(&mut self, gpu: &Gpu, _: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for (label, groups, timed) in [("burn", 64, self.timed), ("tiny", 1, true)] {
            let ts = if timed {
                timer.compute_pass(label)
            } else {
                None
            };
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: ts,
            });
            pass.set_pipeline(&self.pipe);
            pass.set_bind_group(0, &self.bind, &[]);
            pass.dispatch_workgroups(groups, 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats::default())
    }

    fn bytes_allocated(&self) -> u64 {
        64 * 64 * 4
    }
}

impl Prepared for BurnPrepared {
    fn readback(&mut self, _: &Gpu, _: &GpuScene) -> Result<Capture> {
        Ok(Capture::empty())
    }
}

fn gpu_and_wall(timed: bool) -> Option<(f64, f64)> {
    let g = gpu();
    let s = scene("quads", &[("depth_complexity", ParamValue::Int(1))]);
    let gs = GpuScene::upload(g, &s, 16, 16);
    let m = Burn { timed };
    let p = point(&m, &Params::new());
    let mut plan = TimingPlan::once();
    plan.stop.min_samples = 3;
    plan.stop.max_samples = 3;
    let r = measure(g, &gs, &m, &p, &plan).unwrap();
    Some((r.gpu?.median, r.cpu.median))
}

#[test]
fn work_outside_the_timestamps_is_caught_and_the_same_work_timed_is_not() {
    let (Some((gpu_un, wall_un)), Some((gpu_t, wall_t))) =
        (gpu_and_wall(false), gpu_and_wall(true))
    else {
        eprintln!("no timestamp queries on this adapter: nothing to check");
        return;
    };
    // The busy dispatch must dominate the frame for the check to mean anything.
    assert!(
        wall_un > 10.0,
        "the untimed work took only {wall_un} ms of wall time"
    );
    assert!(
        timestamps_incomplete(gpu_un, wall_un),
        "untimed work: GPU {gpu_un} ms of {wall_un} ms wall is not flagged"
    );
    assert!(
        !timestamps_incomplete(gpu_t, wall_t),
        "timed work: GPU {gpu_t} ms of {wall_t} ms wall is flagged"
    );
}
