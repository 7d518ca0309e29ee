// An exact A-buffer built without the raster pipeline: triangles are rasterised in compute, twice.
// Count: every covered pixel centre adds 1 to its pixel (atomicAdd). Scan: an exclusive prefix
// sum turns the counts into each pixel's first slot. Fill: the same coverage again; each fragment
// takes the next slot of its pixel (atomicAdd on the start, which so ends as the pixel's end) and
// stores 8 B: its window depth and its primitive id (bit 31: front facing). Resolve: per pixel,
// sort the slots by (depth, primitive) and fold them, re-deriving colour, normal, view depth and
// object id from the primitive's vertices at the pixel centre (visibility-buffer style), so a
// fragment costs exactly the 8 B of its depth and identity.
//
// Coverage matches the reference rasteriser (`reference/raster.rs`) rule for rule: clip to
// 0 ≤ z ≤ w, clip x/y to a guard band of ±GUARD·w only where a vertex lies outside it, snap to
// 1/256 px, sample pixel centres, top-left fill rule. Edge functions are evaluated exactly (64-bit
// products emulated with 32-bit integers), so shared edges are watertight and ties are decided as
// the reference decides them. Triangles whose bounding box holds at most `small_max` pixels are
// rasterised by one thread each; larger (and clipped) ones are cut into chunks of CHUNK
// bounding-box pixels, one workgroup per chunk (`raster_big`), so neither a full-screen
// triangle stalls one thread nor a 200-pixel one idles a workgroup.

override FILL: bool = false;
// Sizes read at run time, so that one compiled kernel serves every scene and resolution (a
// software driver compiles each specialisation anew).
struct Sizes {
    ntri: u32,
    npix: u32,
    nblocks: u32,
    // Fragment slots allocated (the prepare-time count); a fragment beyond it is counted as lost.
    capacity: u32,
    // Capacity of the big-triangle list (2 words each: primitive, first chunk).
    big_cap: u32,
    // Capacity of the chunk → big-triangle table.
    chunk_cap: u32,
    // Largest bounding box (pixels) one thread rasterises.
    small_max: u32,
};
@group(0) @binding(10) var<uniform> sizes: Sizes;
// Per-pixel sort capacity of the resolve (a register/local array; WGSL needs a constant size).
const SORT_MAX: u32 = 128u;
const GUARD: f32 = 1024.0;
const MAXV: u32 = 9u;
const SUB: f32 = 256.0;

// `work` layout (u32 words): counters, the scan's block sums, the big-triangle list, the chunks.
const W_BIG: u32 = 0u;         // big triangles listed this frame
const W_LOST: u32 = 1u;        // fragments beyond `capacity`
const W_OVF_PIXELS: u32 = 2u;  // pixels with more than SORT_MAX fragments
const W_DROPPED: u32 = 3u;     // fragments dropped by the resolve's sort capacity
const W_TOTAL: u32 = 4u;       // fragments counted (the scan's total)
const W_BIG_LOST: u32 = 5u;    // big triangles beyond `big_cap` (their fragments are missing)
const W_CHUNKS: u32 = 6u;      // chunks of the listed big triangles
const W_BLOCKS: u32 = 16u;
// Bounding-box pixels per chunk: 64 threads × 16.
const CHUNK: u32 = 1024u;

fn list_at(k: u32) -> u32 {
    return W_BLOCKS + sizes.nblocks + 2u * k;
}

fn owner_at(c: u32) -> u32 {
    return W_BLOCKS + sizes.nblocks + 2u * sizes.big_cap + c;
}

@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> colors: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> object_ids: array<u32>;
@group(0) @binding(5) var<storage, read> indices: array<u32>;
// Per pixel: count (after Count) → first slot (after Scan) → one past the last slot (after Fill).
@group(0) @binding(6) var<storage, read_write> offs: array<atomic<u32>>;
// Per fragment: (window depth bits, primitive | front << 31).
@group(0) @binding(7) var<storage, read_write> frags: array<vec2<u32>>;
@group(0) @binding(8) var<storage, read_write> work: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> out_image: array<vec4<f32>>;

fn position(i: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

fn clip_of(i: u32) -> vec4<f32> {
    return camera.clip_from_world * vec4<f32>(position(i), 1.0);
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
    for (var k = 0u; k < 3u; k = k + 1u) {
        p.v[k] = clip_of(indices[3u * prim + k]);
    }
    var inside = true;
    for (var k = 0u; k < 3u; k = k + 1u) {
        let c = p.v[k];
        inside = inside && c.z >= 0.0 && c.w - c.z >= 0.0;
    }
    var guard = false;
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
    }
    if p.n < 3u {
        p.n = 0u;
    }
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

// Pixel-centre bounds (x0, y0, x1, y1) of a screen polygon, clamped to the viewport; x0 > x1 or
// y0 > y1 when it covers no centre.
fn bounds(p: Poly) -> vec4<i32> {
    var lo = vec2<f32>(3.4e38);
    var hi = vec2<f32>(-3.4e38);
    for (var k = 0u; k < p.n; k = k + 1u) {
        lo = min(lo, p.v[k].xy);
        hi = max(hi, p.v[k].xy);
    }
    let vp = camera.viewport.xy;
    let a = max(ceil(lo - 0.5), vec2<f32>(0.0));
    let b = min(floor(hi - 0.5), vp - 1.0);
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

// Window depth at pixel (x, y) if `t` covers its centre, else a negative value.
fn cover(t: Tri, x: i32, y: i32) -> f32 {
    let c = vec2<i32>(x * 256 + 128, y * 256 + 128);
    let s = vec3<i32>(edge_sign(t.i1, t.i2, c), edge_sign(t.i2, t.i0, c), edge_sign(t.i0, t.i1, c));
    if any(s < vec3<i32>(0)) || any((s == vec3<i32>(0)) & !t.tl) {
        return -1.0;
    }
    let cf = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    // The exact area is not 0 (`ok`), but its f32 value can round to 0 on a huge sliver.
    let area = select(t.area, 1.0, t.area == 0.0);
    let b = vec3<f32>(edge_f(t.f1.xy, t.f2.xy, cf), edge_f(t.f2.xy, t.f0.xy, cf), edge_f(t.f0.xy, t.f1.xy, cf)) / area;
    return clamp(b.x * t.f0.z + b.y * t.f1.z + b.z * t.f2.z, 0.0, 1.0);
}

fn emit(x: i32, y: i32, depth: f32, prim: u32, front: bool) {
    let p = u32(y) * u32(camera.viewport.x) + u32(x);
    let slot = atomicAdd(&offs[p], 1u);
    if FILL {
        if slot < sizes.capacity {
            frags[slot] = vec2<u32>(bitcast<u32>(depth), prim | select(0u, 0x80000000u, front));
        } else {
            atomicAdd(&work[W_LOST], 1u);
        }
    }
}

// One thread per triangle; triangles with a large bounding box (or a clipped polygon) are listed
// for `raster_big` by the count pass (the fill pass skips them the same way).
@compute @workgroup_size(64)
fn raster_small(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    for (var prim = gid.x; prim < sizes.ntri; prim = prim + nw.x * 64u) {
        let p = setup(prim);
        let bb = bounds(p);
        if bb.x > bb.z || bb.y > bb.w {
            continue;
        }
        let px = u32(bb.z - bb.x + 1) * u32(bb.w - bb.y + 1);
        if p.n != 3u || px > sizes.small_max {
            if !FILL {
                let k = atomicAdd(&work[W_BIG], 1u);
                let nch = (px + CHUNK - 1u) / CHUNK;
                let first = atomicAdd(&work[W_CHUNKS], nch);
                if k < sizes.big_cap && first + nch <= sizes.chunk_cap {
                    atomicStore(&work[list_at(k)], prim);
                    atomicStore(&work[list_at(k) + 1u], first);
                    for (var c = 0u; c < nch; c = c + 1u) {
                        atomicStore(&work[owner_at(first + c)], k);
                    }
                } else {
                    atomicAdd(&work[W_BIG_LOST], 1u);
                }
            }
            continue;
        }
        let t = make_tri(p, 1u);
        if !t.ok {
            continue;
        }
        for (var y = bb.y; y <= bb.w; y = y + 1) {
            for (var x = bb.x; x <= bb.z; x = x + 1) {
                let z = cover(t, x, y);
                if z >= 0.0 {
                    emit(x, y, z, prim, t.front);
                }
            }
        }
    }
}

// Big triangles: one workgroup per chunk (of CHUNK bounding-box pixels) of a listed triangle.
// Thread 0 sets the triangle up once and shares it (per-thread setup dominated: 64 setups per
// medium triangle cost as much as the rest of the pass).
var<workgroup> wg_poly: Poly;
var<workgroup> wg_prim: u32;
// First bounding-box pixel of this chunk, or 0xffffffff when the workgroup has nothing to do.
var<workgroup> wg_start: u32;

@compute @workgroup_size(64)
fn raster_big(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(num_workgroups) nw: vec3<u32>,
) {
    if li == 0u {
        wg_start = 0xffffffffu;
        let c = wg.x + wg.y * nw.x;
        if c < min(atomicLoad(&work[W_CHUNKS]), sizes.chunk_cap) {
            let k = atomicLoad(&work[owner_at(c)]);
            if k < min(atomicLoad(&work[W_BIG]), sizes.big_cap) {
                let prim = atomicLoad(&work[list_at(k)]);
                let first = atomicLoad(&work[list_at(k) + 1u]);
                let p = setup(prim);
                let bb = bounds(p);
                let px = u32(bb.z - bb.x + 1) * u32(bb.w - bb.y + 1);
                // A stale table entry (only after a listing overflow, which is flagged) is
                // not this triangle's.
                if bb.x <= bb.z && bb.y <= bb.w && c >= first && (c - first) * CHUNK < px {
                    wg_poly = p;
                    wg_prim = prim;
                    wg_start = (c - first) * CHUNK;
                }
            }
        }
    }
    let start = workgroupUniformLoad(&wg_start);
    if start == 0xffffffffu {
        return;
    }
    let p = wg_poly;
    let prim = wg_prim;
    let bb = bounds(p);
    let bw = u32(bb.z - bb.x + 1);
    let px = bw * u32(bb.w - bb.y + 1);
    for (var t_i = 1u; t_i + 1u < p.n; t_i = t_i + 1u) {
        let t = make_tri(p, t_i);
        if !t.ok {
            continue;
        }
        for (var j = li; j < CHUNK; j = j + 64u) {
            let i = start + j;
            if i < px {
                let x = bb.x + i32(i % bw);
                let y = bb.y + i32(i / bw);
                let z = cover(t, x, y);
                if z >= 0.0 {
                    emit(x, y, z, prim, t.front);
                }
            }
        }
    }
}

// Exclusive prefix sum of `offs` (`npix` counts) in three dispatches: blocks of 1,024, the block
// sums (one workgroup, in chunks of 256 with a carry), then each block's offset added back.
var<workgroup> sh: array<u32, 256>;

fn scan_shared(li: u32) {
    for (var off = 1u; off < 256u; off = off * 2u) {
        var t = 0u;
        if li >= off {
            t = sh[li - off];
        }
        workgroupBarrier();
        sh[li] = sh[li] + t;
        workgroupBarrier();
    }
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let base = wg.x * 1024u + li * 4u;
    var v: array<u32, 4>;
    var s = 0u;
    for (var k = 0u; k < 4u; k = k + 1u) {
        let i = base + k;
        var x = 0u;
        if i < sizes.npix {
            x = atomicLoad(&offs[i]);
        }
        v[k] = s;
        s = s + x;
    }
    sh[li] = s;
    workgroupBarrier();
    scan_shared(li);
    let before = sh[li] - s;
    for (var k = 0u; k < 4u; k = k + 1u) {
        let i = base + k;
        if i < sizes.npix {
            atomicStore(&offs[i], v[k] + before);
        }
    }
    if li == 255u {
        atomicStore(&work[W_BLOCKS + wg.x], sh[255]);
    }
}

@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_index) li: u32) {
    var carry = 0u;
    for (var c = 0u; c < sizes.nblocks; c = c + 256u) {
        let i = c + li;
        var x = 0u;
        if i < sizes.nblocks {
            x = atomicLoad(&work[W_BLOCKS + i]);
        }
        sh[li] = x;
        workgroupBarrier();
        scan_shared(li);
        if i < sizes.nblocks {
            atomicStore(&work[W_BLOCKS + i], carry + sh[li] - x);
        }
        carry = carry + sh[255];
        workgroupBarrier();
    }
    if li == 0u {
        atomicStore(&work[W_TOTAL], carry);
    }
}

@compute @workgroup_size(256)
fn scan_add(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let add = atomicLoad(&work[W_BLOCKS + wg.x]);
    let base = wg.x * 1024u + li * 4u;
    for (var k = 0u; k < 4u; k = k + 1u) {
        let i = base + k;
        if i < sizes.npix {
            atomicAdd(&offs[i], add);
        }
    }
}

// Perspective-correct weights of a triangle's three vertices at NDC point `ndc` (2D homogeneous
// rasterisation, Olano & Greer 1997): solve [v0 v1 v2]·λ ∝ (x, y, 1) over the clip-space
// (x, y, w) columns, each scaled to unit size first so vertices at 1e20 neither overflow nor
// cancel; valid for vertices behind the eye too. A covered point lies inside the triangle, so
// its weights are in [0, 1]: they are clamped there (rounding), and a triangle degenerate in clip
// space (collinear vertices that snapping turned into a covering sliver: λ ≈ 0/0) gets equal
// weights instead of NaN.
fn persp_weights(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, ndc: vec2<f32>) -> vec3<f32> {
    let s = 1.0 / max(vec3<f32>(
        max(max(abs(c0.x), abs(c0.y)), abs(c0.w)),
        max(max(abs(c1.x), abs(c1.y)), abs(c1.w)),
        max(max(abs(c2.x), abs(c2.y)), abs(c2.w)),
    ), vec3<f32>(1e-30));
    let a = c0.xyw * s.x;
    let b = c1.xyw * s.y;
    let c = c2.xyw * s.z;
    let q = vec3<f32>(ndc, 1.0);
    let l = vec3<f32>(dot(cross(b, c), q), dot(cross(c, a), q), dot(cross(a, b), q)) * s;
    let sum = l.x + l.y + l.z;
    if !(abs(sum) > 1e-6 * (abs(l.x) + abs(l.y) + abs(l.z))) {
        return vec3<f32>(1.0 / 3.0);
    }
    let w = clamp(l / sum, vec3<f32>(0.0), vec3<f32>(1.0));
    let t = w.x + w.y + w.z;
    if !(t > 0.0) {
        return vec3<f32>(1.0 / 3.0);
    }
    return w / t;
}

fn fragment(depth: f32, tag: u32, ndc: vec2<f32>) -> Frag {
    let prim = tag & 0x7fffffffu;
    let i0 = indices[3u * prim];
    let i1 = indices[3u * prim + 1u];
    let i2 = indices[3u * prim + 2u];
    let p0 = vec4<f32>(position(i0), 1.0);
    let p1 = vec4<f32>(position(i1), 1.0);
    let p2 = vec4<f32>(position(i2), 1.0);
    let m = camera.clip_from_world;
    let b = persp_weights(m * p0, m * p1, m * p2, ndc);
    let v = camera.view_from_world;
    let vz = -vec3<f32>((v * p0).z, (v * p1).z, (v * p2).z);
    let n0 = vec3<f32>(normals[3u * i0], normals[3u * i0 + 1u], normals[3u * i0 + 2u]);
    let n1 = vec3<f32>(normals[3u * i1], normals[3u * i1 + 1u], normals[3u * i1 + 2u]);
    let n2 = vec3<f32>(normals[3u * i2], normals[3u * i2 + 1u], normals[3u * i2 + 2u]);
    return Frag(
        depth,
        dot(b, vz),
        b.x * colors[i0] + b.y * colors[i1] + b.z * colors[i2],
        b.x * n0 + b.y * n1 + b.z * n2,
        object_ids[i0],
        (tag >> 31u) != 0u,
    );
}

// (depth, primitive) of slot a nearer than of slot b: ties keep submission order, as the reference.
fn before(da: f32, pa: u32, db: f32, pb: u32) -> bool {
    return nearer(da, db) || (da == db && (pa & 0x7fffffffu) < (pb & 0x7fffffffu));
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    var start = 0u;
    if p > 0u {
        start = min(atomicLoad(&offs[p - 1u]), sizes.capacity);
    }
    let end = min(atomicLoad(&offs[p]), sizes.capacity);
    var d: array<f32, SORT_MAX>;
    var t: array<u32, SORT_MAX>;
    var n = 0u;
    var dropped = 0u;
    for (var s = start; s < end; s = s + 1u) {
        let e = frags[s];
        let z = bitcast<f32>(e.x);
        if n == SORT_MAX {
            dropped = dropped + 1u;
            if !before(z, e.y, d[n - 1u], t[n - 1u]) {
                continue;
            }
            n = n - 1u;
        }
        var j = n;
        loop {
            if j == 0u || !before(z, e.y, d[j - 1u], t[j - 1u]) {
                break;
            }
            d[j] = d[j - 1u];
            t[j] = t[j - 1u];
            j = j - 1u;
        }
        d[j] = z;
        t[j] = e.y;
        n = n + 1u;
    }
    let centre = vec2<f32>(id.xy) + 0.5;
    let ndc = vec2<f32>(centre.x * camera.viewport.z * 2.0 - 1.0, 1.0 - centre.y * camera.viewport.w * 2.0);
    var st = fold_init_at(centre);
    for (var i = 0u; i < n; i = i + 1u) {
        fold_step(&st, fragment(d[i], t[i], ndc));
    }
    for (var k = 0u; k < fold_image_count(); k = k + 1u) {
        out_image[k * w * h + p] = fold_finish_image(st, k);
    }
    if dropped > 0u {
        atomicAdd(&work[W_OVF_PIXELS], 1u);
        atomicAdd(&work[W_DROPPED], dropped);
    }
}
