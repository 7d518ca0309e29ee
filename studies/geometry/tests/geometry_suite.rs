//! The geometry study through the real runner on lavapipe: suites run end to end, bad axes are
//! refused before any GPU work, and missing meshes become failed rows when a sweep meets them.

use bench_core::record::{cols, Col, Row, Status, VecSink};
use bench_core::testing;
use mfx_geometry::STUDIES;
use scenarios::Suite;

/// A tiny geometry suite through the real runner on lavapipe: one row per point, declared
/// columns only, impossible points skipped with a reason, and the measured vertex-shader
/// invocations consistent with the draw (≤ 3 per triangle, exactly 3 when non-indexed).
#[test]
fn geometry_suite_runs_through_the_runner_mesh_800_at_32px() {
    let text = r#"
name = "geometry-test"
resolutions = [[32, 32]]
[timing]
min_samples = 2
max_samples = 2
warmup_frames = 1
[[study]]
kind = "geometry"
small_viewport_divisor = 4
axes = { indexed = [true, false], primitive = ["list", "strip"], mesh_order = ["original", "shuffled"] }
[[study.scenes]]
generator = "mesh"
triangles = 800
"#;
    let suite = Suite::parse(text, "test").unwrap();
    let gpu = testing::gpu();
    let groups = bench_core::runner::expand(STUDIES, &suite, gpu.facts.is_software).unwrap();
    let mut sink = VecSink(Vec::new());
    let opts = bench_core::runner::RunOptions {
        run_id: "t".into(),
        git_rev: "t".into(),
        shard: (0, 1),
        save_images: None,
        ..Default::default()
    };
    let n = bench_core::runner::run(gpu, STUDIES, &suite, &groups, &opts, &mut sink)
        .unwrap()
        .written;
    assert_eq!(n, bench_core::runner::rows_in(&groups));
    let rows: Vec<&Row> = sink
        .0
        .iter()
        .filter(|r| {
            r.get(cols::STUDY) == Some("geometry") && r.get(cols::METHOD) == Some("geometry")
        })
        .collect();
    assert_eq!(rows.len(), 8);
    for r in &rows {
        let indexed = r.get(cols::INDEXED) == Some("true");
        let strip = r.get(cols::PRIMITIVE) == Some("strip");
        if !indexed && strip {
            assert_eq!(r.status(), Some(Status::Skipped));
            assert!(r.get(cols::REASON).unwrap().contains("indexed"));
            continue;
        }
        assert_eq!(r.status(), Some(Status::Ok), "{:?}", r.cells());
        let tris: f64 = r.get(cols::TRIANGLES).unwrap().parse().unwrap();
        assert!(r.get(cols::ACMR).is_some());
        if gpu.has(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
            let vs: f64 = r.get(cols::VS_INVOCATIONS).unwrap().parse().unwrap();
            if indexed {
                assert!(
                    vs <= 3.0 * tris && vs > 0.0,
                    "{vs} invocations for {tris} triangles"
                );
            } else {
                assert_eq!(
                    vs,
                    3.0 * tris,
                    "non-indexed draws run the vertex shader per corner"
                );
            }
        }
        if gpu.has(wgpu::Features::TIMESTAMP_QUERY) {
            assert!(
                r.get(cols::TRIANGLES_PER_S).is_some() && r.get(cols::RASTER_BOUND_RATIO).is_some()
            );
        }
    }
}

/// Bad suite values are errors naming the axis before any GPU work.
#[test]
fn bad_axes_are_errors_naming_the_axis() {
    let parse = |axes: &str| {
        let text = format!(
            "name = \"x\"\n[[study]]\nkind = \"geometry\"\naxes = {{ {axes} }}\n[[study.scenes]]\ngenerator = \"mesh\"\n"
        );
        let suite = Suite::parse(&text, "t").unwrap();
        let problems = bench_core::check::check_suite(STUDIES, &suite);
        if !problems.is_empty() {
            return Err(scenarios::problem::report(&problems));
        }
        bench_core::study::points(&mfx_geometry::GeometryStudy, &suite.studies[0])
            .map(|p| p.len())
            .map_err(|e| e.join("; "))
    };
    assert_eq!(parse("index_format = [\"uint16\", \"uint32\"]"), Ok(2));
    assert!(parse("vertex_format = [\"snorm8x4\"]")
        .unwrap_err()
        .contains("vertex_format"));
    assert!(parse("batch_sise = [4]")
        .unwrap_err()
        .contains("batch_sise"));
    assert!(parse("extra_attributes = [9]")
        .unwrap_err()
        .contains("extra_attributes"));
}

/// The CI suite `geometry-ci` (every axis of the full suite, at lavapipe size) through the real
/// runner: one row per point, every row ok (none of its points is impossible on lavapipe), with
/// the measured quantities its figures need, and the invariants a row can be checked against:
/// batches = ⌈drawn / batch_size⌉ for 32-bit lists, the vertex-shader count of non-indexed draws
/// exactly 3 per drawn triangle, 16-bit rows never above 65,536 vertices a batch.
#[test]
fn geometry_ci_suite_runs_every_axis_on_lavapipe() {
    let suite = Suite::load("geometry-ci").unwrap();
    let gpu = testing::gpu();
    let groups = bench_core::runner::expand(STUDIES, &suite, gpu.facts.is_software).unwrap();
    let mut sink = VecSink(Vec::new());
    let opts = bench_core::runner::RunOptions {
        run_id: "t".into(),
        git_rev: "t".into(),
        shard: (0, 1),
        save_images: None,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let n = bench_core::runner::run(gpu, STUDIES, &suite, &groups, &opts, &mut sink)
        .unwrap()
        .written;
    eprintln!(
        "geometry-ci: {n} rows in {:.1} s",
        t0.elapsed().as_secs_f64()
    );
    assert_eq!(n, bench_core::runner::rows_in(&groups));
    let rows: Vec<&Row> = sink
        .0
        .iter()
        .filter(|r| r.get(cols::METHOD) == Some("geometry"))
        .collect();
    assert!(rows.len() >= 90, "only {} geometry rows", rows.len());
    let num = |r: &Row, c: Col| -> f64 {
        r.get(c)
            .unwrap_or_else(|| panic!("{c} missing: {:?}", r.cells()))
            .parse()
            .unwrap()
    };
    for r in &rows {
        assert_eq!(r.status(), Some(Status::Ok), "{:?}", r.cells());
        let drawn = match num(r, cols::DRAW_TRIANGLES) {
            0.0 => num(r, cols::TRIANGLES),
            d => d,
        };
        let batches = num(r, cols::BATCHES);
        let batch_size = num(r, cols::BATCH_SIZE);
        let list32 =
            r.get(cols::INDEX_FORMAT) == Some("uint32") && r.get(cols::PRIMITIVE) == Some("list");
        if list32 {
            let want = if batch_size == 0.0 {
                1.0
            } else {
                (drawn / batch_size).ceil()
            };
            assert_eq!(batches, want, "{:?}", r.cells());
        }
        if r.get(cols::INDEX_FORMAT) == Some("uint16") {
            assert!(num(r, cols::BATCH_VERTICES) / batches <= 65_536.0);
        }
        assert!(num(r, cols::VERTEX_STRIDE_BYTES) >= 6.0);
        if gpu.has(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
            let vs = num(r, cols::VS_INVOCATIONS);
            if r.get(cols::INDEXED) == Some("false") {
                assert_eq!(vs, 3.0 * drawn, "{:?}", r.cells());
            } else {
                assert!(vs > 0.0 && vs <= 3.0 * drawn, "{:?}", r.cells());
            }
        }
        if gpu.has(wgpu::Features::TIMESTAMP_QUERY) {
            assert!(num(r, cols::TRIANGLES_PER_S) > 0.0);
        }
    }
    // Every axis value of the full suite's sub-studies appears in some row.
    for (axis, value) in [
        ("mesh_order", "vcache_vfetch"),
        ("primitive", "strip"),
        ("index_format", "uint16"),
        ("indexed", "false"),
        ("layout", "interleaved"),
        ("vertex_format", "snorm16x4"),
        ("normal_format", "unorm10_10_10_2"),
        ("color_format", "snorm8x4"),
        ("texcoord_format", "unorm16x2"),
    ] {
        assert!(
            rows.iter()
                .any(|r| r.get(schema::by_name(axis).unwrap()) == Some(value)),
            "no row with {axis} = {value}"
        );
    }
}

/// The H100-size suites parse and expand (every axis value valid) without a GPU, and their
/// point counts stay those the run-time estimate in the suite descriptions was made for.
#[test]
fn full_size_geometry_suites_expand() {
    for (name, want) in [("geometry", 175), ("geometry-ci", 100)] {
        let suite = Suite::load(name).unwrap();
        let groups = bench_core::runner::expand(STUDIES, &suite, false).unwrap();
        let points: usize = groups.iter().map(|g| g.points.len()).sum();
        assert_eq!(points, want, "{name}: points");
    }
    let models = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/suites/geometry-models.toml");
    let suite = Suite::load(models.to_str().unwrap()).unwrap();
    assert!(!bench_core::runner::expand(STUDIES, &suite, false)
        .unwrap()
        .is_empty());
}

/// geometry-models without its meshes (the test's working directory has no models/): every row
/// of every group names the missing file: skipped with the command that fetches it where a script
/// of this repository does (ogre, cow: optional data), failed where none does (the committed
/// bunny, absent from this working directory); none lost, nothing panics.
#[test]
fn geometry_models_without_the_meshes_skips_rows_naming_the_file() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/suites/geometry-models.toml");
    let suite = Suite::load(path.to_str().unwrap()).unwrap();
    let cwd = std::env::current_dir().unwrap();
    assert!(
        !cwd.join("models/stanford-bunny.obj").exists(),
        "the test needs a working directory without models/"
    );
    let gpu = testing::gpu();
    let groups = bench_core::runner::expand(STUDIES, &suite, gpu.facts.is_software).unwrap();
    let mut sink = VecSink(Vec::new());
    let opts = bench_core::runner::RunOptions {
        run_id: "t".into(),
        git_rev: "t".into(),
        shard: (0, 1),
        save_images: None,
        ..Default::default()
    };
    let n = bench_core::runner::run(gpu, STUDIES, &suite, &groups, &opts, &mut sink)
        .unwrap()
        .written;
    assert_eq!(n, bench_core::runner::rows_in(&groups));
    assert_eq!(sink.0.len(), n);
    for r in &sink.0 {
        let why = r.get(cols::REASON).unwrap();
        let label = r.get(cols::SCENE_LABEL).unwrap();
        let fetchable = scenarios::obj::FETCHABLE
            .iter()
            .any(|(prefix, _)| label.contains(prefix));
        let (status, hint) = if fetchable {
            (Status::Skipped, "fetch it with `bash scripts/")
        } else {
            (Status::Failed, "file not found")
        };
        assert_eq!(r.status(), Some(status), "{:?}", r.cells());
        assert!(
            why.contains("not found") && why.contains("models/") && why.contains(hint),
            "{why}"
        );
    }
}
