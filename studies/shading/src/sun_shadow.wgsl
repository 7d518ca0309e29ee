// The sun shadow of the deferred study (sun_shadow = taps8), appended to paths.wgsl; the CPU
// f64 twin is sun_shadow.rs (ShadowMap::coord / filter8 / hard / fade). Reads the Shade uniform
// `sh` and the group-0 bindings t_shadow (the sun's depth map) and shadow_range (per texel, the
// min/max depth of the texels within ±SHADOW_REACH), declared by paths.wgsl.
//
// A receiver at view-space P has shadow texel coordinates c.xy = ((s.x + 1)/2, (1 − s.y)/2)·S
// and compare depth c.z = s.z − bias, s = shadow_from_view·P (orthographic: w = 1). A texel
// lights it when c.z ≤ its depth. The filter (the seed's CascadeShadowMap_8Taps): 8 taps, each a
// bilinear blend of 4 texel compares (32 loads). The fade class: the depths within
// ±SHADOW_REACH texels of the receiver's texel (every texel the filter reads) lie on both sides
// of c.z, so its compares can disagree; elsewhere one compare is exact (one load, and one more
// to classify).

const SHADOW_REACH: i32 = 3;
// Texel offsets of the 8 taps (a ring of radius ≈ 1.6 texels).
const SHADOW_TAPS: array<vec2<f32>, 8> = array<vec2<f32>, 8>(
    vec2<f32>(-1.5, -0.5), vec2<f32>(1.5, 0.5), vec2<f32>(-0.5, 1.5), vec2<f32>(0.5, -1.5),
    vec2<f32>(-1.5, 0.5), vec2<f32>(1.5, -0.5), vec2<f32>(0.5, 1.5), vec2<f32>(-0.5, -1.5),
);

fn shadow_on() -> bool {
    return sh.shadow.z > 0.5;
}

fn shadow_coord(pos: vec3<f32>) -> vec3<f32> {
    let s = sh.shadow_from_view * vec4<f32>(pos, 1.0);
    let size = sh.shadow.x;
    return vec3<f32>((s.x * 0.5 + 0.5) * size, (0.5 - s.y * 0.5) * size, s.z - sh.shadow.y);
}

// Integer texel of a coordinate, kept well inside i32 (a receiver off the map clamps anyway).
fn shadow_texel(xy: vec2<f32>) -> vec2<i32> {
    return vec2<i32>(clamp(floor(xy), vec2<f32>(-16.0), vec2<f32>(sh.shadow.x + 16.0)));
}

fn shadow_lit(t: vec2<i32>, z: f32) -> f32 {
    let n = i32(sh.shadow.x) - 1;
    let c = clamp(t, vec2<i32>(0), vec2<i32>(n));
    return select(0.0, 1.0, z <= textureLoad(t_shadow, c, 0));
}

// One compare at the receiver's texel: exact wherever the pixel is not in the fade class.
fn shadow_hard(c: vec3<f32>) -> f32 {
    return shadow_lit(shadow_texel(c.xy), c.z);
}

fn shadow_filter8(c: vec3<f32>) -> f32 {
    var sum = 0.0;
    for (var k = 0u; k < 8u; k++) {
        let t = c.xy + SHADOW_TAPS[k] - vec2<f32>(0.5);
        let i = floor(t);
        let f = t - i;
        let ii = shadow_texel(i);
        let a = shadow_lit(ii, c.z);
        let b = shadow_lit(ii + vec2<i32>(1, 0), c.z);
        let d = shadow_lit(ii + vec2<i32>(0, 1), c.z);
        let e = shadow_lit(ii + vec2<i32>(1, 1), c.z);
        sum += mix(mix(a, b, f.x), mix(d, e, f.x), f.y);
    }
    return sum * 0.125;
}

// True when the depths around the receiver's texel (±SHADOW_REACH, clamped to the map: every
// texel the filter reads, also off the map's edge) straddle c.z: its compares can disagree.
// Otherwise all of them equal shadow_hard. (SHADOW_REACH is applied on the CPU, which builds
// shadow_range: sun_shadow.rs range_of.)
fn shadow_fade(c: vec3<f32>) -> bool {
    let n = i32(sh.shadow.x) - 1;
    let i = clamp(shadow_texel(c.xy), vec2<i32>(0), vec2<i32>(n));
    let m = shadow_range[i.y * i32(sh.shadow.x) + i.x];
    return !(c.z <= m.x || c.z > m.y);
}
