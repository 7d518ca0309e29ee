//! The deferred study's `msaa` axis end to end (city, 64×64, lavapipe): every multisampled row
//! (x4: lavapipe multisamples only 4×) runs and stays within the study's error bound of the
//! average of its samples' f64 shading, the classified and uber rows report their edge tiles, and x2 rows
//! run where the adapter multisamples 2× and are skipped with its reason elsewhere.

use bench_core::record::{cols, Status};
use mfx_shading::STUDIES;

#[test]
fn msaa_rows_run_judged_against_the_averaged_reference_city_64px() {
    let gpu = bench_core::testing::gpu();
    let x2 = mfx_shading::msaa::supported(gpu, mfx_shading::msaa::Mode::X2);
    let rows = bench_core::runner::run_suite(
        gpu,
        STUDIES,
        r#"
        resolutions = [[64, 64]]
        [timing]
        min_samples = 1
        max_samples = 1
        warmup_frames = 0
        [[study]]
        kind = "deferred"
        methods = ["naive", "classified", "uber"]
        axes = { msaa = ["off", "x2", "x4"] }
        [[study.scenes]]
        generator = "city"
        blocks = 3
        lights = 8
    "#,
        "test",
    )
    .unwrap();
    let f = |r: &bench_core::record::Row, c| r.get(c).and_then(|v| v.parse::<f64>().ok());
    let (mut ran, mut skipped) = (0, 0);
    for r in rows
        .iter()
        .filter(|r| r.get(cols::STUDY) == Some("deferred"))
        .filter(|r| !r.get(cols::METHOD).unwrap().starts_with("floor_"))
    {
        let m = r.get(cols::METHOD).unwrap();
        let ms = r
            .get(cols::MSAA)
            .unwrap_or_else(|| panic!("{m}: no msaa; {:?}", r.get(cols::REASON)));
        let status = r.status();
        if ms == "x2" && x2.is_err() {
            assert_eq!(status, Some(Status::Skipped), "{m}");
            assert!(r.get(cols::REASON).unwrap().contains("x2"), "{m}");
            skipped += 1;
            continue;
        }
        assert_eq!(
            status,
            Some(Status::Ok),
            "{m} msaa={ms}: {:?}",
            r.get(cols::REASON)
        );
        ran += 1;
        // Each sample is shaded like a single-sample pixel (shading::tests: max relative error
        // 1.5e-4 on lavapipe); judged against the single-sample reference instead, the edge
        // pixels (about 8 % here) would be off by up to the sky/geometry contrast.
        let rmse = f(r, cols::RMSE).unwrap();
        assert!(rmse < 2e-3, "{m} msaa={ms}: rmse {rmse}");
        let edge = f(r, cols::MSAA_EDGE_TILE_FRAC);
        // Classified and uber classify their tiles (uber draws them all with one shader).
        if ms != "off" && m != "naive" {
            let edge = edge.expect("classified and uber msaa rows report their edge tiles");
            assert!(edge > 0.0 && edge < 1.0, "edge tile fraction {edge}");
        } else {
            assert_eq!(edge, None, "{m} {ms}");
        }
    }
    let want_skipped = if x2.is_err() { 3 } else { 0 };
    assert_eq!((ran, skipped), (9 - want_skipped, want_skipped));
}
