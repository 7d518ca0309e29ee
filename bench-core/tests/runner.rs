//! The runner's promises: every point gets a row; bad values are skipped or errors, not panics.

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
    let n = runner::rows_in(&groups);
    let mut sink = Collect(Vec::new());
    let opts = RunOptions {
        run_id: "t".into(),
        git_rev: "t".into(),
        shard: (0, 1),
        save_images: None,
    };
    let written = runner::run(&gpu, &suite, &groups, &opts, &mut sink).unwrap();
    assert_eq!(written, n);
    assert_eq!(sink.0.len(), n, "one row per point, floors included");
    sink.0
}

#[test]
fn out_of_range_axis_is_a_skipped_row_with_reason() {
    let rows = run(r#"
        reps = 1
        warmup = 0
        resolutions = [[16, 16]]
        [[study]]
        kind = "methods"
        methods = ["depth_peel"]
        axes = { max_layers = [0, 4] }
        [[study.scenes]]
        generator = "quads"
        depth_complexity = 2
    "#);
    let peel: Vec<&Row> = rows
        .iter()
        .filter(|r| r.get(cols::METHOD) == Some("depth_peel"))
        .collect();
    assert_eq!(peel.len(), 2);
    let bad = peel
        .iter()
        .find(|r| r.get(cols::MAX_LAYERS) == Some("0"))
        .unwrap();
    assert_eq!(bad.get(cols::STATUS), Some("skipped"));
    assert!(
        bad.get(cols::REASON).unwrap().contains("max_layers"),
        "reason names the axis: {:?}",
        bad.get(cols::REASON)
    );
    let good = peel
        .iter()
        .find(|r| r.get(cols::MAX_LAYERS) == Some("4"))
        .unwrap();
    assert_eq!(good.get(cols::STATUS), Some("ok"));
    assert!(
        good.get(cols::X_FLOOR).is_some(),
        "x_floor is filled from the floor rows"
    );
}

#[test]
fn a_scene_that_cannot_be_built_fails_every_row_of_its_group_with_the_reason() {
    let rows = run(r#"
        reps = 1
        warmup = 0
        resolutions = [[16, 16]]
        [[study]]
        kind = "methods"
        methods = ["depth_peel"]
        [[study.scenes]]
        generator = "obj"
        path = "/nonexistent/mesh.obj"
    "#);
    assert_eq!(rows.len(), 3);
    for r in &rows {
        assert_eq!(r.get(cols::STATUS), Some("failed"));
        assert!(
            r.get(cols::REASON)
                .unwrap()
                .contains("/nonexistent/mesh.obj"),
            "{:?}",
            r.get(cols::REASON)
        );
    }
}

#[test]
fn unknown_method_and_study_are_errors_before_any_gpu_work() {
    let s = Suite::parse("[[study]]\nkind = \"methods\"\nmethods = [\"nope\"]\n[[study.scenes]]\ngenerator = \"quads\"\n", "t").unwrap();
    let e = runner::expand(&s, false).unwrap_err().to_string();
    assert!(e.contains("unknown method 'nope'"), "{e}");
    let s = Suite::parse("[[study]]\nkind = \"nope\"\n", "t").unwrap();
    assert!(runner::expand(&s, false)
        .unwrap_err()
        .to_string()
        .contains("unknown kind 'nope'"));
}

#[test]
fn method_axes_override_the_shared_axes_for_one_method_only() {
    let text = "[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\", \"kbuffer_rmw\"]\n\
                axes = { layers = [4, 8] }\n\
                method_axes = { kbuffer_rmw = { variant = [\"plain\", \"heuristics\"] } }\n\
                [[study.scenes]]\ngenerator = \"quads\"\n";
    let s = Suite::parse(text, "t").unwrap();
    let groups = runner::expand(&s, false).unwrap();
    let pts: Vec<_> = groups.iter().flat_map(|g| g.points.iter()).collect();
    let peel: Vec<_> = pts.iter().filter(|p| p.method == "depth_peel").collect();
    let kbuf: Vec<_> = pts.iter().filter(|p| p.method == "kbuffer_rmw").collect();
    // depth_peel reads neither `layers` nor the k-buffer's variants: one point, no variant.
    assert_eq!(peel.len(), 1);
    assert!(peel[0].params.get("variant").is_none());
    // kbuffer_rmw: 2 layers × 2 variants.
    assert_eq!(kbuf.len(), 4);
    assert!(kbuf
        .iter()
        .any(|p| p.params.get("variant").map(|v| v.to_string()) == Some("heuristics".into())));
    // An override for a method the study does not list is an error naming it.
    let bad = text.replace("kbuffer_rmw = {", "wboit = {");
    let e = Suite::parse(&bad, "t").unwrap_err().to_string();
    assert!(e.contains("method_axes.wboit"), "{e}");
}
