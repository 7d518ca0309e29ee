// The unordered-blend floors: every fragment blended in hardware into RGBA8, premultiplied
// "over", with no depth test and no sort. Both faces.
//
// floor_blend: the methods' own vertex stage (common.wgsl's vs_full: position, normal, colour,
// object id) and each fragment's interpolated colour: what a multi-fragment method reads before
// it stores anything.
@fragment
fn fs_blend(in: Varyings) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color.rgb * in.color.a, in.color.a);
}

// floor_blend_const: positions only (common.wgsl's vs_position) and one constant colour: the
// cheapest honest unordered blend of the same fragments. Premultiplied (1, 0.5, 0.25) at α 0.25;
// with one colour "over" is order-independent. Keep in step with `CONST_PREMUL` in blend.rs.
@fragment
fn fs_const() -> @location(0) vec4<f32> {
    return vec4<f32>(0.25, 0.125, 0.0625, 0.25);
}
