//! The shadows study through the runner, on lavapipe at 32×32: every point gets a row, a scene
//! without an area light is a skipped row with its reason, bad study settings are errors.

use bench_core::record::{Row, Sink};
use bench_core::runner::{self, RunOptions};
use bench_core::testing;
use scenarios::Suite;
use schema::cols;

struct Collect(Vec<Row>);
impl Sink for Collect {
    fn point_done(&mut self, row: &Row) -> bench_core::Result<()> {
        self.0.push(row.clone());
        Ok(())
    }
}

fn run(text: &str) -> Vec<Row> {
    let gpu = testing::gpu();
    let suite = Suite::parse(text, "test").unwrap();
    let groups = runner::expand(&suite, gpu.facts.is_software).unwrap();
    let mut sink = Collect(Vec::new());
    let opts = RunOptions {
        run_id: "t".into(),
        git_rev: "t".into(),
        shard: (0, 1),
        save_images: None,
    };
    let written = runner::run(&gpu, &suite, &groups, &opts, &mut sink).unwrap();
    assert_eq!(written, runner::rows_in(&groups));
    sink.0
}

const HEAD: &str = r#"
    reps = 1
    warmup = 0
    resolutions = [[32, 32]]
    [[study]]
    kind = "shadows"
    shadow_rays = 16
"#;

#[test]
fn shadows_32px_rows_ok_with_errors_and_no_light_scene_skipped() {
    let rows = run(&format!(
        r#"{HEAD}
        axes = {{ layers = [1, 3], shadow_map_res = [64], bias_mode = ["slope", "bogus"] }}
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
                assert_eq!(r.get(cols::STATUS), Some("ok"), "{:?}", r.cells);
                let rmse: f64 = r.get(cols::VIS_RMSE).unwrap().parse().unwrap();
                assert!(rmse.is_finite() && rmse < 0.2, "{:?}", r.cells);
                assert!(
                    r.get(cols::GPU_MS_MEDIAN).is_some() || r.get(cols::CPU_MS_MEDIAN).is_some()
                );
            }
            ("soft_shadow", _) => {
                assert_eq!(r.get(cols::STATUS), Some("skipped"), "{:?}", r.cells);
                assert!(r.get(cols::REASON).unwrap().contains("bias_mode"));
            }
            _ => {
                assert_eq!(r.get(cols::STATUS), Some("skipped"), "{:?}", r.cells);
                assert!(r.get(cols::REASON).unwrap().contains("area light"));
            }
        }
    }
}

#[test]
fn bad_shadows_settings_are_errors_naming_the_value() {
    for (extra, word) in [
        ("shadow_rays = 10", "perfect square"),
        ("axes = { layer = [1] }", "unknown shadows axis 'layer'"),
        ("methods = [\"depth_peel\"]", "layered_ssm"),
        ("rays = 4", "unknown key 'rays'"),
    ] {
        let head = HEAD.replace("shadow_rays = 16", "");
        let text = format!("{head}\n{extra}\n[[study.scenes]]\ngenerator = \"soft_shadow\"\n");
        let suite = Suite::parse(&text, "test").unwrap();
        let e = runner::expand(&suite, true).unwrap_err().to_string();
        assert!(e.contains(word), "{extra}: {e}");
    }
}
