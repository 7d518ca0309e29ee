// An exact A-buffer built without the raster pipeline: triangles are rasterised in compute, twice.
// Transform (override PRETRANSFORM, axis `transform = vertex`): every vertex's clip position once,
// into `clipv`, which every later kernel reads instead of transforming per triangle corner.
// Count: every covered pixel centre adds 1 to its pixel (atomicAdd). Scan: an exclusive prefix
// sum turns the counts into each pixel's first slot. Fill: the same coverage again; each fragment
// takes the next slot of its pixel (atomicAdd on the start, which so ends as the pixel's end) and
// stores 8 B: its window depth and its primitive id (bit 31: front facing). Resolve: per pixel,
// sort the slots by (depth, primitive) and fold them, re-deriving colour, normal, view depth and
// object id from the primitive's vertices at the pixel centre (visibility-buffer style, in
// visibility.wgsl), so a fragment costs exactly the 8 B of its depth and identity.
//
// Coverage matches the reference rasteriser (`reference/raster.rs`) rule for rule: clip to
// 0 ≤ z ≤ w, clip x/y to a guard band of ±GUARD·w only where a vertex lies outside it, snap to
// 1/256 px, sample pixel centres, top-left fill rule. Edge functions are evaluated exactly in
// integers, so shared edges are watertight and ties are decided as the reference decides them:
// with override STEPPED (axis `coverage = stepped`) they are stepped from pixel to pixel — in i32
// for a triangle that spans at most SMALL_EXTENT units (|E| ≤ 2·extent² < 2^31), in emulated
// 64-bit for larger ones, whose 32×32 tiles are first classified from their corners as empty
// (skipped), full (no per-pixel test) or partial; without it (`coverage = direct`) every pixel
// evaluates the three 64-bit products anew (the first version's cost). Triangles whose bounding
// box holds at most `small_max` pixels (and that span at most SMALL_EXTENT when stepped) are
// rasterised by one thread each; larger (and clipped) ones are cut into tiles of TILE_PIXELS
// pixels of their bounding box (32×32, or narrower and taller for a box under 32 px wide), one
// workgroup per tile (`raster_big`), so neither a full-screen triangle stalls one thread nor a
// 200-pixel one idles a workgroup.

override FILL: bool = false;
override PRETRANSFORM: bool = true;
override STEPPED: bool = true;
// MSAA coverage masks (aa = msaa*, aa_capture = coverage): coverage is tested at AA_SAMPLES
// sample positions (Vulkan's standard locations, `sample_off`) by the same exact integer edge
// rule; a pixel with any sample covered gets one fragment, depth at the pixel centre, tagged
// prim | mask << TAG_PRIM_BITS (23) | front << 31; the resolve folds each sample over the
// fragments whose mask has its bit and averages the samples. 1: pixel centres only.
override AA_SAMPLES: u32 = 1u;
// Resolve: sort lists of up to WG_CAP fragments in workgroup memory (axis `resolve_sort =
// workgroup`); longer lists, and every list when false, in a per-thread array.
override WG_SORT: bool = true;
// `capture = tiles` (binned.wgsl): what `raster_small` does not take is binned to 8×8 tiles
// instead of shared by `raster_big`.
override TILES: bool = false;
// `attributes = snapped` (`fragment`): a fragment's attributes weighted as its snapped screen
// triangle's, not its clip-space triangle's.
override SNAPPED_ATTRS: bool = false;
// Sizes read at run time, so that one compiled kernel serves every scene and resolution (a
// software driver compiles each specialisation anew).
struct Sizes {
    ntri: u32,
    npix: u32,
    nblocks: u32,
    // Fragment slots allocated (the prepare-time count); a fragment beyond it is counted as lost.
    capacity: u32,
    // Capacity of the big-triangle list (2 words each: primitive, first tile).
    big_cap: u32,
    // Capacity of the tile → big-triangle table.
    chunk_cap: u32,
    // Largest bounding box (pixels) one thread rasterises.
    small_max: u32,
    nvert: u32,
    // Word of the work counters in their buffer (0, or after the offsets with packed bindings).
    work_base: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};
@group(0) @binding(10) var<uniform> sizes: Sizes;
// Per-pixel sort capacity of the resolve (a register/local array; WGSL needs a constant size).
const SORT_MAX: u32 = 128u;
const GUARD: f32 = 1024.0;
const MAXV: u32 = 9u;
const SUB: f32 = 256.0;
// Largest x or y span (1/256-px units, 126 px) of a triangle whose edge functions are stepped in
// i32: |E| ≤ 2·(SMALL_EXTENT + 256)·SMALL_EXTENT < 2^31 even one step past the bounding box.
const SMALL_EXTENT: i32 = 32256;
// Pixels of a big triangle's tiles: 64 threads × 16 pixels; at most TILE_W wide.
const TILE_PIXELS: u32 = 1024u;
const TILE_W: u32 = 32u;
// Resolve: fragments per pixel sorted in workgroup memory (64 pixels × WG_CAP × 8 B: 16 KiB at
// the plan's WG_CAP of 32, 8 KiB at 16 where workgroup memory is short).
const RING: u32 = WG_CAP - 1u; // WG_CAP is a power of two: slot arithmetic by mask

// `work` layout (u32 words): counters, the scan's block sums, the big-triangle list, the tiles.
const W_BIG: u32 = 0u;         // big triangles listed this frame
const W_LOST: u32 = 1u;        // fragments beyond `capacity`
const W_OVF_PIXELS: u32 = 2u;  // pixels with more than SORT_MAX fragments
const W_DROPPED: u32 = 3u;     // fragments dropped by the resolve's sort capacity
const W_TOTAL: u32 = 4u;       // fragments counted (the scan's total)
const W_BIG_LOST: u32 = 5u;    // big triangles beyond `big_cap` (their fragments are missing)
const W_CHUNKS: u32 = 6u;      // tiles of the listed big triangles
// Count pass, stepped (one atomic per tile: ≤ 1/1024 of its pixel atomics): (fan triangle,
// tile) pairs
const W_TILE_EMPTY: u32 = 7u;  // skipped as empty
const W_TILE_FULL: u32 = 8u;   // … covered whole (no per-pixel test)
const W_TILE_PARTIAL: u32 = 9u; // … tested pixel by pixel
const W_BLOCKS: u32 = 16u;

fn list_at(k: u32) -> u32 {
    return W_BLOCKS + sizes.nblocks + 2u * k;
}

fn owner_at(c: u32) -> u32 {
    return W_BLOCKS + sizes.nblocks + 2u * sizes.big_cap + c;
}

// The mesh, the per-pixel offsets (per pixel: count after Count, first slot after Scan, one past
// the last slot after Fill), the work counters and the fragments (per fragment: window depth bits,
// primitive | front << 31) are declared by the binding plan (plan.rs: native.wgsl or packed.wgsl,
// and the fragments' split), with the accessors offs_*, work_*, frags_load/frags_store and the
// mesh's (visibility.wgsl); WG_CAP, the workgroup ring's capacity, too.
@group(0) @binding(9) var<storage, read_write> out_image: array<vec4<f32>>;
// Per vertex, three elements (written by `transform`; three in all when PRETRANSFORM is off): the
// clip position's (x, y) and (z, w), then the snapped screen position (`screen_of`).
@group(0) @binding(11) var<storage, read_write> clipv: array<vec2<f32>>;

fn clip_at(i: u32) -> vec4<f32> {
    if PRETRANSFORM {
        return vec4<f32>(clipv[3u * i], clipv[3u * i + 1u]);
    }
    return clip_of(i);
}

fn screen_at(i: u32) -> vec2<f32> {
    if PRETRANSFORM {
        return clipv[3u * i + 2u];
    }
    return screen_of(i);
}

// The screen position of a vertex outside the depth range or the guard band (`transform`): no
// triangle of it is drawn unclipped, which is the only case that reads its snapped position, so
// `snapped_weights` needs no clip position to know its triangle was clipped.
const SCREEN_NONE: f32 = -3.0e38;

@compute @workgroup_size(WIDE)
fn transform(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    for (var i = gid.x; i < sizes.nvert; i = i + nw.x * WIDE) {
        let c = clip_of(i);
        clipv[3u * i] = c.xy;
        clipv[3u * i + 1u] = c.zw;
        var s = vec2<f32>(SCREEN_NONE);
        if in_depth_range(c) && !outside_guard(c) {
            s = screen_of(i);
        }
        clipv[3u * i + 2u] = s;
    }
}

// 1.0 that the compiler cannot fold (df32.wgsl): the viewport width is positive.
fn df_one() -> f32 {
    return sign(camera.viewport.x);
}

// A vertex's snapped screen position, as the f64 reference computes it, in double-f32
// (`df_screen`, df32.wgsl): used only for a triangle that is not clipped.
fn screen_of(i: u32) -> vec2<f32> {
    return df_screen(camera.clip_from_world, position(i), camera.viewport.xy);
}

struct Poly {
    v: array<vec4<f32>, MAXV>,
    n: u32,
};

// Sutherland–Hodgman against `dot(plane, v) >= 0`; on a guard plane (`axis` 0 or 1) the new
// vertex is put exactly on the plane, as the reference does.
fn clip_poly(p: ptr<function, Poly>, plane: vec4<f32>, axis: i32, sign: f32) {
    var out: Poly;
    out.n = 0u;
    let n = (*p).n;
    for (var i = 0u; i < n; i = i + 1u) {
        let a = (*p).v[i];
        let b = (*p).v[(i + 1u) % n];
        let da = dot(plane, a);
        let db = dot(plane, b);
        if da >= 0.0 && out.n < MAXV {
            out.v[out.n] = a;
            out.n = out.n + 1u;
        }
        if (da >= 0.0) != (db >= 0.0) && out.n < MAXV {
            var v = a + (b - a) * (da / (da - db));
            if axis == 0 {
                v.x = sign * GUARD * v.w;
            } else if axis == 1 {
                v.y = sign * GUARD * v.w;
            }
            out.v[out.n] = v;
            out.n = out.n + 1u;
        }
    }
    *p = out;
}

// 0 ≤ z, z ≤ w, then x ≤ G·w, −x ≤ G·w, y ≤ G·w, −y ≤ G·w (as `dot(plane, clip) >= 0`).
const CLIP_PLANES = array<vec4<f32>, 6>(
    vec4<f32>(0.0, 0.0, 1.0, 0.0),
    vec4<f32>(0.0, 0.0, -1.0, 1.0),
    vec4<f32>(-1.0, 0.0, 0.0, GUARD),
    vec4<f32>(1.0, 0.0, 0.0, GUARD),
    vec4<f32>(0.0, -1.0, 0.0, GUARD),
    vec4<f32>(0.0, 1.0, 0.0, GUARD),
);
const CLIP_AXIS = array<i32, 6>(-1, -1, 0, 0, 1, 1);
const CLIP_SIGN = array<f32, 6>(0.0, 0.0, 1.0, -1.0, 1.0, -1.0);

// Whether a clip position lies between the near and far planes (0 ≤ z ≤ w).
fn in_depth_range(c: vec4<f32>) -> bool {
    return c.z >= 0.0 && c.w - c.z >= 0.0;
}

fn outside_guard(c: vec4<f32>) -> bool {
    return abs(c.x) > GUARD * c.w || abs(c.y) > GUARD * c.w;
}

// Round half away from zero (Rust's f64::round, which the reference uses).
fn snap(v: f32) -> f32 {
    return sign(v) * floor(abs(v) * SUB + 0.5) / SUB;
}

// The primitive's visible polygon in screen space: (x, y) snapped, z = window depth.
fn setup(prim: u32) -> Poly {
    var p: Poly;
    p.n = 3u;
    let idx = tri_indices(prim);
    p.v[0] = clip_at(idx.x);
    p.v[1] = clip_at(idx.y);
    p.v[2] = clip_at(idx.z);
    var inside = true;
    for (var k = 0u; k < 3u; k = k + 1u) {
        inside = inside && in_depth_range(p.v[k]);
    }
    var guard = false;
    var clipped = false;
    // Near and far planes first, then (only where a vertex still lies outside) the guard band.
    // One loop over the planes keeps a single inlined copy of the clipper.
    for (var k = 0u; k < 6u; k = k + 1u) {
        if k == 2u {
            guard = false;
            for (var j = 0u; j < p.n; j = j + 1u) {
                guard = guard || outside_guard(p.v[j]);
            }
        }
        if p.n < 3u || (k < 2u && inside) || (k >= 2u && !guard) {
            continue;
        }
        clip_poly(&p, CLIP_PLANES[k], CLIP_AXIS[k], CLIP_SIGN[k]);
        clipped = true;
    }
    if p.n < 3u {
        p.n = 0u;
    }
    if !clipped {
        let s = array<vec2<f32>, 3>(screen_at(idx.x), screen_at(idx.y), screen_at(idx.z));
        for (var k = 0u; k < 3u; k = k + 1u) {
            p.v[k] = vec4<f32>(s[k], p.v[k].z * (1.0 / p.v[k].w), 0.0);
        }
        return p;
    }
    // A clipped polygon's new vertices are snapped from f32 (the reference computes them in f64;
    // such triangles reach the near plane or span the guard band, and are rare).
    let w = camera.viewport.x;
    let h = camera.viewport.y;
    for (var k = 0u; k < p.n; k = k + 1u) {
        let c = p.v[k];
        let inv_w = 1.0 / c.w;
        p.v[k] = vec4<f32>(
            snap((c.x * inv_w * 0.5 + 0.5) * w),
            snap((0.5 - c.y * inv_w * 0.5) * h),
            c.z * inv_w,
            0.0,
        );
    }
    return p;
}

// Sample s's position in pixel (x, y)'s square, in 1/256 px from its top-left corner: Vulkan's
// standard sample locations × 256 (the Rust table `reference::multisample::standard_positions`;
// the AA tests compare with it), or the centre.
fn sample_off(s: u32) -> vec2<i32> {
    if AA_SAMPLES == 2u {
        return select(vec2<i32>(64, 64), vec2<i32>(192, 192), s == 0u);
    }
    if AA_SAMPLES == 4u {
        var t = array<vec2<i32>, 4>(vec2<i32>(96, 32), vec2<i32>(224, 96), vec2<i32>(32, 160), vec2<i32>(160, 224));
        return t[s];
    }
    if AA_SAMPLES == 8u {
        var t = array<vec2<i32>, 8>(
            vec2<i32>(144, 80), vec2<i32>(112, 176), vec2<i32>(208, 144), vec2<i32>(80, 48),
            vec2<i32>(48, 208), vec2<i32>(16, 112), vec2<i32>(176, 240), vec2<i32>(240, 16),
        );
        return t[s];
    }
    return vec2<i32>(128, 128);
}

// Pixel bounds (x0, y0, x1, y1) of a screen polygon, clamped to the viewport: the pixels whose
// centre (or, with AA_SAMPLES > 1, any point of whose square) lies within its bounding box; x0 >
// x1 or y0 > y1 when there is none.
fn bounds(p: Poly) -> vec4<i32> {
    var lo = vec2<f32>(3.4e38);
    var hi = vec2<f32>(-3.4e38);
    for (var k = 0u; k < p.n; k = k + 1u) {
        lo = min(lo, p.v[k].xy);
        hi = max(hi, p.v[k].xy);
    }
    let vp = camera.viewport.xy;
    var a = max(ceil(lo - 0.5), vec2<f32>(0.0));
    var b = min(floor(hi - 0.5), vp - 1.0);
    if AA_SAMPLES > 1u {
        a = max(ceil(lo - 1.0), vec2<f32>(0.0));
        b = min(floor(hi), vp - 1.0);
    }
    if p.n < 3u || a.x > b.x || a.y > b.y {
        return vec4<i32>(0, 0, -1, -1);
    }
    return vec4<i32>(vec2<i32>(a), vec2<i32>(b));
}

// |a|, |b| < 2^31: the product as 64-bit two's complement (lo, hi).
fn mul64(a: i32, b: i32) -> vec2<u32> {
    let ua = u32(abs(a));
    let ub = u32(abs(b));
    let a0 = ua & 0xffffu;
    let a1 = ua >> 16u;
    let b0 = ub & 0xffffu;
    let b1 = ub >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    let lo = (p00 & 0xffffu) | (mid << 16u);
    let hi = a1 * b1 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u);
    if (a < 0) != (b < 0) {
        let nlo = ~lo + 1u;
        return vec2<u32>(nlo, ~hi + select(0u, 1u, nlo == 0u));
    }
    return vec2<u32>(lo, hi);
}

// Sign of p − q (64-bit two's complement; |p|, |q| < 2^62).
fn sign_sub64(p: vec2<u32>, q: vec2<u32>) -> i32 {
    let lo = p.x - q.x;
    let hi = p.y - q.y - select(0u, 1u, p.x < q.x);
    if (hi & 0x80000000u) != 0u {
        return -1;
    }
    return select(1, 0, (hi | lo) == 0u);
}

// Exact sign of the edge function of a→b at c, in 1/256-px integer units (y down).
fn edge_sign(a: vec2<i32>, b: vec2<i32>, c: vec2<i32>) -> i32 {
    return sign_sub64(mul64(b.x - a.x, c.y - a.y), mul64(b.y - a.y, c.x - a.x));
}

fn edge_f(a: vec2<f32>, b: vec2<f32>, c: vec2<f32>) -> f32 {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Top-left rule for a positively wound triangle (y down): a top edge is horizontal going right,
// a left edge goes up.
fn top_left(a: vec2<i32>, b: vec2<i32>) -> bool {
    let d = b - a;
    return (d.y == 0 && d.x > 0) || d.y < 0;
}

// One triangle of a polygon's fan, wound positively, ready to test pixel centres.
struct Tri {
    i0: vec2<i32>,
    i1: vec2<i32>,
    i2: vec2<i32>,
    f0: vec3<f32>,
    f1: vec3<f32>,
    f2: vec3<f32>,
    tl: vec3<bool>,
    area: f32,
    front: bool,
    ok: bool,
};

fn units(v: vec4<f32>) -> vec2<i32> {
    return vec2<i32>(v.xy * SUB);
}

fn make_tri(p: Poly, k: u32) -> Tri {
    var t: Tri;
    var a = p.v[0];
    var b = p.v[k];
    var c = p.v[k + 1u];
    let s = edge_sign(units(a), units(b), units(c));
    t.ok = s != 0; // degenerate after snapping: the GPU draws nothing either
    // Counter-clockwise in NDC (y up) is front facing (wgpu's default); y down flips the sign.
    t.front = s < 0;
    if s < 0 {
        let x = b;
        b = c;
        c = x;
    }
    t.i0 = units(a);
    t.i1 = units(b);
    t.i2 = units(c);
    t.f0 = a.xyz;
    t.f1 = b.xyz;
    t.f2 = c.xyz;
    t.tl = vec3<bool>(top_left(t.i1, t.i2), top_left(t.i2, t.i0), top_left(t.i0, t.i1));
    t.area = edge_f(a.xy, b.xy, c.xy);
    return t;
}

// Sign-bit test of a 64-bit two's complement value (lo, hi).
fn neg64(e: vec2<u32>) -> bool {
    return (e.y & 0x80000000u) != 0u;
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// An i32 as 64-bit two's complement.
fn sext64(v: i32) -> vec2<u32> {
    return vec2<u32>(bitcast<u32>(v), select(0u, 0xffffffffu, v < 0));
}

fn sub64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    return vec2<u32>(a.x - b.x, a.y - b.y - select(0u, 1u, a.x < b.x));
}

// Pixel centre (x, y) in 1/256-px units.
fn centre_units(x: i32, y: i32) -> vec2<i32> {
    return vec2<i32>(x * 256 + 128, y * 256 + 128);
}

// Edge k of `t` (0: i1→i2, 1: i2→i0, 2: i0→i1) at pixel (x, y), exactly in 64 bits, minus 1 when
// the edge is not top-left: the pixel is covered iff all three are ≥ 0.
fn edge_biased64(t: Tri, k: u32, x: i32, y: i32) -> vec2<u32> {
    return edge_biased64_at(t, k, centre_units(x, y));
}

// As `edge_biased64`, at point `c` (1/256-px units).
fn edge_biased64_at(t: Tri, k: u32, c: vec2<i32>) -> vec2<u32> {
    var a = t.i0;
    var b = t.i1;
    var tl = t.tl.z;
    if k == 0u {
        a = t.i1;
        b = t.i2;
        tl = t.tl.x;
    } else if k == 1u {
        a = t.i2;
        b = t.i0;
        tl = t.tl.y;
    }
    let e = sub64(mul64(b.x - a.x, c.y - a.y), mul64(b.y - a.y, c.x - a.x));
    return sub64(e, vec2<u32>(select(1u, 0u, tl), 0u));
}

// Window depth of `t` at pixel (x, y)'s centre (screen-space barycentrics of the snapped fan
// triangle, as the reference interpolates window depth).
fn depth_at(t: Tri, x: i32, y: i32) -> f32 {
    let cf = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    // The exact area is not 0 (`ok`), but its f32 value can round to 0 on a huge sliver.
    let area = select(t.area, 1.0, t.area == 0.0);
    let b = vec3<f32>(edge_f(t.f1.xy, t.f2.xy, cf), edge_f(t.f2.xy, t.f0.xy, cf), edge_f(t.f0.xy, t.f1.xy, cf)) / area;
    return clamp(b.x * t.f0.z + b.y * t.f1.z + b.z * t.f2.z, 0.0, 1.0);
}

// Window depth at pixel (x, y) if `t` covers its centre, else a negative value (`coverage =
// direct`: three exact 64-bit edge signs per pixel).
fn cover(t: Tri, x: i32, y: i32) -> f32 {
    let c = centre_units(x, y);
    let s = vec3<i32>(edge_sign(t.i1, t.i2, c), edge_sign(t.i2, t.i0, c), edge_sign(t.i0, t.i1, c));
    if any(s < vec3<i32>(0)) || any((s == vec3<i32>(0)) & !t.tl) {
        return -1.0;
    }
    return depth_at(t, x, y);
}

// Coverage mask of `t` over pixel (x, y)'s AA_SAMPLES samples (`coverage = direct`: three exact
// 64-bit edge signs per sample).
fn cover_mask(t: Tri, x: i32, y: i32) -> u32 {
    var m = 0u;
    for (var s = 0u; s < AA_SAMPLES; s = s + 1u) {
        let c = vec2<i32>(x * 256, y * 256) + sample_off(s);
        let e = vec3<i32>(edge_sign(t.i1, t.i2, c), edge_sign(t.i2, t.i0, c), edge_sign(t.i0, t.i1, c));
        if !(any(e < vec3<i32>(0)) || any((e == vec3<i32>(0)) & !t.tl)) {
            m = m | (1u << s);
        }
    }
    return m;
}

// Per-sample offsets of the three (i32, stepped) edge functions from their pixel-centre value:
// dE/dx·(o.x − 128) + dE/dy·(o.y − 128) for sample offset o.
fn sample_steps(t: Tri) -> array<vec3<i32>, 8> {
    let dx = vec3<i32>(t.i1.y - t.i2.y, t.i2.y - t.i0.y, t.i0.y - t.i1.y);
    let dy = vec3<i32>(t.i2.x - t.i1.x, t.i0.x - t.i2.x, t.i1.x - t.i0.x);
    var out: array<vec3<i32>, 8>;
    for (var s = 0u; s < AA_SAMPLES; s = s + 1u) {
        let o = sample_off(s) - vec2<i32>(128);
        out[s] = dx * o.x + dy * o.y;
    }
    return out;
}

// Whether a 3-vertex polygon spans at most SMALL_EXTENT units in x and y (its i32 edge
// functions cannot overflow over its bounding box).
fn fits_i32(p: Poly) -> bool {
    return spans_fit_i32(units(p.v[0]), units(p.v[1]), units(p.v[2]));
}

// Whether a triangle (1/256-px units) spans at most SMALL_EXTENT each way.
fn spans_fit_i32(a: vec2<i32>, b: vec2<i32>, c: vec2<i32>) -> bool {
    let e = max(max(a, b), c) - min(min(a, b), c);
    return e.x <= SMALL_EXTENT && e.y <= SMALL_EXTENT;
}

fn edge_i32(a: vec2<i32>, b: vec2<i32>, c: vec2<i32>) -> i32 {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

fn emit(x: i32, y: i32, depth: f32, prim: u32, front: bool) {
    emit_mask(x, y, depth, prim, front, 0u);
}

// A fragment with its coverage mask (0 and unused when AA_SAMPLES = 1).
fn emit_mask(x: i32, y: i32, depth: f32, prim: u32, front: bool, mask: u32) {
    let p = u32(y) * u32(camera.viewport.x) + u32(x);
    if FILL {
        let slot = offs_add(p, 1u);
        if slot < sizes.capacity {
            // Single-sample tags have no mask bits: a full tile's all-samples mask (1) would land
            // on bit 31, the front-facing bit (TAG_PRIM_BITS = 31).
            let m = select(0u, mask, AA_SAMPLES > 1u);
            let tag = prim | (m << TAG_PRIM_BITS) | select(0u, 0x80000000u, front);
            frags_store(slot, vec2<u32>(bitcast<u32>(depth), tag));
        } else {
            work_add(W_LOST, 1u);
        }
    } else {
        offs_add(p, 1u);
    }
}

// A covered pixel: the count pass needs no depth.
fn emit_covered(t: Tri, x: i32, y: i32, prim: u32) {
    emit_covered_mask(t, x, y, prim, 0u);
}

fn emit_covered_mask(t: Tri, x: i32, y: i32, prim: u32, mask: u32) {
    var z = 0.0;
    if FILL {
        z = depth_at(t, x, y);
    }
    emit_mask(x, y, z, prim, t.front, mask);
}

// Samples of an edge-function triple `e` (biased, at the pixel centre) that are covered, with
// per-sample offsets `so` (`sample_steps`).
fn stepped_mask(e: vec3<i32>, so: array<vec3<i32>, 8>) -> u32 {
    var m = 0u;
    for (var s = 0u; s < AA_SAMPLES; s = s + 1u) {
        let es = e + so[s];
        if (es.x | es.y | es.z) >= 0 {
            m = m | (1u << s);
        }
    }
    return m;
}

// One thread over a small triangle's bounding box `bb`, edge functions stepped in i32 (exact:
// `fits_i32`).
fn raster_stepped(t: Tri, bb: vec4<i32>, prim: u32) {
    let c0 = centre_units(bb.x, bb.y);
    let bias = select(vec3<i32>(1), vec3<i32>(0), t.tl);
    var row = vec3<i32>(edge_i32(t.i1, t.i2, c0), edge_i32(t.i2, t.i0, c0), edge_i32(t.i0, t.i1, c0)) - bias;
    // dE/dx and dE/dy per pixel of each edge a→b: −(b.y − a.y)·256 and (b.x − a.x)·256.
    let sx = vec3<i32>(t.i1.y - t.i2.y, t.i2.y - t.i0.y, t.i0.y - t.i1.y) * 256;
    let sy = vec3<i32>(t.i2.x - t.i1.x, t.i0.x - t.i2.x, t.i1.x - t.i0.x) * 256;
    let so = sample_steps(t);
    for (var y = bb.y; y <= bb.w; y = y + 1) {
        var e = row;
        for (var x = bb.x; x <= bb.z; x = x + 1) {
            if AA_SAMPLES > 1u {
                let m = stepped_mask(e, so);
                if m != 0u {
                    emit_covered_mask(t, x, y, prim, m);
                }
            } else if (e.x | e.y | e.z) >= 0 {
                emit_covered(t, x, y, prim);
            }
            e = e + sx;
        }
        row = row + sy;
    }
}

fn raster_direct(t: Tri, bb: vec4<i32>, prim: u32) {
    for (var y = bb.y; y <= bb.w; y = y + 1) {
        for (var x = bb.x; x <= bb.z; x = x + 1) {
            direct_pixel(t, x, y, prim);
        }
    }
}

// One pixel of `coverage = direct`: its centre, or its samples' mask.
fn direct_pixel(t: Tri, x: i32, y: i32, prim: u32) {
    if AA_SAMPLES > 1u {
        let m = cover_mask(t, x, y);
        if m != 0u {
            emit_covered_mask(t, x, y, prim, m);
        }
        return;
    }
    let z = cover(t, x, y);
    if z >= 0.0 {
        emit(x, y, z, prim, t.front);
    }
}

// Tile width × height for bounding box `bb`: TILE_W wide, or the power of two at or above a
// narrower box's width (so a vertical sliver keeps every lane busy), TILE_PIXELS in all.
fn tile_shape(bb: vec4<i32>) -> vec2<u32> {
    let bw = u32(bb.z - bb.x + 1);
    let w = min(TILE_W, 1u << (32u - countLeadingZeros(bw - 1u)));
    return vec2<u32>(w, TILE_PIXELS / w);
}

// Tiles (x, y) covering bounding box `bb`.
fn tile_grid(bb: vec4<i32>) -> vec2<u32> {
    let t = tile_shape(bb);
    let size = vec2<u32>(u32(bb.z - bb.x + 1), u32(bb.w - bb.y + 1));
    return (size + t - 1u) / t;
}

// One thread per triangle; triangles with a large bounding box (or a clipped polygon, or, when
// stepped, a span over SMALL_EXTENT) are listed for `raster_big` by the count pass (the fill
// pass skips them the same way).
@compute @workgroup_size(64)
fn raster_small(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    for (var prim = gid.x; prim < sizes.ntri; prim = prim + nw.x * 64u) {
        let p = setup(prim);
        let bb = bounds(p);
        if bb.x > bb.z || bb.y > bb.w {
            continue;
        }
        let px = u32(bb.z - bb.x + 1) * u32(bb.w - bb.y + 1);
        if p.n != 3u || px > sizes.small_max || (STEPPED && !fits_i32(p)) {
            if TILES {
                bin_triangle(p, bb, prim);
                continue;
            }
            if !FILL {
                let k = work_add(W_BIG, 1u);
                let grid = tile_grid(bb);
                let nch = grid.x * grid.y;
                let first = work_add(W_CHUNKS, nch);
                if k < sizes.big_cap && first + nch <= sizes.chunk_cap {
                    work_store(list_at(k), prim);
                    work_store(list_at(k) + 1u, first);
                    for (var c = 0u; c < nch; c = c + 1u) {
                        work_store(owner_at(first + c), k);
                    }
                } else {
                    work_add(W_BIG_LOST, 1u);
                }
            }
            continue;
        }
        let t = make_tri(p, 1u);
        if !t.ok {
            continue;
        }
        if STEPPED {
            raster_stepped(t, bb, prim);
        } else {
            raster_direct(t, bb, prim);
        }
    }
}

// Big triangles: one workgroup per tile (`tile_shape`, w × h) of a listed triangle's bounding
// box. Thread 0 sets the triangle up once and shares it (per-thread setup dominated: 64 setups
// per medium triangle cost as much as the rest of the pass). Thread i covers column i % w, every
// (64 / w)-th row from i / w, so a warp's atomics fall on consecutive pixels.
var<workgroup> wg_poly: Poly;
var<workgroup> wg_prim: u32;
// Top-left pixel of this workgroup's tile; x < 0 when it has nothing to do.
var<workgroup> wg_tile: vec2<i32>;
// Stepped: per (edge, corner), 1 when the biased edge function is negative there.
var<workgroup> wg_cls: array<u32, 12>;

// A partial tile's pixels of thread column x, rows y0, y0 + dy, … ≤ y1: 64-bit edge values
// stepped dy rows at a time.
fn tile_partial(t: Tri, x: i32, y0: i32, y1: i32, dy: i32, prim: u32) {
    var e0 = edge_biased64(t, 0u, x, y0);
    var e1 = edge_biased64(t, 1u, x, y0);
    var e2 = edge_biased64(t, 2u, x, y0);
    // dy rows (256·dy units, ≤ 2^14) of dE/dy = b.x − a.x.
    let s0 = mul64(t.i2.x - t.i1.x, 256 * dy);
    let s1 = mul64(t.i0.x - t.i2.x, 256 * dy);
    let s2 = mul64(t.i1.x - t.i0.x, 256 * dy);
    var so: array<vec3<i32>, 8>;
    if AA_SAMPLES > 1u {
        so = sample_steps(t);
    }
    for (var y = y0; y <= y1; y = y + dy) {
        if AA_SAMPLES > 1u {
            // Per sample: the centre's 64-bit values plus the (small, i32) sample offsets.
            var m = 0u;
            for (var s = 0u; s < AA_SAMPLES; s = s + 1u) {
                let a = add64(e0, sext64(so[s].x));
                let b = add64(e1, sext64(so[s].y));
                let c = add64(e2, sext64(so[s].z));
                if ((a.y | b.y | c.y) & 0x80000000u) == 0u {
                    m = m | (1u << s);
                }
            }
            if m != 0u {
                emit_covered_mask(t, x, y, prim, m);
            }
        } else if ((e0.y | e1.y | e2.y) & 0x80000000u) == 0u {
            emit_covered(t, x, y, prim);
        }
        e0 = add64(e0, s0);
        e1 = add64(e1, s1);
        e2 = add64(e2, s2);
    }
}

@compute @workgroup_size(64)
fn raster_big(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(num_workgroups) nw: vec3<u32>,
) {
    if li == 0u {
        wg_tile = vec2<i32>(-1, 0);
        let c = wg.x + wg.y * nw.x;
        if c < min(work_load(W_CHUNKS), sizes.chunk_cap) {
            let k = work_load(owner_at(c));
            if k < min(work_load(W_BIG), sizes.big_cap) {
                let prim = work_load(list_at(k));
                let first = work_load(list_at(k) + 1u);
                let p = setup(prim);
                let bb = bounds(p);
                // A stale table entry (only after a listing overflow, which is flagged) is
                // not this triangle's.
                if bb.x <= bb.z && bb.y <= bb.w && c >= first {
                    let grid = tile_grid(bb);
                    let ts = tile_shape(bb);
                    let ci = c - first;
                    if ci < grid.x * grid.y {
                        wg_poly = p;
                        wg_prim = prim;
                        wg_tile = bb.xy + vec2<i32>(ts * vec2<u32>(ci % grid.x, ci / grid.x));
                    }
                }
            }
        }
    }
    let tile = workgroupUniformLoad(&wg_tile);
    if tile.x < 0 {
        return;
    }
    let p = workgroupUniformLoad(&wg_poly);
    let prim = workgroupUniformLoad(&wg_prim);
    let bb = bounds(p);
    let ts = tile_shape(bb);
    // Last pixel of the tile inside the bounding box; rows between a thread's pixels.
    let hi = min(tile + vec2<i32>(ts) - 1, bb.zw);
    let x = tile.x + i32(li % ts.x);
    let y0 = tile.y + i32(li / ts.x);
    let dy = i32(64u / ts.x);
    for (var t_i = 1u; t_i + 1u < p.n; t_i = t_i + 1u) {
        let t = make_tri(p, t_i);
        if !t.ok {
            continue;
        }
        if !STEPPED {
            if x <= hi.x {
                for (var y = y0; y <= hi.y; y = y + dy) {
                    direct_pixel(t, x, y, prim);
                }
            }
            continue;
        }
        // Classify the tile from its corner pixels: an edge function is affine, so its extremes
        // over the tile's pixel centres are at the corners.
        // With AA_SAMPLES > 1 the corners of the tile's pixel squares: every sample lies in
        // their rectangle, so the classes hold for every sample.
        if li < 12u {
            let corner = li % 4u;
            let cx = select(tile.x, hi.x, (corner & 1u) != 0u);
            let cy = select(tile.y, hi.y, (corner & 2u) != 0u);
            var c = centre_units(cx, cy);
            if AA_SAMPLES > 1u {
                c = vec2<i32>(
                    select(tile.x * 256, (hi.x + 1) * 256, (corner & 1u) != 0u),
                    select(tile.y * 256, (hi.y + 1) * 256, (corner & 2u) != 0u),
                );
            }
            wg_cls[li] = select(0u, 1u, neg64(edge_biased64_at(t, li / 4u, c)));
        }
        let cls = workgroupUniformLoad(&wg_cls);
        var full = true;
        var empty = false;
        for (var k = 0u; k < 3u; k = k + 1u) {
            let neg = cls[4u * k] + cls[4u * k + 1u] + cls[4u * k + 2u] + cls[4u * k + 3u];
            full = full && neg == 0u;
            empty = empty || neg == 4u;
        }
        // wg_cls is rewritten for the next fan triangle.
        workgroupBarrier();
        if !FILL && li == 0u {
            work_add(select(select(W_TILE_PARTIAL, W_TILE_FULL, full), W_TILE_EMPTY, empty), 1u);
        }
        // No `continue` on a per-thread condition: the next fan triangle's barrier must stay in
        // uniform control flow.
        if !empty && x <= hi.x {
            if full {
                for (var y = y0; y <= hi.y; y = y + dy) {
                    emit_covered_mask(t, x, y, prim, (1u << AA_SAMPLES) - 1u);
                }
            } else {
                tile_partial(t, x, y0, hi.y, dy, prim);
            }
        }
    }
}

// Exclusive prefix sum of `offs` (`npix` counts) in three dispatches: blocks of 1,024, the block
// sums (one workgroup, in chunks of WIDE with a carry), then each block's offset added back.
// WIDE (the plan's): threads of these kernels and `transform`, 256, or 128 where the device
// allows no more (WebGPU's compatibility mode); a thread takes 1024 / WIDE of a block.
const PER_THREAD: u32 = 1024u / WIDE;
var<workgroup> sh: array<u32, WIDE>;

fn scan_shared(li: u32) {
    for (var off = 1u; off < WIDE; off = off * 2u) {
        var t = 0u;
        if li >= off {
            t = sh[li - off];
        }
        workgroupBarrier();
        sh[li] = sh[li] + t;
        workgroupBarrier();
    }
}

@compute @workgroup_size(WIDE)
fn scan_blocks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let base = wg.x * 1024u + li * PER_THREAD;
    var v: array<u32, PER_THREAD>;
    var s = 0u;
    for (var k = 0u; k < PER_THREAD; k = k + 1u) {
        let i = base + k;
        var x = 0u;
        if i < sizes.npix {
            x = offs_load(i);
        }
        v[k] = s;
        s = s + x;
    }
    sh[li] = s;
    workgroupBarrier();
    scan_shared(li);
    let before = sh[li] - s;
    for (var k = 0u; k < PER_THREAD; k = k + 1u) {
        let i = base + k;
        if i < sizes.npix {
            offs_store(i, v[k] + before);
        }
    }
    if li == WIDE - 1u {
        work_store(W_BLOCKS + wg.x, sh[WIDE - 1u]);
    }
}

@compute @workgroup_size(WIDE)
fn scan_sums(@builtin(local_invocation_index) li: u32) {
    var carry = 0u;
    for (var c = 0u; c < sizes.nblocks; c = c + WIDE) {
        let i = c + li;
        var x = 0u;
        if i < sizes.nblocks {
            x = work_load(W_BLOCKS + i);
        }
        sh[li] = x;
        workgroupBarrier();
        scan_shared(li);
        if i < sizes.nblocks {
            work_store(W_BLOCKS + i, carry + sh[li] - x);
        }
        carry = carry + sh[WIDE - 1u];
        workgroupBarrier();
    }
    if li == 0u {
        work_store(W_TOTAL, carry);
    }
}

@compute @workgroup_size(WIDE)
fn scan_add(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let add = work_load(W_BLOCKS + wg.x);
    let base = wg.x * 1024u + li * PER_THREAD;
    for (var k = 0u; k < PER_THREAD; k = k + 1u) {
        let i = base + k;
        if i < sizes.npix {
            offs_add(i, add);
        }
    }
}


// Workgroup-memory sort slots: pixel li's slot j at j·64 + li (consecutive lanes, consecutive
// banks).
var<workgroup> sort_d: array<f32, 64u * WG_CAP>;
var<workgroup> sort_t: array<u32, 64u * WG_CAP>;

// Pixel li's ring (`resolve_sort = workgroup`): a ring of WG_CAP slots whose logical entry i (in
// depth order) is at slot (head + i) & RING. A fragment goes in from the nearer end of the list,
// so lists that arrive in depth order *or in reverse* (the fill's atomics order big triangles
// either way from frame to frame; nested shells alternate near and far) cost no moves, where a
// one-ended insertion sort moved every entry in the reverse case: quads(32) at 1024² on the H200
// ran its resolve at 0.53 or 0.77 ms by which order a frame's fill happened to give. n < WG_CAP.
fn ring_insert(li: u32, head: ptr<function, u32>, n: u32, z: f32, tag: u32) {
    let h0 = *head;
    let mid = (h0 + n / 2u) & RING;
    if n > 0u && before(z, tag, sort_d[mid * 64u + li], sort_t[mid * 64u + li]) {
        // Front half: the entries before z move one slot toward the front.
        let h = (h0 + RING) & RING;
        *head = h;
        var j = 0u;
        loop {
            let k = (h + j + 1u) & RING;
            if !before(sort_d[k * 64u + li], sort_t[k * 64u + li], z, tag) {
                break;
            }
            let m = (h + j) & RING;
            sort_d[m * 64u + li] = sort_d[k * 64u + li];
            sort_t[m * 64u + li] = sort_t[k * 64u + li];
            j = j + 1u;
        }
        let m = (h + j) & RING;
        sort_d[m * 64u + li] = z;
        sort_t[m * 64u + li] = tag;
    } else {
        // Back half (or empty): the entries after z move one slot toward the back.
        var j = n;
        loop {
            let k = (h0 + j + RING) & RING;
            if j == 0u || !before(z, tag, sort_d[k * 64u + li], sort_t[k * 64u + li]) {
                break;
            }
            let m = (h0 + j) & RING;
            sort_d[m * 64u + li] = sort_d[k * 64u + li];
            sort_t[m * 64u + li] = sort_t[k * 64u + li];
            j = j - 1u;
        }
        let m = (h0 + j) & RING;
        sort_d[m * 64u + li] = z;
        sort_t[m * 64u + li] = tag;
    }
}

// Insertion into a per-thread sorted array of SORT_MAX; beyond it the farthest is dropped (and
// counted), keeping the SORT_MAX nearest.
fn private_insert(
    d: ptr<function, array<f32, SORT_MAX>>,
    t: ptr<function, array<u32, SORT_MAX>>,
    n: ptr<function, u32>,
    dropped: ptr<function, u32>,
    z: f32,
    tag: u32,
) {
    if *n == SORT_MAX {
        *dropped = *dropped + 1u;
        if !before(z, tag, (*d)[SORT_MAX - 1u], (*t)[SORT_MAX - 1u]) {
            return;
        }
        *n = SORT_MAX - 1u;
    }
    var j = *n;
    loop {
        if j == 0u || !before(z, tag, (*d)[j - 1u], (*t)[j - 1u]) {
            break;
        }
        (*d)[j] = (*d)[j - 1u];
        (*t)[j] = (*t)[j - 1u];
        j = j - 1u;
    }
    (*d)[j] = z;
    (*t)[j] = tag;
    *n = *n + 1u;
}

// Vertex i's snapped screen position and clip w; x = SCREEN_NONE where it lies outside the depth
// range or the guard band (so its triangles are clipped). With PRETRANSFORM two 8 B loads of the
// clip buffer, the same count as the clip-space weights' (x, y) and (z, w).
fn snapped_vertex(i: u32) -> vec3<f32> {
    if PRETRANSFORM {
        return vec3<f32>(clipv[3u * i + 2u], clipv[3u * i + 1u].y);
    }
    let c = clip_of(i);
    if !in_depth_range(c) || outside_guard(c) {
        return vec3<f32>(SCREEN_NONE, 0.0, 0.0);
    }
    return vec3<f32>(screen_of(i), c.w);
}

// The weights of the snapped screen triangle `i` at pixel `xy`'s centre, perspective-corrected
// (what the reference computes in f64, and a hardware rasteriser from its snapped positions),
// from exact i32 edge functions; (0, 0, 0, 0) where they do not apply: a triangle the capture
// clipped (its fan triangles are other triangles), one over SMALL_EXTENT (i32 would overflow),
// or one degenerate once snapped. The reference's (e_k / area) / w_k normalised is
// e_k·w_l·w_m normalised (area and the product of the w cancel): one division, not seven.
fn snapped_weights(i: vec3<u32>, xy: vec2<u32>) -> vec4<f32> {
    let v0 = snapped_vertex(i.x);
    let v1 = snapped_vertex(i.y);
    let v2 = snapped_vertex(i.z);
    if min(min(v0.x, v1.x), v2.x) == SCREEN_NONE {
        return vec4<f32>(0.0);
    }
    let a = vec2<i32>(v0.xy * SUB);
    let b = vec2<i32>(v1.xy * SUB);
    let d = vec2<i32>(v2.xy * SUB);
    if !spans_fit_i32(a, b, d) {
        return vec4<f32>(0.0);
    }
    let p = centre_units(i32(xy.x), i32(xy.y));
    let e = vec3<i32>(edge_i32(b, d, p), edge_i32(d, a, p), edge_i32(a, b, p));
    if e.x + e.y + e.z == 0 {
        return vec4<f32>(0.0);
    }
    let pw = vec3<f32>(e) * vec3<f32>(v1.z * v2.z, v2.z * v0.z, v0.z * v1.z);
    let sum = pw.x + pw.y + pw.z;
    // Zero or not finite (w products beyond f32): the clip-space weights instead.
    if !(abs(sum) > 0.0 && abs(sum) < 3.0e38) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(pw * (1.0 / sum), 1.0);
}

// The fragment (depth, tag) at pixel `xy` (NDC `ndc`): attributes weighted as the snapped
// screen triangle's (axis `attributes = snapped`) or by the 2D homogeneous weights of the
// unsnapped clip-space triangle (`clip`; also where the snapped ones do not apply). The two
// differ on slivers thinner than a pixel, where snapping moves a vertex by a fair share of the
// triangle's width. Snapped, the clip positions are loaded only where the weights fall back.
fn fragment(depth: f32, tag: u32, ndc: vec2<f32>, xy: vec2<u32>) -> Frag {
    let i = tri_indices(tag_prim(tag));
    if SNAPPED_ATTRS {
        let w = snapped_weights(i, xy);
        if w.w > 0.0 {
            return frag_weighted(depth, tag, i, w.xyz);
        }
    }
    return frag_from(depth, tag, ndc, i, clip_at(i.x), clip_at(i.y), clip_at(i.z));
}

// The pixel's stored fragments' slot range.
fn stored_range(p: u32) -> vec2<u32> {
    var start = 0u;
    if p > 0u {
        start = min(offs_load(p - 1u), sizes.capacity);
    }
    return vec2<u32>(start, min(offs_load(p), sizes.capacity));
}

// Pixel p's folds written: one image per fold image, the mean over the samples with MSAA.
fn store_fold(p: u32, st: FoldState) {
    let wh = u32(camera.viewport.x) * u32(camera.viewport.y);
    for (var k = 0u; k < fold_image_count(); k = k + 1u) {
        out_image[k * wh + p] = fold_finish_image(st, k);
    }
}

fn store_samples(p: u32, ss: ptr<function, array<FoldState, 8>>) {
    let wh = u32(camera.viewport.x) * u32(camera.viewport.y);
    for (var k = 0u; k < fold_image_count(); k = k + 1u) {
        var sum = vec4<f32>(0.0);
        for (var s = 0u; s < AA_SAMPLES; s = s + 1u) {
            sum = sum + fold_finish_image((*ss)[s], k);
        }
        out_image[k * wh + p] = sum / f32(AA_SAMPLES);
    }
}

// One fragment into each sample's fold whose bit its coverage mask has (attributes derived once,
// at the pixel centre).
fn fold_samples(ss: ptr<function, array<FoldState, 8>>, f: Frag, tag: u32) {
    let mask = (tag >> TAG_PRIM_BITS) & 0xffu;
    for (var s = 0u; s < AA_SAMPLES; s = s + 1u) {
        if (mask & (1u << s)) != 0u {
            var st = (*ss)[s];
            fold_step(&st, f);
            (*ss)[s] = st;
        }
    }
}

fn init_samples(ss: ptr<function, array<FoldState, 8>>, xy: vec2<u32>) {
    for (var s = 0u; s < AA_SAMPLES; s = s + 1u) {
        (*ss)[s] = fold_init_at(vec2<f32>(xy) + 0.5);
    }
}

// A list sorted in a per-thread array (`resolve_sort = private`, or longer than the ring). The
// arrays live here and not in `resolve` because WGSL zero-initialises a function's variables on
// entry (naga writes an OpConstantNull initialiser): 1 KiB a thread at SORT_MAX = 128, which a
// pixel whose list fits the ring must not pay.
fn resolve_private(xy: vec2<u32>, p: u32, start: u32, end: u32) {
    var d: array<f32, SORT_MAX>;
    var t: array<u32, SORT_MAX>;
    var n = 0u;
    var dropped = 0u;
    for (var s = start; s < end; s = s + 1u) {
        let e = frags_load(s);
        private_insert(&d, &t, &n, &dropped, bitcast<f32>(e.x), e.y);
    }
    let ndc = pixel_ndc(xy);
    if AA_SAMPLES > 1u {
        var ss: array<FoldState, 8>;
        init_samples(&ss, xy);
        for (var i = 0u; i < n; i = i + 1u) {
            fold_samples(&ss, fragment(d[i], t[i], ndc, xy), t[i]);
        }
        store_samples(p, &ss);
    } else {
        var st = fold_init_at(vec2<f32>(xy) + 0.5);
        for (var i = 0u; i < n; i = i + 1u) {
            fold_step(&st, fragment(d[i], t[i], ndc, xy));
        }
        store_fold(p, st);
    }
    if dropped > 0u {
        work_add(W_OVF_PIXELS, 1u);
        work_add(W_DROPPED, dropped);
    }
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    let r = stored_range(p);
    let start = r.x;
    let end = r.y;
    // resolve_sort = workgroup: lists of up to WG_CAP in the pixel's ring (`ring_insert`).
    if !(WG_SORT && end - start <= WG_CAP) {
        resolve_private(id.xy, p, start, end);
        return;
    }
    var head = 0u;
    var n = 0u;
    for (var s = start; s < end; s = s + 1u) {
        let e = frags_load(s);
        ring_insert(li, &head, n, bitcast<f32>(e.x), e.y);
        n = n + 1u;
    }
    let ndc = pixel_ndc(id.xy);
    if AA_SAMPLES > 1u {
        var ss: array<FoldState, 8>;
        init_samples(&ss, id.xy);
        for (var i = 0u; i < n; i = i + 1u) {
            let k = (head + i) & RING;
            let tag = sort_t[k * 64u + li];
            fold_samples(&ss, fragment(sort_d[k * 64u + li], tag, ndc, id.xy), tag);
        }
        store_samples(p, &ss);
    } else {
        var st = fold_init_at(vec2<f32>(id.xy) + 0.5);
        for (var i = 0u; i < n; i = i + 1u) {
            let k = (head + i) & RING;
            fold_step(&st, fragment(sort_d[k * 64u + li], sort_t[k * 64u + li], ndc, id.xy));
        }
        store_fold(p, st);
    }
}
