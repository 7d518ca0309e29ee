//! `exact` is a fact about fragments (issue 32): on the test adapter, methods that capture
//! every fragment are exact within the f32 bound; a k-buffer that overflows is not, even when
//! its image is within `bad_pixel_tol` of the truth.

use bench_core::record::Flag;
use mfx_multifragment::effects::EffectConfig;
use mfx_multifragment::judge::{judge, Context, Judgement};
use mfx_multifragment::methods;
use mfx_multifragment::testing::{params, run, scene};
use scenarios::ParamValue::{self, Bool, Int};
use scenarios::Scene;

fn judged(method: &str, s: &Scene, w: u32, kv: &[(&str, ParamValue)]) -> Judgement {
    let m = methods::by_name(method).unwrap();
    let (cap, lists) = run(m.as_ref(), s, w, w, &params(kv));
    let effect = EffectConfig::default();
    judge(
        &cap,
        &lists,
        Context {
            scene: s,
            effect: &effect,
            exact: m.exact(),
            flip: false,
            truths: None,
        },
    )
    .unwrap()
}

#[test]
fn methods_with_every_fragment_are_exact_and_an_overflowing_k_buffer_is_not() {
    // quads(32): 32 layers everywhere the quads overlap; k = 16 overflows there.
    let quads = scene("quads", &[("depth_complexity", Int(32))]);
    for (m, kv) in [
        ("depth_peel", vec![]),
        ("linked_list", vec![]),
        ("compute_abuffer", vec![]),
        ("kbuffer_atomic", vec![("layers", Int(32))]),
    ] {
        let j = judged(m, &quads, 48, &kv);
        assert_eq!(
            j.exact,
            Some(true),
            "{m}: {} {:?} {:?}",
            j.flags,
            j.truth,
            j.notes
        );
        assert!(!j.flags.contains(Flag::ImageDiffers), "{m}: {}", j.flags);
    }
    let j = judged(
        "kbuffer_rmw",
        &quads,
        48,
        &[("layers", Int(16)), ("heuristics", Bool(false))],
    );
    assert!(j.overflow_rate > 0.0, "{j:?}");
    assert_eq!(j.exact, Some(false), "{}", j.flags);
}

#[test]
fn the_compute_abuffer_on_a_deep_scene_is_exact_not_image_differs() {
    // Issue 32: on every ≥ 1M-triangle H200 scene it was image_differs with identical fragment
    // sets; the bound (f32 arithmetic over the pixel's layers, fragments at the method's depth
    // precision in any order) is what its image is held to.
    let shells = scene("shells", &[("count", Int(8)), ("segments", Int(24))]);
    let j = judged("compute_abuffer", &shells, 64, &[]);
    assert_eq!(j.fragments_missing, Some(0), "{:?}", j.notes);
    assert_eq!(j.fragments_extra, Some(0), "{:?}", j.notes);
    assert!(
        !j.flags.contains(Flag::ImageDiffers),
        "{} {:?}",
        j.flags,
        j.notes
    );
    assert_eq!(j.exact, Some(true), "{} {:?}", j.flags, j.truth);
}
