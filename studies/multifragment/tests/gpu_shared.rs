//! A point timed while another process held the GPU is flagged `gpu_shared`: the process list
//! read after every timed frame is fed here (NVML's cannot be faked), once with only this
//! process and once with another beside it, through the runner's whole timing path.

use bench_core::clocks::{own_pids, FixedProcesses};
use bench_core::record::{cols, Flag, Row};
use bench_core::{runner, Gpu, GpuOptions};

/// Two points (a floor and wboit) on a 16×16 quads scene; every frame timed by `measure`.
const SUITE: &str = r#"
    resolutions = [[16, 16]]
    [timing]
    min_samples = 2
    max_samples = 2
    warmup_frames = 0
    [[study]]
    kind = "methods"
    methods = ["wboit"]
    [[study.scenes]]
    generator = "quads"
    depth_complexity = 2
"#;

fn gpu_with(pids: Vec<u32>) -> Gpu {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", "/tmp");
    }
    let mut g = Gpu::new(&GpuOptions::default())
        .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter (scripts/setup.sh): {e}"));
    g.process_list = Some(Box::new(FixedProcesses(pids)));
    g
}

fn timed(rows: &[Row]) -> Vec<&Row> {
    let t: Vec<&Row> = rows
        .iter()
        .filter(|r| r.is_ok() && r.get(cols::SAMPLES).is_some())
        .collect();
    assert!(t.len() >= 2, "a floor and wboit timed: {}", t.len());
    t
}

#[test]
fn rows_timed_beside_another_process_are_flagged_gpu_shared_and_alone_are_not() {
    let me = own_pids()[0];
    // A pid no process of this test has.
    let other = u32::MAX - 7;
    let shared = runner::run_suite(
        &gpu_with(vec![me, other]),
        mfx_multifragment::STUDIES,
        SUITE,
        "test",
    )
    .unwrap();
    for r in timed(&shared) {
        assert!(r.has_flag(Flag::GpuShared), "{:?}", r.get(cols::POINT_KEY));
        assert_eq!(r.get(cols::GPU_OTHER_PROCESSES), Some("1"));
    }
    let alone = runner::run_suite(
        &gpu_with(vec![me]),
        mfx_multifragment::STUDIES,
        SUITE,
        "test",
    )
    .unwrap();
    for r in timed(&alone) {
        assert!(!r.has_flag(Flag::GpuShared), "{:?}", r.get(cols::POINT_KEY));
        assert_eq!(r.get(cols::GPU_OTHER_PROCESSES), Some("0"));
    }
    // Without a process list (lavapipe has no NVML) the column stays empty, no flag.
    let mut plain = gpu_with(vec![]);
    plain.process_list = None;
    if plain.monitor.is_ok() {
        return; // NVML's own list here: what it holds is not this test's to know
    }
    let none = runner::run_suite(&plain, mfx_multifragment::STUDIES, SUITE, "test").unwrap();
    for r in timed(&none) {
        assert!(!r.has_flag(Flag::GpuShared));
        assert_eq!(r.get(cols::GPU_OTHER_PROCESSES), None);
    }
}
