//! Issue 41 goals 5 and 6 on lavapipe: the compute A-buffer within WebGPU's default limits
//! (packed bindings, its fragments split over several, both captures, lists over the workgroup
//! ring), the compatibility-mode profile (compute captures run, fragment-storage methods over its
//! limit are skipped naming it), and the linked list's node pool split over bindings; each
//! against the f64 reference.

use bench_core::gpu::{Gpu, GpuOptions};
use bench_core::gpu_scene::GpuScene;
use bench_core::limits::Profile;
use bench_core::measure::TimingPlan;
use mfx_multifragment::method::measure;
use mfx_multifragment::methods;
use mfx_multifragment::testing::{count_mismatch, max_err, params, point, scene};
use mfx_reference::rasterize;
use scenarios::ParamValue::{Int, Str};
use scenarios::{Params, Scene};
use schema::{cols, Status};

fn open(limits: Profile) -> Gpu {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", "/tmp");
    }
    Gpu::new(&GpuOptions {
        limits,
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter (scripts/setup.sh): {e}"))
}

/// Composite of up to ~40 layers in f32 vs f64 (the methods' own tests' bound at 16 layers,
/// with room for 40).
const IMAGE_TOL: f64 = 1e-4;

/// One run's split column and image, or why it could not be prepared (an unsupported point, a
/// measuring error).
type RunResult = Result<(Option<String>, Vec<[f32; 4]>), Box<dyn std::error::Error>>;

/// Runs `method` at `p` on `s` (w × h) on `gpu` once; Ok: (split column, image), after checking
/// counts and image against the f64 reference; Err: why it could not be prepared.
fn exact_run(gpu: &Gpu, method: &str, s: &Scene, (w, h): (u32, u32), p: &Params) -> RunResult {
    let m = methods::by_name(method).unwrap();
    let pt = point(m.as_ref(), p);
    mfx_multifragment::method::supports(m.as_ref(), gpu, &pt)?;
    let gs = GpuScene::upload(gpu, s, w, h);
    let mut r = measure(gpu, &gs, m.as_ref(), &pt, &TimingPlan::once())?;
    let mut cap = r.prepared.readback(gpu, &gs).unwrap();
    let lists = rasterize(s, w, h);
    r.prepared.judge(&mut cap, &lists);
    let what = format!("{method} {} {p:?}", s.label());
    assert!(cap.flag.is_empty(), "{what}: {} {}", cap.flag, cap.notes);
    let (bad, first) = count_mismatch(&cap, &lists, u32::MAX);
    assert_eq!(bad, 0, "{what}: counts differ first at {first:?}");
    let (e, at) = max_err(&cap, &lists);
    assert!(
        e <= IMAGE_TOL,
        "{what}: error {e} at pixel {at}: {}",
        cap.notes
    );
    Ok((r.prepared.split(), cap.image.unwrap()))
}

/// The largest storage binding (a test-only limit: the device allows more) at which `run`
/// splits over more than one binding and succeeds, trying smaller limits in turn; its split.
fn split_somewhere(
    what: &str,
    gpu: &mut Gpu,
    run: impl Fn(&Gpu) -> RunResult,
) -> (String, Vec<[f32; 4]>) {
    let full = gpu.limits.max_storage_buffer_binding_size;
    let mut tried = Vec::new();
    for kib in [512u64, 256, 128, 96, 64, 48, 32] {
        gpu.limits.max_storage_buffer_binding_size = kib << 10;
        let r = run(gpu);
        gpu.limits.max_storage_buffer_binding_size = full;
        match r {
            Ok((Some(s), img)) if s.contains("bindings:") => return (s, img),
            other => tried.push(format!("{kib} KiB: {:?}", other.map(|o| o.0))),
        }
    }
    panic!("{what}: no binding limit split the buffer: {tried:?}");
}

fn abuffer(capture: &str, small_max: i64) -> Params {
    params(&[
        ("capture", Str(capture.into())),
        ("small_max", Int(small_max)),
    ])
}

#[test]
fn the_compute_abuffer_under_webgpu_limits_packs_splits_and_equals_the_reference() {
    let mut web = open(Profile::WebGpu);
    assert_eq!(web.limits.max_storage_buffers_per_shader_stage, 8);
    // 40 layers at the centre: lists over both workgroup rings (32 and, binned, 16), under the
    // resolve's SORT_MAX. Shells: small and big triangles, the big ones binned.
    let quads = scene("quads", &[("depth_complexity", Int(40))]);
    let shells = scene("shells", &[("count", Int(8)), ("segments", Int(24))]);
    let adapter = open(Profile::Adapter);
    // Every quad binned (small_max 1): a few hundred 8 B entries, no slot array to split.
    for (s, (w, h), small, capture, splits) in [
        (&quads, (48, 40), 256, "pixels", true),
        (&quads, (48, 40), 1, "tiles", false),
        (&shells, (96, 80), 256, "tiles", true),
        (&shells, (96, 80), 256, "pixels", true),
    ] {
        let p = abuffer(capture, small);
        let what = format!("{} {capture}", s.label());
        // Unsplit under WebGPU's own limits: packed, as the device allows only 8.
        let (split, img) = exact_run(&web, "compute_abuffer", s, (w, h), &p).unwrap();
        assert_eq!(split.as_deref(), Some("packed"), "{what}");
        // The same fragments in the same order as the native bindings of the adapter's limits.
        let (native, native_img) = exact_run(&adapter, "compute_abuffer", s, (w, h), &p).unwrap();
        assert_eq!(native, None, "{what}: native bindings where 10 are allowed");
        assert_eq!(
            img, native_img,
            "{what}: packing changes where buffers live only"
        );
        // The fragments over several bindings of a smaller (test-only) limit.
        if splits {
            let (split, img) = split_somewhere(&what, &mut web, |g| {
                exact_run(g, "compute_abuffer", s, (w, h), &p)
            });
            assert!(split.starts_with("packed,bindings:"), "{what}: {split}");
            assert_eq!(img, native_img, "{what} split {split}");
        }
    }
}

#[test]
fn bindings_packed_runs_on_any_adapter_and_equals_native() {
    let g = open(Profile::Adapter);
    let s = scene("grass", &[("blades", Int(300))]);
    for capture in ["pixels", "tiles"] {
        let mut p = abuffer(capture, 128);
        let (_, native) = exact_run(&g, "compute_abuffer", &s, (48, 40), &p).unwrap();
        p.0.insert("bindings".into(), Str("packed".into()));
        let (split, packed) = exact_run(&g, "compute_abuffer", &s, (48, 40), &p).unwrap();
        assert_eq!(split.as_deref(), Some("packed"));
        assert_eq!(packed, native, "{capture}");
    }
}

fn rows(gpu: &Gpu, text: &str) -> Vec<bench_core::record::Row> {
    bench_core::runner::run_suite(gpu, mfx_multifragment::STUDIES, text, "test")
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn compatibility_mode_runs_the_compute_captures_and_skips_fragment_storage_over_its_limit() {
    let compat = open(Profile::WebGpuCompat);
    assert_eq!(compat.limits.max_compute_invocations_per_workgroup, 128);
    let text = r#"
        resolutions = [[48, 40]]
        [timing]
        min_samples = 1
        max_samples = 1
        warmup_frames = 0
        [[study]]
        kind = "methods"
        methods = ["compute_abuffer", "linked_list", "wboit"]
        method_axes = { compute_abuffer = { capture = ["pixels", "tiles"] }, linked_list = { node = ["full"] } }
        [[study.scenes]]
        generator = "quads"
        depth_complexity = 6
    "#;
    let r = rows(&compat, text);
    let of = |m: &'static str| r.iter().filter(move |x| x.get(cols::METHOD) == Some(m));
    for row in of("compute_abuffer") {
        assert_eq!(
            row.get(cols::STATUS),
            Some(Status::Ok.name()),
            "{:?}",
            row.get(cols::REASON)
        );
        assert_eq!(
            row.get(cols::EXACT),
            Some("true"),
            "{:?}",
            row.get(cols::FLAG)
        );
        assert_eq!(row.get(cols::LIMITS), Some("webgpu-compat"));
    }
    assert_eq!(of("compute_abuffer").count(), 2);
    // Full nodes bind 7 storage buffers to the fragment stage (compact ones 12 in all, over
    // the 8 of every stage); wgpu does not count per stage, mfx does.
    let ll = of("linked_list").next().unwrap();
    assert_eq!(ll.get(cols::STATUS), Some(Status::Skipped.name()));
    let why = ll.get(cols::REASON).unwrap();
    assert!(
        why.contains("maxStorageBuffersInFragmentStage") && why.contains("compatibility"),
        "{why}"
    );
    // A method without storage buffers runs.
    let wb = of("wboit").next().unwrap();
    assert_eq!(
        wb.get(cols::STATUS),
        Some(Status::Ok.name()),
        "{:?}",
        wb.get(cols::REASON)
    );
}

#[test]
fn a_split_linked_list_pool_equals_the_reference_and_the_unsplit_pool() {
    // A fixed pool (16 nodes a pixel) and a counted one (the true fragments), compact and full
    // nodes: over a test-only binding limit their nodes take several bindings (at 2048² on the
    // H200 a 2 GiB fixed pool was over the 2 GiB − 4 limit: 5 rows skipped).
    let mut g = open(Profile::Adapter);
    let s = scene("quads", &[("depth_complexity", Int(12))]);
    for pool in ["fixed", "counted", "pixel"] {
        for node in ["compact", "full"] {
            let p = params(&[
                ("pool", Str(pool.into())),
                ("node", Str(node.into())),
                ("layers", Int(16)),
            ]);
            let (unsplit, img) = exact_run(&g, "linked_list", &s, (48, 40), &p).unwrap();
            assert_eq!(unsplit, None);
            let what = format!("{pool} {node}");
            let (split, split_img) = split_somewhere(&what, &mut g, |g| {
                exact_run(g, "linked_list", &s, (48, 40), &p)
            });
            assert_eq!(split_img, img, "{pool} {node} {split}: split image differs");
        }
    }
}
