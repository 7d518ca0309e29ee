// Shared by bdp, bdp2 and adp (Liu et al., "Multi-Fragment Effects on the GPU Using Bucket
// Sort", GPU Pro ch. 1): the per-pixel depth-range pre-pass, the routing rule, the packings, the
// fragment counter behind the collision count, and the in-order resolve through the effects fold.
// Every rule here has a CPU twin of the same name in bucket/mod.rs.
//
// Buckets live in 32-bit float channels of RGBA32F render targets (one 2D-array texture, one
// layer per attachment) updated with MAX blending: a fragment writes its value into its bucket's
// channel and 0 everywhere else, so after the pass each channel holds the largest value routed
// to it and 0 means "empty".

override K: u32 = 8u;
// Resolve layout: 0 = one pack_color per bucket (bdp single), 1 = near/far pack_keyed pair per
// bucket (bdp paired), 2 = pack_keyed farthest in slots_a and the next one in slots_b (bdp2),
// 3 = one pack_color per bucket, bucket j holding occupied histogram bin adp_bounds[j] (adp),
// 4 = a near/far pair per bucket in slots_a and the next pair inside it in slots_b (bdp2 paired,
// §1.4), 5 = a near/far pair per bucket of occupied bin adp_bounds[j] (adp paired, §1.5).
override MODE: u32 = 0u;
override HIST_BINS: u32 = 1024u;
// 6 = multi-pass BDP (bdpn, §1.4's loop): pass p's pairs gathered into adp_bounds' buffer at
// ((i·K + b)·MAX_PASSES + p)·2 (near, far bits); occupied_max[0] holds the passes filled.
override MAX_PASSES: u32 = 1u;
// Effects on (depth, normal) bucket pairs (translucency, fresnel; GPU Pro ch. 1 §1.6.2–1.6.3):
// bucket b owns channels 2b (pack_viewz_facing) and 2b + 1 (pack_normal_f32), MAX-blended.
override FX: bool = false;

const NO_CHANNEL: u32 = 0xffffffffu;
// Smallest positive normal f32's bit pattern: every packed value is offset by it.
const MIN_NORMAL_BITS: u32 = 0x00800000u;

struct PassInfo {
    index: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
};

@group(0) @binding(1) var depth_range_tex: texture_2d<f32>;
@group(0) @binding(2) var<uniform> pass_info: PassInfo;
@group(0) @binding(3) var<storage, read_write> frag_count: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> hist: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> adp_bounds: array<u32>;
@group(0) @binding(6) var<storage, read_write> occupied_max: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> fold_states: array<FoldState>;
@group(0) @binding(8) var<storage, read_write> accum: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> counts: array<u32>;
@group(1) @binding(0) var slots_a: texture_2d_array<f32>;
@group(2) @binding(0) var slots_b: texture_2d_array<f32>;

fn pixel_index(p: vec2<f32>) -> u32 {
    return u32(p.y) * u32(camera.viewport.x) + u32(p.x);
}

// ---- depth-range pre-pass: MAX blending of (−d, d) gives (−zmin, zmax) -------------------

@fragment
fn fs_bounds(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(-p.z, p.z, 0.0, 0.0);
}

// (zmin, zmax) of the pixel; zmax < zmin where no fragment fell (cleared to −2).
fn depth_range(px: vec2<i32>) -> vec2<f32> {
    let b = textureLoad(depth_range_tex, px, 0);
    return vec2<f32>(-b.x, b.y);
}

// ---- routing (CPU twins: rel_position, uniform_bucket, bucket_key, adp_bin) ----------------

// Nearness-relative position of window depth d in the pixel's range: 0 at the nearest
// fragment, 1 at the farthest, under either depth convention.
fn rel_position(d: f32, zr: vec2<f32>) -> f32 {
    let span = zr.y - zr.x;
    if !(span > 0.0) {
        return 0.0;
    }
    if camera.near_far.z > 0.5 {
        return clamp((zr.y - d) / span, 0.0, 1.0);
    }
    return clamp((d - zr.x) / span, 0.0, 1.0);
}

fn uniform_bucket(t: f32) -> u32 {
    return min(u32(t * f32(K)), K - 1u);
}

// Position inside bucket b quantised to 0..126 (0 nearest): the order key of pack_keyed.
fn bucket_key(t: f32, b: u32) -> u32 {
    let r = t * f32(K) - f32(b);
    return min(u32(max(r, 0.0) * 127.0), 126u);
}

fn adp_bin(t: f32) -> u32 {
    return min(u32(t * f32(HIST_BINS)), HIST_BINS - 1u);
}

// ---- packings (CPU twins: pack_color, unpack_color, pack_keyed, keyed_key, keyed_color) ------
// Both put a payload p < 127·2^24 at bits p + 2^23: always a positive *normal* float in
// [f32::MIN_POSITIVE, f32::MAX], never 0 (empty), denormal (flushed by some blend units), Inf
// or NaN, and ordered like p (positive IEEE floats order like their bit patterns).

// Colour only (order inside a bucket is not kept): R, G, B 7 bits each, alpha 0..1015.
fn pack_color(c: vec4<f32>) -> f32 {
    let s = clamp(c, vec4<f32>(0.0), vec4<f32>(1.0));
    let q = vec3<u32>(floor(s.rgb * 127.0 + 0.5));
    let a = u32(floor(s.a * 1015.0 + 0.5));
    let p = (a << 21u) | (q.r << 14u) | (q.g << 7u) | q.b;
    return bitcast<f32>(p + MIN_NORMAL_BITS);
}

fn unpack_color(v: f32) -> vec4<f32> {
    let p = bitcast<u32>(v) - MIN_NORMAL_BITS;
    return vec4<f32>(
        f32((p >> 14u) & 127u) / 127.0,
        f32((p >> 7u) & 127u) / 127.0,
        f32(p & 127u) / 127.0,
        f32(p >> 21u) / 1015.0,
    );
}

// Order key (0..126) above RGBA 6 bits each: MAX keeps the largest key, with its colour.
fn pack_keyed(key: u32, c: vec4<f32>) -> f32 {
    let q = vec4<u32>(floor(clamp(c, vec4<f32>(0.0), vec4<f32>(1.0)) * 63.0 + 0.5));
    let p = (min(key, 126u) << 24u) | (q.r << 18u) | (q.g << 12u) | (q.b << 6u) | q.a;
    return bitcast<f32>(p + MIN_NORMAL_BITS);
}

fn keyed_key(v: f32) -> u32 {
    return (bitcast<u32>(v) - MIN_NORMAL_BITS) >> 24u;
}

fn keyed_color(v: f32) -> vec4<f32> {
    let p = bitcast<u32>(v) - MIN_NORMAL_BITS;
    return vec4<f32>(
        f32((p >> 18u) & 63u),
        f32((p >> 12u) & 63u),
        f32((p >> 6u) & 63u),
        f32(p & 63u),
    ) / 63.0;
}

// FX: the fragment's pair for bucket b.
fn fx_emit(b: u32, in: Varyings, ff: bool) -> BucketOut {
    return emit(2u * b, pack_viewz_facing(in.view_z, ff), 2u * b + 1u, pack_normal_f32(in.normal));
}

// FX: the fold's fragment from a pair (depth channel v, normal channel nv); window depth and
// colour are not stored (translucency and fresnel read neither).
fn fx_frag(v: f32, nv: f32) -> Frag {
    let n = select(vec3<f32>(0.0), unpack_normal_f32(nv), nv != 0.0);
    return Frag(0.0, v, vec4<f32>(0.0), n, 0u, viewz_front(v));
}

// ---- the untimed fragment counter (readback): true fragments per pixel ----------------------

@fragment
fn fs_count(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    atomicAdd(&frag_count[pixel_index(p.xy)], 1u);
    return vec4<f32>(0.0);
}

// ---- resolve: buckets nearest first through the effects fold ----------------------------------

fn slot_a(px: vec2<i32>, ch: u32) -> f32 {
    return textureLoad(slots_a, px, i32(ch / 4u), 0)[ch % 4u];
}

fn slot_b(px: vec2<i32>, ch: u32) -> f32 {
    return textureLoad(slots_b, px, i32(ch / 4u), 0)[ch % 4u];
}

// The payload holds no depth: depth is estimated from the fragment's nearness position t.
fn frag_at(c: vec4<f32>, t: f32, zr: vec2<f32>) -> Frag {
    let span = zr.y - zr.x;
    let d = select(zr.x + t * span, zr.y - t * span, camera.near_far.z > 0.5);
    return Frag(d, 0.0, c, vec3<f32>(0.0), 0u, true);
}

fn keyed_t(b: u32, key: u32) -> f32 {
    return (f32(b) + (f32(key) + 0.5) / 127.0) / f32(K);
}

// Position inside histogram bin `bin` quantised to 0..126 (adp paired's order key; CPU twin:
// bucket_key(t, bin, hist_bins)).
fn bin_key(t: f32, bin: u32) -> u32 {
    let r = t * f32(HIST_BINS) - f32(bin);
    return min(u32(max(r, 0.0) * 127.0), 126u);
}

// Folds one (near, far) keyed pair of sub-interval `b` of `scale` (K buckets, or HIST_BINS bins):
// the nearer first; a pair whose two slots hold one value (one fragment, or all of one key) is
// one fragment. Returns how many fragments it folded; `near` is 0 where the bucket is empty.
fn fold_pair(s: ptr<function, FoldState>, near: f32, far: f32, b: u32, scale: f32, zr: vec2<f32>) -> u32 {
    if near == 0.0 {
        return 0u;
    }
    let kn = 126u - keyed_key(near);
    fold_step(s, frag_at(keyed_color(near), pair_t(b, kn, scale), zr));
    let kf = keyed_key(far);
    let same_color = (bitcast<u32>(near) & 0xffffffu) == (bitcast<u32>(far) & 0xffffffu);
    if kf == kn && same_color {
        return 1u;
    }
    fold_step(s, frag_at(keyed_color(far), pair_t(b, kf, scale), zr));
    return 2u;
}

// keyed_t over `scale` sub-intervals (the same f32 arithmetic for scale = K).
fn pair_t(b: u32, key: u32, scale: f32) -> f32 {
    return (f32(b) + (f32(key) + 0.5) / 127.0) / scale;
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let px = vec2<i32>(id.xy);
    let i = id.y * w + id.x;
    var s = fold_init_at(vec2<f32>(id.xy) + 0.5);
    var n = 0u;
    // Passes after the first (adp with more occupied bins than buckets) continue the fold.
    if pass_info.index > 0u {
        s = fold_states[i];
        n = counts[i];
    }
    let zr = depth_range(px);
    if FX && zr.y >= zr.x {
        // Pairs nearest first; bdp2's second pass (slots_b) holds the nearer of its bucket's two.
        for (var b = 0u; b < K; b++) {
            if MODE == 2u {
                let v2 = slot_b(px, 2u * b);
                if v2 != 0.0 {
                    fold_step(&s, fx_frag(v2, slot_b(px, 2u * b + 1u)));
                    n += 1u;
                }
            }
            let v = slot_a(px, 2u * b);
            if v != 0.0 {
                fold_step(&s, fx_frag(v, slot_a(px, 2u * b + 1u)));
                n += 1u;
            }
        }
    } else if zr.y >= zr.x {
        for (var b = 0u; b < K; b++) {
            let tb = (f32(b) + 0.5) / f32(K);
            if MODE == 0u {
                let v = slot_a(px, b);
                if v != 0.0 {
                    fold_step(&s, frag_at(unpack_color(v), tb, zr));
                    n += 1u;
                }
            } else if MODE == 1u {
                n += fold_pair(&s, slot_a(px, 2u * b), slot_a(px, 2u * b + 1u), b, f32(K), zr);
            } else if MODE == 4u {
                // dmin¹ ≤ dmin² ≤ dmax² ≤ dmax¹ (§1.4): pass 2's pair sits inside pass 1's.
                let vn = slot_a(px, 2u * b);
                let vf = slot_a(px, 2u * b + 1u);
                if vn != 0.0 {
                    let kn = 126u - keyed_key(vn);
                    fold_step(&s, frag_at(keyed_color(vn), keyed_t(b, kn), zr));
                    n += 1u;
                    n += fold_pair(&s, slot_b(px, 2u * b), slot_b(px, 2u * b + 1u), b, f32(K), zr);
                    let kf = keyed_key(vf);
                    let same_color = (bitcast<u32>(vn) & 0xffffffu) == (bitcast<u32>(vf) & 0xffffffu);
                    if !(kf == kn && same_color) {
                        fold_step(&s, frag_at(keyed_color(vf), keyed_t(b, kf), zr));
                        n += 1u;
                    }
                }
            } else if MODE == 5u {
                let bin = adp_bounds[i * K + b];
                if bin != 0xffffffffu {
                    n += fold_pair(&s, slot_a(px, 2u * b), slot_a(px, 2u * b + 1u), bin, f32(HIST_BINS), zr);
                }
            } else if MODE == 6u {
                // Nearest sides outside in, then farthest sides inside out: pass p + 1's pair
                // lies strictly inside pass p's, and an empty pass ends the bucket.
                let filled = atomicLoad(&occupied_max[0]);
                let base = (i * K + b) * MAX_PASSES;
                var deepest = 0u;
                for (var p = 0u; p < filled; p++) {
                    let vn = bitcast<f32>(adp_bounds[(base + p) * 2u]);
                    if vn == 0.0 {
                        break;
                    }
                    fold_step(&s, frag_at(keyed_color(vn), keyed_t(b, 126u - keyed_key(vn)), zr));
                    n += 1u;
                    deepest = p + 1u;
                }
                for (var p = deepest; p > 0u; p--) {
                    let vn = bitcast<f32>(adp_bounds[(base + p - 1u) * 2u]);
                    let vf = bitcast<f32>(adp_bounds[(base + p - 1u) * 2u + 1u]);
                    let same_color = (bitcast<u32>(vn) & 0xffffffu) == (bitcast<u32>(vf) & 0xffffffu);
                    if !(keyed_key(vf) == 126u - keyed_key(vn) && same_color) {
                        fold_step(&s, frag_at(keyed_color(vf), keyed_t(b, keyed_key(vf)), zr));
                        n += 1u;
                    }
                }
            } else if MODE == 2u {
                // slots_b holds the largest key below slots_a's: the nearer of the two.
                let v1 = slot_a(px, b);
                let v2 = slot_b(px, b);
                if v2 != 0.0 {
                    fold_step(&s, frag_at(keyed_color(v2), keyed_t(b, keyed_key(v2)), zr));
                    n += 1u;
                }
                if v1 != 0.0 {
                    fold_step(&s, frag_at(keyed_color(v1), keyed_t(b, keyed_key(v1)), zr));
                    n += 1u;
                }
            } else {
                let v = slot_a(px, b);
                if v != 0.0 {
                    let bin = adp_bounds[i * K + b];
                    let t = (f32(bin) + 0.5) / f32(HIST_BINS);
                    fold_step(&s, frag_at(unpack_color(v), t, zr));
                    n += 1u;
                }
            }
        }
    }
    fold_states[i] = s;
    counts[i] = n;
    accum[i] = fold_finish(s);
}
