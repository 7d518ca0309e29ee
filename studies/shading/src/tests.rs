//! Shading tests on lavapipe (tiny city scenes): every path against the f64 reference, the
//! culling proof, the per-id tile lists, and the CPU path's determinism.

#![allow(
    clippy::needless_range_loop,
    reason = "tests index several per-pixel arrays by one pixel index"
)]

use std::sync::OnceLock;

use scenarios::{ParamValue, Params, Scene, SceneSpec};

use super::cpu_tiled::{self, CpuOptions, TileList};
use super::gpu_paths::{Deferred, Path};
use super::reference::{self, intensity_att, surface};
use super::{class, pixel_class, pixel_class_margin, sun_shadow, GBuffer, ShadeSetup};
use bench_core::gpu::{Gpu, GpuOptions};
use bench_core::gpu_scene::GpuScene;
use bench_core::timed::Timed;
use bench_core::timing::GpuTimer;

pub(crate) fn gpu() -> &'static Gpu {
    static G: OnceLock<Gpu> = OnceLock::new();
    G.get_or_init(|| Gpu::new(&GpuOptions::default()).expect("a Vulkan adapter (lavapipe)"))
}

pub(crate) fn city(lights: i64, room: bool) -> Scene {
    SceneSpec::new(
        "city",
        Params::new()
            .with("lights", ParamValue::Int(lights))
            .with("blocks", ParamValue::Int(3))
            .with("room", ParamValue::Bool(room)),
    )
    .build()
    .unwrap()
}

/// Tolerance of an f32 path against the f64 reference, per channel, relative to max(1, |ref|):
/// f32 rounding of N·H is amplified by the specular power (up to 2^11) and the position
/// reconstruction from depth loses ~1e-5 relative; lavapipe shows 2.6e-4 (printed by the
/// tests), 2e-3 leaves 8× margin yet catches any model error (a wrong term is ≥ 10% somewhere).
pub(crate) const PATH_TOL: f64 = 2e-3;

pub(crate) fn max_rel_err(r: &[[f64; 4]], g: &[[f32; 4]]) -> f64 {
    assert_eq!(r.len(), g.len());
    let mut m = 0.0f64;
    for (a, b) in r.iter().zip(g) {
        for c in 0..4 {
            let e = (b[c] as f64 - a[c]).abs() / a[c].abs().max(1.0);
            m = m.max(if e.is_finite() { e } else { f64::INFINITY });
        }
    }
    m
}

struct Run {
    d: Deferred,
    gb: GBuffer,
    setup: ShadeSetup,
    image: Vec<[f32; 4]>,
    reference: Vec<[f64; 4]>,
}

fn run(scene: &Scene, size: u32, path: Path, tau: f64, store: bool) -> Run {
    run_with(scene, size, path, tau, store, 0.0)
}

/// [`run`] with `diffuse_only` of the lights flagged diffuse-only (GPU path and reference).
fn run_with(scene: &Scene, size: u32, path: Path, tau: f64, store: bool, diffuse_only: f64) -> Run {
    run_shadowed(
        scene,
        size,
        path,
        tau,
        store,
        diffuse_only,
        sun_shadow::Mode::Off,
    )
}

/// [`run_with`] with the sun shaded through its shadow map or not (the reference uses the
/// map the path rendered, read back, as it uses the G-buffer).
fn run_shadowed(
    scene: &Scene,
    size: u32,
    path: Path,
    tau: f64,
    store: bool,
    diffuse_only: f64,
    shadow: sun_shadow::Mode,
) -> Run {
    let g = gpu();
    let gs = GpuScene::upload(g, scene, size, size);
    let mut d = Deferred::new_with(
        g,
        scene,
        &gs,
        path,
        tau,
        store,
        diffuse_only,
        shadow,
        super::msaa::Mode::Off,
    )
    .unwrap();
    let mut timer = GpuTimer::new(g);
    timer.begin_frame();
    d.frame(g, &gs, &mut timer).unwrap();
    g.wait().unwrap();
    let image = d.read_image(g).unwrap();
    let gb = d.read_gbuffer(g).unwrap();
    let setup = ShadeSetup::new(scene, size, size)
        .with_diffuse_only(diffuse_only)
        .with_sun_shadow(d.sun_shadow_map());
    let reference = reference::shade(&setup, &gb);
    Run {
        d,
        gb,
        setup,
        image,
        reference,
    }
}

#[test]
fn scene_has_sky_geometry_and_lit_pixels() {
    let s = city(24, false);
    let r = run(&s, 64, Path::Naive, 0.0, false);
    let sky = (0..r.gb.pixels()).filter(|&i| r.gb.is_sky(i)).count();
    assert!(sky > 0 && sky < r.gb.pixels() / 2, "sky pixels: {sky}");
    // Some pixels get local light beyond ambient + sun: the lights reach the geometry.
    let t = reference::all_terms(&r.setup, &r.gb);
    let lit = t.iter().filter(|t| t.diffuse.max_element() > 1.5).count();
    assert!(lit > 0);
}

#[test]
fn naive_and_volumes_equal_reference() {
    let s = city(48, false);
    for path in [Path::Naive, Path::Volumes] {
        let r = run(&s, 64, path, 0.0, false);
        let e = max_rel_err(&r.reference, &r.image);
        println!("{path:?}: max_rel_err {e:.2e}");
        assert!(e < PATH_TOL, "{path:?}: {e}");
    }
}

#[test]
fn tiled_equals_reference_at_zero_threshold() {
    let s = city(48, false);
    for path in [
        Path::Tiled { tile: 8, levels: 1 },
        Path::Tiled {
            tile: 16,
            levels: 1,
        },
        Path::Tiled {
            tile: 32,
            levels: 1,
        },
        Path::Tiled {
            tile: 64,
            levels: 1,
        },
        Path::Tiled {
            tile: 64,
            levels: 2,
        },
    ] {
        let r = run(&s, 80, path, 0.0, false);
        let e = max_rel_err(&r.reference, &r.image);
        println!("{path:?}: max_rel_err {e:.2e}");
        assert!(e < PATH_TOL, "{path:?}: {e}");
    }
}

#[test]
fn tiled_batches_many_lights() {
    // More lights than one culling batch (256): the batch loop must keep every light.
    let s = city(700, false);
    for path in [
        Path::Tiled {
            tile: 16,
            levels: 1,
        },
        Path::Tiled {
            tile: 64,
            levels: 2,
        },
    ] {
        let r = run(&s, 64, path, 0.0, false);
        let e = max_rel_err(&r.reference, &r.image);
        assert!(e < PATH_TOL, "{path:?}: {e}");
    }
}

/// Every light missing from a tile's list has I·att ≤ τ at every non-sky pixel of the tile
/// (evaluated in f64 at the reference's positions).
fn check_culled_below(r: &Run, lists: &[TileList], tau: f64) -> usize {
    let mut culled = 0;
    for tl in lists {
        let mut keep = vec![false; r.setup.lights.len()];
        for &l in &tl.lights {
            keep[l as usize] = true;
        }
        for y in tl.rect[1]..tl.rect[3] {
            for x in tl.rect[0]..tl.rect[2] {
                let i = (y * r.gb.width + x) as usize;
                if r.gb.is_sky(i) {
                    continue;
                }
                let p = surface(&r.setup, &r.gb, i).pos;
                for (li, l) in r.setup.lights.iter().enumerate() {
                    if !keep[li] {
                        let v = intensity_att(l, p);
                        assert!(
                            v <= tau * (1.0 + 1e-6) + 1e-9,
                            "light {li} culled from tile {:?} reaches {v} > τ {tau} at ({x},{y})",
                            tl.rect
                        );
                        culled += 1;
                    }
                }
            }
        }
    }
    culled
}

#[test]
fn gpu_culled_lights_stay_below_threshold() {
    let s = city(64, false);
    for tau in [0.0, 0.05, 0.3] {
        let r = run(
            &s,
            64,
            Path::Tiled {
                tile: 16,
                levels: 1,
            },
            tau,
            true,
        );
        let lists = r.d.tile_lists(gpu()).unwrap().unwrap();
        let tl: Vec<TileList> = lists
            .into_iter()
            .enumerate()
            .map(|(i, l)| {
                let (tx, ty) = (i as u32 % 4, i as u32 / 4);
                TileList {
                    rect: [tx * 16, ty * 16, tx * 16 + 16, ty * 16 + 16],
                    lights: l,
                }
            })
            .collect();
        let culled = check_culled_below(&r, &tl, tau);
        // The test must be able to fail: culling has to actually drop lights here.
        assert!(culled > 0, "τ {tau}: nothing was culled");
    }
}

#[test]
fn cpu_path_equals_reference_is_deterministic_and_culls_soundly() {
    let s = city(64, false);
    let r = run(&s, 80, Path::Naive, 0.0, false);
    for tau in [0.0, 0.1] {
        let lights = r.setup.gpu_lights(tau);
        let mut first: Option<Vec<[f32; 4]>> = None;
        for threads in [1, 2, 3, 8] {
            let o = CpuOptions {
                threads,
                keep_lists: true,
                ..Default::default()
            };
            let res = cpu_tiled::shade(&r.setup, &r.gb, &lights, &o);
            if tau == 0.0 {
                let e = max_rel_err(&r.reference, &res.image);
                assert!(e < PATH_TOL, "cpu: {e}");
            }
            let bits: Vec<[u32; 4]> = res.image.iter().map(|p| p.map(f32::to_bits)).collect();
            match &first {
                None => {
                    let c1 = check_culled_below(&r, &res.lists, tau);
                    let c2 = check_culled_below(&r, &res.sub_lists, tau);
                    assert!(c1 > 0 && c2 > c1, "culls: tile {c1}, sub-tile {c2}");
                    first = Some(res.image.clone());
                }
                Some(f) => {
                    let fb: Vec<[u32; 4]> = f.iter().map(|p| p.map(f32::to_bits)).collect();
                    assert_eq!(fb, bits, "{threads} threads differ from 1 thread");
                }
            }
        }
    }
}

/// BF3's material classification (`classify = materials`): each sub-tile shaded by the code
/// permutation its material + light mask picks gives the übershader's image bit for bit and
/// matches the f64 reference, for both light loops, one and two culling levels, the light
/// buffer and an image whose side is not a multiple of 4 (edge lanes); on the city (matte
/// buildings without specular, sky, three light kinds) some 32×16 sub-tiles take a narrower
/// permutation. A permutation narrower than a sub-tile's mask changes
/// the image: the mask is what keeps the permutations exact.
#[test]
fn material_classification_permutations_equal_the_ubershader_and_the_reference() {
    use cpu_tiled::{perm, Classify, LightLoop};
    let s = city(64, false);
    for size in [80, 78] {
        let base = run(&s, size, Path::Naive, 0.0, false);
        let setup = base.setup.clone().with_diffuse_only(0.5);
        let reference = reference::shade(&setup, &base.gb);
        let lights = setup.gpu_lights(0.0);
        for (light_loop, sub, light_buffer) in [
            (LightLoop::Bf3, Some((32, 16)), false),
            (LightLoop::Mfx, Some((32, 16)), false),
            (LightLoop::Bf3, None, false),
            (LightLoop::Bf3, Some((32, 16)), true),
        ] {
            let shade = |classify, force_perm| {
                let o = CpuOptions {
                    classify,
                    force_perm,
                    light_loop,
                    sub,
                    threads: 2,
                    light_buffer,
                    ..Default::default()
                };
                cpu_tiled::shade(&setup, &base.gb, &lights, &o)
            };
            let what = format!("{size}px {light_loop:?} sub {sub:?} lb {light_buffer}");
            let uber = shade(Classify::None, None);
            let mat = shade(Classify::Materials, None);
            assert_eq!(differing(&uber.image, &mat.image), 0, "{what}");
            // The reorder into rows by bands on a rayon pool (the pre-pass's parallel host)
            // places every tile where the serial reorder does, partial edge tiles included.
            let banded = rayon::ThreadPoolBuilder::new()
                .num_threads(3)
                .build()
                .unwrap()
                .install(|| {
                    let o = CpuOptions {
                        light_loop,
                        sub,
                        threads: 2,
                        light_buffer,
                        parallel_reorder: true,
                        ..Default::default()
                    };
                    cpu_tiled::shade(&setup, &base.gb, &lights, &o)
                });
            assert_eq!(differing(&uber.image, &banded.image), 0, "{what}: banded");
            let regions: u64 = mat.perm_regions.iter().sum();
            assert_eq!(regions, uber.perm_regions[perm::ALL as usize], "{what}");
            let narrow = regions - mat.perm_regions[perm::ALL as usize];
            // 32×16 sub-tiles are small enough to miss a feature (a 64² tile at 78 px has
            // them all).
            assert!(
                narrow > 0 || sub.is_none(),
                "{what}: no sub-tile took a narrower permutation"
            );
            if !light_buffer {
                let e = max_rel_err(&reference, &mat.image);
                assert!(e < PATH_TOL, "{what}: {e}");
            }
            // Every sub-tile forced to the narrowest permutation: no sky or edge lanes, no
            // specular, spot or line terms. The city has all of them: the image must change.
            let wrong = shade(Classify::Materials, Some(0));
            assert!(differing(&uber.image, &wrong.image) > 0, "{what}");
        }
    }
}

/// The per-quad culls only drop exact zeros: skipping a light whose 16 attenuations are all 0,
/// and skipping the specular term of a quad without specular colour (matte buildings), leave the
/// image bit-identical; on a many-light city both do skip something.
#[test]
fn quad_culls_change_nothing_but_the_work() {
    let s = city(64, false);
    let r = run(&s, 80, Path::Naive, 0.0, false);
    let lights = r.setup.gpu_lights(0.0);
    let shade = |quad_skip, spec_skip| {
        let o = CpuOptions {
            threads: 2,
            quad_skip,
            spec_skip,
            ..Default::default()
        };
        cpu_tiled::shade(&r.setup, &r.gb, &lights, &o)
    };
    let bits =
        |img: &[[f32; 4]]| -> Vec<[u32; 4]> { img.iter().map(|p| p.map(f32::to_bits)).collect() };
    let off = shade(false, false);
    assert_eq!((off.quad_skips, off.spec_skipped_quads), (0, 0));
    for (q, sp) in [(true, false), (false, true), (true, true)] {
        let on = shade(q, sp);
        assert_eq!(on.quad_skips > 0, q, "quad skip {q}");
        assert_eq!(on.spec_skipped_quads > 0, sp, "spec skip {sp}");
        assert!(on.spec_skipped_quads < on.quads);
        assert_eq!(bits(&on.image), bits(&off.image), "quad {q} spec {sp}");
    }
}

/// BF3's per-phase clocks only observe: the image is bit-identical with them on, every phase
/// of a lit city takes some time, the phases add up to their total, and without them no
/// phases are reported (the timed frames carry no clock reads).
#[test]
fn phase_clocks_change_nothing_but_report_every_phase() {
    let s = city(64, false);
    let r = run(&s, 80, Path::Naive, 0.0, false);
    let lights = r.setup.gpu_lights(0.0);
    let shade = |phase_times| {
        let o = CpuOptions {
            threads: 2,
            phase_times,
            ..Default::default()
        };
        cpu_tiled::shade(&r.setup, &r.gb, &lights, &o)
    };
    let off = shade(false);
    assert!(off.phases.is_none());
    let on = shade(true);
    assert_eq!(bits(&on.image), bits(&off.image));
    let ph = on.phases.expect("phases with phase_times");
    for (name, ns) in [
        ("cull", ph.cull),
        ("unpack", ph.unpack),
        ("lights", ph.lights),
        ("sun", ph.sun),
        ("pack", ph.pack),
    ] {
        assert!(ns > 0, "{name}: {ph:?}");
    }
    assert_eq!(
        ph.total(),
        ph.cull + ph.unpack + ph.lights + ph.sun + ph.pack
    );
    assert!(on.quad_evals > 0);
}

fn bits(img: &[[f32; 4]]) -> Vec<[u32; 4]> {
    img.iter().map(|p| p.map(f32::to_bits)).collect()
}

/// Pixels whose bits differ between two images.
fn differing(a: &[[f32; 4]], b: &[[f32; 4]]) -> usize {
    bits(a)
        .iter()
        .zip(bits(b))
        .filter(|(x, y)| **x != *y)
        .count()
}

/// BF3's normal-cone cull per sub-tile is exact: with it the image is bit-identical to the
/// unculled path, at one and two levels, on an open city and a room (walls facing away from
/// lights), and it does drop (light, 32×16 sub-tile) pairs. A deliberately non-conservative cone
/// (margin −0.6 rad: drops lights up to ~34° short of facing away) must break bit-identity,
/// which proves the comparison can catch an unsound cull.
#[test]
fn normal_cone_cull_is_exact_and_drops_lights() {
    for room in [false, true] {
        let s = city(64, room);
        let r = run(&s, 80, Path::Naive, 0.0, false);
        let lights = r.setup.gpu_lights(0.0);
        let shade = |sub: Option<(u32, u32)>, cone_cull: bool, cone_margin: f64| {
            let o = CpuOptions {
                threads: 2,
                sub,
                cone_cull,
                cone_margin,
                ..Default::default()
            };
            cpu_tiled::shade(&r.setup, &r.gb, &lights, &o)
        };
        for sub in [Some((32, 16)), None] {
            let off = shade(sub, false, cpu_tiled::CONE_MARGIN);
            assert_eq!((off.cone_culls, off.cone_tests), (0, 0));
            let on = shade(sub, true, cpu_tiled::CONE_MARGIN);
            println!(
                "room {room} sub {sub:?}: cone culls {} of {}",
                on.cone_culls, on.cone_tests
            );
            assert_eq!(
                differing(&on.image, &off.image),
                0,
                "room {room} sub {sub:?}: the cone cull changed the image"
            );
            // One 64×64 level: the tiles' normal cones are too wide to cull (exact, no work).
            if sub.is_none() {
                continue;
            }
            assert!(on.cone_culls > 0, "room {room} sub {sub:?}: nothing culled");
            assert!(on.quad_evals < off.quad_evals);
            assert_eq!(
                differing(&on.image, &off.image),
                0,
                "room {room} sub {sub:?}: the cone cull changed the image"
            );
            let bad = shade(sub, true, -0.6);
            assert!(bad.cone_culls > on.cone_culls);
            let d = differing(&bad.image, &off.image);
            println!("  non-conservative cone: {d} pixels differ");
            assert!(d > 0, "room {room} sub {sub:?}: a wrong cull went unseen");
        }
    }
}

/// Diffuse-only lights: every GPU path and the CPU path still equal the f64 reference (whose
/// diffuse-only lights have no specular term) with half the lights flagged; the flag changes
/// the image (so a path ignoring it fails); the CPU path's specular skip is bit-identical to
/// evaluating and discarding the term, and skips something.
#[test]
fn diffuse_only_lights_match_reference_in_every_path() {
    let s = city(48, false);
    let base = run(&s, 64, Path::Naive, 0.0, false);
    for path in [
        Path::Naive,
        Path::Volumes,
        Path::Tiled {
            tile: 16,
            levels: 1,
        },
        Path::Tiled {
            tile: 64,
            levels: 2,
        },
        Path::Classified { uber: false },
        Path::Classified { uber: true },
    ] {
        let r = run_with(&s, 64, path, 0.0, false, 0.5);
        assert_eq!(r.setup.lights.iter().filter(|l| l.diffuse_only).count(), 24);
        let e = max_rel_err(&r.reference, &r.image);
        println!("{path:?} diffuse-only 0.5: max_rel_err {e:.2e}");
        assert!(e < PATH_TOL, "{path:?}: {e}");
        // Ignoring the flag is an error the test sees: the unflagged image is far off.
        let e0 = max_rel_err(&r.reference, &base.image);
        assert!(e0 > 10.0 * PATH_TOL, "{path:?}: flag invisible ({e0})");
    }
    let setup = base.setup.clone().with_diffuse_only(0.5);
    let reference = reference::shade(&setup, &base.gb);
    let lights = setup.gpu_lights(0.0);
    assert_eq!(lights.iter().filter(|l| l.diffuse_only()).count(), 24);
    let shade = |diffuse_skip: bool, light_buffer: bool| {
        let o = CpuOptions {
            threads: 3,
            diffuse_skip,
            light_buffer,
            ..Default::default()
        };
        cpu_tiled::shade(&setup, &base.gb, &lights, &o)
    };
    let on = shade(true, false);
    let off = shade(false, false);
    let e = max_rel_err(&reference, &on.image);
    println!(
        "cpu diffuse-only 0.5: max_rel_err {e:.2e}, skips {}",
        on.diffuse_skips
    );
    assert!(e < PATH_TOL, "cpu: {e}");
    assert!(on.diffuse_skips > 0 && off.diffuse_skips == 0);
    assert_eq!(differing(&on.image, &off.image), 0);
    // Light-buffer mode: Σ spec_lum drops the flagged lights too.
    let lb_on = shade(true, true);
    let lb_off = shade(false, true);
    assert_eq!(differing(&lb_on.image, &lb_off.image), 0);
    let t = reference::all_terms(&setup, &base.gb);
    let mut m = 0.0f64;
    for (i, p) in lb_on.image.iter().enumerate() {
        let want = t[i].spec_lum;
        m = m.max((p[3] as f64 - want).abs() / want.abs().max(1.0));
    }
    assert!(m < PATH_TOL, "light buffer spec_lum: {m}");
}

/// BF3's light loop (all 16 lanes per light, masked, no per-lane early-out) against mfx's
/// (per-lane early-outs): the same image bit for bit and the same counts, within the f64
/// reference's tolerance, for combinations of the skips, the light buffer and diffuse-only
/// lights. Masked lanes carry NaN directions (a pixel at the light) and unlit specular terms:
/// a mask that let one through would show here as a differing or non-finite pixel.
#[test]
fn bf3_light_loop_matches_mfx_loop_bitwise_and_the_reference() {
    use cpu_tiled::LightLoop;
    let s = city(64, false);
    let base = run(&s, 80, Path::Naive, 0.0, false);
    for frac in [0.0, 0.5] {
        let setup = base.setup.clone().with_diffuse_only(frac);
        let reference = reference::shade(&setup, &base.gb);
        let lights = setup.gpu_lights(0.0);
        for (spec_skip, diffuse_skip, light_buffer) in [
            (true, true, false),
            (false, false, false),
            (true, false, false),
            (false, true, true),
        ] {
            let shade = |light_loop| {
                let o = CpuOptions {
                    light_loop,
                    threads: 2,
                    spec_skip,
                    diffuse_skip,
                    light_buffer,
                    ..Default::default()
                };
                cpu_tiled::shade(&setup, &base.gb, &lights, &o)
            };
            let bf3 = shade(LightLoop::Bf3);
            let mfx = shade(LightLoop::Mfx);
            let what = format!(
                "frac {frac} spec_skip {spec_skip} diffuse_skip {diffuse_skip} lb {light_buffer}"
            );
            assert_eq!(differing(&bf3.image, &mfx.image), 0, "{what}");
            assert_eq!(
                (bf3.quad_evals, bf3.quad_skips, bf3.diffuse_skips),
                (mfx.quad_evals, mfx.quad_skips, mfx.diffuse_skips),
                "{what}"
            );
            assert!(bf3.quad_evals > 0 && bf3.quad_skips > 0, "{what}");
            if !light_buffer {
                let e = max_rel_err(&reference, &bf3.image);
                assert!(e < PATH_TOL, "{what}: {e}");
            }
        }
    }
}

#[test]
fn classified_lists_every_tile_once_and_matches_uber() {
    for room in [false, true] {
        let s = city(32, room);
        let rc = run(&s, 64, Path::Classified { uber: false }, 0.0, false);
        let ru = run(&s, 64, Path::Classified { uber: true }, 0.0, false);
        let e = max_rel_err(&rc.reference, &rc.image);
        assert!(e < PATH_TOL, "classified room={room}: {e}");
        let e = max_rel_err(&ru.reference, &ru.image);
        assert!(e < PATH_TOL, "uber room={room}: {e}");
        let (ids, counts, offsets, list) = rc.d.classification(gpu()).unwrap().unwrap();
        let (tx, ty) = rc.d.class_tiles().unwrap();
        let n = (tx * ty) as usize;
        let mut seen = vec![0u32; n];
        for id in 0..class::IDS as usize {
            let range = offsets[id] as usize..(offsets[id] + counts[id]) as usize;
            for &t in &list[range] {
                seen[t as usize] += 1;
                assert_eq!(
                    ids[t as usize], id as u32,
                    "tile {t} listed under the wrong id"
                );
            }
        }
        assert!(
            seen.iter().all(|&c| c == 1),
            "a tile is missing or repeated"
        );
        // GPU ids equal the CPU classification of the same G-buffer.
        for t in 0..n {
            let (x0, y0) = ((t as u32 % tx) * 4, (t as u32 / tx) * 4);
            let mut bits = 0;
            for y in y0..(y0 + 4).min(64) {
                for x in x0..(x0 + 4).min(64) {
                    bits |= pixel_class(&rc.setup, &rc.gb, (y * 64 + x) as usize);
                }
            }
            assert_eq!(ids[t], bits, "tile {t}");
        }
        if room {
            // No sky, no sun: those permutations are neither compiled nor drawn.
            assert_eq!(rc.d.permutations, 2);
            for id in 0..class::IDS {
                if id & (class::SKY | class::SUN) != 0 {
                    assert_eq!(counts[id as usize], 0);
                }
            }
        } else {
            assert_eq!(rc.d.permutations, 9);
        }
    }
}

mod msaa_tests {
    use super::*;
    use crate::msaa;

    struct MsRun {
        d: Deferred,
        samples: Vec<GBuffer>,
        setup: ShadeSetup,
        image: Vec<[f32; 4]>,
        reference: Vec<[f64; 4]>,
    }

    /// One frame of `path` over a 4×MSAA G-buffer (lavapipe multisamples only 4×; x2 is the same
    /// code with SAMPLES 2); the reference averages the f64 shading of each read-back sample.
    fn run_ms(scene: &Scene, size: u32, path: Path) -> MsRun {
        let g = gpu();
        let gs = GpuScene::upload(g, scene, size, size);
        let mut d = Deferred::new_with(
            g,
            scene,
            &gs,
            path,
            0.0,
            false,
            0.0,
            sun_shadow::Mode::Off,
            msaa::Mode::X4,
        )
        .unwrap();
        let mut timer = GpuTimer::new(g);
        timer.begin_frame();
        d.frame(g, &gs, &mut timer).unwrap();
        g.wait().unwrap();
        let image = d.read_image(g).unwrap();
        let samples = d.read_samples(g).unwrap();
        assert_eq!(samples.len(), 4);
        let setup = ShadeSetup::new(scene, size, size);
        let reference = msaa::reference(&setup, &samples);
        MsRun {
            d,
            samples,
            setup,
            image,
            reference,
        }
    }

    /// Every MSAA path equals the averaged f64 reference within PATH_TOL: each sample is shaded
    /// with the same f32 model as without MSAA, and averaging four values adds ~2 roundings, so
    /// the single-sample tolerance (and its reason) holds unchanged.
    #[test]
    fn msaa_paths_equal_the_averaged_reference() {
        let s = city(32, false);
        for path in [
            Path::Naive,
            Path::Classified { uber: false },
            Path::Classified { uber: true },
        ] {
            let r = run_ms(&s, 64, path);
            let e = max_rel_err(&r.reference, &r.image);
            println!("msaa x4 {path:?}: max_rel_err {e:.2e}");
            assert!(e < PATH_TOL, "msaa x4 {path:?}: {e}");
        }
    }

    /// The GPU's tile ids equal the CPU twin (every sample's bits, EDGE where the samples
    /// differ: exact comparisons of the same read-back values); edge tiles exist (the city has
    /// silhouettes) and are a minority of geometry tiles (else the class would save nothing);
    /// at edge pixels the averaged image is not the sample-0 image (the class is needed), and
    /// elsewhere it is (shading once is exact there).
    #[test]
    fn msaa_edge_class_matches_the_cpu_twin_and_changes_the_image() {
        let s = city(32, false);
        let size = 64u32;
        let r = run_ms(&s, size, Path::Classified { uber: false });
        let (ids, _, _, _) = r.d.classification(gpu()).unwrap().unwrap();
        let (tx, ty) = r.d.class_tiles().unwrap();
        for t in 0..(tx * ty) as usize {
            let (x0, y0) = ((t as u32 % tx) * 4, (t as u32 / tx) * 4);
            let mut bits = 0;
            for y in y0..(y0 + 4).min(size) {
                for x in x0..(x0 + 4).min(size) {
                    bits |= msaa::pixel_class_ms(&r.setup, &r.samples, (y * size + x) as usize);
                }
            }
            assert_eq!(
                ids[t],
                bits,
                "tile {t}: gpu {} cpu {}",
                class::names(ids[t]),
                class::names(bits)
            );
            assert!(class::valid(ids[t]), "tile {t}: {}", class::names(ids[t]));
        }
        let edge = ids.iter().filter(|&&id| id & class::EDGE != 0).count();
        let geom = ids.iter().filter(|&&id| id & class::GEOM != 0).count();
        println!(
            "msaa edge tiles {edge} of {geom} geometry tiles ({} tiles)",
            ids.len()
        );
        assert!(edge > 0, "no edge tile");
        assert!(
            edge < geom,
            "every geometry tile is an edge tile: {edge} of {geom}"
        );
        // Pixels whose samples differ: the MSAA image there differs from shading sample 0.
        let one = reference::shade(&r.setup, &r.samples[0]);
        let n = r.samples[0].pixels();
        let edge_px: Vec<usize> = (0..n)
            .filter(|&i| msaa::samples_differ(&r.samples, i))
            .collect();
        assert!(
            !edge_px.is_empty() && edge_px.len() < n / 4,
            "edge pixels: {}",
            edge_px.len()
        );
        let moved = edge_px
            .iter()
            .filter(|&&i| {
                (0..3).any(|c| {
                    (r.image[i][c] as f64 - one[i][c]).abs()
                        > 10.0 * PATH_TOL * one[i][c].abs().max(1.0)
                })
            })
            .count();
        println!(
            "msaa edge pixels {} of {n}; {moved} differ from sample 0",
            edge_px.len()
        );
        assert!(moved > 0, "no edge pixel's image differs from its sample 0");
        for i in 0..n {
            if !msaa::samples_differ(&r.samples, i) {
                assert_eq!(
                    r.reference[i], one[i],
                    "pixel {i}: equal samples shade alike"
                );
            }
        }
    }

    /// The MSAA G-buffer keeps sky and geometry where the single-sample one has them: sample 0
    /// of the 2-sample G-buffer has sky pixels and geometry pixels, and edge pixels exist on
    /// the sky silhouette (a sample of sky, one of geometry).
    #[test]
    fn msaa_sky_silhouettes_are_edges() {
        let s = city(8, false);
        let r = run_ms(&s, 64, Path::Naive);
        let n = r.samples[0].pixels();
        let mixed = (0..n)
            .filter(|&i| r.samples[0].is_sky(i) != r.samples[1].is_sky(i))
            .count();
        assert!(mixed > 0, "no pixel with one sky and one geometry sample");
        assert!(
            (0..n).all(|i| r.samples[0].is_sky(i) == r.samples[1].is_sky(i)
                || msaa::samples_differ(&r.samples, i))
        );
    }
}

mod msaa_x2_tests {
    use super::*;
    use crate::msaa;

    /// x2 (the paper's count) builds where the adapter multisamples every G-buffer format 2×,
    /// and is refused with the adapter's reason elsewhere (lavapipe: 1 and 4 only), never
    /// silently rendered wrong; x4 is always allowed (WebGPU guarantees it).
    #[test]
    fn msaa_x2_builds_or_is_refused_with_the_adapters_reason() {
        let g = gpu();
        assert!(msaa::supported(g, msaa::Mode::X4).is_ok());
        let s = city(4, false);
        let gs = GpuScene::upload(g, &s, 32, 32);
        let d = Deferred::new_with(
            g,
            &s,
            &gs,
            Path::Classified { uber: false },
            0.0,
            false,
            0.0,
            sun_shadow::Mode::Off,
            msaa::Mode::X2,
        );
        match msaa::supported(g, msaa::Mode::X2) {
            Ok(()) => assert!(d.is_ok()),
            Err(why) => {
                println!("x2 refused: {why}");
                assert!(why.contains("x2") && d.is_err());
            }
        }
        // Paths without the MSAA variant refuse it.
        let t = Deferred::new_with(
            g,
            &s,
            &gs,
            Path::Tiled {
                tile: 16,
                levels: 1,
            },
            0.0,
            false,
            0.0,
            sun_shadow::Mode::Off,
            msaa::Mode::X4,
        );
        assert!(t.is_err());
    }
}

mod prepass_tests {
    use super::*;
    use crate::prepass::{Accum, HostWork, LbFormat, PrePass};

    /// RGBA16F light buffer: f16 keeps 11 bits (4.9e-4 relative), the metal model divides by
    /// lum(D); lavapipe shows ~1e-3 relative, 5e-3 leaves 5× margin.
    const LB_TOL: f64 = 5e-3;

    fn frame(s: &Scene, fmt: LbFormat, accum: Accum, view2: bool) -> (PrePass, GpuScene) {
        let g = gpu();
        let gs = GpuScene::upload(g, s, 64, 64);
        let mut p = PrePass::new(g, s, &gs, fmt, accum, 0.0, view2).unwrap();
        let mut timer = GpuTimer::new(g);
        timer.begin_frame();
        p.frame(g, &gs, &mut timer).unwrap();
        g.wait().unwrap();
        (p, gs)
    }

    #[test]
    fn prepass_image_equals_packed_reference_and_loss_is_bounded() {
        let s = city(48, false);
        let g = gpu();
        let r = run(&s, 64, Path::Naive, 0.0, false);
        let terms = reference::all_terms(&r.setup, &r.gb);
        let packed = reference::prepass_image(&r.gb, &terms);
        for accum in [Accum::Naive, Accum::Tiled { tile: 16 }] {
            let (p, _) = frame(&s, LbFormat::Rgba16F, accum, false);
            let img = p.read_image(g).unwrap();
            let e = max_rel_err(&packed, &img);
            println!("{accum:?}: vs packed {e:.2e}");
            assert!(e < LB_TOL, "{accum:?}: {e}");
        }
        // The packing loss: dielectric pixels lose spec·(S − A) per channel (4% grey specular
        // here); metals replace the specular chroma by the diffuse light's. It is real (> 0)
        // and bounded by spec·|S − A| per pixel.
        let mut loss = 0.0f64;
        for i in 0..r.gb.pixels() {
            if r.gb.is_sky(i) || r.gb.albedo[i] == [0.0; 3] {
                continue;
            }
            for c in 0..3 {
                let d = (packed[i][c] - r.reference[i][c]).abs();
                let bound =
                    r.gb.spec[i][c] as f64 * (terms[i].specular[c] - terms[i].spec_lum).abs();
                assert!(
                    d <= bound * (1.0 + 1e-9) + 1e-12,
                    "pixel {i}: {d} > {bound}"
                );
                loss = loss.max(d);
            }
        }
        assert!(loss > 0.0);
    }

    #[test]
    fn cpu_light_buffer_equals_gpu_and_any_thread_count() {
        let s = city(48, false);
        let g = gpu();
        let (p, _) = frame(&s, LbFormat::Rgba16F, Accum::Naive, false);
        let gpu_lb = p.read_light_buffer(g).unwrap();
        let gb = p.gbuf.read(g).unwrap();
        let setup = ShadeSetup::new(&s, 64, 64);
        let lights = setup.gpu_lights(0.0);
        let mut first: Option<Vec<[u32; 4]>> = None;
        for threads in [1, 3] {
            let o = CpuOptions {
                threads,
                light_buffer: true,
                ..Default::default()
            };
            let r = cpu_tiled::shade(&setup, &gb, &lights, &o);
            let mut m = 0.0f64;
            for (a, b) in r.image.iter().zip(&gpu_lb) {
                for c in 0..4 {
                    m = m.max((a[c] - b[c]).abs() as f64 / (a[c].abs() as f64).max(1.0));
                }
            }
            assert!(m < LB_TOL, "CPU vs GPU light buffer: {m}");
            let bits: Vec<[u32; 4]> = r.image.iter().map(|p| p.map(f32::to_bits)).collect();
            match &first {
                None => first = Some(bits),
                Some(f) => assert_eq!(f, &bits, "{threads} threads"),
            }
        }
    }

    #[test]
    fn overlapped_frame_equals_serial_frame() {
        let s = city(48, false);
        let g = gpu();
        let mut imgs = vec![];
        for overlap in [false, true] {
            let (p, _) = frame(
                &s,
                LbFormat::Rgba16F,
                Accum::Cpu {
                    threads: 2,
                    overlap,
                    host: HostWork::Parallel,
                },
                true,
            );
            let view2 = p.view2.as_ref().unwrap().1.read_image(g).unwrap();
            imgs.push((p.read_image(g).unwrap(), view2));
        }
        assert!(imgs[0].0 == imgs[1].0, "main view differs with overlap");
        assert!(imgs[0].1 == imgs[1].1, "second view differs with overlap");
        // And the CPU-lit image is the packed reference within the light-buffer tolerance.
        let r = run(&s, 64, Path::Naive, 0.0, false);
        let packed = reference::prepass_image(&r.gb, &reference::all_terms(&r.setup, &r.gb));
        let e = max_rel_err(&packed, &imgs[0].0);
        assert!(e < LB_TOL, "cpu prepass vs packed reference: {e}");
    }

    /// The host work on the lighting's workers (rayon: decode by rows, the tiles' reorder by
    /// bands, the pack by chunks) gives the serial host's frame bit for bit, in every light
    /// buffer format the adapter renders, and its functions give the serial ones' G-buffer
    /// (rows padded to 256 bytes, a width not a multiple of 64) and bytes.
    #[test]
    fn parallel_host_work_equals_serial_host_work() {
        use crate::prepass::{decode_prepass, decode_prepass_par, pack, pack_par};
        let s = city(48, false);
        let g = gpu();
        for fmt in [LbFormat::Rgba16F, LbFormat::Rgba8, LbFormat::Rg11b10] {
            let cpu = |host| Accum::Cpu {
                threads: 3,
                overlap: true,
                host,
            };
            if crate::prepass::supports(g, fmt, cpu(HostWork::Serial)).is_err() {
                continue;
            }
            let mut out = vec![];
            for host in [HostWork::Serial, HostWork::Parallel] {
                let (p, _) = frame(&s, fmt, cpu(host), true);
                out.push((
                    p.read_image(g).unwrap(),
                    p.read_light_buffer(g).unwrap(),
                    p.view2.as_ref().unwrap().1.read_image(g).unwrap(),
                ));
            }
            assert!(out[0].0 == out[1].0, "{fmt:?}: main view differs");
            assert!(out[0].1 == out[1].1, "{fmt:?}: light buffer differs");
            assert!(out[0].2 == out[1].2, "{fmt:?}: second view differs");
            let lb: Vec<[f32; 4]> = out[0].1.clone();
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(3)
                .build()
                .unwrap();
            assert_eq!(
                pack(fmt, &lb),
                pool.install(|| pack_par(fmt, &lb)),
                "{fmt:?}"
            );
        }
        // Decoding: rows padded to 256 bytes, a width that is not a multiple of 64.
        let (w, h) = (70u32, 9u32);
        let (rd, rn) = (
            crate::gbuffer::padded_row(w, 4) as usize,
            crate::gbuffer::padded_row(w, 8) as usize,
        );
        let depth: Vec<u8> = (0..rd * h as usize).map(|i| (i * 7 % 251) as u8).collect();
        let normal: Vec<u8> = (0..rn * h as usize).map(|i| (i * 13 % 241) as u8).collect();
        let clear = f32::from_le_bytes([depth[4], depth[5], depth[6], depth[7]]);
        let a = decode_prepass(&depth, &normal, w, h, clear);
        let b = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| decode_prepass_par(&depth, &normal, w, h, clear));
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.depth), bits(&b.depth));
        assert_eq!(
            a.normal
                .iter()
                .map(|n| n.map(f32::to_bits))
                .collect::<Vec<_>>(),
            b.normal
                .iter()
                .map(|n| n.map(f32::to_bits))
                .collect::<Vec<_>>()
        );
        assert_eq!(a.material, b.material);
        assert!(
            a.material.contains(&crate::SKY_MATERIAL),
            "the clear value marks sky"
        );
    }

    #[test]
    fn ufloat_packing_rounds_to_nearest_and_clamps() {
        use crate::prepass::{from_ufloat, to_ufloat};
        for m in [5u32, 6] {
            // Every representable value survives exactly.
            for u in 0..(31u32 << m) {
                assert_eq!(to_ufloat(from_ufloat(u, m), m), u, "m={m} u={u}");
            }
            // Anything else rounds to within half an ulp (relative 2^-(m+1) for normals).
            let mut x = 1e-3f32;
            while x < 6e4 {
                let y = from_ufloat(to_ufloat(x, m), m);
                let tol = x * 2f32.powi(-(m as i32) - 1) * 1.0001;
                assert!((y - x).abs() <= tol, "m={m}: {x} -> {y}");
                x *= 1.013;
            }
            let max = from_ufloat((30 << m) | ((1 << m) - 1), m);
            assert_eq!(from_ufloat(to_ufloat(1e9, m), m), max);
            for bad in [0.0, -1.0, f32::NAN] {
                assert_eq!(to_ufloat(bad, m), 0);
            }
        }
    }

    /// RG11B10 (+ R16F specular) light buffer: the CPU packer and the GPU's render target agree
    /// to one ulp per channel (a GPU may round or truncate), and the CPU-lit image stays within
    /// the format's precision of the packed reference (6- and 5-bit mantissas: 1.6% and 3.1%
    /// per value, the metal model's D/lum(D) adds up to twice that; 0.1 relative to max(1, |ref|)
    /// still catches any decoding error).
    #[test]
    fn rg11b10_cpu_packer_matches_the_gpu_target() {
        let s = city(48, false);
        let g = gpu();
        let (pg, _) = frame(&s, LbFormat::Rg11b10, Accum::Naive, false);
        let (pc, _) = frame(
            &s,
            LbFormat::Rg11b10,
            Accum::Cpu {
                threads: 2,
                overlap: false,
                host: HostWork::Parallel,
            },
            false,
        );
        let (a, b) = (
            pg.read_light_buffer(g).unwrap(),
            pc.read_light_buffer(g).unwrap(),
        );
        for (i, (x, y)) in a.iter().zip(&b).enumerate() {
            for (c, m) in [(0, 6), (1, 6), (2, 5), (3, 10)] {
                let tol = 2f32.powi(-m) * x[c].abs().max(y[c].abs()) * 1.01 + 1e-6;
                assert!(
                    (x[c] - y[c]).abs() <= tol,
                    "pixel {i} channel {c}: GPU {} CPU {}",
                    x[c],
                    y[c]
                );
            }
        }
        let r = run(&s, 64, Path::Naive, 0.0, false);
        let packed = reference::prepass_image(&r.gb, &reference::all_terms(&r.setup, &r.gb));
        for p in [&pg, &pc] {
            let e = max_rel_err(&packed, &p.read_image(g).unwrap());
            assert!(e < 0.1, "rg11b10 vs packed reference: {e}");
        }
    }
}

/// Max relative error (as [`max_rel_err`]) over the pixels that are not sun-shadow ties, and
/// how many ties there were.
fn max_rel_err_off_ties(r: &Run) -> (f64, usize) {
    let ties = reference::sun_shadow_ties(&r.setup, &r.gb);
    let keep = |i: &usize| !ties[*i];
    let idx: Vec<usize> = (0..ties.len()).filter(keep).collect();
    let rr: Vec<[f64; 4]> = idx.iter().map(|&i| r.reference[i]).collect();
    let gg: Vec<[f32; 4]> = idx.iter().map(|&i| r.image[i]).collect();
    (max_rel_err(&rr, &gg), ties.iter().filter(|&&t| t).count())
}

#[test]
fn sun_shadow_taps8_city_64px_naive_classified_uber_match_reference_within_path_tol() {
    let s = city(8, false);
    let n = 64 * 64;
    let off = run(&s, 64, Path::Naive, 0.0, false);
    for path in [
        Path::Naive,
        Path::Classified { uber: false },
        Path::Classified { uber: true },
    ] {
        let r = run_shadowed(&s, 64, path, 0.0, false, 0.0, sun_shadow::Mode::Taps8);
        let (e, ties) = max_rel_err_off_ties(&r);
        println!("{}: max rel err {e:.2e} off {ties} tie pixels", path.name());
        // PATH_TOL's reason holds: the filter adds only f32 bilinear weights (≤ 1e-7 relative).
        assert!(e < PATH_TOL, "{} sun_shadow=taps8: {e}", path.name());
        // Ties: compares within TIE_EPS of equal, where the f32 GPU may go either way (a few
        // pixels on faces nearly parallel to the sun); more would mean a wrong bias or transform.
        assert!(ties * 100 <= n, "{} tie pixels of {n}", ties);
        // The shadow is there: the shadowed reference is darker than the unshadowed one on
        // many pixels, and some pixels are in a penumbra (neither 0 nor 1).
        let darker = (0..n)
            .filter(|&i| r.reference[i][1] < off.reference[i][1] - 0.05)
            .count();
        assert!(darker * 20 > n, "only {darker} shadowed pixels of {n}");
        assert!(
            (0..n).all(|i| r.reference[i][1] <= off.reference[i][1] + 1e-9),
            "a shadow brightened a pixel"
        );
    }
    let r = run_shadowed(
        &s,
        64,
        Path::Naive,
        0.0,
        false,
        0.0,
        sun_shadow::Mode::Taps8,
    );
    let m = r.setup.sun_shadow.as_ref().expect("city has a sun");
    let (d, _) = r.setup.sun.unwrap();
    let penumbra = (0..n)
        .filter(|&i| {
            let su = surface(&r.setup, &r.gb, i);
            !r.gb.is_sky(i) && su.n.dot(d) > 0.0 && {
                let v = m.visibility(su.pos).value;
                v > 0.0 && v < 1.0
            }
        })
        .count();
    assert!(penumbra > 0, "no penumbra pixel on the test city");
}

#[test]
fn sun_shadow_fade_class_city_64px_gpu_equals_cpu_off_ties_and_is_a_minority() {
    let s = city(8, false);
    let rc = run_shadowed(
        &s,
        64,
        Path::Classified { uber: false },
        0.0,
        false,
        0.0,
        sun_shadow::Mode::Taps8,
    );
    let (ids, counts, _, _) = rc.d.classification(gpu()).unwrap().unwrap();
    let (tx, ty) = rc.d.class_tiles().unwrap();
    let n = (tx * ty) as usize;
    let (mut tie_tiles, mut fade, mut sun) = (0, 0, 0);
    for t in 0..n {
        let (x0, y0) = ((t as u32 % tx) * 4, (t as u32 / tx) * 4);
        let (mut bits, mut margin) = (0, f64::INFINITY);
        for y in y0..(y0 + 4).min(64) {
            for x in x0..(x0 + 4).min(64) {
                let (b, m) = pixel_class_margin(&rc.setup, &rc.gb, (y * 64 + x) as usize);
                bits |= b;
                margin = margin.min(m);
            }
        }
        if ids[t] != bits {
            println!("tile {t}: gpu {} cpu {} margin {margin:e}", ids[t], bits);
        }
        if margin < sun_shadow::TIE_EPS {
            // The f32 GPU may decide a tie the other way; only the fade bit may differ.
            tie_tiles += 1;
            assert_eq!(ids[t] & !class::FADE, bits & !class::FADE, "tile {t}");
        } else {
            assert_eq!(ids[t], bits, "tile {t}");
        }
        fade += (ids[t] & class::FADE != 0) as usize;
        sun += (ids[t] & class::SUN != 0) as usize;
    }
    println!("{fade} fade tiles of {sun} sun tiles ({n} tiles, {tie_tiles} with a tie)");
    assert!(tie_tiles * 20 <= n, "{tie_tiles} tie tiles of {n}");
    // Both kinds exist: filtered tiles, and sun tiles the classified path shades with one tap.
    assert!(
        fade > 0 && fade < sun,
        "{fade} fade tiles of {sun} sun tiles"
    );
    assert_eq!(counts.iter().sum::<u32>() as usize, n);
    // 9 permutations without the shadow (classified_lists_every_tile_once_and_matches_uber), 4
    // more with fade (fade needs sun and geometry: ± sky, ± spec).
    assert_eq!(rc.d.permutations, 13);
}
