// Stochastic transparency (Enderton, Sintorn, Shirley & Luebke, I3D 2010 / TVCG 2011). Each
// pass draws the scene twice into SAMPLES-sample targets:
// 1. depth: every fragment keeps a random subset of about α·S of its covered samples (the
//    `sample_mask` output: ⌊α·S + ξ⌋ samples, a uniformly random subset of that size) and
//    depth-tests and writes only those, so each sample ends with the depth of the nearest
//    fragment that kept it: sample s survives fragment j with probability 1 − α_j, independently.
// 2. accumulate: every fragment again, depth test "nearer or equal" against that depth and no
//    write, adding (α·c, α) to each covered sample where it passes: it passes at s exactly when
//    no nearer fragment kept s, so the sample mean of the sum estimates Σ α_i c_i Π_{j<i}(1 − α_j)
//    without bias (the under-composite), and its alpha Σ α_i Π(1 − α_j).
// A compute pass adds each pass's per-pixel sample mean into `sum`. With the alpha correction
// (ALPHA pass, once per frame) the exact total alpha 1 − Π(1 − α_i) is blended per sample
// (revealage, as in WBOIT) and the final colour is sum.rgb · α_total / sum.a, alpha α_total
// (the paper's §3.3), where sum.a > 0; elsewhere the uncorrected estimate stays.
//
// Randomness: a hash of (pixel, the fragment's window depth bits, seed, pass), so one seed gives
// the same frame every time and distinct fragments of a pixel draw independent masks (fragments
// at exactly equal depth draw the same one: coplanar layers are correlated).

override SAMPLES: u32 = 4u;

struct StParams {
    seed: u32,
    passes: u32,
    correction: u32,
    pad: u32,
};
@group(0) @binding(1) var<uniform> st: StParams;

struct StVaryings {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
    @location(1) @interpolate(flat) pass_index: u32,
};

struct StIn {
    @location(0) position: vec3<f32>,
    @location(2) color: vec4<f32>,
};

// The pass index is the draw's instance index (one instance per draw, first_instance = pass).
@vertex
fn vs_st(v: StIn, @builtin(instance_index) pass_index: u32) -> StVaryings {
    var out: StVaryings;
    out.clip = camera.clip_from_world * vec4<f32>(v.position, 1.0);
    out.color = v.color;
    out.pass_index = pass_index;
    return out;
}

// PCG hash (Jarzynski & Olano 2020).
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform in [0, 1) from the top 24 bits.
fn unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// ⌊α·S + ξ⌋ of the S samples, a uniformly random subset of that size (selection sampling:
// sample t is taken with probability still-needed / still-left), so each sample is kept with
// probability α exactly.
fn random_mask(alpha: f32, key: u32) -> u32 {
    var h = pcg(key);
    var need = u32(floor(clamp(alpha, 0.0, 1.0) * f32(SAMPLES) + unit(h)));
    need = min(need, SAMPLES);
    var mask = 0u;
    for (var t = 0u; t < SAMPLES; t = t + 1u) {
        h = pcg(h);
        if unit(h) * f32(SAMPLES - t) < f32(need) {
            mask = mask | (1u << t);
            need = need - 1u;
        }
    }
    return mask;
}

struct MaskOut {
    @builtin(sample_mask) mask: u32,
};

@fragment
fn fs_depth(in: StVaryings) -> MaskOut {
    let px = vec2<u32>(in.clip.xy);
    let key = pcg(px.x ^ pcg(px.y ^ pcg(bitcast<u32>(in.clip.z) ^ pcg(st.seed * 65537u + in.pass_index))));
    return MaskOut(random_mask(in.color.a, key));
}

@fragment
fn fs_accum(in: StVaryings) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color.rgb * in.color.a, in.color.a);
}

// Revealage Π(1 − α) by blending dst · (1 − src).
@fragment
fn fs_alpha(in: StVaryings) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color.a);
}

@group(0) @binding(2) var accum_ms: texture_multisampled_2d<f32>;
@group(0) @binding(3) var reveal_ms: texture_multisampled_2d<f32>;
@group(0) @binding(4) var<storage, read_write> sum: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> out_image: array<vec4<f32>>;

fn pixel(id: vec3<u32>) -> i32 {
    let w = u32(camera.viewport.x);
    if id.x >= w || id.y >= u32(camera.viewport.y) {
        return -1;
    }
    return i32(id.y * w + id.x);
}

// After each pass: sum += the pass's sample mean (sum is cleared at the start of the frame).
@compute @workgroup_size(8, 8)
fn resolve_pass(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = pixel(id);
    if p < 0 {
        return;
    }
    var m = vec4<f32>(0.0);
    for (var s = 0u; s < SAMPLES; s = s + 1u) {
        m = m + textureLoad(accum_ms, vec2<i32>(id.xy), i32(s));
    }
    sum[p] = sum[p] + m / f32(SAMPLES);
}

@compute @workgroup_size(8, 8)
fn finish(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = pixel(id);
    if p < 0 {
        return;
    }
    var c = sum[p] / f32(st.passes);
    if st.correction != 0u {
        var total = 0.0;
        for (var s = 0u; s < SAMPLES; s = s + 1u) {
            total = total + (1.0 - textureLoad(reveal_ms, vec2<i32>(id.xy), i32(s)).r);
        }
        total = total / f32(SAMPLES);
        if c.a > 0.0 {
            c = vec4<f32>(c.rgb * (total / c.a), total);
        }
    }
    out_image[p] = c;
}
