//! The shadows study through the runner, on lavapipe at 32×32: every point gets a row, a scene
//! without an area light is a skipped row with its reason, bad study settings are errors.

use bench_core::record::{Row, Status};
use bench_core::runner::{self};
use bench_core::testing;
use mfx_shadows::STUDIES;
use scenarios::Suite;
use schema::cols;

fn run(text: &str) -> Vec<Row> {
    runner::run_suite(testing::gpu(), STUDIES, text, "test").unwrap_or_else(|e| panic!("{e}"))
}

const HEAD: &str = r#"
    resolutions = [[32, 32]]
    [timing]
    min_samples = 1
    max_samples = 1
    warmup_frames = 0
    [[study]]
    kind = "shadows"
    shadow_rays = 16
"#;

#[test]
fn shadows_32px_rows_ok_with_errors_and_no_light_scene_skipped() {
    let rows = run(&format!(
        r#"{HEAD}
        axes = {{ layers = [1, 3], shadow_map_res = [64], bias_mode = ["slope", "midpoint"] }}
        [[study.scenes]]
        generator = "soft_shadow"
        case = "quad"
        [[study.scenes]]
        generator = "quads"
        depth_complexity = 2
    "#
    ));
    let ssm: Vec<&Row> = rows
        .iter()
        .filter(|r| r.get(cols::METHOD) == Some("layered_ssm"))
        .collect();
    assert_eq!(ssm.len(), 8, "2 scenes × 2 layers × 2 bias modes");
    for r in &ssm {
        let scene = r.get(cols::SCENE).unwrap();
        let mode = r.get(cols::BIAS_MODE).unwrap();
        match (scene, mode) {
            ("soft_shadow", "slope") => {
                assert_eq!(r.status(), Some(Status::Ok), "{:?}", r.cells());
                let rmse: f64 = r.get(cols::VIS_RMSE).unwrap().parse().unwrap();
                assert!(rmse.is_finite() && rmse < 0.2, "{:?}", r.cells());
                assert!(
                    r.get(cols::GPU_MS_MEDIAN).is_some() || r.get(cols::CPU_MS_MEDIAN).is_some()
                );
            }
            ("soft_shadow", _) => {
                assert_eq!(r.status(), Some(Status::Ok), "{:?}", r.cells());
            }
            _ => {
                assert_eq!(r.status(), Some(Status::Skipped), "{:?}", r.cells());
                assert!(r.get(cols::REASON).unwrap().contains("area light"));
            }
        }
    }
}

#[test]
fn bad_shadows_settings_are_errors_naming_the_value() {
    for (extra, word) in [
        ("shadow_rays = 10", "perfect square"),
        (
            "axes = { layer = [1] }",
            "'layer': no method of this study declares this axis",
        ),
        ("methods = [\"depth_peel\"]", "takes no methods list"),
        ("rays = 4", "'rays' = 4: unknown key"),
        (
            "axes = { bias_mode = [\"bogus\"] }",
            "'bias_mode' = bogus: must be one of midpoint, slope, hybrid",
        ),
    ] {
        let head = HEAD.replace("shadow_rays = 16", "");
        let text = format!("{head}\n{extra}\n[[study.scenes]]\ngenerator = \"soft_shadow\"\n");
        let suite = Suite::parse(&text, "test").unwrap();
        let e = scenarios::problem::report(&bench_core::check::check_suite(STUDIES, &suite));
        assert!(e.contains(word), "{extra}: {e}");
    }
}
