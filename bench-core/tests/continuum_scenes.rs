//! The continuum scenes stress what they are meant to: `particles` reaches depth complexity in
//! the hundreds, `hair` stacks many thin layers, and neither has f32 depth ties where it
//! promises distinct depths (exact f64 reference rasterizer, 128²).

use bench_core::reference::rasterize;
use scenarios::{Params, SceneSpec};

fn lists(generator: &str, params: Params, size: u32) -> bench_core::reference::FragmentLists {
    let scene = SceneSpec::new(generator, params).build().unwrap();
    rasterize(&scene, size, size)
}

/// Mean fragments over covered pixels and the fraction of pixels covered.
fn coverage(l: &bench_core::reference::FragmentLists) -> (f64, f64) {
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
