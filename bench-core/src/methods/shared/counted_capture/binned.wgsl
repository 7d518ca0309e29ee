// `capture = tiles`: the same exact fragments without a fragment array. Triangles are binned to
// the 8×8-pixel tiles their bounding box touches (count → scan → fill, as the pixel capture does
// for fragments, but one 4 B entry per (tile, triangle) instead of 8 B per fragment); then one
// 8×8 workgroup per tile loads its triangles 64 at a time into workgroup memory (set up once per
// tile) and every pixel tests them all, inserting what covers its centre straight into its sort
// ring. No per-fragment atomic, no fragment store or reload: for a few big triangles (quads,
// shells) the bins are small and the fragments never leave the SM; for many tiny ones the bins are
// about one entry per triangle. Coverage is the same exact integer rule (`make_tri`, top-left,
// 1/256-px snapping) and depth the same `depth_at`, so the fragment set and order equal the
// pixel capture's. Single-sample only (no coverage masks).
//
// Buffers, as the pixel capture binds them: `offs` holds the tiles' counts → first entries → ends
// (sizes.npix = the tile count), then each pixel's fragment count (written by the resolve, read
// back as the row's counts); `frags` holds the bin entries, two u32 primitive ids per element.

// Tile edge (pixels): one resolve workgroup.
const BIN: i32 = 8;
// Tiles of a triangle's bounding box that one thread bins; larger boxes (and clipped polygons)
// are listed for `bin_big`, one workgroup each.
override BIN_SMALL: u32 = 16u;
// A "fast" triangle (every edge's |Δx| + |Δy| under FAST_SPAN units) steps its edge functions
// from the tile's first pixel in i32: a step over the tile is at most 7·256·FAST_SPAN < 2^30, so
// the 64-bit value at the first pixel, clamped to ±2^30, keeps every sign in the tile.
const FAST_SPAN: i32 = 598000;
const CLAMP_E: i32 = 1073741824;
const K_NONE: i32 = 0;
const K_FAST: i32 = 1;
const K_SLOW: i32 = 2; // 64-bit edge values per pixel
const K_POLY: i32 = 3; // a clipped polygon: every pixel sets it up and walks its fan

fn bin_tiles_x() -> u32 {
    return (u32(camera.viewport.x) + 7u) / 8u;
}

fn bin_at(s: u32) -> u32 {
    let e = frags[s >> 1u];
    return select(e.x, e.y, (s & 1u) != 0u);
}

fn bin_emit(tile: u32, prim: u32) {
    if FILL {
        let slot = atomicAdd(&offs[tile], 1u);
        if slot < sizes.capacity {
            if (slot & 1u) == 0u {
                frags[slot >> 1u].x = prim;
            } else {
                frags[slot >> 1u].y = prim;
            }
        } else {
            atomicAdd(&work[W_LOST], 1u);
        }
    } else {
        atomicAdd(&offs[tile], 1u);
    }
}

// Whether edge a→b (E(c) = (b − a) × (c − a), ≥ 0 inside) can be ≥ 0 at a point of the
// rectangle lo..hi: E is affine, so its largest value is at one corner. f32 with a margin far
// above its rounding (the snapped f32 positions are the integer units exactly), so a tile is
// never dropped that the exact rule would cover.
fn edge_touch(a: vec2<f32>, b: vec2<f32>, lo: vec2<f32>, hi: vec2<f32>) -> bool {
    let d = b - a;
    let c = vec2<f32>(select(lo.x, hi.x, d.y < 0.0), select(lo.y, hi.y, d.x > 0.0));
    let p = d.x * (c.y - a.y);
    let q = d.y * (c.x - a.x);
    return p - q >= -(1e-5 * (abs(p) + abs(q)) + 1e-3);
}

// Whether `t` may cover a pixel centre of tile (tx, ty).
fn tile_touch(t: Tri, tx: i32, ty: i32) -> bool {
    let lo = vec2<f32>(f32(tx * BIN) + 0.5, f32(ty * BIN) + 0.5);
    let hi = lo + f32(BIN - 1);
    return edge_touch(t.f1.xy, t.f2.xy, lo, hi) && edge_touch(t.f2.xy, t.f0.xy, lo, hi) && edge_touch(t.f0.xy, t.f1.xy, lo, hi);
}

// One thread per triangle whose bounding box spans at most BIN_SMALL tiles; the others are
// listed (count pass) for `bin_big` and skipped by the fill pass.
@compute @workgroup_size(64)
fn bin_small(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let tx_n = bin_tiles_x();
    for (var prim = gid.x; prim < sizes.ntri; prim = prim + nw.x * 64u) {
        let p = setup(prim);
        let bb = bounds(p);
        if bb.x > bb.z || bb.y > bb.w {
            continue;
        }
        let tb = bb / BIN;
        let nt = u32(tb.z - tb.x + 1) * u32(tb.w - tb.y + 1);
        if p.n != 3u || nt > BIN_SMALL {
            if !FILL {
                let k = atomicAdd(&work[W_BIG], 1u);
                if k < sizes.big_cap {
                    atomicStore(&work[list_at(k)], prim);
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
        for (var ty = tb.y; ty <= tb.w; ty = ty + 1) {
            for (var tx = tb.x; tx <= tb.z; tx = tx + 1) {
                if nt == 1u || tile_touch(t, tx, ty) {
                    bin_emit(u32(ty) * tx_n + u32(tx), prim);
                }
            }
        }
    }
}

var<workgroup> wb_poly: Poly;
var<workgroup> wb_prim: u32;
var<workgroup> wb_ok: u32;

// One workgroup per listed triangle: its threads share the bounding box's tiles.
@compute @workgroup_size(64)
fn bin_big(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(num_workgroups) nw: vec3<u32>,
) {
    if li == 0u {
        wb_ok = 0u;
        let k = wg.x + wg.y * nw.x;
        if k < min(atomicLoad(&work[W_BIG]), sizes.big_cap) {
            let prim = atomicLoad(&work[list_at(k)]);
            wb_poly = setup(prim);
            wb_prim = prim;
            wb_ok = 1u;
        }
    }
    if workgroupUniformLoad(&wb_ok) == 0u {
        return;
    }
    let p = workgroupUniformLoad(&wb_poly);
    let prim = workgroupUniformLoad(&wb_prim);
    let bb = bounds(p);
    if bb.x > bb.z || bb.y > bb.w {
        return;
    }
    let tb = bb / BIN;
    let gw = u32(tb.z - tb.x + 1);
    let nt = gw * u32(tb.w - tb.y + 1);
    let tx_n = bin_tiles_x();
    for (var i = li; i < nt; i = i + 64u) {
        let tx = tb.x + i32(i % gw);
        let ty = tb.y + i32(i / gw);
        // A polygon is binned once per tile, whichever of its fan triangles touches it.
        var touch = false;
        for (var f = 1u; f + 1u < p.n; f = f + 1u) {
            let t = make_tri(p, f);
            touch = touch || (t.ok && tile_touch(t, tx, ty));
        }
        if touch {
            bin_emit(u32(ty) * tx_n + u32(tx), prim);
        }
    }
}

// A tile's triangles, 64 at a time, set up once for all its pixels. Fast: (E at the tile's first
// pixel, clamped, kind), (dE/dx, tag), (dE/dy, −); slow: (i0, i1.x, kind), (i1.y, i2, tag),
// (top-left bits, −); polygon: (−, kind), (−, primitive). Then (f0, area), (f1, −), (f2, −) for
// `depth_at`.
var<workgroup> be_e: array<vec4<i32>, 64>;
var<workgroup> be_s: array<vec4<i32>, 64>;
var<workgroup> be_y: array<vec4<i32>, 64>;
var<workgroup> be_f: array<vec4<f32>, 192>;
var<workgroup> bt_range: vec2<u32>;

// A 64-bit edge value clamped to ±CLAMP_E.
fn clamp_e(e: vec2<u32>) -> i32 {
    let v = bitcast<i32>(e.x);
    if (e.y == 0u && v >= 0 && v <= CLAMP_E) || (e.y == 0xffffffffu && v < 0 && v >= -CLAMP_E) {
        return v;
    }
    return select(CLAMP_E, -CLAMP_E, neg64(e));
}

// The triangle of entry j with what `depth_at` and the 64-bit edges read.
fn entry_tri(j: u32) -> Tri {
    var t: Tri;
    let a = be_f[3u * j];
    t.f0 = a.xyz;
    t.area = a.w;
    t.f1 = be_f[3u * j + 1u].xyz;
    t.f2 = be_f[3u * j + 2u].xyz;
    let e = be_e[j];
    let s = be_s[j];
    t.i0 = e.xy;
    t.i1 = vec2<i32>(e.z, s.x);
    t.i2 = s.yz;
    let tl = be_y[j].x;
    t.tl = vec3<bool>((tl & 1) != 0, (tl & 2) != 0, (tl & 4) != 0);
    return t;
}

// Thread li sets up bin entry `s` (primitive `prim`) for tile origin `o` (pixels).
fn load_entry(li: u32, prim: u32, o: vec2<i32>) {
    let p = setup(prim);
    var kind = K_NONE;
    var tag = prim;
    if p.n > 3u {
        kind = K_POLY;
    } else if p.n == 3u {
        let t = make_tri(p, 1u);
        if t.ok {
            tag = prim | select(0u, 0x80000000u, t.front);
            be_f[3u * li] = vec4<f32>(t.f0, t.area);
            be_f[3u * li + 1u] = vec4<f32>(t.f1, 0.0);
            be_f[3u * li + 2u] = vec4<f32>(t.f2, 0.0);
            let d0 = abs(t.i2 - t.i1);
            let d1 = abs(t.i0 - t.i2);
            let d2 = abs(t.i1 - t.i0);
            if max(max(d0.x + d0.y, d1.x + d1.y), d2.x + d2.y) < FAST_SPAN {
                kind = K_FAST;
                let e = vec3<i32>(
                    clamp_e(edge_biased64(t, 0u, o.x, o.y)),
                    clamp_e(edge_biased64(t, 1u, o.x, o.y)),
                    clamp_e(edge_biased64(t, 2u, o.x, o.y)),
                );
                let sx = vec3<i32>(t.i1.y - t.i2.y, t.i2.y - t.i0.y, t.i0.y - t.i1.y) * 256;
                let sy = vec3<i32>(t.i2.x - t.i1.x, t.i0.x - t.i2.x, t.i1.x - t.i0.x) * 256;
                be_e[li] = vec4<i32>(e, kind);
                be_s[li] = vec4<i32>(sx, bitcast<i32>(tag));
                be_y[li] = vec4<i32>(sy, 0);
                return;
            }
            kind = K_SLOW;
            let tl = select(0, 1, t.tl.x) | select(0, 2, t.tl.y) | select(0, 4, t.tl.z);
            be_e[li] = vec4<i32>(t.i0, t.i1.x, kind);
            be_s[li] = vec4<i32>(t.i1.y, t.i2, bitcast<i32>(tag));
            be_y[li] = vec4<i32>(tl, 0, 0, 0);
            return;
        }
    }
    be_e[li] = vec4<i32>(0, 0, 0, kind);
    be_s[li] = vec4<i32>(0, 0, 0, bitcast<i32>(tag));
}

// A pixel's sort state: its ring while it holds at most WG_CAP (`resolve_sort = workgroup`),
// then the per-thread array.
struct SortState {
    n: u32,
    head: u32,
    dropped: u32,
    in_wg: bool,
};

fn sort_insert(
    li: u32,
    st: ptr<function, SortState>,
    d: ptr<function, array<f32, SORT_MAX>>,
    t: ptr<function, array<u32, SORT_MAX>>,
    z: f32,
    tag: u32,
) {
    if (*st).in_wg && (*st).n == WG_CAP {
        // The ring is full: move it, in order, to the per-thread array.
        for (var i = 0u; i < WG_CAP; i = i + 1u) {
            let k = ((*st).head + i) & RING;
            (*d)[i] = sort_d[k * 64u + li];
            (*t)[i] = sort_t[k * 64u + li];
        }
        (*st).in_wg = false;
    }
    if (*st).in_wg {
        var head = (*st).head;
        ring_insert(li, &head, (*st).n, z, tag);
        (*st).head = head;
        (*st).n = (*st).n + 1u;
    } else {
        var n = (*st).n;
        var dropped = (*st).dropped;
        private_insert(d, t, &n, &dropped, z, tag);
        (*st).n = n;
        (*st).dropped = dropped;
    }
}

@compute @workgroup_size(8, 8)
fn resolve_binned(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    let tile = wg.y * bin_tiles_x() + wg.x;
    if li == 0u {
        var start = 0u;
        if tile > 0u {
            start = min(atomicLoad(&offs[tile - 1u]), sizes.capacity);
        }
        bt_range = vec2<u32>(start, min(atomicLoad(&offs[tile]), sizes.capacity));
    }
    let range = workgroupUniformLoad(&bt_range);
    let o = vec2<i32>(wg.xy * 8u);
    let px = wg.xy * 8u + lid.xy;
    let inside = px.x < w && px.y < h;
    let x = i32(px.x);
    let y = i32(px.y);
    var d: array<f32, SORT_MAX>;
    var t: array<u32, SORT_MAX>;
    var st = SortState(0u, 0u, 0u, WG_SORT);
    for (var base = range.x; base < range.y; base = base + 64u) {
        if base + li < range.y {
            load_entry(li, bin_at(base + li), o);
        }
        workgroupBarrier();
        let m = min(64u, range.y - base);
        for (var j = 0u; j < m && inside; j = j + 1u) {
            let e = be_e[j];
            let s = be_s[j];
            if e.w == K_FAST {
                let v = e.xyz + s.xyz * i32(lid.x) + be_y[j].xyz * i32(lid.y);
                if (v.x | v.y | v.z) >= 0 {
                    sort_insert(li, &st, &d, &t, depth_at(entry_tri(j), x, y), bitcast<u32>(s.w));
                }
            } else if e.w == K_SLOW {
                let tr = entry_tri(j);
                let a = edge_biased64(tr, 0u, x, y);
                let b = edge_biased64(tr, 1u, x, y);
                let c = edge_biased64(tr, 2u, x, y);
                if ((a.y | b.y | c.y) & 0x80000000u) == 0u {
                    sort_insert(li, &st, &d, &t, depth_at(tr, x, y), bitcast<u32>(s.w));
                }
            } else if e.w == K_POLY {
                let prim = bitcast<u32>(s.w);
                let p = setup(prim);
                for (var f = 1u; f + 1u < p.n; f = f + 1u) {
                    let tr = make_tri(p, f);
                    if tr.ok {
                        let z = cover(tr, x, y);
                        if z >= 0.0 {
                            sort_insert(li, &st, &d, &t, z, prim | select(0u, 0x80000000u, tr.front));
                        }
                    }
                }
            }
        }
        workgroupBarrier();
    }
    if !inside {
        return;
    }
    let p = px.y * w + px.x;
    atomicStore(&offs[sizes.npix + p], st.n + st.dropped);
    let ndc = pixel_ndc(px);
    var fs = fold_init_at(vec2<f32>(px) + 0.5);
    for (var i = 0u; i < st.n; i = i + 1u) {
        if st.in_wg {
            let k = (st.head + i) & RING;
            fold_step(&fs, fragment(sort_d[k * 64u + li], sort_t[k * 64u + li], ndc));
        } else {
            fold_step(&fs, fragment(d[i], t[i], ndc));
        }
    }
    for (var k = 0u; k < fold_image_count(); k = k + 1u) {
        out_image[k * w * h + p] = fold_finish_image(fs, k);
    }
    if st.dropped > 0u {
        atomicAdd(&work[W_OVF_PIXELS], 1u);
        atomicAdd(&work[W_DROPPED], st.dropped);
    }
}
