// `capture = tiles`: the pixel capture for small triangles, bins for the rest. A triangle that
// `raster_small` takes (bounding box ≤ small_max pixels, spanning ≤ SMALL_EXTENT) stores its
// fragments as before; every other one (and each fan triangle of a clipped polygon) is binned
// instead: one entry per 8×8-pixel tile it may touch, counted, scanned and filled in the same
// passes and the same slot space as the fragments. The resolve runs one 8×8 workgroup per tile:
// each pixel inserts its stored fragments, then the workgroup loads the tile's bin entries 64 at
// a time into workgroup memory (each set up once for the tile) and every pixel tests them,
// inserting what covers its centre straight into its sort. A big triangle so costs no
// per-fragment atomic, store or reload; a small one costs what it did. Coverage is the same
// exact integer rule (`make_tri`, top-left, 1/256-px snapping) and depth the same `depth_at`, so
// the fragment set and order equal the pixel capture's. Single-sample only (no coverage masks).
//
// `offs`: each pixel's count → first slot → end, then each tile's (scanned together:
// sizes.npix = pixels + tiles), then each pixel's fragment total (the resolve writes it; the
// row's counts). A bin entry is a slot (8 B) of `frags`: (primitive | fan triangle << 28, 0).

// Tile edge (pixels): one resolve workgroup.
const BIN: i32 = 8;
// Tiles of a triangle's bounding box that the thread that found it bins; larger boxes (and
// clipped polygons) are listed for `bin_big`, one workgroup each.
const BIN_SMALL: u32 = 16u;
// Bits of a bin entry below its fan triangle's index.
const FAN_SHIFT: u32 = 28u;
// A "fast" triangle (every edge's |Δx| + |Δy| under FAST_SPAN units) decides a tile's pixels in
// i32: E(pixel) = E(first pixel) + 256·F with F = dE/dx'·dx + dE/dy'·dy, |F| ≤ 7·FAST_SPAN <
// 2^30, and E + 256·F ≥ 0 ⟺ ⌊E/256⌋ + F ≥ 0, so ⌊E/256⌋ clamped to ±2^30 keeps every sign.
// (An override only so that tests can send every binned triangle down the 64-bit path.)
override FAST_SPAN: i32 = 150000000;
const CLAMP_E: i32 = 1073741824;
const K_NONE: i32 = 0;
const K_FAST: i32 = 1;
const K_SLOW: i32 = 2; // 64-bit edge values per pixel (edges over FAST_SPAN: guard-band sizes)

fn tiles_x() -> u32 {
    return (u32(camera.viewport.x) + 7u) / 8u;
}

// The word of `offs` that counts tile t's entries (after the pixels').
fn tile_word(t: u32) -> u32 {
    return u32(camera.viewport.x) * u32(camera.viewport.y) + t;
}

fn bin_emit(tile: u32, entry: u32) {
    let w = tile_word(tile);
    if FILL {
        let slot = offs_add(w, 1u);
        if slot < sizes.capacity {
            frags_store(slot, vec2<u32>(entry, 0u));
        } else {
            work_add(W_LOST, 1u);
        }
    } else {
        offs_add(w, 1u);
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

// Bins polygon `p` (bounding box `bb`) of `prim`, called by `raster_small` for what it does not
// rasterise: a triangle over at most BIN_SMALL tiles here, anything else listed for `bin_big`.
fn bin_triangle(p: Poly, bb: vec4<i32>, prim: u32) {
    let tb = bb / BIN;
    let nt = u32(tb.z - tb.x + 1) * u32(tb.w - tb.y + 1);
    if p.n != 3u || nt > BIN_SMALL {
        if !FILL {
            let k = work_add(W_BIG, 1u);
            if k < sizes.big_cap {
                work_store(list_at(k), prim);
            } else {
                work_add(W_BIG_LOST, 1u);
            }
        }
        return;
    }
    let t = make_tri(p, 1u);
    if !t.ok {
        return;
    }
    let tx_n = tiles_x();
    for (var ty = tb.y; ty <= tb.w; ty = ty + 1) {
        for (var tx = tb.x; tx <= tb.z; tx = tx + 1) {
            if nt == 1u || tile_touch(t, tx, ty) {
                bin_emit(u32(ty) * tx_n + u32(tx), prim);
            }
        }
    }
}

var<workgroup> wb_poly: Poly;
var<workgroup> wb_prim: u32;
var<workgroup> wb_ok: u32;

// One workgroup per listed polygon: its threads share the bounding box's tiles; each fan
// triangle gets its own entries (so the resolve sees triangles only).
@compute @workgroup_size(64)
fn bin_big(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(num_workgroups) nw: vec3<u32>,
) {
    if li == 0u {
        wb_ok = 0u;
        let k = wg.x + wg.y * nw.x;
        if k < min(work_load(W_BIG), sizes.big_cap) {
            let prim = work_load(list_at(k));
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
    let tx_n = tiles_x();
    for (var f = 1u; f + 1u < p.n; f = f + 1u) {
        let t = make_tri(p, f);
        if !t.ok {
            continue;
        }
        for (var i = li; i < nt; i = i + 64u) {
            let tx = tb.x + i32(i % gw);
            let ty = tb.y + i32(i / gw);
            if tile_touch(t, tx, ty) {
                bin_emit(u32(ty) * tx_n + u32(tx), prim | ((f - 1u) << FAN_SHIFT));
            }
        }
    }
}

// A tile's triangles, 64 at a time, set up once for all its pixels. Fast: (⌊E/256⌋ at the
// tile's first pixel, clamped, kind), (dE/dx', tag), (dE/dy', −); slow: (i0, i1.x, kind),
// (i1.y, i2, tag), (top-left bits, −). Then (f0, area), (f1, −), (f2, −) for `depth_at`.
var<workgroup> be_e: array<vec4<i32>, 64>;
var<workgroup> be_s: array<vec4<i32>, 64>;
var<workgroup> be_y: array<vec4<i32>, 64>;
var<workgroup> be_f: array<vec4<f32>, 192>;
var<workgroup> bt_range: vec2<u32>;
// Whether a pixel of the tile outgrew its ring (`resolve_binned`), and its uniform copy.
var<workgroup> bt_over: atomic<u32>;
var<workgroup> bt_over_u: u32;
// The chunk's entries in the order the pixels visit them: by their plane's depth at the tile's
// centre. Bins fill in whatever order the binning workgroups reach a tile (all of a scene's big
// triangles are binned at once), and a pixel's ring inserts a list that comes nearly in depth
// order, or reversed, without moves, a shuffled one with n/4 moves per fragment: on the H200
// that doubled the resolve of quads(32) at 1024² against the pixel capture's (whose fill lists
// a pixel's fragments in triangle order).
var<workgroup> be_key: array<f32, 64>;
var<workgroup> be_ord: array<u32, 64>;

// ⌊e/256⌋ of a 64-bit value, clamped to ±CLAMP_E.
fn clamp_e(e: vec2<u32>) -> i32 {
    let lo = (e.x >> 8u) | (e.y << 24u);
    let hi = bitcast<u32>(bitcast<i32>(e.y) >> 8u);
    let v = bitcast<i32>(lo);
    if (hi == 0u && v >= 0 && v <= CLAMP_E) || (hi == 0xffffffffu && v < 0 && v >= -CLAMP_E) {
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

// Thread li sets up bin entry `entry` for the tile whose first pixel is `o`.
fn load_entry(li: u32, entry: u32, o: vec2<i32>) {
    let prim = entry & ((1u << FAN_SHIFT) - 1u);
    let p = setup(prim);
    let f = (entry >> FAN_SHIFT) + 1u;
    be_e[li] = vec4<i32>(0, 0, 0, K_NONE);
    be_key[li] = 3.4e38;
    if f + 1u >= p.n {
        return;
    }
    let t = make_tri(p, f);
    if !t.ok {
        return;
    }
    // The plane's depth at the tile's centre, unclamped (a visiting order only).
    let c = vec2<f32>(o) + 4.0;
    let area = select(t.area, 1.0, t.area == 0.0);
    let b = vec3<f32>(edge_f(t.f1.xy, t.f2.xy, c), edge_f(t.f2.xy, t.f0.xy, c), edge_f(t.f0.xy, t.f1.xy, c)) / area;
    let key = b.x * t.f0.z + b.y * t.f1.z + b.z * t.f2.z;
    be_key[li] = select(3.4e38, key, key == key);
    let tag = bitcast<i32>(prim | select(0u, 0x80000000u, t.front));
    be_f[3u * li] = vec4<f32>(t.f0, t.area);
    be_f[3u * li + 1u] = vec4<f32>(t.f1, 0.0);
    be_f[3u * li + 2u] = vec4<f32>(t.f2, 0.0);
    let d0 = abs(t.i2 - t.i1);
    let d1 = abs(t.i0 - t.i2);
    let d2 = abs(t.i1 - t.i0);
    if max(max(d0.x + d0.y, d1.x + d1.y), d2.x + d2.y) < FAST_SPAN {
        let e = vec3<i32>(
            clamp_e(edge_biased64(t, 0u, o.x, o.y)),
            clamp_e(edge_biased64(t, 1u, o.x, o.y)),
            clamp_e(edge_biased64(t, 2u, o.x, o.y)),
        );
        be_e[li] = vec4<i32>(e, K_FAST);
        be_s[li] = vec4<i32>(t.i1.y - t.i2.y, t.i2.y - t.i0.y, t.i0.y - t.i1.y, tag);
        be_y[li] = vec4<i32>(t.i2.x - t.i1.x, t.i0.x - t.i2.x, t.i1.x - t.i0.x, 0);
        return;
    }
    let tl = select(0, 1, t.tl.x) | select(0, 2, t.tl.y) | select(0, 4, t.tl.z);
    be_e[li] = vec4<i32>(t.i0, t.i1.x, K_SLOW);
    be_s[li] = vec4<i32>(t.i1.y, t.i2, tag);
    be_y[li] = vec4<i32>(tl, 0, 0, 0);
}

// Chunk [base, base + m) of the tile's bin set up in workgroup memory and ranked by depth at the
// tile centre (`be_ord`). Called by the whole workgroup.
fn load_chunk(li: u32, base: u32, m: u32, o: vec2<i32>) {
    if li < m {
        load_entry(li, frags_load(base + li).x, o);
    }
    workgroupBarrier();
    if li < m {
        // Rank by (key, slot): a permutation of 0..m.
        let k = be_key[li];
        var r = 0u;
        for (var i = 0u; i < m; i = i + 1u) {
            let ki = be_key[i];
            r = r + select(0u, 1u, ki < k || (ki == k && i < li));
        }
        be_ord[r] = li;
    }
    workgroupBarrier();
}

// Whether set-up entry j covers pixel (x, y), lane `lid` of the tile.
fn entry_hit(j: u32, lid: vec2<u32>, x: i32, y: i32) -> bool {
    let e = be_e[j];
    if e.w == K_FAST {
        let v = e.xyz + be_s[j].xyz * i32(lid.x) + be_y[j].xyz * i32(lid.y);
        return (v.x | v.y | v.z) >= 0;
    } else if e.w == K_SLOW {
        let tr = entry_tri(j);
        let a = edge_biased64(tr, 0u, x, y);
        let b = edge_biased64(tr, 1u, x, y);
        let c = edge_biased64(tr, 2u, x, y);
        return ((a.y | b.y | c.y) & 0x80000000u) == 0u;
    }
    return false;
}

// Pixel p's fold and its fragment count (after the tiles' words).
fn store_binned(p: u32, st: FoldState, n: u32) {
    offs_store(sizes.npix + p, n);
    store_fold(p, st);
}

// The tile resolved with per-thread arrays, by the whole workgroup (it sets up the bin again);
// only pixels with `mine` insert and store. Its own function because WGSL zero-initialises a
// function's variables on entry (1 KiB a thread): tiles whose lists all fit the ring never pay it.
fn resolve_binned_private(li: u32, lid: vec2<u32>, px: vec2<u32>, range: vec2<u32>, mine: bool) {
    var d: array<f32, SORT_MAX>;
    var t: array<u32, SORT_MAX>;
    var n = 0u;
    var dropped = 0u;
    let w = u32(camera.viewport.x);
    let p = px.y * w + px.x;
    let o = vec2<i32>(px - lid);
    let x = i32(px.x);
    let y = i32(px.y);
    if mine {
        let r = stored_range(p);
        for (var s = r.x; s < r.y; s = s + 1u) {
            let e = frags_load(s);
            private_insert(&d, &t, &n, &dropped, bitcast<f32>(e.x), e.y);
        }
    }
    for (var base = range.x; base < range.y; base = base + 64u) {
        let m = min(64u, range.y - base);
        load_chunk(li, base, m, o);
        for (var jj = 0u; jj < m && mine; jj = jj + 1u) {
            let j = be_ord[jj];
            if entry_hit(j, lid, x, y) {
                private_insert(&d, &t, &n, &dropped, depth_at(entry_tri(j), x, y), bitcast<u32>(be_s[j].w));
            }
        }
        workgroupBarrier();
    }
    if !mine {
        return;
    }
    let ndc = pixel_ndc(px);
    var fs = fold_init_at(vec2<f32>(px) + 0.5);
    for (var i = 0u; i < n; i = i + 1u) {
        fold_step(&fs, fragment(d[i], t[i], ndc, px));
    }
    store_binned(p, fs, n + dropped);
    if dropped > 0u {
        work_add(W_OVF_PIXELS, 1u);
        work_add(W_DROPPED, dropped);
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
    let tile = wg.y * tiles_x() + wg.x;
    if li == 0u {
        // The tiles' words follow the pixels': tile 0 starts where the last pixel ends.
        let tw = tile_word(tile);
        bt_range = vec2<u32>(min(offs_load(tw - 1u), sizes.capacity), min(offs_load(tw), sizes.capacity));
        atomicStore(&bt_over, 0u);
    }
    let range = workgroupUniformLoad(&bt_range);
    let o = vec2<i32>(wg.xy * 8u);
    let px = wg.xy * 8u + lid.xy;
    let inside = px.x < w && px.y < h;
    let p = px.y * w + px.x;
    let x = i32(px.x);
    let y = i32(px.y);
    if !WG_SORT {
        resolve_binned_private(li, lid.xy, px, range, inside);
        return;
    }
    // resolve_sort = workgroup: every list in its ring; a pixel whose list outgrows it marks the
    // tile, which then resolves those pixels again with per-thread arrays.
    var n = 0u;
    var head = 0u;
    var over = false;
    if inside {
        let r = stored_range(p);
        for (var s = r.x; s < r.y; s = s + 1u) {
            if n == WG_CAP {
                over = true;
                break;
            }
            let e = frags_load(s);
            ring_insert(li, &head, n, bitcast<f32>(e.x), e.y);
            n = n + 1u;
        }
    }
    for (var base = range.x; base < range.y; base = base + 64u) {
        let m = min(64u, range.y - base);
        load_chunk(li, base, m, o);
        for (var jj = 0u; jj < m && inside && !over; jj = jj + 1u) {
            let j = be_ord[jj];
            if entry_hit(j, lid.xy, x, y) {
                if n == WG_CAP {
                    over = true;
                } else {
                    ring_insert(li, &head, n, depth_at(entry_tri(j), x, y), bitcast<u32>(be_s[j].w));
                    n = n + 1u;
                }
            }
        }
        workgroupBarrier();
    }
    if over {
        atomicStore(&bt_over, 1u);
    }
    workgroupBarrier();
    if li == 0u {
        bt_over_u = atomicLoad(&bt_over);
    }
    if workgroupUniformLoad(&bt_over_u) != 0u {
        resolve_binned_private(li, lid.xy, px, range, inside && over);
    }
    if !inside || over {
        return;
    }
    let ndc = pixel_ndc(px);
    var fs = fold_init_at(vec2<f32>(px) + 0.5);
    for (var i = 0u; i < n; i = i + 1u) {
        let k = (head + i) & RING;
        fold_step(&fs, fragment(sort_d[k * 64u + li], sort_t[k * 64u + li], ndc, px));
    }
    store_binned(p, fs, n);
}
