// floor_blend: what an engine without OIT pays for transparency. Every fragment is blended in
// hardware into RGBA8 in primitive order, premultiplied "over" (later primitives on top), with
// no depth test and no sort: the cheapest transparency, and wrong wherever primitive order is not
// back to front. The vertex stage reads position and colour only.

struct BlendIn {
    @location(0) position: vec3<f32>,
    @location(2) color: vec4<f32>,
};

struct BlendOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_blend(v: BlendIn) -> BlendOut {
    return BlendOut(camera.clip_from_world * vec4<f32>(v.position, 1.0), v.color);
}

@fragment
fn fs_blend(in: BlendOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color.rgb * in.color.a, in.color.a);
}
