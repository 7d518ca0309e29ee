//! Every study's rows are timed by `measure`: a geometry point and a light pre-pass point
//! (GPU-lit and CPU-lit) carry the same timing columns as a method's — samples, the stopping
//! rule's target, the CI of the median and the per-sample tail — on lavapipe. No speed is
//! asserted: only that the columns exist and agree with each other.

use bench_core::record::{cols, Row};
use bench_core::testing;
use mfx::STUDIES;

fn rows(text: &str) -> Vec<Row> {
    bench_core::runner::run_suite(testing::gpu(), STUDIES, text, "test").unwrap()
}

fn f(r: &Row, c: bench_core::record::Col) -> f64 {
    r.get_f(c)
        .unwrap_or_else(|| panic!("{} empty in {:?}", c.name, r))
}

/// The timing columns `measure` writes, and their relations.
fn assert_timed(r: &Row, samples: usize) {
    assert_eq!(r.status(), Some(bench_core::record::Status::Ok), "{:?}", r);
    assert_eq!(r.get(cols::SAMPLES), Some(samples.to_string().as_str()));
    assert!(r.get(cols::TARGET_REACHED).is_some(), "{:?}", r);
    assert!(r.get(cols::STOP_REASON).is_some());
    let (med, lo, hi) = (
        f(r, cols::GPU_MS_MEDIAN),
        f(r, cols::GPU_MS_CI_LO),
        f(r, cols::GPU_MS_CI_HI),
    );
    assert!(lo <= med && med <= hi, "CI [{lo}, {hi}] around {med}");
    let (p50, p95, p99, max) = (
        f(r, cols::GPU_MS_P50),
        f(r, cols::GPU_MS_P95),
        f(r, cols::GPU_MS_P99),
        f(r, cols::GPU_MS_MAX),
    );
    assert_eq!(p50, med);
    assert!(
        p50 <= p95 && p95 <= p99 && p99 <= max,
        "{p50} {p95} {p99} {max}"
    );
    assert!(f(r, cols::BYTES_PER_S) > 0.0);
    // lavapipe has no NVML: the peak is unknown, so the fraction is empty, not guessed.
    assert_eq!(r.get(cols::PEAK_BANDWIDTH_FRAC), None);
    let rule = r.get(cols::TIMING_RULE).unwrap();
    assert!(rule.contains("samples, stop at"), "{rule}");
}

#[test]
fn geometry_and_prepass_rows_carry_the_timing_columns() {
    let geometry = rows(
        r#"
name = "t-geometry"
resolutions = [[32, 32]]
[timing]
min_samples = 3
max_samples = 3
warmup_frames = 1
warmup_max_frames = 1
[[study]]
kind = "geometry"
small_viewport_divisor = 4
axes = { batch_size = [0, 64] }
[[study.scenes]]
generator = "mesh"
triangles = 400
"#,
    );
    let g: Vec<&Row> = geometry
        .iter()
        .filter(|r| r.get(cols::METHOD) == Some("geometry"))
        .collect();
    assert_eq!(g.len(), 2);
    for r in g {
        assert_timed(r, 3);
        // The small viewport is timed by the same rule.
        assert!(r.get_f(cols::GPU_MS_SMALL_VIEWPORT).is_some());
    }
    let prepass = rows(
        r#"
name = "t-prepass"
resolutions = [[32, 24]]
[timing]
min_samples = 3
max_samples = 3
warmup_frames = 1
warmup_max_frames = 1
[[study]]
kind = "prepass"
methods = ["deferred", "prepass", "prepass_cpu"]
axes = { light_accum = ["tiled"], light_buffer_format = ["rgba16f"], thread_count = [1] }
[[study.scenes]]
generator = "city"
blocks = 2
lights = 8
"#,
    );
    let p: Vec<&Row> = prepass
        .iter()
        .filter(|r| r.get(cols::STUDY) == Some("prepass"))
        .filter(|r| !r.get(cols::METHOD).unwrap().starts_with("floor"))
        .collect();
    assert_eq!(p.len(), 3);
    for r in &p {
        assert_timed(r, 3);
        assert!(f(r, cols::FRAME_MS) > 0.0);
    }
    // The CPU-lit frame's CPU parts are medians of the same kept samples.
    let cpu = p
        .iter()
        .find(|r| r.get(cols::METHOD) == Some("prepass_cpu"))
        .unwrap();
    assert!(f(cpu, cols::CPU_LIGHT_MS) > 0.0);
    assert!(f(cpu, cols::LATENCY_MS) > 0.0);
}
