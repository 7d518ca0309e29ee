//! Issue 41 goal 7 on lavapipe: the memory roofs are measured (values not asserted: a software
//! adapter's are the CPU's) and recorded in run.json; each row is read against the roof of its
//! declared working set (`l2_resident`, `roof_bytes_per_s`); `[timing] cold = true` is echoed in
//! `timing_rule` and reads every row against the DRAM roof.

use bench_core::gpu::{Gpu, GpuOptions};
use bench_core::manifest::{AdapterInfo, RunManifest};
use schema::cols;

fn open() -> Gpu {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", "/tmp");
    }
    Gpu::new(&GpuOptions::default())
        .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter (scripts/setup.sh): {e}"))
}

const SUITE: &str = r#"
    resolutions = [[48, 40]]
    [timing]
    min_samples = 2
    max_samples = 2
    warmup_frames = 0
    [[study]]
    kind = "methods"
    methods = ["compute_abuffer", "kbuffer_rmw"]
    [[study.scenes]]
    generator = "quads"
    depth_complexity = 4
"#;

#[test]
fn roofs_are_measured_recorded_and_every_row_is_read_against_its_working_sets_roof() {
    let g = open();
    assert!(g.measured_roofs().is_none(), "measured only when asked");
    let r = g.roofs().expect("lavapipe has timestamp queries").clone();
    assert!(!r.points.is_empty() && r.l2_bytes > 0, "{r:?}");
    assert!(r.points.iter().all(|p| p.bytes_per_s > 0.0), "{r:?}");

    // run.json keeps them.
    let dir = tempfile::tempdir().unwrap();
    let mut m = RunManifest::new(
        vec!["mfx".into()],
        "test",
        "test",
        SUITE,
        AdapterInfo::of(&g.adapter.get_info()),
        (0, 1),
    );
    m.roofs = Some(r.clone());
    m.write(dir.path()).unwrap();
    let back = RunManifest::read(dir.path()).unwrap();
    assert_eq!(back.roofs.as_ref(), Some(&r));

    for cold in [false, true] {
        let text = SUITE.replace(
            "warmup_frames = 0",
            &format!("warmup_frames = 0\ncold = {cold}"),
        );
        let rows =
            bench_core::runner::run_suite(&g, mfx_multifragment::STUDIES, &text, "test").unwrap();
        let mut read = 0;
        for row in rows
            .iter()
            .filter(|x| x.get(cols::STUDY) == Some("methods"))
        {
            let rule = row.get(cols::TIMING_RULE).unwrap();
            assert_eq!(rule.contains("cold"), cold, "{rule}");
            let ws: u64 = row.get(cols::WORKING_SET_BYTES).unwrap().parse().unwrap();
            let alloc: u64 = row.get(cols::BYTES_ALLOCATED).unwrap().parse().unwrap();
            assert!(
                ws > alloc,
                "the scene's geometry is part of the working set"
            );
            let Some(roof) = row.get_f(cols::ROOF_BYTES_PER_S) else {
                continue; // no GPU time, nothing to read against a roof
            };
            read += 1;
            let resident = row.get(cols::L2_RESIDENT) == Some("true");
            assert_eq!(resident, !cold && ws <= r.l2_bytes, "working set {ws}");
            let want = if resident {
                r.l2_bytes_per_s
            } else {
                r.dram_bytes_per_s
            };
            assert_eq!(roof, want);
            let bps = row.get_f(cols::BYTES_PER_S).unwrap();
            let frac = row.get_f(cols::PEAK_BANDWIDTH_FRAC).unwrap();
            assert!((frac - bps / roof).abs() <= 1e-9 * frac.abs().max(1.0));
        }
        assert!(read > 0, "cold {cold}: some row was read against a roof");
    }
}
