// Moment-based order-independent transparency (Münstermann, Krumpen, Klein & Peters 2018), the
// two-pass scheme, as the CPU twin `oit::moments` defines it:
// 1. Moments pass: every fragment adds its absorbance A = min(−ln(1 − α), 10) to b₀ and A·φ(z)
//    to the moments (φ: powers z¹…zᶜ, or e^{ijφ(z)} as (re, im) pairs), z the log-warped view
//    distance. `f32`: additive blending into R32F (b₀) and RGBA32F/RG32F targets, ordered and
//    exact up to f32 rounding. `unorm16` (UNORM16): the paper's 16-bit scheme stores the moments
//    normalised by b₀ and quantised, so every fragment must read, update and write them: without
//    rasterizer-ordered views this is an unguarded read-modify-write of a storage buffer, whose
//    races (two fragments of a pixel in flight at once) lose updates, as the k-buffer's do.
// 2. Resolve pass: every fragment reconstructs the transmittance in front of itself from the
//    biased moments (moment_math.wgsl) and adds (T·α·c, T·α) into an RGBA32F target.
// 3. Composite (compute): A = 1 − exp(−b₀); colour the resolve's sum, or with the total-absorbance
//    normalisation A·ΣTαc / ΣTα. Pixels with b₀ < b0_min resolve to nothing (the paper's cut).

override KIND: u32 = 0u;      // 0: power, 1: trigonometric
override COUNT: u32 = 4u;     // power 4, 6, 8; trigonometric 2, 3, 4
override REALS: u32 = 4u;     // stored reals besides b₀: COUNT (power) or 2·COUNT (trigonometric)
override UNORM16: bool = false;

const ALPHA_MIN: f32 = 1e-7;
const ABSORBANCE_MAX: f32 = 10.0;

struct MomentParams {
    // ln near, ln far of the warp range (view distance), 0, 0
    warp: vec4<f32>,
    // β, overestimation, b0_min, normalise (0|1)
    bias: vec4<f32>,
    // wrapping-zone constants (angle, phase scale, ramp slope, ramp offset)
    zone: vec4<f32>,
    // power moments: the bias target b*₁…b*₈
    star: array<vec4<f32>, 2>,
    // unorm16 power moments: rows of (quantise odd, quantise even, dequantise odd, dequantise
    // even), 4 rows each, zero-padded to 4×4
    quant: array<vec4<f32>, 16>,
    // unorm16: offset added after quantising, per stored real
    offset: array<vec4<f32>, 2>,
};

@group(0) @binding(1) var<uniform> mp: MomentParams;
// unorm16: per pixel 1 + REALS/2 words: b₀ (f32 bits), then the quantised reals, two per word.
@group(0) @binding(2) var<storage, read_write> store16: array<u32>;

fn warp(z: f32) -> f32 {
    let w = (log(z) - mp.warp.x) / (mp.warp.y - mp.warp.x);
    return clamp(w * 2.0 - 1.0, -1.0, 1.0);
}

fn get8(a: array<vec4<f32>, 2>, i: u32) -> f32 {
    return a[i / 4u][i % 4u];
}

// φ(z) of warped depth z (features).
fn features(z: f32) -> array<f32, 8> {
    var v: array<f32, 8>;
    if KIND == 0u {
        var p = 1.0;
        for (var j = 0u; j < COUNT; j = j + 1u) {
            p = p * z;
            v[j] = p;
        }
    } else {
        let c = circle_point(z, mp.zone);
        var p = vec2<f32>(1.0, 0.0);
        for (var j = 0u; j < COUNT; j = j + 1u) {
            p = cmul(p, c);
            v[2u * j] = p.x;
            v[2u * j + 1u] = p.y;
        }
    }
    return v;
}

fn absorbance(alpha: f32) -> f32 {
    return min(-log(1.0 - alpha), ABSORBANCE_MAX);
}

fn pixel_index(pos: vec4<f32>) -> u32 {
    return u32(pos.y) * u32(camera.viewport.x) + u32(pos.x);
}

// ---- 1. moments pass ----

struct Moments2 {
    @location(0) b0: vec4<f32>,
    @location(1) m0: vec4<f32>,
};

struct Moments3 {
    @location(0) b0: vec4<f32>,
    @location(1) m0: vec4<f32>,
    @location(2) m1: vec4<f32>,
};

// A·φ(z) of a fragment, and A (discarded below ALPHA_MIN, as the paper's code clips it).
fn contribution(in: Varyings) -> array<f32, 9> {
    var r: array<f32, 9>;
    let a = absorbance(in.color.a);
    let phi = features(warp(in.view_z));
    r[0] = a;
    for (var i = 0u; i < REALS; i = i + 1u) {
        r[i + 1u] = a * phi[i];
    }
    return r;
}

@fragment
fn fs_moments2(in: Varyings) -> Moments2 {
    if in.color.a < ALPHA_MIN {
        discard;
    }
    let r = contribution(in);
    var o: Moments2;
    o.b0 = vec4<f32>(r[0]);
    o.m0 = vec4<f32>(r[1], r[2], r[3], r[4]);
    return o;
}

@fragment
fn fs_moments3(in: Varyings) -> Moments3 {
    if in.color.a < ALPHA_MIN {
        discard;
    }
    let r = contribution(in);
    var o: Moments3;
    o.b0 = vec4<f32>(r[0]);
    o.m0 = vec4<f32>(r[1], r[2], r[3], r[4]);
    o.m1 = vec4<f32>(r[5], r[6], r[7], r[8]);
    return o;
}

// The paper's quantisation of power moments (odd then even), not yet offset.
fn quantize(phi: array<f32, 8>) -> array<f32, 8> {
    let m = COUNT / 2u;
    var odd = vec4<f32>(0.0);
    var even = vec4<f32>(0.0);
    for (var i = 0u; i < m; i = i + 1u) {
        odd[i] = phi[2u * i];
        even[i] = phi[2u * i + 1u];
    }
    var q: array<f32, 8>;
    for (var i = 0u; i < m; i = i + 1u) {
        q[i] = dot(mp.quant[i], odd);
        q[m + i] = dot(mp.quant[4u + i], even);
    }
    return q;
}

fn load16(base: u32, i: u32) -> f32 {
    let v = unpack2x16unorm(store16[base + 1u + i / 2u]);
    return select(v.x, v.y, (i & 1u) == 1u);
}

// unorm16 moments pass: read, update and write the pixel's normalised quantised moments.
@fragment
fn fs_moments16(in: Varyings) {
    if in.color.a < ALPHA_MIN {
        return;
    }
    let words = 1u + REALS / 2u;
    let base = pixel_index(in.clip) * words;
    let a = absorbance(in.color.a);
    let phi = features(warp(in.view_z));
    var fresh: array<f32, 8>;
    if KIND == 0u {
        fresh = quantize(phi);
    } else {
        // Stored as 0.5 + 0.5·b/b₀: the feature itself scales by 0.5.
        for (var i = 0u; i < REALS; i = i + 1u) {
            fresh[i] = phi[i] * 0.5;
        }
    }
    let b0 = bitcast<f32>(store16[base]);
    let b0_new = b0 + a;
    var q: array<f32, 8>;
    for (var i = 0u; i < REALS; i = i + 1u) {
        let off = get8(mp.offset, i);
        let old = (load16(base, i) - off) * b0;
        q[i] = (old + a * fresh[i]) / b0_new + off;
    }
    for (var w = 0u; w < REALS / 2u; w = w + 1u) {
        store16[base + 1u + w] = pack2x16unorm(vec2<f32>(q[2u * w], q[2u * w + 1u]));
    }
    store16[base] = bitcast<u32>(b0_new);
}

// ---- 2. resolve pass ----

@group(0) @binding(3) var b0_tex: texture_2d<f32>;
@group(0) @binding(4) var m0_tex: texture_2d<f32>;
@group(0) @binding(5) var m1_tex: texture_2d<f32>;

// b₀ and the normalised moments bⱼ/b₀ of the pixel at `xy` (normalized), before bias.
fn pixel_moments(xy: vec2<u32>, b: ptr<function, array<f32, 8>>) -> f32 {
    if UNORM16 {
        let words = 1u + REALS / 2u;
        let base = (xy.y * u32(camera.viewport.x) + xy.x) * words;
        let b0 = bitcast<f32>(store16[base]);
        if KIND == 0u {
            // Offset removed, then dequantised into natural order b₁…b₂ₘ.
            let m = COUNT / 2u;
            var qo = vec4<f32>(0.0);
            var qe = vec4<f32>(0.0);
            for (var i = 0u; i < m; i = i + 1u) {
                qo[i] = load16(base, i) - get8(mp.offset, i);
                qe[i] = load16(base, m + i) - get8(mp.offset, m + i);
            }
            for (var i = 0u; i < m; i = i + 1u) {
                (*b)[2u * i] = dot(mp.quant[8u + i], qo);
                (*b)[2u * i + 1u] = dot(mp.quant[12u + i], qe);
            }
        } else {
            for (var i = 0u; i < REALS; i = i + 1u) {
                (*b)[i] = load16(base, i) * 2.0 - 1.0;
            }
        }
        return b0;
    }
    let p = vec2<i32>(xy);
    let b0 = textureLoad(b0_tex, p, 0).x;
    let m0 = textureLoad(m0_tex, p, 0);
    var raw: array<f32, 8>;
    raw[0] = m0.x;
    raw[1] = m0.y;
    raw[2] = m0.z;
    raw[3] = m0.w;
    if REALS > 4u {
        let m1 = textureLoad(m1_tex, p, 0);
        raw[4] = m1.x;
        raw[5] = m1.y;
        raw[6] = m1.z;
        raw[7] = m1.w;
    }
    for (var i = 0u; i < REALS; i = i + 1u) {
        (*b)[i] = raw[i] / b0;
    }
    return b0;
}

// T in front of view distance z (transmittance_at); 1 where the pixel has no absorbance; −1
// where the reconstruction failed (a non-finite fraction), which the twin resolves as T = 0.
fn transmittance_at(xy: vec2<u32>, z: f32) -> f32 {
    var b: array<f32, 8>;
    let b0 = pixel_moments(xy, &b);
    if b0 <= 0.0 {
        return 1.0;
    }
    let zw = warp(z);
    let beta = mp.bias.x;
    let over = mp.bias.y;
    var fraction: f32;
    if KIND == 0u {
        var biased: array<f32, 8>;
        for (var i = 0u; i < REALS; i = i + 1u) {
            biased[i] = (1.0 - beta) * b[i] + beta * get8(mp.star, i);
        }
        fraction = power_fraction(biased, zw, over);
    } else {
        let scale = 1.0 - beta;
        var tb: array<vec2<f32>, 4>;
        for (var j = 0u; j < COUNT; j = j + 1u) {
            tb[j] = vec2<f32>(b[2u * j] * scale, b[2u * j + 1u] * scale);
        }
        fraction = trig_fraction(tb, circle_point(zw, mp.zone), over, mp.zone);
    }
    // A bit test, not `fraction != fraction`: it survives compilers that assume no NaNs.
    if (bitcast<u32>(fraction) & 0x7f800000u) == 0x7f800000u {
        return -1.0;
    }
    return clamp(exp(-b0 * fraction), 0.0, 1.0);
}

// Fragments whose reconstruction failed (counted, resolved as T = 0).
@group(0) @binding(8) var<storage, read_write> failures: array<atomic<u32>>;

@fragment
fn fs_resolve(in: Varyings) -> @location(0) vec4<f32> {
    let a = in.color.a;
    if a < ALPHA_MIN {
        discard;
    }
    var t = transmittance_at(vec2<u32>(in.clip.xy), in.view_z);
    if t < 0.0 {
        atomicAdd(&failures[0], 1u);
        t = 0.0;
    }
    let w = t * a;
    return vec4<f32>(in.color.rgb * w, w);
}

// ---- 3. composite ----

@group(0) @binding(6) var accum_tex: texture_2d<f32>;
@group(0) @binding(7) var<storage, read_write> out_image: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn composite(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    var b0: f32;
    if UNORM16 {
        b0 = bitcast<f32>(store16[(id.y * w + id.x) * (1u + REALS / 2u)]);
    } else {
        b0 = textureLoad(b0_tex, vec2<i32>(id.xy), 0).x;
    }
    var o = vec4<f32>(0.0);
    if b0 >= mp.bias.z {
        let sum = textureLoad(accum_tex, vec2<i32>(id.xy), 0);
        let alpha = 1.0 - exp(-b0);
        var rgb = sum.rgb;
        if mp.bias.w > 0.5 {
            rgb = select(vec3<f32>(0.0), alpha * sum.rgb / sum.a, sum.a > 0.0);
        }
        o = vec4<f32>(rgb, alpha);
    }
    out_image[id.y * w + id.x] = o;
}
