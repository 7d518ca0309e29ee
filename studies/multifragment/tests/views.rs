//! The `views` study on lavapipe (issue 42's done-when): an exact method neither flickers nor
//! pops beyond its f32 bound over an orbit; a k-buffer keeping fewer layers than the scene has,
//! with a blended tail, pops exactly where two surfaces cross in depth as the camera moves (the
//! test says at which views and pixels); a racy method's at-rest difference is reported, and the
//! at-rest measure counts exactly the pixels a race reordered; a camera path is checked like
//! every axis, before any GPU work.

use bench_core::check;
use bench_core::gpu_scene::GpuScene;
use bench_core::record::{Row, Status};
use bench_core::runner;
use bench_core::study::{self, GroupCtx};
use glam::{DVec3, Vec3};
use mfx_multifragment::effects::EffectConfig;
use mfx_multifragment::method::Expected;
use mfx_multifragment::testing;
use mfx_multifragment::STUDIES;
use mfx_reference::temporal::{self, Frame, POP_EPSILON};
use mfx_reference::{rasterize, FragmentLists};
use scenarios::path::{CameraPath, PathKind};
use scenarios::{Camera, Mesh, Params, Scene, SceneSpec, Suite};
use schema::cols;

fn run_suite(text: &str) -> Vec<Row> {
    runner::run_suite(testing::gpu(), STUDIES, text, "views-test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
}

fn study_rows(rows: &[Row]) -> Vec<&Row> {
    rows.iter()
        .filter(|r| {
            r.get(cols::STUDY) == Some("views")
                && !r.get(cols::METHOD).unwrap().starts_with("floor_")
        })
        .collect()
}

fn series(row: &Row, key: &str) -> Vec<Option<f64>> {
    let v: serde_json::Value = serde_json::from_str(row.get(cols::PATH_SERIES).unwrap()).unwrap();
    v[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64())
        .collect()
}

#[test]
fn exact_methods_neither_flicker_nor_pop_over_an_orbit_of_shells_at_64px() {
    // Two nested spheres (4 layers) seen from 6 views 20° apart at 40° elevation.
    let rows = run_suite(
        r#"
name = "views-exact"
resolutions = [[64, 64]]
[timing]
min_samples = 1
max_samples = 1
warmup_frames = 0
[[study]]
kind = "views"
methods = ["depth_peel", "compute_abuffer"]
[[study.scenes]]
generator = "shells"
count = 2
segments = 16
camera_path = "orbit"
path_views = 6
orbit_step = 20
orbit_elevation = 40
"#,
    );
    let rows = study_rows(&rows);
    assert_eq!(rows.len(), 2);
    for r in rows {
        let m = r.get(cols::METHOD).unwrap();
        assert_eq!(
            r.status(),
            Some(Status::Ok),
            "{m}: {:?}",
            r.get(cols::REASON)
        );
        assert_eq!(r.get(cols::PATH_VIEWS), Some("6"));
        assert_eq!(r.get_bool(cols::EXACT), Some(true), "{m}: every view exact");
        // Within the f32 bound at every pixel of every step, so no pixel pops.
        assert_eq!(r.get(cols::FLICKER_BEYOND_BOUND), Some("0"), "{m}");
        let (fl, bound) = (
            r.get_f(cols::FLICKER_MEAN).unwrap(),
            r.get_f(cols::FLICKER_BOUND_MEAN).unwrap(),
        );
        assert!(fl <= bound, "{m}: flicker {fl} over its bound {bound}");
        assert_eq!(r.get_f(cols::POPPING_MAX), Some(0.0), "{m}");
        // Six views of time and error; five steps, none at view 0.
        assert_eq!(series(r, "gpu_ms").len(), 6);
        let fl = series(r, "flicker");
        assert!(
            fl[0].is_none() && fl[1..].iter().all(|x| x.is_some()),
            "{fl:?}"
        );
    }
}

/// Three screen-filling quads: A and B tilted opposite ways about the vertical line x = 0.3,
/// z = 0 (they cross there in depth), C behind both. Every pixel holds three fragments at every
/// view of the fly-through, so what changes from view to view is only which of A and B is
/// nearer, where the crossing line moves across the screen.
fn crossing_quads() -> Scene {
    let mut mesh = Mesh::default();
    let quad = |x0: f32, x1: f32, z: &dyn Fn(f32) -> f32| {
        [
            Vec3::new(x0, -10.0, z(x0)),
            Vec3::new(x1, -10.0, z(x1)),
            Vec3::new(x1, 10.0, z(x1)),
            Vec3::new(x0, 10.0, z(x0)),
        ]
    };
    mesh.push_quad(
        quad(-4.0, 4.0, &|x| 0.25 * (x - 0.3)),
        [0.9, 0.15, 0.1, 0.5],
        0,
    );
    mesh.push_quad(
        quad(-4.0, 4.0, &|x| -0.25 * (x - 0.3)),
        [0.1, 0.85, 0.2, 0.5],
        1,
    );
    mesh.push_quad(quad(-4.0, 4.0, &|_| -1.5), [0.15, 0.2, 0.9, 0.5], 2);
    let camera = Camera::look_at(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO, 45.0, 0.1, 20.0);
    let mut scene = Scene::new(SceneSpec::new("crossing", Params::new()), mesh, camera);
    let path = CameraPath {
        kind: PathKind::Fly { depth: 0.5 },
        views: 5,
    };
    scene.views = path.cameras(&scene).unwrap();
    scene.camera = scene.views[0].clone();
    scene.path = Some(path.name());
    scene
}

/// Runs a views study table (its scene replaced by `scene`, whose path it renders) on lavapipe.
fn run_on(scene: &Scene, table: &str, w: u32) -> Vec<Row> {
    let text = format!(
        "name = \"views-scene\"\nresolutions = [[{w}, {w}]]\n[timing]\nmin_samples = 1\nmax_samples = 1\nwarmup_frames = 0\n[[study]]\nkind = \"views\"\n{table}\n[[study.scenes]]\ngenerator = \"quads\"\ncamera_path = \"at_rest\"\n"
    );
    let suite = Suite::parse(&text, "views-scene.toml").unwrap();
    assert!(
        check::check_suite(STUDIES, &suite).is_empty(),
        "{:?}",
        check::check_suite(STUDIES, &suite)
    );
    let gpu = testing::gpu();
    let groups = runner::expand(STUDIES, &suite, true).unwrap();
    let group = &groups[0];
    let gscene = GpuScene::upload(gpu, scene, w, w);
    let plan = runner::timing_plan(&suite, true).unwrap();
    let ctx = GroupCtx::new(gpu, &suite, &suite.studies[0], group, scene, &gscene, plan);
    let mut rows: Vec<Option<Row>> = vec![None; group.points.len()];
    let study = study::by_kind(STUDIES, study::StudyKind::Views).unwrap();
    study
        .run_group(&ctx, &mut |i, row| {
            rows[i] = Some(row);
            Ok(())
        })
        .unwrap();
    rows.into_iter()
        .map(|r| r.expect("every point emitted"))
        .collect()
}

/// The nearest fragment's object at every pixel.
fn nearest(lists: &FragmentLists) -> Vec<Option<u32>> {
    (0..lists.pixels())
        .map(|p| lists.pixel(p).first().map(|f| f.object_id))
        .collect()
}

#[test]
fn a_one_layer_kbuffer_with_a_tail_pops_where_two_surfaces_cross_in_depth_at_48px() {
    let scene = crossing_quads();
    let w = 48;
    let rows = run_on(
        &scene,
        "methods = [\"kbuffer_atomic\"]\naxes = { layers = [1, 4], tail = [\"blend\"] }",
        w,
    );
    let (one, four) = (&rows[0], &rows[1]);
    assert_eq!(one.get(cols::LAYERS), Some("1"));
    for r in [one, four] {
        // The study sets a status only on a row that failed or was skipped (the runner marks
        // the rest ok).
        assert_eq!(r.status(), None, "{:?}", r.get(cols::REASON));
    }
    // Where A and B swap places as nearest between consecutive views: a vertical band that the
    // crossing line sweeps, every pixel still three fragments deep.
    let mut view_scene = scene.clone();
    let lists: Vec<FragmentLists> = scene
        .views
        .iter()
        .map(|c| {
            view_scene.camera = c.clone();
            rasterize(&view_scene, w, w)
        })
        .collect();
    assert!(lists
        .iter()
        .all(|l| l.depth_complexity().iter().all(|&d| d == 3)));
    let popping = series(one, "popping");
    let px = (w * w) as f64;
    for t in 1..lists.len() {
        let (a, b) = (nearest(&lists[t - 1]), nearest(&lists[t]));
        let swapped: Vec<usize> = (0..a.len()).filter(|&p| a[p] != b[p]).collect();
        let cols_swapped: std::collections::BTreeSet<u32> =
            swapped.iter().map(|&p| p as u32 % w).collect();
        assert!(
            !swapped.is_empty(),
            "view {t}: the crossing line did not move"
        );
        // The k-buffer keeps the nearest of A and B and averages the other with C in its tail:
        // the error jumps (beyond ε) exactly where the nearest one changed, and nowhere else.
        let share = popping[t].unwrap();
        assert!(
            (share - swapped.len() as f64 / px).abs() <= 2.0 / px,
            "view {t}: popped {:.0} pixels, the nearest surface changed at {} (columns {:?})",
            share * px,
            swapped.len(),
            cols_swapped
        );
    }
    // Keeping all three layers, nothing pops: the pops are the tail's, not the path's.
    assert_eq!(four.get_f(cols::POPPING_MAX), Some(0.0));
    assert!(one.get_f(cols::FLICKER_MEAN).unwrap() > four.get_f(cols::FLICKER_MEAN).unwrap());
}

#[test]
fn a_racy_kbuffer_at_rest_reports_how_many_pixels_change_between_repeated_frames() {
    // 16 quads over the centre, one draw: the RMW k-buffer's insertions race where fragments
    // of one pixel arrive together. Whether lavapipe races is its own business: the row must
    // say what it saw.
    let rows = run_suite(
        r#"
name = "views-rest"
resolutions = [[48, 48]]
[timing]
min_samples = 1
max_samples = 1
warmup_frames = 0
[[study]]
kind = "views"
methods = ["kbuffer_rmw", "kbuffer_atomic"]
axes = { layers = [4] }
[[study.scenes]]
generator = "quads"
depth_complexity = 16
camera_path = "at_rest"
path_views = 4
"#,
    );
    for r in study_rows(&rows) {
        let m = r.get(cols::METHOD).unwrap();
        assert_eq!(
            r.status(),
            Some(Status::Ok),
            "{m}: {:?}",
            r.get(cols::REASON)
        );
        let mean = r
            .get_f(cols::AT_REST_CHANGED_MEAN)
            .unwrap_or_else(|| panic!("{m}: not reported"));
        let max = r.get_f(cols::AT_REST_CHANGED_MAX).unwrap();
        assert!(
            (0.0..=1.0).contains(&mean) && mean <= max && max <= 1.0,
            "{m}: {mean} {max}"
        );
        let changed = series(r, "changed");
        assert_eq!(changed.len(), 4);
        let from_series = changed[1..].iter().map(|c| c.unwrap()).sum::<f64>() / 3.0;
        assert!((from_series - mean).abs() < 1e-12, "{m}");
        eprintln!(
            "{m}: at rest, {:.4} of pixels changed between repeated frames (max {max:.4})",
            mean
        );
        if m == "kbuffer_atomic" {
            // No hazard: the same frame every time.
            assert_eq!(max, 0.0, "kbuffer_atomic changed at rest");
        }
    }
}

#[test]
fn the_at_rest_measure_counts_exactly_the_pixels_a_race_reordered() {
    // A race made on purpose: frame B composites the two nearest fragments of chosen pixels
    // in the wrong order, as an RMW k-buffer whose insertions collided would.
    let scene = testing::scene(
        "quads",
        &[("depth_complexity", scenarios::ParamValue::Int(6))],
    );
    let lists = rasterize(&scene, 32, 32);
    let effect = EffectConfig::default();
    let truth = effect.reference(&scene, &lists, Expected::All);
    let a: Vec<[f32; 4]> = truth.iter().map(|p| p.map(|c| c as f32)).collect();
    let mut b = a.clone();
    let raced: Vec<usize> = (0..lists.pixels())
        .filter(|&p| lists.pixel(p).len() >= 2 && p % 7 == 0)
        .collect();
    assert!(raced.len() > 10);
    for &p in &raced {
        let f = lists.pixel(p);
        let over = |front: &[f64; 4], back: &[f64; 4]| -> [f64; 4] {
            let pm = |c: &[f64; 4]| [c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]];
            let (x, y) = (pm(front), pm(back));
            std::array::from_fn(|i| x[i] + (1.0 - x[3]) * y[i])
        };
        // The two nearest swapped, the rest behind them in order.
        let mut acc = over(&f[1].color, &f[0].color);
        for g in &f[2..] {
            let pm = [
                g.color[0] * g.color[3],
                g.color[1] * g.color[3],
                g.color[2] * g.color[3],
                g.color[3],
            ];
            acc = std::array::from_fn(|i| acc[i] + (1.0 - acc[3]) * pm[i]);
        }
        b[p] = acc.map(|c| c as f32);
    }
    let share = temporal::differing_share(&a, &b);
    assert_eq!(share, raced.len() as f64 / lists.pixels() as f64);
    // Seen as two frames of one view: every reordered pixel changed; its error jumped by the
    // swap, beyond ε where the two colours differ enough.
    let s = temporal::step(
        &Frame {
            image: &a,
            truth: &truth,
            bound: None,
        },
        &Frame {
            image: &b,
            truth: &truth,
            bound: None,
        },
        POP_EPSILON,
    );
    assert_eq!(s.changed, share);
    assert!(s.popping > 0.0 && s.popping <= share);
}

#[test]
fn a_bad_keyframe_file_is_refused_before_any_gpu_work_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let keys = dir.path().join("walk.keys");
    std::fs::write(&keys, "# t eye target\n0 0 0 4 0 0 0\n1 0 0 3 0 0\n").unwrap();
    let text = format!(
        "name = \"views-bad\"\n[[study]]\nkind = \"views\"\nmethods = [\"depth_peel\"]\n[[study.scenes]]\ngenerator = \"quads\"\ncamera_path = \"file\"\npath_file = \"{}\"\n[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\"]\n[[study.scenes]]\ngenerator = \"quads\"\ncamera_path = \"orbit\"\n",
        keys.display()
    );
    let (_, problems) = check::check_text(STUDIES, &text, "views-bad.toml");
    let lines: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
    assert_eq!(lines.len(), 2, "{lines:#?}");
    assert!(
        lines.iter().any(|l| l.contains("'path_file'")
            && l.contains(&format!("{}:3:", keys.display()))
            && l.contains("6 fields")),
        "{lines:#?}"
    );
    // A path in a study that renders one view is refused, not narrowed to its first view.
    assert!(
        lines
            .iter()
            .any(|l| l.contains("study 1 (methods)") && l.contains("'camera_path'")),
        "{lines:#?}"
    );
    // The runner refuses it the same way.
    let e = runner::run_suite(testing::gpu(), STUDIES, &text, "views-bad.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("walk.keys:3"), "{e}");
    // A views study needs a path on every scene.
    let (_, p) = check::check_text(
        STUDIES,
        "name = \"v\"\n[[study]]\nkind = \"views\"\nmethods = [\"depth_peel\"]\n[[study.scenes]]\ngenerator = \"quads\"\n",
        "v.toml",
    );
    assert!(
        p.iter().any(|x| x.message.contains("no camera_path")),
        "{p:?}"
    );
}

#[test]
fn the_views_ci_suite_runs_and_its_exact_rows_neither_flicker_nor_pop_where_tails_do() {
    // The built-in suite as CI runs it: every path kind (orbit, the glTF file's camera
    // animation, at rest) on lavapipe at 48².
    let (text, _) = Suite::read("views-ci").unwrap();
    // Tests run in the crate's folder: the committed glTF scene is the repository's.
    let glb = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/teapot-trio.glb");
    let rows = run_suite(&text.replace("models/teapot-trio.glb", glb));
    let rows = study_rows(&rows);
    assert_eq!(rows.len(), 21);
    for r in &rows {
        let m = r.get(cols::METHOD).unwrap();
        let scene = r.get(cols::SCENE_LABEL).unwrap();
        assert_eq!(
            r.status(),
            Some(Status::Ok),
            "{m} on {scene}: {:?}",
            r.get(cols::REASON)
        );
        let views: usize = r.get(cols::PATH_VIEWS).unwrap().parse().unwrap();
        assert_eq!(series(r, "rmse").len(), views, "{m} on {scene}");
        // An exact row (every view within its f32 bound) has no pixel whose unexplained
        // change exceeds the two views' bounds, so none pops.
        if r.get_bool(cols::EXACT) == Some(true) {
            assert_eq!(
                r.get(cols::FLICKER_BEYOND_BOUND),
                Some("0"),
                "{m} on {scene}"
            );
            assert_eq!(r.get_f(cols::POPPING_MAX), Some(0.0), "{m} on {scene}");
            assert_eq!(r.get(cols::POPPING_WORST_VIEW), None, "{m} on {scene}");
        }
    }
    // On the teapots' animation the compute A-buffer is exact at every view, and the k-buffer
    // keeping 2 of up to 11 layers, its tail blended, pops.
    let on_teapots = |m: &str| {
        *rows
            .iter()
            .find(|r| {
                r.get(cols::METHOD) == Some(m)
                    && r.get(cols::SCENE_LABEL).unwrap().starts_with("gltf")
            })
            .unwrap()
    };
    let exact = on_teapots("compute_abuffer");
    assert_eq!(exact.get(cols::CAMERA_PATH), Some("file"));
    assert_eq!(exact.get(cols::VIEWS_EXACT), Some("6"));
    let k = on_teapots("kbuffer_atomic");
    let pops = k.get_f(cols::POPPING_MAX).unwrap();
    assert!(
        pops > 0.0,
        "kbuffer_atomic layers=2 tail=blend did not pop on the teapots"
    );
    assert!(k.get(cols::POPPING_WORST_VIEW).is_some());
    assert!(k.get_f(cols::FLICKER_MEAN).unwrap() > exact.get_f(cols::FLICKER_MEAN).unwrap());
    // At rest the measure is reported for every row; the atomic k-buffer has no hazard, so
    // its frames repeat exactly.
    let at_rest: Vec<&&Row> = rows
        .iter()
        .filter(|r| r.get(cols::CAMERA_PATH) == Some("at_rest"))
        .collect();
    assert_eq!(at_rest.len(), 3);
    for r in at_rest {
        assert!(r.get_f(cols::AT_REST_CHANGED_MEAN).is_some());
        if r.get(cols::METHOD) == Some("kbuffer_atomic") {
            assert_eq!(r.get_f(cols::AT_REST_CHANGED_MAX), Some(0.0));
        }
        // A static path: an exact, race-free method draws the same image every frame and the
        // truth does not move, so nothing is unexplained.
        if r.get(cols::METHOD) == Some("depth_peel") {
            assert_eq!(r.get_bool(cols::EXACT), Some(true));
            assert_eq!(r.get_f(cols::FLICKER_MAX), Some(0.0));
            assert_eq!(r.get_f(cols::AT_REST_CHANGED_MAX), Some(0.0));
        }
    }
}
