//! BF3's per-phase columns on cpu_tiled rows of the deferred study.

use bench_core::record::cols;
use mfx_shading::STUDIES;

/// cpu_tiled rows carry BF3's phases (thread-summed, adding up to cpu_phases_ms) and the
/// light loop's cost per evaluation for none and all lights diffuse-only; GPU rows none.
#[test]
fn cpu_tiled_rows_carry_the_phases_and_the_per_light_cost_64px() {
    let rows = bench_core::runner::run_suite(
        bench_core::testing::gpu(),
        STUDIES,
        r#"
        resolutions = [[64, 64]]
        [timing]
        min_samples = 1
        max_samples = 1
        warmup_frames = 0
        [[study]]
        kind = "deferred"
        methods = ["naive", "cpu_tiled"]
        axes = { thread_count = [2], diffuse_only_frac = [0.0, 1.0] }
        cpu_reps = 1
        [[study.scenes]]
        generator = "city"
        blocks = 2
        lights = 48
    "#,
        "test",
    )
    .unwrap();
    let f = |r: &bench_core::record::Row, c| r.get(c).and_then(|v| v.parse::<f64>().ok());
    let mut cpu = 0;
    for r in rows
        .iter()
        .filter(|r| r.get(cols::STUDY) == Some("deferred"))
    {
        let m = r.get(cols::METHOD).unwrap();
        if m != "cpu_tiled" {
            assert_eq!(f(r, cols::CPU_CULL_MS), None, "{m}");
            continue;
        }
        cpu += 1;
        let parts = [
            cols::CPU_CULL_MS,
            cols::CPU_UNPACK_MS,
            cols::CPU_SHADE_MS,
            cols::CPU_PACK_MS,
        ]
        .map(|c| f(r, c).unwrap_or_else(|| panic!("no {c}")));
        assert!(parts.iter().all(|&p| p > 0.0), "{parts:?}");
        let total = f(r, cols::CPU_PHASES_MS).unwrap();
        // Each column is rounded on its own when written.
        assert!(
            (parts.iter().sum::<f64>() - total).abs() <= 1e-3 * total,
            "{parts:?} {total}"
        );
        assert!(f(r, cols::SHADE_NS_PER_LIGHT_QUAD).unwrap() > 0.0);
    }
    assert_eq!(cpu, 2);
}

const LOOP_SUITE: &str = r#"
    resolutions = [[64, 64]]
    [timing]
    min_samples = 1
    max_samples = 1
    warmup_frames = 0
    [[study]]
    kind = "deferred"
    methods = ["cpu_tiled"]
    axes = { thread_count = [2], light_loop = ["bf3", "mfx"] }
    cpu_reps = 1
    phase_reps = 6
    [[study.scenes]]
    generator = "city"
    blocks = 2
    lights = 48
"#;

/// BF3's light loop is an axis of cpu_tiled: a value it does not know is an error naming the
/// axis and the values, before any GPU work; both loops give the same image (same error
/// against the f64 reference); with 6 phase-clock frames shade_ns_per_light_quad carries its
/// 95 % interval around the median, and with one frame none.
#[test]
fn light_loop_is_an_axis_and_the_per_light_cost_carries_an_interval_64px() {
    let e = bench_core::runner::run_suite(
        bench_core::testing::gpu(),
        STUDIES,
        &LOOP_SUITE.replace("\"mfx\"]", "\"mfx\", \"spu\"]"),
        "test",
    )
    .expect_err("an unknown light loop is an error")
    .to_string();
    assert!(
        e.contains("light_loop") && e.contains("spu") && e.contains("bf3"),
        "{e}"
    );
    let run = |text: &str| {
        bench_core::runner::run_suite(bench_core::testing::gpu(), STUDIES, text, "test").unwrap()
    };
    let f = |r: &bench_core::record::Row, c| r.get(c).and_then(|v| v.parse::<f64>().ok());
    let rows = run(LOOP_SUITE);
    let cpu: Vec<_> = rows
        .iter()
        .filter(|r| r.get(cols::METHOD) == Some("cpu_tiled"))
        .collect();
    assert_eq!(cpu.len(), 2);
    let mut loops: Vec<_> = cpu
        .iter()
        .map(|r| r.get(cols::LIGHT_LOOP).unwrap())
        .collect();
    loops.sort();
    assert_eq!(loops, ["bf3", "mfx"]);
    assert_eq!(cpu[0].get(cols::RMSE), cpu[1].get(cols::RMSE));
    for r in &cpu {
        let m = f(r, cols::SHADE_NS_PER_LIGHT_QUAD).unwrap();
        let lo = f(r, cols::SHADE_NS_PER_LIGHT_QUAD_CI_LO).unwrap();
        let hi = f(r, cols::SHADE_NS_PER_LIGHT_QUAD_CI_HI).unwrap();
        assert!(0.0 < lo && lo <= m && m <= hi, "{lo} {m} {hi}");
    }
    let one = run(&LOOP_SUITE.replace("phase_reps = 6", "phase_reps = 1"));
    for r in one
        .iter()
        .filter(|r| r.get(cols::METHOD) == Some("cpu_tiled"))
    {
        assert!(f(r, cols::SHADE_NS_PER_LIGHT_QUAD).is_some());
        assert_eq!(f(r, cols::SHADE_NS_PER_LIGHT_QUAD_CI_LO), None);
    }
}
