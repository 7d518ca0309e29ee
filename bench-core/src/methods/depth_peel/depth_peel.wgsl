// Classic depth peeling (Everitt 2001). Pass i keeps, per pixel, the nearest fragment strictly
// behind layer i−1's depth: the fragment stage discards what is not behind, the depth test keeps
// the nearest of the rest. A compute pass then composites the layer under the accumulation.
// Strict comparison means a fragment at exactly the previous layer's depth (coplanar) is lost:
// the classic method's known failure, reported by the stability suite.

override PEEL: bool = true;

@group(0) @binding(1) var prev_depth: texture_depth_2d;

@fragment
fn fs_peel(in: Varyings) -> @location(0) vec4<f32> {
    if PEEL {
        let prev = textureLoad(prev_depth, vec2<i32>(in.clip.xy), 0);
        if !nearer(prev, in.clip.z) {
            discard;
        }
    }
    return in.color;
}

// ---- composite: accum = accum "under" layer, count += 1 where the layer has a fragment ----

@group(1) @binding(0) var layer_color: texture_2d<f32>;
@group(1) @binding(1) var layer_depth: texture_depth_2d;
@group(1) @binding(2) var<storage, read_write> accum: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read_write> counts: array<u32>;

@compute @workgroup_size(8, 8)
fn composite(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let d = textureLoad(layer_depth, vec2<i32>(id.xy), 0);
    // Empty where the depth buffer still holds its clear value.
    if d == camera.near_far.w {
        return;
    }
    let c = textureLoad(layer_color, vec2<i32>(id.xy), 0);
    let i = id.y * w + id.x;
    var acc = accum[i];
    let t = 1.0 - acc.a;
    acc = vec4<f32>(acc.rgb + t * c.a * c.rgb, acc.a + t * c.a);
    accum[i] = acc;
    counts[i] = counts[i] + 1u;
}
