// The resolve side of a blended tail for the k-buffers (bindings 5–7 of their tail resolve
// layout; tail.wgsl comes first): the kept fragments' composite with the tail behind it.
// MEAN_ALPHA: the tail's opacity from its mean alpha (hybrid transparency) instead of exactly.

override MEAN_ALPHA: bool = false;

@group(0) @binding(5) var tail_sums: texture_2d<f32>;
@group(0) @binding(6) var tail_trans: texture_2d<f32>;
@group(0) @binding(7) var tail_count: texture_2d<f32>;

fn with_tail(xy: vec2<u32>, kept: vec4<f32>) -> vec4<f32> {
    let p = vec2<i32>(xy);
    return tail_behind(kept.rgb, 1.0 - kept.a, textureLoad(tail_sums, p, 0), textureLoad(tail_trans, p, 0).x, textureLoad(tail_count, p, 0).x, MEAN_ALPHA);
}
