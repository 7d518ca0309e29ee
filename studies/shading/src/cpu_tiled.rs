//! The BF3 tile design on CPU cores ("another processor does the lighting"): worker threads
//! (std threads, `threads` of them) take 64×64 tiles by atomically incrementing a shared tile
//! counter (automatic load balancing); per tile they reconstruct positions, take the min/max
//! view depth of the non-sky pixels, cull every light's sphere against the tile frustum, then
//! (two-level) again per 32×16 sub-tile, and shade 4×4-pixel quads in structure-of-arrays form:
//! 16 lanes per attribute, a light skipped for the whole quad when all 16 attenuations are 0.
//!
//! BF3's further culls, each switchable (all exact: the image is bit-identical with them off):
//! - `cone_cull`: per sub-tile (per tile with one level), a cone bounding the unit normals of
//!   its non-sky pixels (mean axis, largest angle) and a box bounding their view positions; a
//!   light is dropped for the sub-tile when every direction from a point of the box to a point
//!   of the light's source (its position; the segment's bounding ball for a line light) makes
//!   more than 90° + [`CONE_MARGIN`] with every normal of the cone, so N·L ≤ 0 at every pixel.
//! - `spec_skip`: no specular colour in a 4×4 quad → no specular term for it.
//! - `diffuse_skip`: a diffuse-only light (the model's flag) is shaded without the specular
//!   term; off, the term is evaluated and thrown away (the cost the flag saves).
//!
//! `light_loop`: the loop over a quad's lights. [`LightLoop::Bf3`] (the default) is DICE's
//! (slides "SPU Shading - 4x4 Pixel Quads": "Operates on 16 pixels at a time … Unpack source
//! data to Structure of Arrays (SoA) format"; "Algorithmic optimization #4: Branch on 4x4 pixel
//! tile intersection with light based on the calculated lighting attenuation term … if (all 16
//! pixels have an attenuation value of 0 or less) continue on to next light"): a light that
//! passes the whole-quad branch is evaluated on all 16 lanes, N·L, half vector and BF3's
//! energy-conserving specular ("Specular power LUT": `pow(2, 1+smoothness*10)`, normalised by
//! `(specularPower+8)/8`, Sloan & Hoffman) included, with lanes masked by selects instead of
//! per-lane branches; diffuse-only lights and quads without specular albedo take a second,
//! diffuse-only loop ("Adds additional lighting loop"). [`LightLoop::Mfx`] is mfx's earlier
//! loop: the same whole-quad branch, then per-lane early-outs on N·L ≤ 0 and a zero
//! attenuation. Both add the same terms in the same order, and a masked lane adds +0.0, so the
//! images are bit-identical. The slides also list a Fresnel term and a spherical-Gaussian
//! specular (optimisation #6) without their formulas: neither is built (the f64 reference has
//! neither).
//!
//! `classify`: BF3's material classification ("Algorithmic optimization #0 Material
//! Classification: Knowing which materials reside in a tile = choose optimal SPU code
//! permutation that avoids unneeded work … Use SPU shading code permutations!"; "Material +
//! Light Tile permutations. Still need a catch-all übershader"). [`Classify::None`] shades
//! every 4×4 quad with the catch-all übershader: every feature compiled in, with runtime tests
//! (sky lanes and image-edge lanes, the per-quad no-specular test, the light kind's
//! attenuation branches). [`Classify::Materials`] reads each sub-tile's material mask from the
//! G-buffer (sky present, specular albedo present: the city's matte material has none) and its
//! light list's kinds (spot, line present), and shades the sub-tile with the code permutation
//! compiled for exactly that mask ([`perm`]; const generics stand for the deck's `#define`s):
//! a permutation without `HOLES` has no per-lane sky or edge test, one without `SPEC` no
//! specular code, one without `SPOT` or `LINE` no such attenuation. The deck names Skin,
//! Translucent, Metal, Foliage and Emissive shading without giving their formulas, so the only
//! materials mfx shades are the model's (albedo, specular colour, smoothness): their mask bits
//! are the features above. A permutation leaves out only code whose branch the übershader
//! would not take for that sub-tile, so the images are bit-identical.
//!
//! `phase_times`: BF3's per-phase costs (its slides give culling as 1–4 ms of a 40 ms budget),
//! summed over worker threads: cull (tile and sub-tile frusta, the cone cull), unpack (G-buffer
//! reads, position reconstruction, the quads' SoA lanes), shade (the light loop, then the sun)
//! and pack (writing each quad's pixels, then the reorder into rows). Off by default: the clock
//! reads (a few per 4×4 quad) would be in the timed frame.
//!
//! Deterministic for any thread count, bitwise: a pixel's value depends only on its own lanes
//! and on the light list, which keeps light index order; which thread shades a tile does not
//! matter. Output goes to per-tile chunks (no sharing), reordered to rows at the end.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use glam::{Mat4, Vec4};

use super::{sphere_outside, tile_planes, GBuffer, GpuLight, ShadeSetup, AMBIENT, SKY};

/// Angular safety margin (radians) of the normal-cone cull: a light is dropped only when it is
/// at least this much beyond facing away, so f32 rounding in the shading's N·L cannot flip a
/// dropped light's sign (f32 direction errors are ~1e-6 rad at the distances the cull allows).
pub const CONE_MARGIN: f64 = 0.01;

/// The light loop of a 4×4 quad (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightLoop {
    /// DICE's: all 16 lanes per light, masked, after the whole-quad attenuation branch.
    #[default]
    Bf3,
    /// mfx's earlier loop: per-lane early-outs.
    Mfx,
}

impl LightLoop {
    pub const NAMES: &'static [&'static str] = &["bf3", "mfx"];
    pub fn parse(s: &str) -> Option<LightLoop> {
        match s {
            "bf3" => Some(LightLoop::Bf3),
            "mfx" => Some(LightLoop::Mfx),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            LightLoop::Bf3 => "bf3",
            LightLoop::Mfx => "mfx",
        }
    }
}

/// BF3's material classification (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Classify {
    /// The catch-all übershader on every quad (mfx's earlier path).
    #[default]
    None,
    /// Per sub-tile: the material + light mask picks a compiled permutation.
    Materials,
}

impl Classify {
    pub const NAMES: &'static [&'static str] = &["none", "materials"];
    pub fn parse(s: &str) -> Option<Classify> {
        match s {
            "none" => Some(Classify::None),
            "materials" => Some(Classify::Materials),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Classify::None => "none",
            Classify::Materials => "materials",
        }
    }
}

/// Feature bits of a shading permutation: a sub-tile's material + light mask.
pub mod perm {
    /// Some lane of a quad is not shaded: a sky pixel, or outside the image.
    pub const HOLES: u32 = 1;
    /// Some pixel has a specular colour (the specular term is compiled in).
    pub const SPEC: u32 = 2;
    /// Spot lights in the list (the cone attenuation is compiled in).
    pub const SPOT: u32 = 4;
    /// Line lights in the list (the nearest point on the segment is compiled in).
    pub const LINE: u32 = 8;
    /// The catch-all übershader: every feature.
    pub const ALL: u32 = 15;
    /// Number of permutations.
    pub const COUNT: usize = 16;
}

#[derive(Clone, Copy, Debug)]
pub struct CpuOptions {
    /// BF3's material classification (see the module doc).
    pub classify: Classify,
    /// Tests only: shade every sub-tile with this permutation whatever its mask (a wrong one
    /// must change the image: the proof that the mask matters).
    pub force_perm: Option<u32>,
    /// The light loop (see the module doc).
    pub light_loop: LightLoop,
    /// Tile side (BF3: 64).
    pub tile: u32,
    /// Sub-tile size for the second culling level (BF3: 32×16); `None`: one level.
    pub sub: Option<(u32, u32)>,
    pub threads: usize,
    /// Skip a light for a 4×4 quad when all 16 attenuations are 0 (exact).
    pub quad_skip: bool,
    /// BF3's "no specular" fast path, per 4×4 quad: when no pixel of the quad has a specular
    /// colour, the specular term (half vector, power) is not evaluated (exact: it is multiplied
    /// by 0). Not in light-buffer mode (the light buffer does not know the materials).
    pub spec_skip: bool,
    /// BF3's normal-cone cull per sub-tile (exact; see the module doc).
    pub cone_cull: bool,
    /// The cone cull's margin in radians ([`CONE_MARGIN`]); tests make it negative to prove
    /// that a non-conservative cull is caught.
    pub cone_margin: f64,
    /// Skip the specular term of diffuse-only lights (exact: it is 0 by the model).
    pub diffuse_skip: bool,
    /// Keep the per-tile (and per-sub-tile) light lists for inspection.
    pub keep_lists: bool,
    /// Light pre-pass output instead of the shaded colour: RGB = Σ diffuse light (sun
    /// included), A = Σ lum(contrib)·spec_term; sky pixels 0.
    pub light_buffer: bool,
    /// Time the phases ([`Phases`]; see the module doc).
    pub phase_times: bool,
    /// Reorder the tiles into rows on the calling rayon pool's threads (bands of tile rows)
    /// instead of on the calling thread; the same image. The light pre-pass's host work.
    pub parallel_reorder: bool,
}

impl Default for CpuOptions {
    fn default() -> Self {
        CpuOptions {
            classify: Classify::None,
            force_perm: None,
            light_loop: LightLoop::Bf3,
            tile: 64,
            sub: Some((32, 16)),
            threads: 1,
            quad_skip: true,
            spec_skip: true,
            cone_cull: true,
            cone_margin: CONE_MARGIN,
            diffuse_skip: true,
            keep_lists: false,
            light_buffer: false,
            phase_times: false,
            parallel_reorder: false,
        }
    }
}

/// Thread-summed nanoseconds per phase of one frame (with `phase_times`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Phases {
    pub cull: u64,
    pub unpack: u64,
    /// The scene's lights (each (light, quad) evaluation counted in `quad_evals`).
    pub lights: u64,
    /// The sun, once per quad.
    pub sun: u64,
    pub pack: u64,
}

impl Phases {
    fn add(&mut self, o: &Phases) {
        self.cull += o.cull;
        self.unpack += o.unpack;
        self.lights += o.lights;
        self.sun += o.sun;
        self.pack += o.pack;
    }
    /// Shading: the lights and the sun.
    pub fn shade(&self) -> u64 {
        self.lights + self.sun
    }
    pub fn total(&self) -> u64 {
        self.cull + self.unpack + self.shade() + self.pack
    }
}

/// A stopwatch that adds the time since its last lap to a phase (nothing when off).
struct Lap(Option<Instant>);

impl Lap {
    fn start(on: bool) -> Lap {
        Lap(on.then(Instant::now))
    }
    fn lap(&mut self, acc: &mut u64) {
        if let Some(t) = &mut self.0 {
            let now = Instant::now();
            *acc += (now - *t).as_nanos() as u64;
            *t = now;
        }
    }
}

/// A light list of one tile or sub-tile: its pixel rectangle and the lights kept.
#[derive(Clone, Debug)]
pub struct TileList {
    pub rect: [u32; 4],
    pub lights: Vec<u32>,
}

pub struct CpuResult {
    /// Row-major RGBA.
    pub image: Vec<[f32; 4]>,
    /// Lights kept per level-1 tile (row-major tiles).
    pub tile_counts: Vec<u32>,
    /// Wall-clock ms of the lighting (threads start to last tile done).
    pub ms: f64,
    /// Level-1 lists, then (two-level) level-2 lists, when `keep_lists`.
    pub lists: Vec<TileList>,
    pub sub_lists: Vec<TileList>,
    /// Light evaluations skipped by the quad test / done.
    pub quad_skips: u64,
    pub quad_evals: u64,
    /// 4×4 quads shaded without the specular term / all quads shaded.
    pub spec_skipped_quads: u64,
    pub quads: u64,
    /// (light, region) pairs dropped by the normal-cone cull / tested by it.
    pub cone_culls: u64,
    pub cone_tests: u64,
    /// (light, quad) evaluations of diffuse-only lights done without the specular term.
    pub diffuse_skips: u64,
    /// Per-phase times, thread-summed, when `phase_times`.
    pub phases: Option<Phases>,
    /// Sub-tiles (tiles with one level) shaded by each permutation ([`perm`] bits), with
    /// `classify = materials`; all in [`perm::ALL`] (the übershader) without.
    pub perm_regions: [u64; perm::COUNT],
}

struct TileOut {
    pixels: Vec<[f32; 4]>,
    count: u32,
    list: Option<TileList>,
    subs: Vec<TileList>,
    skips: u64,
    evals: u64,
    nospec: u64,
    quads: u64,
    cone_culls: u64,
    cone_tests: u64,
    diffuse_skips: u64,
    phases: Phases,
    perms: [u64; perm::COUNT],
}

/// Lights (with culling spheres for the threshold already in `lights`) on the G-buffer `gb`.
pub fn shade(
    setup: &ShadeSetup,
    gb: &GBuffer,
    lights: &[GpuLight],
    opts: &CpuOptions,
) -> CpuResult {
    let (w, h) = (gb.width, gb.height);
    let t = opts.tile;
    let (tx, ty) = (w.div_ceil(t), h.div_ceil(t));
    let ntiles = (tx * ty) as usize;
    let vfc = setup.view_from_clip_f32();
    let sun = setup
        .sun
        .map(|(d, c)| (d.as_vec3().to_array(), c.as_vec3().to_array()));
    let next = AtomicUsize::new(0);
    let outs: Vec<Mutex<Option<TileOut>>> = (0..ntiles).map(|_| Mutex::new(None)).collect();
    let t0 = Instant::now();
    std::thread::scope(|s| {
        for _ in 0..opts.threads.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= ntiles {
                    break;
                }
                let rect = [
                    (i as u32 % tx) * t,
                    (i as u32 / tx) * t,
                    ((i as u32 % tx) * t + t).min(w),
                    ((i as u32 / tx) * t + t).min(h),
                ];
                let out = shade_tile(&vfc, gb, lights, sun, rect, opts);
                *outs[i].lock().unwrap() = Some(out);
            });
        }
    });
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let mut image = vec![[0.0f32; 4]; (w * h) as usize];
    let mut tile_counts = Vec::with_capacity(ntiles);
    let mut lists = Vec::new();
    let mut sub_lists = Vec::new();
    let (mut quad_skips, mut quad_evals, mut spec_skipped_quads, mut quads) = (0, 0, 0, 0);
    let (mut cone_culls, mut cone_tests, mut diffuse_skips) = (0, 0, 0);
    let mut phases = Phases::default();
    let mut perm_regions = [0u64; perm::COUNT];
    let mut lap = Lap::start(opts.phase_times);
    let outs: Vec<TileOut> = outs
        .into_iter()
        .map(|o| o.into_inner().unwrap().expect("every tile was taken"))
        .collect();
    if opts.parallel_reorder {
        use rayon::prelude::*;
        // One band of tile rows per task: its image rows are its own.
        image
            .par_chunks_mut((w * t) as usize)
            .enumerate()
            .for_each(|(by, band)| {
                for bx in 0..tx {
                    let o = &outs[(by as u32 * tx + bx) as usize];
                    let x0 = bx * t;
                    let tw = (x0 + t).min(w) - x0;
                    for (ry, row) in o.pixels.chunks(tw as usize).enumerate() {
                        let at = ry * w as usize + x0 as usize;
                        band[at..at + tw as usize].copy_from_slice(row);
                    }
                }
            });
    }
    for (i, o) in outs.into_iter().enumerate() {
        if !opts.parallel_reorder {
            let (x0, y0) = ((i as u32 % tx) * t, (i as u32 / tx) * t);
            let tw = (x0 + t).min(w) - x0;
            for (k, p) in o.pixels.iter().enumerate() {
                let (x, y) = (x0 + k as u32 % tw, y0 + k as u32 / tw);
                image[(y * w + x) as usize] = *p;
            }
        }
        tile_counts.push(o.count);
        lists.extend(o.list);
        sub_lists.extend(o.subs);
        quad_skips += o.skips;
        quad_evals += o.evals;
        spec_skipped_quads += o.nospec;
        quads += o.quads;
        cone_culls += o.cone_culls;
        cone_tests += o.cone_tests;
        diffuse_skips += o.diffuse_skips;
        phases.add(&o.phases);
        for (a, b) in perm_regions.iter_mut().zip(o.perms) {
            *a += b;
        }
    }
    // The reorder into rows is packing (on this thread, after the workers).
    lap.lap(&mut phases.pack);
    CpuResult {
        image,
        tile_counts,
        ms,
        lists,
        sub_lists,
        quad_skips,
        quad_evals,
        spec_skipped_quads,
        quads,
        cone_culls,
        cone_tests,
        diffuse_skips,
        phases: opts.phase_times.then_some(phases),
        perm_regions,
    }
}

fn view_pos(vfc: &Mat4, w: u32, h: u32, x: u32, y: u32, d: f32) -> [f32; 3] {
    let ndc_x = (x as f32 + 0.5) * (1.0 / w as f32) * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) * (1.0 / h as f32) * 2.0;
    let v = *vfc * Vec4::new(ndc_x, ndc_y, d, 1.0);
    (v.truncate() / v.w).to_array()
}

fn cull(
    vfc: &Mat4,
    size: (u32, u32),
    rect: [u32; 4],
    zr: (f32, f32),
    lights: &[GpuLight],
    from: &mut dyn Iterator<Item = u32>,
) -> Vec<u32> {
    if zr.0 > zr.1 {
        return Vec::new(); // all sky
    }
    let planes = tile_planes(
        vfc,
        size,
        [
            rect[0] as f32,
            rect[1] as f32,
            rect[2] as f32,
            rect[3] as f32,
        ],
        zr.0,
        zr.1,
    );
    from.filter(|&i| !sphere_outside(&planes, lights[i as usize].cull))
        .collect()
}

#[allow(
    clippy::needless_range_loop,
    reason = "the lane index addresses several SoA arrays at once"
)]
fn shade_tile(
    vfc: &Mat4,
    gb: &GBuffer,
    lights: &[GpuLight],
    sun: Option<([f32; 3], [f32; 3])>,
    rect: [u32; 4],
    opts: &CpuOptions,
) -> TileOut {
    let (w, h) = (gb.width, gb.height);
    let tw = rect[2] - rect[0];
    let th = rect[3] - rect[1];
    let mut lap = Lap::start(opts.phase_times);
    let mut ph = Phases::default();
    // Positions of the tile's pixels, and the depth range of its non-sky pixels.
    let mut pos = vec![[0.0f32; 3]; (tw * th) as usize];
    let mut zr = (f32::MAX, 0.0f32);
    for y in 0..th {
        for x in 0..tw {
            let gi = ((rect[1] + y) * w + rect[0] + x) as usize;
            if gb.is_sky(gi) {
                continue;
            }
            let p = view_pos(vfc, w, h, rect[0] + x, rect[1] + y, gb.depth[gi]);
            pos[(y * tw + x) as usize] = p;
            zr.0 = zr.0.min(-p[2]);
            zr.1 = zr.1.max(-p[2]);
        }
    }
    lap.lap(&mut ph.unpack);
    let list = cull(vfc, (w, h), rect, zr, lights, &mut (0..lights.len() as u32));
    lap.lap(&mut ph.cull);
    let mut out = TileOut {
        pixels: vec![[0.0; 4]; (tw * th) as usize],
        count: list.len() as u32,
        list: opts.keep_lists.then(|| TileList {
            rect,
            lights: list.clone(),
        }),
        subs: Vec::new(),
        skips: 0,
        evals: 0,
        nospec: 0,
        quads: 0,
        cone_culls: 0,
        cone_tests: 0,
        diffuse_skips: 0,
        phases: ph,
        perms: [0; perm::COUNT],
    };
    let (sw, sh) = opts.sub.unwrap_or((tw, th));
    let mut sy = 0;
    while sy < th {
        let mut sx = 0;
        while sx < tw {
            let sub = [sx, sy, (sx + sw).min(tw), (sy + sh).min(th)];
            let sub_list = if opts.sub.is_some() {
                let mut szr = (f32::MAX, 0.0f32);
                for y in sub[1]..sub[3] {
                    for x in sub[0]..sub[2] {
                        let gi = ((rect[1] + y) * w + rect[0] + x) as usize;
                        if !gb.is_sky(gi) {
                            let z = -pos[(y * tw + x) as usize][2];
                            szr.0 = szr.0.min(z);
                            szr.1 = szr.1.max(z);
                        }
                    }
                }
                let abs = [
                    rect[0] + sub[0],
                    rect[1] + sub[1],
                    rect[0] + sub[2],
                    rect[1] + sub[3],
                ];
                let l = cull(vfc, (w, h), abs, szr, lights, &mut list.iter().copied());
                if opts.keep_lists {
                    out.subs.push(TileList {
                        rect: abs,
                        lights: l.clone(),
                    });
                }
                l
            } else {
                list.clone()
            };
            let sub_list = if opts.cone_cull {
                let (kept, tested) =
                    cone_cull(gb, lights, rect, tw, sub, &pos, opts.cone_margin, sub_list);
                out.cone_tests += tested;
                out.cone_culls += tested - kept.len() as u64;
                kept
            } else {
                sub_list
            };
            lap.lap(&mut out.phases.cull);
            // The permutation: the übershader, or the sub-tile's material + light mask.
            let p = match (opts.force_perm, opts.classify) {
                // Lanes outside the image stay masked (their reads would leave the buffers).
                (Some(p), _) => p & perm::ALL | edge_holes(sub),
                (None, Classify::None) => perm::ALL,
                (None, Classify::Materials) => {
                    mask(gb, lights, rect, sub, &sub_list, opts.light_buffer)
                }
            };
            out.perms[p as usize] += 1;
            lap.lap(&mut out.phases.unpack);
            let quad = QUAD_PERMS[p as usize];
            // 4×4 quads of the sub-tile.
            let mut qy = sub[1];
            while qy < sub[3] {
                let mut qx = sub[0];
                while qx < sub[2] {
                    quad(
                        gb,
                        lights,
                        sun,
                        &sub_list,
                        rect,
                        tw,
                        [qx, qy],
                        [sub[2], sub[3]],
                        &pos,
                        opts.quad_skip,
                        opts.spec_skip && !opts.light_buffer,
                        opts.diffuse_skip,
                        opts.light_buffer,
                        opts.light_loop,
                        &mut out,
                        &mut lap,
                    );
                    qx += 4;
                }
                qy += 4;
            }
            sx += sw;
        }
        sy += sh;
    }
    out
}

/// BF3's tile material mask of sub-tile `sub` (tile-relative) of tile `rect`, from the
/// G-buffer (sky, specular colour) and its light list (kinds): the [`perm`] bits it needs. The
/// light buffer stores specular luminance whatever the material: `SPEC` always.
fn mask(
    gb: &GBuffer,
    lights: &[GpuLight],
    rect: [u32; 4],
    sub: [u32; 4],
    list: &[u32],
    light_buffer: bool,
) -> u32 {
    let mut m = edge_holes(sub);
    if light_buffer {
        m |= perm::SPEC;
    }
    for y in sub[1]..sub[3] {
        let row = ((rect[1] + y) * gb.width + rect[0]) as usize;
        for gi in row + sub[0] as usize..row + sub[2] as usize {
            if gb.is_sky(gi) {
                m |= perm::HOLES;
            } else if gb.spec[gi] != [0.0; 3] {
                m |= perm::SPEC;
            }
        }
    }
    for &li in list {
        m |= match lights[li as usize].dir_kind[3] as u32 {
            1 => perm::SPOT,
            2 => perm::LINE,
            _ => 0,
        };
    }
    m
}

/// [`perm::HOLES`] when a quad of the sub-tile reaches past it (an image edge that is not a
/// multiple of 4): lanes outside the image.
fn edge_holes(sub: [u32; 4]) -> u32 {
    if !(sub[2] - sub[0]).is_multiple_of(4) || !(sub[3] - sub[1]).is_multiple_of(4) {
        perm::HOLES
    } else {
        0
    }
}

/// A quad shader: one permutation of [`shade_quad`].
type QuadFn = fn(
    &GBuffer,
    &[GpuLight],
    Option<([f32; 3], [f32; 3])>,
    &[u32],
    [u32; 4],
    u32,
    [u32; 2],
    [u32; 2],
    &[[f32; 3]],
    bool,
    bool,
    bool,
    bool,
    LightLoop,
    &mut TileOut,
    &mut Lap,
);

/// Every permutation, compiled (index: its [`perm`] bits).
const QUAD_PERMS: [QuadFn; perm::COUNT] = [
    shade_quad::<0>,
    shade_quad::<1>,
    shade_quad::<2>,
    shade_quad::<3>,
    shade_quad::<4>,
    shade_quad::<5>,
    shade_quad::<6>,
    shade_quad::<7>,
    shade_quad::<8>,
    shade_quad::<9>,
    shade_quad::<10>,
    shade_quad::<11>,
    shade_quad::<12>,
    shade_quad::<13>,
    shade_quad::<14>,
    shade_quad::<15>,
];

/// One 4×4 quad in SoA lanes: lane k is pixel (q.x + k%4, q.y + k/4) of the tile. `P`: the
/// features compiled in ([`perm`]); [`perm::ALL`] is the übershader.
#[allow(
    clippy::too_many_arguments,
    clippy::needless_range_loop,
    reason = "a hot SoA kernel: its inputs passed apart, lanes indexed across arrays"
)]
fn shade_quad<const P: u32>(
    gb: &GBuffer,
    lights: &[GpuLight],
    sun: Option<([f32; 3], [f32; 3])>,
    list: &[u32],
    rect: [u32; 4],
    tw: u32,
    q: [u32; 2],
    end: [u32; 2],
    pos: &[[f32; 3]],
    quad_skip: bool,
    spec_skip: bool,
    diffuse_skip: bool,
    light_buffer: bool,
    light_loop: LightLoop,
    out: &mut TileOut,
    lap: &mut Lap,
) {
    const N: usize = 16;
    let mut active = [false; N];
    let (mut px, mut py, mut pz) = ([0f32; N], [0f32; N], [0f32; N]);
    let (mut nx, mut ny, mut nz) = ([0f32; N], [0f32; N], [0f32; N]);
    let (mut vx, mut vy, mut vz) = ([0f32; N], [0f32; N], [0f32; N]);
    let (mut pw, mut norm) = ([0f32; N], [0f32; N]);
    let mut gidx = [0usize; N];
    for k in 0..N {
        let (x, y) = (q[0] + k as u32 % 4, q[1] + k as u32 / 4);
        if P & perm::HOLES != 0 && (x >= end[0] || y >= end[1]) {
            continue;
        }
        let gi = ((rect[1] + y) * gb.width + rect[0] + x) as usize;
        gidx[k] = gi;
        if P & perm::HOLES != 0 && gb.is_sky(gi) {
            continue;
        }
        active[k] = true;
        let p = pos[(y * tw + x) as usize];
        (px[k], py[k], pz[k]) = (p[0], p[1], p[2]);
        let n = gb.normal[gi];
        (nx[k], ny[k], nz[k]) = (n[0], n[1], n[2]);
        let il = 1.0 / (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        (vx[k], vy[k], vz[k]) = (-p[0] * il, -p[1] * il, -p[2] * il);
        pw[k] = (1.0 + 10.0 * n[3]).exp2();
        norm[k] = (pw[k] + 8.0) / 8.0;
    }
    let no_spec = P & perm::SPEC == 0
        || (spec_skip && (0..N).all(|k| !active[k] || gb.spec[gidx[k]] == [0.0; 3]));
    lap.lap(&mut out.phases.unpack);
    if active.iter().any(|&a| a) {
        out.quads += 1;
        out.nospec += no_spec as u64;
    }
    let mut diff = [[0f32; 3]; N];
    let mut spec = [[0f32; 4]; N];
    let mut att = [0f32; N];
    let (mut lx, mut ly, mut lz) = ([0f32; N], [0f32; N], [0f32; N]);
    // `d_only`: the light is diffuse-only (specular term 0 by the model). `no_spec`
    // (quad without specular colour) or `diffuse_skip` skip the evaluation; otherwise a
    // diffuse-only light's term is evaluated and thrown away (the cost the skip saves).
    let add = |k: usize,
               l: [f32; 3],
               color: [f32; 3],
               a: f32,
               d_only: bool,
               diff: &mut [[f32; 3]; N],
               spec: &mut [[f32; 4]; N]| {
        let ndl = nx[k] * l[0] + ny[k] * l[1] + nz[k] * l[2];
        if ndl <= 0.0 || a <= 0.0 {
            return;
        }
        let s = a * ndl;
        let c = [color[0] * s, color[1] * s, color[2] * s];
        if no_spec || (d_only && diffuse_skip) {
            for j in 0..3 {
                diff[k][j] += c[j];
            }
            return;
        }
        let (hx, hy, hz) = (l[0] + vx[k], l[1] + vy[k], l[2] + vz[k]);
        let hl = 1.0 / (hx * hx + hy * hy + hz * hz).sqrt();
        let ndh = ((nx[k] * hx + ny[k] * hy + nz[k] * hz) * hl).max(0.0);
        let st = if ndh > 0.0 {
            norm[k] * ndh.powf(pw[k])
        } else {
            0.0
        };
        if d_only {
            std::hint::black_box(st);
            for j in 0..3 {
                diff[k][j] += c[j];
            }
            return;
        }
        for j in 0..3 {
            diff[k][j] += c[j];
            spec[k][j] += c[j] * st;
        }
        spec[k][3] += (c[0] * 0.2126 + c[1] * 0.7152 + c[2] * 0.0722) * st;
    };
    for &li in list {
        let l = &lights[li as usize];
        let kind = l.dir_kind[3] as u32;
        let r2 = l.pos_range[3] * l.pos_range[3];
        let mut any = false;
        // SoA attenuation of all 16 lanes (the part that vectorises).
        for k in 0..N {
            let (mut qx, mut qy, mut qz) = (l.pos_range[0], l.pos_range[1], l.pos_range[2]);
            if P & perm::LINE != 0 && kind == 2 {
                let t = ((px[k] - qx) * l.dir_kind[0]
                    + (py[k] - qy) * l.dir_kind[1]
                    + (pz[k] - qz) * l.dir_kind[2])
                    .clamp(0.0, l.extra[0]);
                qx += l.dir_kind[0] * t;
                qy += l.dir_kind[1] * t;
                qz += l.dir_kind[2] * t;
            }
            let (dx, dy, dz) = (qx - px[k], qy - py[k], qz - pz[k]);
            let d2 = dx * dx + dy * dy + dz * dz;
            let ok = active[k] && d2 < r2 && d2 >= 1e-12;
            let d = d2.sqrt();
            let id = 1.0 / d;
            (lx[k], ly[k], lz[k]) = (dx * id, dy * id, dz * id);
            let x = 1.0 - d2 / r2;
            let mut a = x * x;
            if P & perm::SPOT != 0 && kind == 1 {
                let c = l.color_cos[3];
                let cosang =
                    -(lx[k] * l.dir_kind[0] + ly[k] * l.dir_kind[1] + lz[k] * l.dir_kind[2]);
                let sf = ((cosang - c) / (1.0 - c)).clamp(0.0, 1.0);
                a *= sf * sf;
            }
            att[k] = if ok { a } else { 0.0 };
            any |= att[k] > 0.0;
        }
        if quad_skip && !any {
            out.skips += 1;
            continue;
        }
        out.evals += 1;
        let d_only = l.diffuse_only();
        out.diffuse_skips += (d_only && diffuse_skip && !no_spec) as u64;
        let color = [l.color_cos[0], l.color_cos[1], l.color_cos[2]];
        if light_loop == LightLoop::Bf3 {
            bf3_light(
                &BfLanes {
                    n: [&nx, &ny, &nz],
                    v: [&vx, &vy, &vz],
                    pw: &pw,
                    norm: &norm,
                },
                [&lx, &ly, &lz],
                &att,
                color,
                no_spec || (d_only && diffuse_skip),
                d_only,
                &mut diff,
                &mut spec,
            );
            continue;
        }
        for k in 0..N {
            if att[k] > 0.0 {
                add(
                    k,
                    [lx[k], ly[k], lz[k]],
                    color,
                    att[k],
                    d_only,
                    &mut diff,
                    &mut spec,
                );
            }
        }
    }
    lap.lap(&mut out.phases.lights);
    if let Some((d, c)) = sun {
        for k in 0..N {
            if active[k] {
                add(k, d, c, 1.0, false, &mut diff, &mut spec);
            }
        }
    }
    lap.lap(&mut out.phases.sun);
    for k in 0..N {
        let (x, y) = (q[0] + k as u32 % 4, q[1] + k as u32 / 4);
        if P & perm::HOLES != 0 && (x >= end[0] || y >= end[1]) {
            continue;
        }
        let gi = gidx[k];
        let o = &mut out.pixels[(y * tw + x) as usize];
        if light_buffer {
            *o = if active[k] {
                [diff[k][0], diff[k][1], diff[k][2], spec[k][3]]
            } else {
                [0.0; 4]
            };
            continue;
        }
        if !active[k] {
            *o = [SKY[0], SKY[1], SKY[2], 1.0];
            continue;
        }
        let a = gb.albedo[gi];
        let s = gb.spec[gi];
        for j in 0..3 {
            o[j] = a[j] * (diff[k][j] + AMBIENT[j]) + s[j] * spec[k][j];
        }
        o[3] = 1.0;
    }
    lap.lap(&mut out.phases.pack);
}

/// A quad's SoA lanes that BF3's light loop reads.
struct BfLanes<'a> {
    n: [&'a [f32; 16]; 3],
    v: [&'a [f32; 16]; 3],
    pw: &'a [f32; 16],
    norm: &'a [f32; 16],
}

/// One light on all 16 lanes of a quad, BF3's way: no per-lane branch; a lane outside the
/// light (attenuation 0) or facing away (N·L ≤ 0) is masked by selects and adds +0.0, which
/// leaves its sums bit-identical to the per-lane loop's. `diffuse_only`: BF3's second loop
/// (no specular evaluation). `d_only` without it: the specular term is evaluated on every lane
/// and thrown away (the cost the diffuse-only skip saves).
#[allow(
    clippy::too_many_arguments,
    clippy::needless_range_loop,
    reason = "a hot SoA kernel: its inputs passed apart, lanes indexed across arrays"
)]
#[inline(never)]
fn bf3_light(
    q: &BfLanes<'_>,
    l: [&[f32; 16]; 3],
    att: &[f32; 16],
    color: [f32; 3],
    diffuse_only: bool,
    d_only: bool,
    diff: &mut [[f32; 3]; 16],
    spec: &mut [[f32; 4]; 16],
) {
    const N: usize = 16;
    let [nx, ny, nz] = q.n;
    let [lx, ly, lz] = l;
    let mut s = [0f32; N];
    let mut lit = [false; N];
    for k in 0..N {
        let ndl = nx[k] * lx[k] + ny[k] * ly[k] + nz[k] * lz[k];
        lit[k] = ndl > 0.0 && att[k] > 0.0;
        s[k] = if lit[k] { att[k] * ndl } else { 0.0 };
    }
    if diffuse_only {
        for k in 0..N {
            for j in 0..3 {
                diff[k][j] += color[j] * s[k];
            }
        }
        return;
    }
    let [vx, vy, vz] = q.v;
    let mut st = [0f32; N];
    for k in 0..N {
        let (hx, hy, hz) = (lx[k] + vx[k], ly[k] + vy[k], lz[k] + vz[k]);
        let hl = 1.0 / (hx * hx + hy * hy + hz * hz).sqrt();
        let ndh = ((nx[k] * hx + ny[k] * hy + nz[k] * hz) * hl).max(0.0);
        let e = q.norm[k] * ndh.powf(q.pw[k]);
        st[k] = if lit[k] && ndh > 0.0 { e } else { 0.0 };
    }
    if d_only {
        std::hint::black_box(&st);
        for k in 0..N {
            for j in 0..3 {
                diff[k][j] += color[j] * s[k];
            }
        }
        return;
    }
    for k in 0..N {
        let c = [color[0] * s[k], color[1] * s[k], color[2] * s[k]];
        for j in 0..3 {
            diff[k][j] += c[j];
            spec[k][j] += c[j] * st[k];
        }
        spec[k][3] += (c[0] * 0.2126 + c[1] * 0.7152 + c[2] * 0.0722) * st[k];
    }
}

/// BF3's normal-cone cull of one region `sub` (tile-relative) of tile `rect`: keeps the lights
/// of `list` that some pixel of it may face (see the module doc); returns them and how many
/// were tested. f64 throughout, on the same f32 positions and normals the shading reads.
#[allow(
    clippy::too_many_arguments,
    clippy::needless_range_loop,
    reason = "a hot SoA kernel: its inputs passed apart, lanes indexed across arrays"
)]
fn cone_cull(
    gb: &GBuffer,
    lights: &[GpuLight],
    rect: [u32; 4],
    tw: u32,
    sub: [u32; 4],
    pos: &[[f32; 3]],
    margin: f64,
    list: Vec<u32>,
) -> (Vec<u32>, u64) {
    let tested = list.len() as u64;
    let (mut sum, mut lo, mut hi) = ([0f64; 3], [f64::MAX; 3], [f64::MIN; 3]);
    let mut normals = Vec::with_capacity(((sub[2] - sub[0]) * (sub[3] - sub[1])) as usize);
    for y in sub[1]..sub[3] {
        for x in sub[0]..sub[2] {
            let gi = ((rect[1] + y) * gb.width + rect[0] + x) as usize;
            if gb.is_sky(gi) {
                continue;
            }
            let p = pos[(y * tw + x) as usize];
            for j in 0..3 {
                lo[j] = lo[j].min(p[j] as f64);
                hi[j] = hi[j].max(p[j] as f64);
            }
            let n = gb.normal[gi];
            let n = [n[0] as f64, n[1] as f64, n[2] as f64];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if len == 0.0 {
                continue; // N·L = 0 exactly: this pixel takes no light
            }
            let u = [n[0] / len, n[1] / len, n[2] / len];
            for j in 0..3 {
                sum[j] += u[j];
            }
            normals.push(u);
        }
    }
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let sl = dot(sum, sum).sqrt();
    if normals.is_empty() || sl < 1e-6 * normals.len() as f64 {
        return (list, tested);
    }
    let axis = [sum[0] / sl, sum[1] / sl, sum[2] / sl];
    let cos_t = normals.iter().map(|&u| dot(u, axis)).fold(1.0f64, f64::min);
    let theta = cos_t.clamp(-1.0, 1.0).acos();
    if theta >= std::f64::consts::FRAC_PI_2 {
        return (list, tested);
    }
    let bc = [
        0.5 * (lo[0] + hi[0]),
        0.5 * (lo[1] + hi[1]),
        0.5 * (lo[2] + hi[2]),
    ];
    let half = [hi[0] - bc[0], hi[1] - bc[1], hi[2] - bc[2]];
    let hb = dot(half, half).sqrt();
    let bcl = dot(bc, bc).sqrt();
    let kept = list
        .into_iter()
        .filter(|&i| {
            let l = &lights[i as usize];
            let (mut cs, mut rs) = (
                [
                    l.pos_range[0] as f64,
                    l.pos_range[1] as f64,
                    l.pos_range[2] as f64,
                ],
                0.0,
            );
            if l.dir_kind[3] as u32 == 2 {
                let h = 0.5 * l.extra[0] as f64;
                for j in 0..3 {
                    cs[j] += l.dir_kind[j] as f64 * h;
                }
                rs = h * 1.001; // the f32 direction is unit only up to rounding
            }
            let m = [cs[0] - bc[0], cs[1] - bc[1], cs[2] - bc[2]];
            let ml = dot(m, m).sqrt();
            let rho = rs + hb;
            // Too close to judge directions in f32: keep.
            if ml - rho <= 1e-4 * (dot(cs, cs).sqrt() + bcl + 1.0) {
                return true;
            }
            let phi = (rho / ml).asin();
            let alpha = (dot(axis, m) / ml).clamp(-1.0, 1.0).acos();
            alpha - theta - phi <= std::f64::consts::FRAC_PI_2 + margin
        })
        .collect();
    (kept, tested)
}
