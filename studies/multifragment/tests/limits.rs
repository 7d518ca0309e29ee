//! Limits profiles and splitting (`--limits`, bench-core/src/limits.rs): a k-buffer whose entries
//! are over the largest storage binding splits them over several bindings and still matches the
//! f64 reference as the unsplit one does; a browser's limits give `skipped` rows naming the limit.

use bench_core::gpu::{Gpu, GpuOptions};
use bench_core::gpu_scene::GpuScene;
use bench_core::limits::Profile;
use bench_core::measure::TimingPlan;
use bench_core::record::Row;
use mfx_multifragment::method::measure;
use mfx_multifragment::methods;
use mfx_multifragment::testing::{count_mismatch, max_err, params, point, scene};
use mfx_multifragment::STUDIES;
use mfx_reference::rasterize;
use scenarios::ParamValue::Int;
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

#[test]
fn a_split_k_buffer_matches_the_reference_exactly_as_the_unsplit_one_does() {
    // 40×40 pixels × 8 slots × 16 B of colour entries = 204.8 kB; a test-only binding limit of
    // 64 KiB (the device itself allows more) splits them over 4 bindings.
    let unsplit = open(Profile::Adapter);
    let mut small = open(Profile::Adapter);
    small.limits.max_storage_buffer_binding_size = 64 << 10;
    let s = scene("shells", &[("count", Int(4)), ("segments", Int(12))]);
    let lists = rasterize(&s, 40, 40);
    for name in ["kbuffer_atomic", "kbuffer_rmw"] {
        let m = methods::by_name(name).unwrap();
        let p = point(m.as_ref(), &params(&[("layers", Int(8))]));
        let mut images = Vec::new();
        for (gpu, want) in [(&unsplit, None), (&small, Some("bindings:4"))] {
            let gs = GpuScene::upload(gpu, &s, 40, 40);
            let mut r = measure(gpu, &gs, m.as_ref(), &p, &TimingPlan::once())
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(r.prepared.split().as_deref(), want, "{name}");
            let mut cap = r.prepared.readback(gpu, &gs).unwrap();
            r.prepared.judge(&mut cap, &lists);
            // The same bound as the k-buffers' own tests: k layers composited in f32.
            let (e, at) = max_err(&cap, &lists);
            assert!(e <= 1e-5, "{name} split {want:?}: error {e} at pixel {at}");
            let (bad, first) = count_mismatch(&cap, &lists, 8);
            assert_eq!(bad, 0, "{name} split {want:?}: counts differ at {first:?}");
            images.push(cap.image.unwrap());
        }
        // Same fragments, same order of compositing: the split changes where entries live only.
        assert_eq!(
            images[0], images[1],
            "{name}: split image differs from unsplit"
        );
    }
}

fn rows(gpu: &Gpu, text: &str) -> Vec<Row> {
    bench_core::runner::run_suite(gpu, STUDIES, text, "test").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_split_mlab_matches_the_unsplit_one_and_says_how_it_was_split() {
    // 40×40 pixels × 8 layers × 20 B = 256 kB of MLAB layers; a test-only binding limit of
    // 64 KiB splits them over 4 bindings (issue 34: MLAB at 4K needs 2.65 GB, over 2 GiB).
    let unsplit = open(Profile::Adapter);
    let mut small = open(Profile::Adapter);
    small.limits.max_storage_buffer_binding_size = 64 << 10;
    // Depth complexity ≤ k: MLAB keeps every fragment, so both builds equal the reference.
    let s = scene("quads", &[("depth_complexity", Int(6))]);
    let lists = rasterize(&s, 40, 40);
    let m = methods::by_name("mlab").unwrap();
    let p = point(m.as_ref(), &params(&[("layers", Int(8))]));
    let mut images = Vec::new();
    for (gpu, want) in [(&unsplit, None), (&small, Some("bindings:4"))] {
        let gs = GpuScene::upload(gpu, &s, 40, 40);
        let mut r = measure(gpu, &gs, m.as_ref(), &p, &TimingPlan::once())
            .unwrap_or_else(|e| panic!("mlab split {want:?}: {e}"));
        assert_eq!(r.prepared.split().as_deref(), want);
        let cap = r.prepared.readback(gpu, &gs).unwrap();
        // ≤ 6 layers composited in f32 (the method's own tests' bound).
        let (e, at) = max_err(&cap, &lists);
        assert!(e <= 1e-5, "mlab split {want:?}: error {e} at pixel {at}");
        images.push(cap.image.unwrap());
    }
    assert_eq!(images[0], images[1], "split image differs from unsplit");
}

#[test]
fn dual_peeling_names_the_colour_bytes_limit_before_any_gpu_work() {
    // 8 + 16 + 16 B per sample in one pass, over WebGPU's 32: once a raw validation error at
    // prepare, now a reason from `supports`.
    let web = open(Profile::WebGpu);
    let m = methods::by_name("dual_peel").unwrap();
    let p = point(m.as_ref(), &params(&[]));
    let why = mfx_multifragment::method::supports(m.as_ref(), &web, &p).unwrap_err();
    assert!(
        why.contains("40 bytes per sample") && why.contains("WebGPU") && why.contains("32"),
        "{why}"
    );
    assert!(mfx_multifragment::method::supports(m.as_ref(), &open(Profile::Adapter), &p).is_ok());
}

#[test]
fn webgpu_limits_split_or_skip_naming_the_limit_and_downlevel_skips_storage_methods() {
    // 528×256 pixels × 64 slots × 16 B = 138 MB of k-buffer entries: over WebGPU's 128 MiB
    // storage binding, so split over 2; WBOIT needs no storage buffer that large.
    let text = r#"
        resolutions = [[528, 256]]
        [timing]
        min_samples = 1
        max_samples = 1
        warmup_frames = 0
        [[study]]
        kind = "methods"
        methods = ["kbuffer_atomic", "wboit"]
        axes = { layers = [64] }
        [[study.scenes]]
        generator = "quads"
        depth_complexity = 2
    "#;
    let web = open(Profile::WebGpu);
    assert_eq!(web.limits.max_storage_buffer_binding_size, 128 << 20);
    let r = rows(&web, text);
    let get = |m: &str| r.iter().find(|x| x.get(cols::METHOD) == Some(m)).unwrap();
    let k = get("kbuffer_atomic");
    assert_eq!(
        k.get(cols::STATUS),
        Some(Status::Ok.name()),
        "{:?}",
        k.get(cols::REASON)
    );
    assert_eq!(k.get(cols::SPLIT), Some("bindings:2"));
    assert_eq!(k.get(cols::EXACT), Some("true"), "{:?}", k.get(cols::FLAG));
    assert_eq!(k.get(cols::LIMITS), Some("webgpu"));
    assert_eq!(get("wboit").get(cols::STATUS), Some(Status::Ok.name()));
    assert_eq!(get("wboit").get(cols::SPLIT), None);

    let down = open(Profile::Downlevel);
    let r = rows(&down, &text.replace("[[528, 256]]", "[[16, 16]]"));
    let get = |m: &str| r.iter().find(|x| x.get(cols::METHOD) == Some(m)).unwrap();
    let k = get("kbuffer_atomic");
    assert_eq!(
        k.get(cols::STATUS),
        Some(Status::Skipped.name()),
        "{:?}",
        k.get(cols::REASON)
    );
    let why = k.get(cols::REASON).unwrap();
    assert!(why.contains("WebGL2") && why.contains("limit"), "{why}");
    assert_eq!(k.get(cols::LIMITS), Some("downlevel"));
}
