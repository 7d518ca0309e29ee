//! The deferred study's `sun_shadow` axis end to end (city, 64×64, lavapipe): every shadowed row
//! runs and stays within the study's error bound of its own (shadowed) f64 reference, the
//! classified row reports its fade tiles, and a scene without a sun skips the shadowed points.

use bench_core::record::{cols, Status};
use mfx_shading::STUDIES;

#[test]
fn sun_shadow_rows_run_judged_against_the_shadowed_reference_city_64px() {
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
        methods = ["naive", "classified", "uber"]
        axes = { sun_shadow = ["off", "taps8"] }
        [[study.scenes]]
        generator = "city"
        blocks = 3
        lights = 8
        room = [false, true]
    "#,
        "test",
    )
    .unwrap();
    let f = |r: &bench_core::record::Row, c| r.get(c).and_then(|v| v.parse::<f64>().ok());
    let (mut shadowed, mut skipped) = (0, 0);
    for r in rows
        .iter()
        .filter(|r| r.get(cols::STUDY) == Some("deferred"))
        .filter(|r| !r.get(cols::METHOD).unwrap().starts_with("floor_"))
    {
        let m = r.get(cols::METHOD).unwrap();
        let room = r.get(cols::SCENE_LABEL).unwrap().contains("room=true");
        let shadow = r
            .get(cols::SUN_SHADOW)
            .unwrap_or_else(|| panic!("{m}: no sun_shadow; {:?}", r.get(cols::REASON)));
        let status = r.status();
        if shadow == "taps8" && room {
            // The room has no sun: nothing to shadow.
            assert_eq!(status, Some(Status::Skipped), "{m}");
            skipped += 1;
            continue;
        }
        assert_eq!(status, Some(Status::Ok), "{m} {shadow} room={room}");
        // The tie pixels (sun_shadow::TIE_EPS) may differ by up to the sun's share of a pixel;
        // the RMSE over 4096 pixels stays far below 2e-3 anyway. Judged against an unshadowed
        // reference it would be > 1e-2 (the shadow darkens > 5 % of this city's pixels by
        // > 0.05: shading::tests, the same scene).
        let rmse = f(r, cols::RMSE).unwrap();
        assert!(rmse < 2e-3, "{m} {shadow} room={room}: rmse {rmse}");
        let fade = f(r, cols::SHADOW_FADE_TILE_FRAC);
        if shadow == "taps8" {
            shadowed += 1;
            if m == "classified" {
                let fade = fade.expect("classified taps8 reports its fade tiles");
                assert!(fade > 0.0 && fade < 1.0, "fade tile fraction {fade}");
            }
        } else {
            assert_eq!(fade, None, "{m} off");
        }
    }
    assert_eq!((shadowed, skipped), (3, 3));
}
