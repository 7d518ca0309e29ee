//! The continuum scenes stress what they are meant to: `particles` reaches depth complexity in
//! the hundreds, `hair` stacks many thin layers, and neither has f32 depth ties where it
//! promises distinct depths (exact f64 reference rasterizer, 128²).

use mfx_reference::rasterize;
use scenarios::{Params, SceneSpec};

fn lists(generator: &str, params: Params, size: u32) -> mfx_reference::FragmentLists {
    let scene = SceneSpec::new(generator, params).build().unwrap();
    rasterize(&scene, size, size)
}

/// Mean fragments over covered pixels and the fraction of pixels covered.
fn coverage(l: &mfx_reference::FragmentLists) -> (f64, f64) {
    let dc = l.depth_complexity();
    let covered: Vec<u32> = dc.into_iter().filter(|&d| d > 0).collect();
    let mean = covered.iter().map(|&d| d as f64).sum::<f64>() / covered.len().max(1) as f64;
    (mean, covered.len() as f64 / l.pixels() as f64)
}

#[test]
fn particles_default_at_128_reaches_depth_complexity_100_without_depth_ties() {
    let l = lists("particles", Params::new(), 128);
    let (mean, covered) = coverage(&l);
    eprintln!(
        "particles 128²: max {} mean(covered) {mean:.1} covered {covered:.3} fragments {}",
        l.max_depth_complexity(),
        l.total_fragments()
    );
    assert!(
        l.max_depth_complexity() >= 100,
        "max {}",
        l.max_depth_complexity()
    );
    // Stratified depths: no two fragments of a pixel within one f32 step of window depth.
    let ties = l.depth_tie_pixels(1).iter().filter(|&&t| t).count();
    assert_eq!(ties, 0, "pixels with f32 depth ties");
}

#[test]
fn hair_default_at_128_stacks_many_layers() {
    let l = lists("hair", Params::new(), 128);
    let (mean, covered) = coverage(&l);
    eprintln!(
        "hair 128²: max {} mean(covered) {mean:.1} covered {covered:.3} fragments {}",
        l.max_depth_complexity(),
        l.total_fragments()
    );
    assert!(
        l.max_depth_complexity() >= 32,
        "max {}",
        l.max_depth_complexity()
    );
    assert!(mean >= 8.0, "mean over covered pixels {mean}");
}

use mfx_reference::metrics::{image_error, BAD_PIXEL_TOL};
use mfx_reference::oit::{self, Keep, MomentConfig, MomentKind, MomentStorage, TailMode};
use mfx_reference::FragmentLists;

fn max_abs_image(a: &[[f64; 4]], b: &[[f64; 4]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| (0..4).map(move |c| (x[c] - y[c]).abs()))
        .fold(0.0, f64::max)
}

fn f32_image(v: &[[f64; 4]]) -> Vec<[f32; 4]> {
    v.iter().map(|p| p.map(|c| c as f32)).collect()
}

/// Every twin of `mfx_reference::oit` with its name, as an image function over `lists`.
#[allow(
    clippy::type_complexity,
    reason = "a table of named image functions, read once"
)]
fn twins(
    near: f64,
    far: f64,
) -> Vec<(
    String,
    bool,
    Box<dyn Fn(&[mfx_reference::RefFragment]) -> [f64; 4] + Sync>,
)> {
    let mut v: Vec<(String, bool, Box<dyn Fn(&[_]) -> [f64; 4] + Sync>)> = Vec::new();
    v.push(("wboit".into(), true, Box::new(oit::wboit)));
    for k in [1usize, 4, 8] {
        v.push((
            format!("mlab k={k} (ideal order)"),
            true,
            Box::new(move |f| oit::mlab(f, k)),
        ));
        v.push((
            format!("adaptive k={k}"),
            true,
            Box::new(move |f| oit::adaptive(f, k)),
        ));
        v.push((
            format!("hybrid k={k}"),
            true,
            Box::new(move |f| oit::hybrid(f, k)),
        ));
        for (keep, tail) in [
            (Keep::Nearest, TailMode::Drop),
            (Keep::Nearest, TailMode::Blend),
            (Keep::First, TailMode::Blend),
        ] {
            v.push((
                format!("tail k={k} keep={} tail={}", keep.name(), tail.name()),
                true,
                Box::new(move |f| oit::tail_blend(f, k, keep, tail).rgba),
            ));
        }
    }
    for (kind, count) in [
        (MomentKind::Power, 4),
        (MomentKind::Power, 6),
        (MomentKind::Power, 8),
        (MomentKind::Trigonometric, 2),
        (MomentKind::Trigonometric, 3),
        (MomentKind::Trigonometric, 4),
    ] {
        for storage in [MomentStorage::F32, MomentStorage::Unorm16] {
            let cfg = MomentConfig::new(kind, count, storage, near, far).unwrap();
            v.push((
                format!("moments {kind:?} {count} {storage:?}"),
                true,
                Box::new(move |f| oit::moments(f, &cfg)),
            ));
        }
    }
    v
}

#[test]
fn bounded_twins_are_exact_on_quads_within_k_over_whole_images() {
    // quads(depth_complexity = 4): no pixel has more than 4 fragments, so every twin keeping 4
    // (or more) is exact; the image helper must hand each pixel's fragments over intact.
    let params = Params::new().with("depth_complexity", scenarios::ParamValue::Int(4));
    let l: FragmentLists = lists("quads", params, 48);
    assert_eq!(l.max_depth_complexity(), 4);
    let want = l.composite();
    for arrival in [true, false] {
        for (name, img) in [
            ("mlab", oit::image(&l, arrival, |f| oit::mlab(f, 4))),
            ("adaptive", oit::image(&l, arrival, |f| oit::adaptive(f, 4))),
            ("hybrid", oit::image(&l, arrival, |f| oit::hybrid(f, 4))),
            (
                "tail first",
                oit::image(&l, arrival, |f| {
                    oit::tail_blend(f, 4, Keep::First, TailMode::Drop).rgba
                }),
            ),
        ] {
            let e = max_abs_image(&img, &want);
            // Same products in the same order as the reference: rounding only.
            assert!(e < 1e-12, "{name} (arrival {arrival}): {e}");
        }
    }
    // With k = 2 and the tail dropped: the reference's own 2-nearest definition.
    let img = oit::image(&l, true, |f| {
        oit::tail_blend(f, 2, Keep::Nearest, TailMode::Drop).rgba
    });
    assert!(max_abs_image(&img, &l.composite_first(2)) < 1e-12);
}

/// Error of every twin against the reference on the continuum scenes at `size`², printed as a
/// table (the CPU preview of the continuum suite); asserts the twins' invariants.
fn continuum_table(size: u32) {
    let scenes = [
        ("particles", Params::new()),
        ("hair", Params::new()),
        ("shells", Params::new()),
        ("grass", Params::new()),
    ];
    for (g, p) in scenes {
        let scene = SceneSpec::new(g, p).build().unwrap();
        let l = rasterize(&scene, size, size);
        let want = l.composite();
        eprintln!(
            "\n{g} {size}²: max depth complexity {}",
            l.max_depth_complexity()
        );
        let (near, far) = oit::moments::depth_range(&scene);
        for (name, arrival, f) in twins(near, far) {
            let img = oit::image(&l, arrival, &f);
            let e = image_error(&want, &f32_image(&img), BAD_PIXEL_TOL);
            eprintln!(
                "  {name:42} rmse {:.5} max {:.4} bad {:.4}",
                e.rmse, e.max_abs, e.bad_pixel_frac
            );
            assert_eq!(e.non_finite, 0, "{g} {name}");
            assert!(
                img.iter().all(|p| (0.0..=1.0 + 1e-9).contains(&p[3])),
                "{g} {name}: A outside [0,1]"
            );
        }
    }
}

#[test]
fn twins_are_finite_and_report_their_error_on_the_continuum_scenes_at_64() {
    continuum_table(64);
}

/// `cargo test -p bench-core --test continuum_scenes -- --ignored --nocapture`: the same table
/// at 128² and the scenes' depth complexity at 1024² (minutes, GBs of fragments).
#[test]
#[ignore]
fn continuum_preview_at_128_and_depth_complexity_at_1024() {
    continuum_table(128);
    for g in ["particles", "hair", "shells", "grass"] {
        let l = lists(g, Params::new(), 1024);
        let (mean, covered) = coverage(&l);
        eprintln!(
            "{g} 1024²: max {} mean(covered) {mean:.1} covered {covered:.3} fragments {}",
            l.max_depth_complexity(),
            l.total_fragments()
        );
    }
}

/// WBOIT's error grows with alpha (McGuire & Bavoil's known failure at high opacity), moments'
/// far less: shells at alpha 0.05…0.95, 64².
#[test]
fn wboit_error_grows_with_alpha_on_shells() {
    let mut wb = Vec::new();
    for a in [0.05, 0.25, 0.5, 0.75, 0.95] {
        let scene = SceneSpec::new(
            "shells",
            Params::new().with("alpha", scenarios::ParamValue::Float(a)),
        )
        .build()
        .unwrap();
        let l = rasterize(&scene, 64, 64);
        let want = l.composite();
        let w = image_error(
            &want,
            &f32_image(&oit::image(&l, true, oit::wboit)),
            BAD_PIXEL_TOL,
        )
        .rmse;
        let cfg = MomentConfig::new(
            MomentKind::Power,
            6,
            MomentStorage::F32,
            scene.camera.near,
            scene.camera.far,
        )
        .unwrap();
        let m = image_error(
            &want,
            &f32_image(&oit::image(&l, true, |f| oit::moments(f, &cfg))),
            BAD_PIXEL_TOL,
        )
        .rmse;
        eprintln!("shells alpha {a}: wboit rmse {w:.5}, 6 power moments rmse {m:.5}");
        wb.push(w);
    }
    // From nearly transparent to nearly opaque layers the weighted average's error must grow.
    assert!(wb[4] > 2.0 * wb[0], "{wb:?}");
}
