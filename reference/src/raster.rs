//! The f64 rasterizer behind [`super::FragmentLists`].

use glam::{DMat4, DVec4};
use rayon::prelude::*;
use scenarios::Scene;

use super::FragmentLists;

/// Sub-pixel precision of vertex positions: Vulkan's `subPixelPrecisionBits` is 8 on the
/// drivers we target (NVIDIA, lavapipe), and snapping alike makes coverage decisions identical.
pub const SUBPIXEL_BITS: u32 = 8;

/// Rows per parallel strip.
const STRIP: u32 = 8;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefFragment {
    /// Window depth z/w in [0, 1] (reversed-Z: 1 at the near plane).
    pub depth: f64,
    /// Linear view-space distance along the view axis (positive in front of the eye).
    pub view_z: f64,
    /// Straight RGBA.
    pub color: [f64; 4],
    /// Interpolated (not renormalised) world-space normal.
    pub normal: [f64; 3],
    pub object_id: u32,
    pub front_facing: bool,
    /// Triangle index in the scene's index buffer (submission order).
    pub prim: u32,
    /// |∂depth/∂x| + |∂depth/∂y| of the fragment's triangle (window depth per pixel, on the
    /// snapped vertices): how far a GPU's depth of this fragment may sit from `depth` when it
    /// sets depth up from the unsnapped vertices (lavapipe does; ≤ 1/512 px per coordinate,
    /// times this, to first order). A sliver seen edge-on has a large one.
    pub depth_slope: f32,
}

/// A vertex after projection, carrying what is interpolated.
#[derive(Clone, Copy)]
struct ClipVert {
    clip: DVec4,
    /// color rgba, normal xyz, view_z: interpolated linearly in clip space when clipping.
    attrs: [f64; 8],
}

/// Screen-space vertex ready for edge functions.
#[derive(Clone, Copy)]
struct ScreenVert {
    x: f64,
    y: f64,
    z: f64,
    inv_w: f64,
    attrs: [f64; 8],
}

struct Tri {
    v: [ScreenVert; 3],
    /// |∂z/∂x| + |∂z/∂y| of window depth ([`RefFragment::depth_slope`]).
    depth_slope: f32,
    area: f64,
    front: bool,
    prim: u32,
    object_id: u32,
    /// The snapped vertices' bounds (min x, max x, min y, max y): each sampling's pixel box.
    bounds: [f64; 4],
    /// Pixels any sampling may cover: the union of the samplings' boxes.
    y0: u32,
    y1: u32,
    x0: u32,
    x1: u32,
}

/// The pixels `[x0, x1] × [y0, y1]` whose samples, at offsets within `[omin, omax]`, may lie in
/// the triangle bounds `b` (min x, max x, min y, max y) of a `w` × `h` image; `None` when none.
fn pixel_box(b: [f64; 4], omin: (f64, f64), omax: (f64, f64), w: f64, h: f64) -> Option<[u32; 4]> {
    let x0 = (b[0] - omax.0).ceil().max(0.0);
    let x1 = (b[1] - omin.0).floor().min(w - 1.0);
    let y0 = (b[2] - omax.1).ceil().max(0.0);
    let y1 = (b[3] - omin.1).floor().min(h - 1.0);
    if x0 > x1 || y0 > y1 {
        return None;
    }
    Some([x0 as u32, x1 as u32, y0 as u32, y1 as u32])
}

/// Guard band half-width in NDC units (viewports are ±1): see `rasterize`.
const GUARD: f64 = 1024.0;

fn lerp(a: &ClipVert, b: &ClipVert, t: f64) -> ClipVert {
    let attrs = std::array::from_fn(|i| a.attrs[i] + (b.attrs[i] - a.attrs[i]) * t);
    ClipVert {
        clip: a.clip + (b.clip - a.clip) * t,
        attrs,
    }
}

/// Sutherland–Hodgman against one plane `d(v) >= 0`.
fn clip_plane(poly: &[ClipVert], d: impl Fn(&DVec4) -> f64) -> Vec<ClipVert> {
    let mut out = Vec::with_capacity(poly.len() + 2);
    for i in 0..poly.len() {
        let a = &poly[i];
        let b = &poly[(i + 1) % poly.len()];
        let (da, db) = (d(&a.clip), d(&b.clip));
        if da >= 0.0 {
            out.push(*a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(lerp(a, b, da / (da - db)));
        }
    }
    out
}

/// Clips to `sign·c[axis] ≤ GUARD·w`. The new vertices are put exactly on the plane: lerping
/// between endpoints at ±1e20 cancels, and would scatter them by ~1e4 (back into the view).
fn clip_guard(poly: &[ClipVert], axis: usize, sign: f64) -> Vec<ClipVert> {
    let d = |c: &DVec4| GUARD * c.w - sign * c[axis];
    let mut out = Vec::with_capacity(poly.len() + 2);
    for i in 0..poly.len() {
        let a = &poly[i];
        let b = &poly[(i + 1) % poly.len()];
        let (da, db) = (d(&a.clip), d(&b.clip));
        if da >= 0.0 {
            out.push(*a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let mut v = lerp(a, b, da / (da - db));
            v.clip[axis] = sign * GUARD * v.clip.w;
            out.push(v);
        }
    }
    out
}

/// |∂z/∂x| + |∂z/∂y| of window depth over the positively wound screen triangle `t` of twice
/// the area `area` (the derivatives of [`fragment`]'s barycentric interpolation).
fn depth_slope(t: &[ScreenVert; 3], area: f64) -> f32 {
    let [a, b, c] = t;
    let zx = -((c.y - b.y) * a.z + (a.y - c.y) * b.z + (b.y - a.y) * c.z) / area;
    let zy = ((c.x - b.x) * a.z + (a.x - c.x) * b.z + (b.x - a.x) * c.z) / area;
    (zx.abs() + zy.abs()) as f32
}

fn snap(v: f64) -> f64 {
    let s = (1u32 << SUBPIXEL_BITS) as f64;
    (v * s).round() / s
}

/// Twice the signed area in screen space (y down), and the edge function of edge a→b at p.
fn edge(a: (f64, f64), b: (f64, f64), p: (f64, f64)) -> f64 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

/// Top-left rule for triangles wound so that `edge(v0, v1, v2) > 0` in y-down screen space:
/// a top edge is horizontal going right, a left edge goes up.
fn top_left(a: (f64, f64), b: (f64, f64)) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    (dy == 0.0 && dx > 0.0) || dy < 0.0
}

/// Where one raster pass samples: the coverage sample positions and the point attributes and
/// depth are evaluated at, as offsets within a pixel (x right, y down, pixel corner = (0, 0)).
#[derive(Clone, Copy, Debug)]
pub struct Sampling<'a> {
    /// Coverage samples; a fragment is emitted where any of them is covered, with bit `i` of
    /// its mask set for sample `i`.
    pub coverage: &'a [(f64, f64)],
    /// Where attributes are interpolated (extrapolated when the point lies outside the
    /// triangle, as a GPU does for a pixel-rate fragment that covers only some samples).
    pub attributes: (f64, f64),
    /// Where window depth is interpolated; `None`: at `attributes`.
    pub depth: Option<(f64, f64)>,
}

/// The pixel centre: one sample, attributes there (the single-sample reference).
pub const CENTRE: Sampling<'static> = Sampling {
    coverage: &[(0.5, 0.5)],
    attributes: (0.5, 0.5),
    depth: None,
};

/// Projects, clips and snaps every triangle, then rasterizes row strips in parallel.
pub fn rasterize(scene: &Scene, width: u32, height: u32) -> FragmentLists {
    rasterize_with(scene, width, height, CENTRE).0
}

/// [`rasterize`] at the sample positions and attribute point of `sampling`: the fragment lists
/// and, parallel to `frags`, each fragment's coverage mask (bit i: `sampling.coverage[i]`).
/// With [`CENTRE`] the lists are exactly those of [`rasterize`].
pub fn rasterize_with(
    scene: &Scene,
    width: u32,
    height: u32,
    sampling: Sampling<'_>,
) -> (FragmentLists, Vec<u32>) {
    rasterize_each(scene, width, height, &[sampling])
        .pop()
        .expect("one sampling, one result")
}

/// One sampling's fragments of one strip, nearest first per pixel.
struct StripLists {
    /// Fragments per pixel of the strip (row-major).
    counts: Vec<u32>,
    frags: Vec<RefFragment>,
    masks: Vec<u32>,
}

/// [`rasterize_with`] for several samplings in one traversal: every triangle is projected,
/// clipped and set up once, and each pixel of its box tests every sampling's positions in the
/// same loop. Element i is exactly `rasterize_with(scene, width, height, samplings[i])` (the
/// same coverage decisions, the same f64 arithmetic per sampling, the same order in every
/// list). It holds every sampling's lists at once and saves no time where fragments, not
/// triangles, are the work (1024² shells, one thread: ~10 % more CPU than a pass per position),
/// so the multisampled truth makes one pass per position.
pub fn rasterize_each(
    scene: &Scene,
    width: u32,
    height: u32,
    samplings: &[Sampling<'_>],
) -> Vec<(FragmentLists, Vec<u32>)> {
    for sampling in samplings {
        assert!(
            !sampling.coverage.is_empty() && sampling.coverage.len() <= 32,
            "1 to 32 coverage samples, not {}",
            sampling.coverage.len()
        );
    }
    // Pixels whose samples may lie in [min, max]: pixel x samples x + o for each offset o.
    let offset_bounds: Vec<((f64, f64), (f64, f64))> = samplings
        .iter()
        .map(|sampling| {
            sampling.coverage.iter().fold(
                (
                    (f64::INFINITY, f64::INFINITY),
                    (f64::NEG_INFINITY, f64::NEG_INFINITY),
                ),
                |(lo, hi), &(x, y)| ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y))),
            )
        })
        .collect();
    let aspect = width as f64 / height as f64;
    let m: DMat4 = scene.camera.clip_from_world_gpu(aspect).as_dmat4();
    let view: DMat4 = scene.camera.view().as_mat4().as_dmat4();
    let mesh = &scene.mesh;
    let (w, h) = (width as f64, height as f64);

    let tris: Vec<Tri> = mesh
        .indices
        .par_chunks_exact(3)
        .enumerate()
        .flat_map_iter(|(prim, idx)| {
            let verts: Vec<ClipVert> = idx
                .iter()
                .map(|&i| {
                    let i = i as usize;
                    let p = glam::Vec3::from(mesh.positions[i]).as_dvec3().extend(1.0);
                    let c = mesh.colors[i];
                    let n = mesh.normals[i];
                    let view_z = -(view * p).z;
                    ClipVert {
                        clip: m * p,
                        attrs: [
                            c[0] as f64,
                            c[1] as f64,
                            c[2] as f64,
                            c[3] as f64,
                            n[0] as f64,
                            n[1] as f64,
                            n[2] as f64,
                            view_z,
                        ],
                    }
                })
                .collect();
            let object_id = mesh.object_ids[idx[0] as usize];
            // Vulkan clips to 0 ≤ z ≤ w (x and y are handled by the guard band and scissor).
            let poly = clip_plane(&verts, |c| c.z);
            let poly = if poly.len() >= 3 {
                clip_plane(&poly, |c| c.w - c.z)
            } else {
                poly
            };
            // Guard band: a vertex far outside the view (|x| or |y| ≫ w, e.g. at 1e20) makes
            // the edge functions cancel catastrophically even in f64, and the barycentrics (and
            // so depth and attributes) come out as garbage or NaN. Clipping x and y to ±GUARD·w
            // first changes no covered pixel (the planes lie far outside the viewport) and keeps
            // screen coordinates within ~1e6 px. Only triangles that need it are clipped, so the
            // snapped vertices of every other triangle are untouched.
            let outside = |v: &ClipVert| {
                v.clip.x.abs() > GUARD * v.clip.w || v.clip.y.abs() > GUARD * v.clip.w
            };
            let poly = if poly.len() >= 3 && poly.iter().any(outside) {
                let p = clip_guard(&poly, 0, 1.0);
                let p = clip_guard(&p, 0, -1.0);
                let p = clip_guard(&p, 1, 1.0);
                clip_guard(&p, 1, -1.0)
            } else {
                poly
            };
            let mut out = Vec::new();
            if poly.len() < 3 {
                return out.into_iter();
            }
            let sv: Vec<ScreenVert> = poly
                .iter()
                .map(|v| {
                    let inv_w = 1.0 / v.clip.w;
                    ScreenVert {
                        x: snap((v.clip.x * inv_w * 0.5 + 0.5) * w),
                        y: snap((0.5 - v.clip.y * inv_w * 0.5) * h),
                        z: v.clip.z * inv_w,
                        inv_w,
                        attrs: v.attrs,
                    }
                })
                .collect();
            for k in 1..sv.len() - 1 {
                let mut t = [sv[0], sv[k], sv[k + 1]];
                let area = edge((t[0].x, t[0].y), (t[1].x, t[1].y), (t[2].x, t[2].y));
                if area == 0.0 {
                    continue; // degenerate after snapping: the GPU draws nothing either
                }
                // Counter-clockwise in NDC (y up) is front-facing (wgpu's default); y-down flips the sign.
                let front = area < 0.0;
                if area < 0.0 {
                    t.swap(1, 2);
                }
                let xs = [t[0].x, t[1].x, t[2].x];
                let ys = [t[0].y, t[1].y, t[2].y];
                let bounds = [
                    xs.iter().cloned().fold(f64::INFINITY, f64::min),
                    xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
                    ys.iter().cloned().fold(f64::INFINITY, f64::min),
                    ys.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
                ];
                // Pixels with a sample (i + o) inside the bounds (the centres, i + 0.5, when
                // the one sample is the centre), for any sampling.
                let union = offset_bounds
                    .iter()
                    .filter_map(|&(omin, omax)| pixel_box(bounds, omin, omax, w, h))
                    .reduce(|a, b| {
                        [
                            a[0].min(b[0]),
                            a[1].max(b[1]),
                            a[2].min(b[2]),
                            a[3].max(b[3]),
                        ]
                    });
                let Some([x0, x1, y0, y1]) = union else {
                    continue;
                };
                out.push(Tri {
                    depth_slope: depth_slope(&t, area.abs()),
                    v: t,
                    area: area.abs(),
                    front,
                    prim: prim as u32,
                    object_id,
                    bounds,
                    x0,
                    x1,
                    y0,
                    y1,
                });
            }
            out.into_iter()
        })
        .collect();

    // Bin triangles into row strips.
    let nstrips = height.div_ceil(STRIP) as usize;
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nstrips];
    for (i, t) in tris.iter().enumerate() {
        for s in (t.y0 / STRIP)..=(t.y1 / STRIP) {
            bins[s as usize].push(i as u32);
        }
    }
    let reversed = scene.camera.reversed_z;
    let n = samplings.len();

    // Per strip, per sampling: its fragments, nearest first per pixel.
    let strips: Vec<Vec<StripLists>> = bins
        .par_iter()
        .enumerate()
        .map(|(s, bin)| {
            let row0 = s as u32 * STRIP;
            let rows = STRIP.min(height - row0);
            // Per sampling, (pixel in the strip, fragment, mask) in submission order.
            let mut pushed: Vec<Vec<(u32, RefFragment, u32)>> = vec![Vec::new(); n];
            let mut boxes: Vec<Option<[u32; 4]>> = vec![None; n];
            for &ti in bin {
                let t = &tris[ti as usize];
                let p = [
                    (t.v[0].x, t.v[0].y),
                    (t.v[1].x, t.v[1].y),
                    (t.v[2].x, t.v[2].y),
                ];
                let tl = top_left_edges(p);
                for (b, &(omin, omax)) in boxes.iter_mut().zip(&offset_bounds) {
                    *b = pixel_box(t.bounds, omin, omax, w, h);
                }
                for y in t.y0.max(row0)..=t.y1.min(row0 + rows - 1) {
                    for x in t.x0..=t.x1 {
                        for (k, sampling) in samplings.iter().enumerate() {
                            // Only the pixels this sampling alone would visit.
                            let Some([bx0, bx1, by0, by1]) = boxes[k] else {
                                continue;
                            };
                            if x < bx0 || x > bx1 || y < by0 || y > by1 {
                                continue;
                            }
                            let mut mask = 0u32;
                            for (i, &(ox, oy)) in sampling.coverage.iter().enumerate() {
                                if covers(p, tl, (x as f64 + ox, y as f64 + oy)) {
                                    mask |= 1 << i;
                                }
                            }
                            if mask == 0 {
                                continue;
                            }
                            let f = fragment(t, p, sampling, x, y);
                            pushed[k].push(((y - row0) * width + x, f, mask));
                        }
                    }
                }
            }
            pushed
                .into_iter()
                .map(|pushed| sort_strip(pushed, (rows * width) as usize, reversed))
                .collect()
        })
        .collect();

    // Each sampling's strips, one after another.
    let mut per_sampling: Vec<Vec<StripLists>> = (0..n).map(|_| Vec::new()).collect();
    for strip in strips {
        for (k, l) in strip.into_iter().enumerate() {
            per_sampling[k].push(l);
        }
    }
    per_sampling
        .into_iter()
        .map(|strips| {
            let mut offsets = Vec::with_capacity((width * height + 1) as usize);
            offsets.push(0u32);
            // Where each strip's fragments start in the whole image's.
            let mut starts = Vec::with_capacity(strips.len() + 1);
            starts.push(0usize);
            for l in &strips {
                let mut at = *offsets.last().unwrap_or(&0);
                for &c in &l.counts {
                    at += c;
                    offsets.push(at);
                }
                starts.push(at as usize);
            }
            let total = starts.last().copied().unwrap_or(0);
            // Joined in parallel (written in place by rayon's indexed collect): joined by one
            // thread, this copy was ~35 % of a 1024² pass's CPU time, serial on any core count.
            let at = |i: usize| {
                let s = starts.partition_point(|&x| x <= i) - 1;
                (s, i - starts[s])
            };
            let frags: Vec<RefFragment> = (0..total)
                .into_par_iter()
                .with_min_len(1 << 12)
                .map(|i| {
                    let (s, j) = at(i);
                    strips[s].frags[j]
                })
                .collect();
            let masks: Vec<u32> = (0..total)
                .into_par_iter()
                .with_min_len(1 << 12)
                .map(|i| {
                    let (s, j) = at(i);
                    strips[s].masks[j]
                })
                .collect();
            let lists = FragmentLists {
                width,
                height,
                reversed_z: reversed,
                offsets,
                frags,
            };
            (lists, masks)
        })
        .collect()
}

/// The fragment of triangle `t` (screen vertices `p`) at pixel (x, y) under `sampling`: depth
/// linear in screen space, attributes perspective-correct, each at its sampling's point.
fn fragment(t: &Tri, p: [(f64, f64); 3], sampling: &Sampling<'_>, x: u32, y: u32) -> RefFragment {
    let (ax, ay) = sampling.attributes;
    let c = (x as f64 + ax, y as f64 + ay);
    let e = [
        edge(p[1], p[2], c),
        edge(p[2], p[0], c),
        edge(p[0], p[1], c),
    ];
    let b = [e[0] / t.area, e[1] / t.area, e[2] / t.area];
    let bd = match sampling.depth {
        None => b,
        Some((dx, dy)) => {
            let c = (x as f64 + dx, y as f64 + dy);
            let e = [
                edge(p[1], p[2], c),
                edge(p[2], p[0], c),
                edge(p[0], p[1], c),
            ];
            [e[0] / t.area, e[1] / t.area, e[2] / t.area]
        }
    };
    let depth = (bd[0] * t.v[0].z + bd[1] * t.v[1].z + bd[2] * t.v[2].z).clamp(0.0, 1.0);
    let pw = [
        b[0] * t.v[0].inv_w,
        b[1] * t.v[1].inv_w,
        b[2] * t.v[2].inv_w,
    ];
    let sum = pw[0] + pw[1] + pw[2];
    let mut a = [0.0; 8];
    for (k, ak) in a.iter_mut().enumerate() {
        *ak = (pw[0] * t.v[0].attrs[k] + pw[1] * t.v[1].attrs[k] + pw[2] * t.v[2].attrs[k]) / sum;
    }
    RefFragment {
        depth,
        view_z: a[7],
        color: [a[0], a[1], a[2], a[3]],
        normal: [a[4], a[5], a[6]],
        object_id: t.object_id,
        front_facing: t.front,
        prim: t.prim,
        depth_slope: t.depth_slope,
    }
}

/// A strip's fragments `(pixel, fragment, mask)` in submission order, grouped by pixel and
/// sorted nearest first within each (`pixels`: the strip's pixel count).
fn sort_strip(pushed: Vec<(u32, RefFragment, u32)>, pixels: usize, reversed: bool) -> StripLists {
    let mut counts = vec![0u32; pixels];
    for e in &pushed {
        counts[e.0 as usize] += 1;
    }
    let mut start = Vec::with_capacity(pixels + 1);
    start.push(0usize);
    for &c in &counts {
        start.push(start.last().copied().unwrap_or(0) + c as usize);
    }
    // Indices grouped by pixel, each group in submission order (a stable counting sort).
    let mut fill = start.clone();
    let mut order = vec![0u32; pushed.len()];
    for (i, e) in pushed.iter().enumerate() {
        let at = &mut fill[e.0 as usize];
        order[*at] = i as u32;
        *at += 1;
    }
    for p in 0..pixels {
        // Nearest first; ties keep submission order (a stable, documented choice).
        order[start[p]..start[p + 1]].sort_by(|&i, &j| {
            let (a, b) = (&pushed[i as usize].1, &pushed[j as usize].1);
            let o = if reversed {
                b.depth.total_cmp(&a.depth)
            } else {
                a.depth.total_cmp(&b.depth)
            };
            o.then(a.prim.cmp(&b.prim))
        });
    }
    StripLists {
        counts,
        frags: order.iter().map(|&i| pushed[i as usize].1).collect(),
        masks: order.iter().map(|&i| pushed[i as usize].2).collect(),
    }
}

/// Whether point `c` is inside the positively wound triangle `p` (y down) under the top-left
/// rule: every edge function positive, or zero on a top or left edge (`tl`, per edge
/// p1→p2, p2→p0, p0→p1). Shared edges are watertight: a point on one is owned by exactly one of
/// the two triangles.
pub fn covers(p: [(f64, f64); 3], tl: [bool; 3], c: (f64, f64)) -> bool {
    let e = [
        edge(p[1], p[2], c),
        edge(p[2], p[0], c),
        edge(p[0], p[1], c),
    ];
    !(0..3).any(|i| e[i] < 0.0 || (e[i] == 0.0 && !tl[i]))
}

/// The top-left flags of a positively wound screen triangle's edges p1→p2, p2→p0, p0→p1.
pub fn top_left_edges(p: [(f64, f64); 3]) -> [bool; 3] {
    [
        top_left(p[1], p[2]),
        top_left(p[2], p[0]),
        top_left(p[0], p[1]),
    ]
}
