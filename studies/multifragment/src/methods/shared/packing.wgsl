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

// A unit normal in 4 bytes (the chapter's pack_4byte, GPU Pro ch. 1 §1.6.3): octahedral
// coordinates, 15 bits each, so the 30-bit code offset by PACK_NORMAL_OFFSET is again a positive
// normal finite float (a MAX-blended bucket channel keeps it) and a plain u32 elsewhere. Angular
// error < 2e-4 rad (a code step is 2/32767 of the octahedron), where 8 bits per component would
// give ~4e-3. CPU twin: packing.rs `pack_normal_oct`. A zero normal decodes to +z.
fn pack_normal_oct(n: vec3<f32>) -> u32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    var p = select(vec2<f32>(0.0), n.xy / l1, l1 > 0.0);
    if n.z < 0.0 {
        let s = select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
        p = (vec2<f32>(1.0) - abs(p.yx)) * s;
    }
    let q = vec2<u32>(round((clamp(p, vec2<f32>(-1.0), vec2<f32>(1.0)) * 0.5 + 0.5) * 32767.0));
    return q.x | (q.y << 15u);
}

fn unpack_normal_oct(code: u32) -> vec3<f32> {
    let q = vec2<f32>(f32(code & 0x7fffu), f32((code >> 15u) & 0x7fffu));
    let p = q / 32767.0 * 2.0 - 1.0;
    var n = vec3<f32>(p, 1.0 - abs(p.x) - abs(p.y));
    let t = max(-n.z, 0.0);
    n.x = n.x + select(t, -t, n.x >= 0.0);
    n.y = n.y + select(t, -t, n.y >= 0.0);
    return normalize(n);
}

fn pack_normal_f32(n: vec3<f32>) -> f32 {
    return bitcast<f32>(pack_normal_oct(n) + PACK_NORMAL_OFFSET);
}

fn unpack_normal_f32(v: f32) -> vec3<f32> {
    return unpack_normal_oct(bitcast<u32>(v) - PACK_NORMAL_OFFSET);
}

// Linear view depth with the facing in its lowest mantissa bit (1 = front facing): a positive
// normal float MAX blending orders like the depth (to 1 ulp), so a bucket pair's depth channel
// carries the facing too.
fn pack_viewz_facing(z: f32, front: bool) -> f32 {
    return bitcast<f32>((bitcast<u32>(z) & ~1u) | select(0u, 1u, front));
}

fn viewz_front(v: f32) -> bool {
    return (bitcast<u32>(v) & 1u) != 0u;
}
