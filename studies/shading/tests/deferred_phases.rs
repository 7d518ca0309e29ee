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
