// Colour packed into one f32 (bucket methods: BDP stores colour where only a float fits, and
// merges with MAX blending). The naive packing reinterprets pack4x8unorm's bits as a float: the
// alpha byte lands on the sign and exponent, so alpha ≥ 0.5 gives a negative float (MAX against
// a cleared 0 discards it), alpha & 0x7F = 0x7F with blue ≥ 0.5 gives NaN or Inf, and alpha & 0x7F
// = 0 with blue < 0.5 gives a denormal that flush-to-zero destroys. The fix keeps every packed
// value a positive, normal, finite float, ordered like its 30-bit code: RGB 8 bits, alpha 6 bits,
// offset by one exponent step past the denormals (largest value 0x40FFFFFF < Inf 0x7F800000).
// CPU twin: bench-core/src/methods/packing.rs.

const PACK_NORMAL_OFFSET: u32 = 0x00800000u;

fn pack_rgba_f32_naive(c: vec4<f32>) -> f32 {
    return bitcast<f32>(pack4x8unorm(c));
}

fn pack_rgba_f32(c: vec4<f32>) -> f32 {
    let q = clamp(c, vec4<f32>(0.0), vec4<f32>(1.0));
    let r = u32(round(q.r * 255.0));
    let g = u32(round(q.g * 255.0));
    let b = u32(round(q.b * 255.0));
    let a = u32(round(q.a * 63.0));
    return bitcast<f32>((r | (g << 8u) | (b << 16u) | (a << 24u)) + PACK_NORMAL_OFFSET);
}

fn unpack_rgba_f32(f: f32) -> vec4<f32> {
    let q = bitcast<u32>(f) - PACK_NORMAL_OFFSET;
    return vec4<f32>(
        f32(q & 0xFFu) / 255.0,
        f32((q >> 8u) & 0xFFu) / 255.0,
        f32((q >> 16u) & 0xFFu) / 255.0,
        f32((q >> 24u) & 0x3Fu) / 63.0,
    );
}
