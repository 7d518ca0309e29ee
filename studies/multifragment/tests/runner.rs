//! The runner's promises: every point gets a row; bad values are skipped or errors, not panics.

use bench_core::record::{Row, Status};
use bench_core::runner::{self};
use mfx_multifragment::testing;
use mfx_multifragment::STUDIES;
use scenarios::Suite;
use schema::cols;

fn run(text: &str) -> Vec<Row> {
    runner::run_suite(testing::gpu(), STUDIES, text, "test").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn out_of_range_axis_is_refused_before_any_gpu_work_and_a_valid_one_runs() {
    let text = r#"
        resolutions = [[16, 16]]
        [timing]
        min_samples = 1
        max_samples = 1
        warmup_frames = 0
        [[study]]
        kind = "methods"
        methods = ["depth_peel"]
        axes = { max_layers = [0, 4] }
        [[study.scenes]]
        generator = "quads"
        depth_complexity = 2
    "#;
    // No adapter could run max_layers = 0: a bad suite, not a skipped row.
    let e = runner::run_suite(testing::gpu(), STUDIES, text, "test")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'max_layers' = 0") && e.contains("1..=4096"),
        "the error names the axis, the value and the range: {e}"
    );
    let rows = run(&text.replace("[0, 4]", "[4]"));
    let good: Vec<&Row> = rows
        .iter()
        .filter(|r| r.get(cols::METHOD) == Some("depth_peel"))
        .collect();
    assert_eq!(good.len(), 1);
    assert_eq!(good[0].status(), Some(Status::Ok));
    assert_eq!(good[0].get(cols::MAX_LAYERS), Some("4"));
    // Axes the suite left out are written with their defaults.
    assert_eq!(good[0].get(cols::OCCLUSION_STOP), Some("true"));
    // x_floor is the row's median over the depth-only floor's, wherever both exist (a floor
    // pass on a 16² lavapipe target can time at 0 ms: then no ratio is a result).
    let floor = rows
        .iter()
        .find(|r| r.get(cols::METHOD) == Some("floor_depth"))
        .expect("the group's floor row");
    let floor_ms = floor.get_f(cols::GPU_MS_MEDIAN).filter(|f| *f > 0.0);
    let g = good[0].get_f(cols::GPU_MS_MEDIAN).expect("a timed row");
    match floor_ms.filter(|_| bench_core::record::gpu_time_trusted(good[0])) {
        Some(f) => {
            let x = good[0]
                .get_f(cols::X_FLOOR)
                .expect("x_floor filled from the floor row");
            assert!(
                (x - g / f).abs() <= 1e-6 * (g / f).abs().max(1.0),
                "{x} vs {g}/{f}"
            );
        }
        None => assert_eq!(good[0].get(cols::X_FLOOR), None, "no floor time, no ratio"),
    }
}

#[test]
fn a_scene_that_cannot_be_built_fails_every_row_of_its_group_with_the_reason() {
    // The check refuses a missing model before any GPU work; a file that goes missing after the
    // check (or a sweep that skips it) still gives a failed row per point, none lost.
    let text = r#"
        resolutions = [[16, 16]]
        [timing]
        min_samples = 1
        max_samples = 1
        warmup_frames = 0
        [[study]]
        kind = "methods"
        methods = ["depth_peel"]
        [[study.scenes]]
        generator = "obj"
        path = "/nonexistent/mesh.obj"
    "#;
    let e = runner::run_suite(testing::gpu(), STUDIES, text, "test")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'path' = /nonexistent/mesh.obj") && e.contains("file not found"),
        "{e}"
    );
    let suite = Suite::parse(text, "test").unwrap();
    let groups = runner::expand(STUDIES, &suite, true).unwrap();
    let mut sink = bench_core::record::VecSink::default();
    let opts = runner::RunOptions {
        run_id: "t".into(),
        git_rev: "t".into(),
        shard: (0, 1),
        save_images: None,
        ..Default::default()
    };
    runner::run(testing::gpu(), STUDIES, &suite, &groups, &opts, &mut sink).unwrap();
    let rows = sink.0;
    assert_eq!(rows.len(), 5, "four floors and the point");
    for r in &rows {
        assert_eq!(r.status(), Some(Status::Failed));
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
    let e = runner::expand(STUDIES, &s, false).unwrap_err().to_string();
    assert!(e.contains("unknown method 'nope'"), "{e}");
    // A kind is read where the suite is parsed: an unknown one never reaches the runner.
    let e = Suite::parse("[[study]]\nkind = \"nope\"\n", "t")
        .unwrap_err()
        .to_string();
    assert!(e.contains("'kind' = nope: unknown study kind"), "{e}");
}

#[test]
fn method_axes_override_the_shared_axes_for_one_method_only() {
    let text = "[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\", \"kbuffer_rmw\"]\n\
                axes = { layers = [4, 8] }\n\
                method_axes = { kbuffer_rmw = { heuristics = [false, true] } }\n\
                [[study.scenes]]\ngenerator = \"quads\"\n";
    let s = Suite::parse(text, "t").unwrap();
    let groups = runner::expand(STUDIES, &s, false).unwrap();
    let pts: Vec<_> = groups.iter().flat_map(|g| g.points.iter()).collect();
    let peel: Vec<_> = pts.iter().filter(|p| p.method == "depth_peel").collect();
    let kbuf: Vec<_> = pts.iter().filter(|p| p.method == "kbuffer_rmw").collect();
    // depth_peel reads neither `layers` nor the k-buffer's variants: one point, no variant.
    assert_eq!(peel.len(), 1);
    assert!(peel[0].point.get("heuristics").is_none());
    // kbuffer_rmw: 2 layers × 2 variants.
    assert_eq!(kbuf.len(), 4);
    assert!(kbuf
        .iter()
        .any(|p| p.point.get("heuristics").map(|v| v.to_string()) == Some("true".into())));
    // An override for a method the study does not list is an error naming it.
    let bad = text.replace("kbuffer_rmw = {", "wboit = {");
    let e = Suite::parse(&bad, "t").unwrap_err().to_string();
    assert!(e.contains("method_axes.wboit"), "{e}");
}

#[test]
fn a_buffer_over_the_adapters_storage_binding_is_a_skipped_row_naming_the_limit() {
    // 64 slots of 40 B for each of 4 samples of 1024² pixels: 10.7 GB of k-buffer entries, over
    // any adapter's largest storage binding (the H200's is 2 GiB − 4) and more than a split
    // over 8 bindings holds on lavapipe (128 MiB each): known before any GPU work, so the
    // point is skipped with the limit named, never a `failed` row.
    let text = r#"
        resolutions = [[1024, 1024]]
        [timing]
        min_samples = 1
        max_samples = 1
        warmup_frames = 0
        [[study]]
        kind = "methods"
        methods = ["kbuffer_atomic"]
        axes = { layers = [64], aa = ["msaa4"] }
        [[study.scenes]]
        generator = "quads"
        depth_complexity = 2
    "#;
    let rows = run(text);
    let k: Vec<&Row> = rows
        .iter()
        .filter(|r| r.get(cols::METHOD) == Some("kbuffer_atomic"))
        .collect();
    assert_eq!(k.len(), 1);
    assert_eq!(k[0].status(), Some(Status::Skipped), "{:?}", k[0]);
    let why = k[0].get(cols::REASON).unwrap_or("");
    assert!(
        why.contains("maxStorageBufferBindingSize") && why.contains("k-buffer entries"),
        "{why}"
    );
}
