//! `[timing] sessions`: a point measured in independent sessions (each prepared afresh) pools
//! their samples and reports a CI of the median that covers every session's median, with the
//! spread in `session_spread`; one session is today's single measurement, unchanged.

use bench_core::gpu_scene::GpuScene;
use bench_core::measure::TimingPlan;
use mfx_multifragment::method::measure;
use mfx_multifragment::methods;
use mfx_multifragment::testing::{gpu, params, point, scene};
use scenarios::{ParamValue, TimingSpec};

fn plan(sessions: u32) -> TimingPlan {
    TimingPlan::from_spec(&TimingSpec {
        min_samples: Some(4),
        max_samples: Some(4),
        warmup_frames: Some(1),
        warmup_max_frames: Some(1),
        sessions: Some(sessions),
        ..Default::default()
    })
    .unwrap()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[test]
fn sessions_pool_their_samples_and_the_ci_covers_every_sessions_median() {
    let g = gpu();
    let s = scene("quads", &[("depth_complexity", ParamValue::Int(4))]);
    let gs = GpuScene::upload(g, &s, 32, 32);
    let m = methods::get("depth_peel");
    let p = point(&*m, &params(&[]));

    let one = measure(g, &gs, &*m, &p, &plan(1)).unwrap();
    assert_eq!(one.samples.len(), 4);
    assert!(one.session_spread.is_none());

    let three = measure(g, &gs, &*m, &p, &plan(3)).unwrap();
    assert_eq!(three.samples.len(), 12, "every session's samples are kept");
    // Each sample names its session (samples.csv's `session`, what mfx compare resamples).
    let sessions: Vec<u32> = three.samples.iter().map(|x| x.session).collect();
    assert_eq!(sessions, [0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2]);
    assert!(one.samples.iter().all(|x| x.session == 0));
    let spread = three.session_spread.expect("a spread with 3 sessions");
    assert!(spread.is_finite() && spread >= 0.0);
    let sum = three.gpu.as_ref().unwrap_or(&three.cpu);
    let (lo, hi) = sum.median_ci;
    let time = |x: &bench_core::record::Sample| x.gpu_ms.unwrap_or(x.cpu_ms);
    let mut meds = Vec::new();
    for chunk in three.samples.chunks(4) {
        let mut v: Vec<f64> = chunk.iter().filter(|x| !x.discarded).map(time).collect();
        let med = median(&mut v);
        assert!(
            lo <= med && med <= hi,
            "session median {med} outside [{lo}, {hi}]"
        );
        meds.push(med);
    }
    let (mn, mx) = meds
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    assert!((spread - (mx - mn) / sum.median).abs() <= 1e-9 * (1.0 + spread));
    assert!(plan(3).describe().contains("3 sessions"));
    // Later sessions prepare after a placement pad of a seeded size: in range, and not one size.
    let pads: Vec<u64> = (1..6)
        .map(|k| bench_core::measure::placement_pad_mib(1, k))
        .collect();
    assert!(pads.iter().all(|&m| (1..=255).contains(&m)), "{pads:?}");
    assert!(pads.windows(2).any(|w| w[0] != w[1]), "{pads:?}");
}

#[test]
fn the_time_cap_counts_samples_only_not_the_warm_up_before_them() {
    // A warm-up of 60 frames takes several times the 15-frame sampling cap: the cap must still
    // leave room for the 3 samples asked for (before, the warm-up's time was charged to it and
    // the point stopped at one sample, `noisy`: 51 of the H200 aa run's 62 noisy rows).
    let g = gpu();
    let s = scene("quads", &[("depth_complexity", ParamValue::Int(4))]);
    let gs = GpuScene::upload(g, &s, 32, 32);
    let m = methods::get("depth_peel");
    let p = point(&*m, &params(&[]));
    let frame = {
        let once = measure(g, &gs, &*m, &p, &plan(1)).unwrap();
        let mut v: Vec<f64> = once.samples.iter().map(|x| x.cpu_ms).collect();
        median(&mut v)
    };
    let mut long = plan(1);
    long.warmup.min_frames = 60;
    long.warmup.max_frames = 60;
    long.warmup.max_time_ms = 1e6;
    long.stop.min_samples = 3;
    long.stop.max_samples = 3;
    long.stop.max_time_ms = 15.0 * frame;
    let r = measure(g, &gs, &*m, &p, &long).unwrap();
    assert_eq!(r.warmup_frames, 60);
    assert_eq!(
        r.samples.len(),
        3,
        "{:?} after a warm-up of 60 frames of ~{frame:.3} ms",
        r.stop_reason
    );
}

#[test]
fn a_relocated_scene_holds_the_same_bytes_in_new_buffers() {
    // Sessions after the first run on a GPU-side copy of the geometry: every buffer must hold
    // exactly what the original holds (a copy into a buffer without COPY_DST left the index
    // buffer zero on the H200 and every later session drew nothing).
    let g = gpu();
    let s = scene(
        "shells",
        &[
            ("count", ParamValue::Int(2)),
            ("segments", ParamValue::Int(8)),
        ],
    );
    let gs = GpuScene::upload(g, &s, 32, 32);
    let moved = gs.relocated(g).unwrap();
    for (a, b) in [
        (&gs.positions, &moved.positions),
        (&gs.normals, &moved.normals),
        (&gs.colors, &moved.colors),
        (&gs.object_ids, &moved.object_ids),
        (&gs.indices, &moved.indices),
    ] {
        assert_eq!(a.size(), b.size());
        let (x, y) = (
            g.read_buffer(a, a.size()).unwrap(),
            g.read_buffer(b, b.size()).unwrap(),
        );
        assert!(x.iter().any(|&v| v != 0), "a scene buffer is not all zero");
        assert_eq!(x, y);
    }
    assert_eq!(moved.index_count, gs.index_count);
    // And a method measured in sessions renders the same image in its last (relocated) session.
    let m = methods::get("wboit");
    let p = point(&*m, &params(&[]));
    let mut one = measure(g, &gs, &*m, &p, &plan(1)).unwrap();
    let mut three = measure(g, &gs, &*m, &p, &plan(3)).unwrap();
    let a = one.prepared.readback(g, &gs).unwrap().image.unwrap();
    let b = three.prepared.readback(g, &gs).unwrap().image.unwrap();
    assert!(
        a.iter().any(|px| px[3] > 0.0),
        "the scene covers some pixels"
    );
    assert_eq!(a, b);
}
