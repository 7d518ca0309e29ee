//! The canary rule: a fixed kernel timed after every sample, and a sample discarded when its
//! canary ran over `canary_max_ratio` × the process's baseline (the H200's slow states that NVML
//! does not report). Off by default on a software adapter; set explicitly, it runs anywhere.

use bench_core::gpu_scene::GpuScene;
use bench_core::measure::{set_timing, TimingPlan};
use bench_core::record::{cols, Flag, Row};
use mfx_multifragment::method::measure;
use mfx_multifragment::methods;
use mfx_multifragment::testing::{gpu, params, point, scene};
use scenarios::{ParamValue, TimingSpec};

fn plan(samples: u32, canary: Option<f64>) -> TimingPlan {
    TimingPlan::from_spec(&TimingSpec {
        min_samples: Some(samples),
        max_samples: Some(samples),
        warmup_frames: Some(1),
        warmup_max_frames: Some(1),
        canary_max_ratio: canary,
        ..Default::default()
    })
    .unwrap()
}

#[test]
fn the_canary_is_off_by_default_on_a_software_adapter() {
    let g = gpu();
    assert!(g.facts.is_software, "these tests run on lavapipe");
    let s = scene("quads", &[("depth_complexity", ParamValue::Int(4))]);
    let gs = GpuScene::upload(g, &s, 32, 32);
    let m = methods::get("wboit");
    let p = point(&*m, &params(&[]));
    let r = measure(g, &gs, &*m, &p, &plan(4, None)).unwrap();
    assert!(r.canary.is_none());
    assert!(r.samples.iter().all(|x| x.canary_ratio.is_none()));
    assert!(
        r.samples.iter().all(|x| x.unix_ms > 1.6e12),
        "wall clock per sample"
    );
    assert!(plan(4, None).describe().contains("hardware adapters"));
    // 0 turns it off everywhere; the description says nothing of it then.
    assert!(!plan(4, Some(0.0)).describe().contains("canary"));
}

#[test]
fn a_sample_is_discarded_exactly_when_its_canary_ran_over_the_ratio() {
    let g = gpu();
    if !g.has(wgpu::Features::TIMESTAMP_QUERY) {
        eprintln!("skipped: no timestamp queries");
        return;
    }
    let s = scene("quads", &[("depth_complexity", ParamValue::Int(4))]);
    let gs = GpuScene::upload(g, &s, 32, 32);
    let m = methods::get("wboit");
    let p = point(&*m, &params(&[]));

    // A ratio no jitter reaches: every sample has a canary, none is discarded.
    let lax = measure(g, &gs, &*m, &p, &plan(6, Some(1e6))).unwrap();
    assert!(lax
        .samples
        .iter()
        .all(|x| x.canary_ratio.is_some_and(|r| r > 0.0)));
    assert_eq!(lax.discarded(), 0);
    let (n, max) = lax.canary.expect("canary columns");
    assert_eq!(n, 0);
    assert!(max > 0.0);

    // A ratio barely above 1: any canary slower than the baseline (the fifth-fastest so far)
    // discards its sample, and only those (lavapipe has no NVML: no clock rule).
    let strict = 1.0 + 1e-9;
    let r = measure(g, &gs, &*m, &p, &plan(24, Some(strict))).unwrap();
    for x in &r.samples {
        assert_eq!(x.discarded, x.canary_ratio.unwrap() > strict, "{x:?}");
    }
    let (n, _) = r.canary.unwrap();
    assert_eq!(n, r.discarded());
    assert!(
        n > 0,
        "24 canaries on a CPU never ran slower than their fifth-fastest?"
    );
    // Discarded samples are not in the statistics; the rows say how many and why.
    let kept = r.samples.iter().filter(|x| !x.discarded).count();
    let mut row = Row::default();
    set_timing(&mut row, &r, &s.mesh);
    if kept > 0 {
        assert_eq!(row.get(cols::SAMPLES), Some(kept.to_string().as_str()));
    }
    assert_eq!(
        row.get(cols::CANARY_DISCARDED),
        Some(n.to_string().as_str())
    );
    assert!(row.get(cols::CANARY_RATIO_MAX).is_some());
    assert!(
        row.get(cols::GPU_MS_MEDIAN).is_some(),
        "a median even if all were discarded"
    );
    assert!(row.has_flag(Flag::Throttled), "{}", row.flags());
}
