// Per-pixel linked lists (an A-buffer; Yang et al. 2010). Capture: every fragment takes the next
// node of its pool (atomicAdd on the pool's cursor), stores its payload there and pushes the node
// onto its pixel's list (atomicExchange of the head). A fragment finding its pool full is counted
// as lost in its pixel (atomicAdd), never dropped silently. Resolve: per pixel, walk the list,
// insertion-sort it (bounded by SORT_MAX, beyond which the farthest are dropped and counted),
// fold nearest first, and count overflowed pixels and lost fragments.
//
// Pools (override TILED): one pool with one cursor (`pool = fixed`: every fragment of the frame
// increments the same word), or one sub-pool per 8×8-pixel tile sized from a prepare-time count
// of that tile's fragments (`pool = counted`), so the cursors a frame increments are spread over
// the screen. Nodes (the variant file appended to this one): `full` (32 B: colour, depths,
// object id, next) or `compact` (12 B: depth, primitive | front << 31, next; the resolve
// re-derives attributes from the primitive, as compute_abuffer does).

override TILED: bool = false;
// pool = pixel: one pool per pixel, sized by a prepare-time count of its fragments, so its
// nodes lie one after another: no head to exchange, no link to write or follow (single-sample).
override PIXEL_POOLS: bool = false;
// MSAA (aa = msaa*): samples per pixel (1: none). COVERAGE: one node per pixel-rate fragment with
// its coverage mask in the tag (compact nodes, aa_capture = coverage), lists per pixel; else
// with SAMPLES > 1 every fragment entry runs per sample (gpu_util::per_sample_source sets SAMPLE)
// and each sample has its own list (aa_capture = sample: heads × SAMPLES).
override SAMPLES: u32 = 1u;
override COVERAGE: bool = false;
var<private> SAMPLE: i32 = 0;
// Per-pixel sort capacity of the resolve (a register/local array; WGSL needs a constant size).
const SORT_MAX: u32 = 128u;
// Side (pixels) of a counted pool's tiles.
const TILE_SIDE: u32 = 8u;
const NO_NODE: u32 = 0xffffffffu;

// node index + 1 of the list's newest node; 0 = empty list. One list per pixel, or per pixel and
// sample (aa_capture = sample).
@group(0) @binding(1) var<storage, read_write> heads: array<atomic<u32>>;
// NODE_WORDS words per node (layout in the variant file); word NEXT: next node index + 1, 0 ends.
// `nodes` (binding 2), and where the pool is over the largest storage binding its further parts
// (bindings 16, 17, …), are declared by the Rust side (`limits::Split::wgsl`) with the word
// accessors `nodes_load(w)` / `nodes_store(w, v)`; a node's words lie in one part.
@group(0) @binding(3) var<storage, read_write> out_image: array<vec4<f32>>;
// 0: overflowed pixels, 1: lost fragments (pool full or over SORT_MAX)
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>>;
// Per pixel p: [2p] fragments lost to a full pool, [2p + 1] fragments resolved.
@group(0) @binding(5) var<storage, read_write> pix: array<atomic<u32>>;
// Per pool (one, or one per tile): nodes taken this frame.
@group(0) @binding(6) var<storage, read_write> cursors: array<atomic<u32>>;
// Per pool: (first node, nodes).
@group(0) @binding(7) var<storage, read> ranges: array<vec2<u32>>;

fn pixel_of(pos: vec4<f32>) -> u32 {
    return u32(pos.y) * u32(camera.viewport.x) + u32(pos.x);
}

fn pool_of(pos: vec4<f32>) -> u32 {
    if PIXEL_POOLS {
        return pixel_of(pos);
    }
    if !TILED {
        return 0u;
    }
    let tiles_x = (u32(camera.viewport.x) + TILE_SIDE - 1u) / TILE_SIDE;
    return (u32(pos.y) / TILE_SIDE) * tiles_x + u32(pos.x) / TILE_SIDE;
}

// A free node for the fragment at `pos`, or NO_NODE (counted as lost) when its pool is full.
fn take_node(pos: vec4<f32>) -> u32 {
    let t = pool_of(pos);
    let i = atomicAdd(&cursors[t], 1u);
    let r = ranges[t];
    if i >= r.y {
        atomicAdd(&pix[2u * pixel_of(pos)], 1u);
        return NO_NODE;
    }
    return r.x + i;
}

// Lists a pixel has: one, or one per sample.
fn lists_per_pixel() -> u32 {
    return select(1u, SAMPLES, SAMPLES > 1u && !COVERAGE);
}

// Links node `n` (payload written) at the head of its pixel's (or sample's) list; with pixel
// pools its place in its pixel's pool is the link.
fn push_node(pos: vec4<f32>, n: u32) {
    if PIXEL_POOLS {
        return;
    }
    let h = pixel_of(pos) * lists_per_pixel() + select(0u, u32(SAMPLE), lists_per_pixel() > 1u);
    nodes_store(n * NODE_WORDS + NEXT, atomicExchange(&heads[h], n + 1u));
}

// Nodes of pixel pool h this frame (within its pool).
fn pool_used(h: u32) -> u32 {
    return min(atomicLoad(&cursors[h]), ranges[h].y);
}

// List h's first node + 1 (0: empty), and the node after node ni + 1 (0: the end).
fn list_first(h: u32) -> u32 {
    if PIXEL_POOLS {
        return select(0u, ranges[h].x + 1u, pool_used(h) > 0u);
    }
    return atomicLoad(&heads[h]);
}

fn list_next(ni: u32, h: u32) -> u32 {
    if PIXEL_POOLS {
        return select(0u, ni + 2u, ni + 1u < ranges[h].x + pool_used(h));
    }
    return nodes_load(ni * NODE_WORDS + NEXT);
}

// Prepare-time sizing of counted pools: fragments per tile (or per pixel).
@fragment
fn fs_count(@builtin(position) pos: vec4<f32>) {
    atomicAdd(&cursors[pool_of(pos)], 1u);
}

// tail = blend: the fragments the sort drops are summed here (tail.wgsl of this folder
// composites them with the pool's tail targets); tail = drop leaves this unused.
override TAIL: bool = false;
var<private> sort_tail_sums: vec4<f32>;
var<private> sort_tail_trans: f32;
var<private> sort_tail_count: f32;

fn sort_drops(f: Frag) {
    let a = f.color.a;
    sort_tail_sums = sort_tail_sums + vec4<f32>(f.color.rgb * a, a);
    sort_tail_trans = sort_tail_trans * (1.0 - a);
    sort_tail_count = sort_tail_count + 1.0;
}

// Lists of up to SHORT_CAP nodes are sorted in workgroup memory (lane li's slot j at j·64 + li):
// a function's or a private array is zero-initialised on every invocation (naga writes an
// OpConstantNull initialiser: 1 KiB a pixel at SORT_MAX), workgroup memory here is not. Longer
// lists are walked again into the per-thread arrays of `sort_list`.
const SHORT_CAP: u32 = 32u;
var<workgroup> short_d: array<f32, 2048>;
var<workgroup> short_k: array<u32, 2048>;

// List `head` sorted nearest first into lane li's slots; SHORT_CAP + 1 when it is longer.
fn sort_short(head: u32, li: u32) -> u32 {
    var n = 0u;
    var cur = list_first(head);
    loop {
        if cur == 0u {
            break;
        }
        if n == SHORT_CAP {
            return SHORT_CAP + 1u;
        }
        let ni = cur - 1u;
        let z = node_depth(ni);
        let k = node_key(ni);
        cur = list_next(ni, head);
        var j = n;
        loop {
            let q = (j - 1u) * 64u + li;
            if j == 0u || !list_before(z, k, short_d[q], short_k[q]) {
                break;
            }
            short_d[j * 64u + li] = short_d[q];
            short_k[j * 64u + li] = short_k[q];
            j = j - 1u;
        }
        short_d[j * 64u + li] = z;
        short_k[j * 64u + li] = k;
        n = n + 1u;
    }
    return n;
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    var s: FoldState;
    let n = sort_short(p, li);
    if n <= SHORT_CAP {
        sort_dropped = 0u;
        let ndc = centre_ndc(id.xy);
        s = fold_init_at(vec2<f32>(id.xy) + 0.5);
        for (var i = 0u; i < n; i = i + 1u) {
            fold_step(&s, list_frag(short_d[i * 64u + li], short_k[i * 64u + li], ndc));
        }
        count_resolved(p, n);
    } else {
        s = resolve_lists(id.xy);
    }
    for (var k = 0u; k < fold_image_count(); k = k + 1u) {
        out_image[k * w * h + p] = fold_finish_image(s, k);
    }
}

// A list sorted nearest first (its SORT_MAX nearest) in the caller's `sort_d`/`sort_key`; what is
// beyond the capacity is dropped (counted in `sort_dropped`, summed into the tail under TAIL).
var<private> sort_dropped: u32;

fn sort_list(
    head: u32,
    ndc: vec2<f32>,
    sort_d: ptr<function, array<f32, SORT_MAX>>,
    sort_key: ptr<function, array<u32, SORT_MAX>>,
) -> u32 {
    var n = 0u;
    var cur = list_first(head);
    loop {
        if cur == 0u {
            break;
        }
        let ni = cur - 1u;
        let z = node_depth(ni);
        let k = node_key(ni);
        cur = list_next(ni, head);
        if n == SORT_MAX {
            sort_dropped = sort_dropped + 1u;
            if !list_before(z, k, (*sort_d)[n - 1u], (*sort_key)[n - 1u]) {
                if TAIL {
                    sort_drops(list_frag(z, k, ndc));
                }
                continue;
            }
            if TAIL {
                sort_drops(list_frag((*sort_d)[n - 1u], (*sort_key)[n - 1u], ndc));
            }
            n = n - 1u;
        }
        var j = n;
        loop {
            if j == 0u || !list_before(z, k, (*sort_d)[j - 1u], (*sort_key)[j - 1u]) {
                break;
            }
            (*sort_d)[j] = (*sort_d)[j - 1u];
            (*sort_key)[j] = (*sort_key)[j - 1u];
            j = j - 1u;
        }
        (*sort_d)[j] = z;
        (*sort_key)[j] = k;
        n = n + 1u;
    }
    return n;
}

fn centre_ndc(xy: vec2<u32>) -> vec2<f32> {
    return vec2<f32>((f32(xy.x) + 0.5) * camera.viewport.z * 2.0 - 1.0, 1.0 - (f32(xy.y) + 0.5) * camera.viewport.w * 2.0);
}

// Pixel p's resolved fragments and losses (pool full or over SORT_MAX) into the counters.
fn count_resolved(p: u32, n: u32) {
    atomicStore(&pix[2u * p + 1u], n);
    let gone = atomicLoad(&pix[2u * p]) + sort_dropped;
    if gone > 0u {
        atomicAdd(&counters[0], 1u);
        atomicAdd(&counters[1], gone);
    }
}

// Pixel `xy`'s list sorted (the SORT_MAX nearest) and folded; counts written.
fn resolve_lists(xy: vec2<u32>) -> FoldState {
    let w = u32(camera.viewport.x);
    let p = xy.y * w + xy.x;
    sort_tail_sums = vec4<f32>(0.0);
    sort_tail_trans = 1.0;
    sort_tail_count = 0.0;
    sort_dropped = 0u;
    let ndc = centre_ndc(xy);
    var sort_d: array<f32, SORT_MAX>;
    var sort_key: array<u32, SORT_MAX>;
    let n = sort_list(p, ndc, &sort_d, &sort_key);
    var s = fold_init_at(vec2<f32>(xy) + 0.5);
    for (var i = 0u; i < n; i = i + 1u) {
        fold_step(&s, list_frag(sort_d[i], sort_key[i], ndc));
    }
    count_resolved(p, n);
    return s;
}

// MSAA: the mean over the pixel's samples of each sample's fold: per sample over its own list
// (aa_capture = sample), or over the pixel's list's fragments whose coverage mask has the
// sample's bit (COVERAGE); attributes at the pixel centre, as a pixel-rate fragment is shaded.
@compute @workgroup_size(8, 8)
fn resolve_ms(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    let ndc = centre_ndc(id.xy);
    sort_dropped = 0u;
    var sort_d: array<f32, SORT_MAX>;
    var sort_key: array<u32, SORT_MAX>;
    var acc: array<vec4<f32>, 3>;
    var total = 0u;
    if COVERAGE {
        let n = sort_list(p, ndc, &sort_d, &sort_key);
        total = n;
        var ss: array<FoldState, 8>;
        for (var s = 0u; s < SAMPLES; s = s + 1u) {
            ss[s] = fold_init_at(vec2<f32>(id.xy) + 0.5);
        }
        for (var i = 0u; i < n; i = i + 1u) {
            let f = list_frag(sort_d[i], sort_key[i], ndc);
            let mask = node_mask(sort_key[i]);
            for (var s = 0u; s < SAMPLES; s = s + 1u) {
                if (mask & (1u << s)) != 0u {
                    var st = ss[s];
                    fold_step(&st, f);
                    ss[s] = st;
                }
            }
        }
        for (var s = 0u; s < SAMPLES; s = s + 1u) {
            for (var k = 0u; k < fold_image_count(); k = k + 1u) {
                acc[k] = acc[k] + fold_finish_image(ss[s], k);
            }
        }
    } else {
        for (var s = 0u; s < SAMPLES; s = s + 1u) {
            let n = sort_list(p * SAMPLES + s, ndc, &sort_d, &sort_key);
            total = total + n;
            var st = fold_init_at(vec2<f32>(id.xy) + 0.5);
            for (var i = 0u; i < n; i = i + 1u) {
                fold_step(&st, list_frag(sort_d[i], sort_key[i], ndc));
            }
            for (var k = 0u; k < fold_image_count(); k = k + 1u) {
                acc[k] = acc[k] + fold_finish_image(st, k);
            }
        }
    }
    for (var k = 0u; k < fold_image_count(); k = k + 1u) {
        out_image[k * w * h + p] = acc[k] / f32(SAMPLES);
    }
    count_resolved(p, total);
}
