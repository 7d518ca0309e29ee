// Dual depth peeling (Bavoil & Myers 2008). Depths are mapped to keys n (smaller = nearer, in
// both depth conventions) and a RG32F target with MAX blending keeps (−min n, max n) per pixel:
// the nearest and farthest fragments still to peel. The first pass fills it with every
// fragment; each peel pass reads the previous (near, far), discards fragments outside it
// (already peeled), writes the fragments strictly inside to the next (near, far), and sends the
// fragment at `near` to the front layer and the one at `far` to the back layer (MAX blending,
// only one fragment matches each; exact ties merge: the coplanar failure of every peeler).
// A compute pass then composites the front layer under the front accumulation, the back layer
// over the back accumulation, and counts the pixels that still have fragments to peel; a final
// pass combines front over back. ⌈n/2⌉ peel passes + 1 for n layers.

const BIG: f32 = 3.0e38;

fn near_key(d: f32) -> f32 {
    return select(d, -d, camera.near_far.z > 0.5);
}

@group(0) @binding(1) var prev_depth: texture_2d<f32>;

@fragment
fn fs_init(in: Varyings) -> @location(0) vec2<f32> {
    let n = near_key(in.clip.z);
    return vec2<f32>(-n, n);
}

struct PeelOut {
    @location(0) depth: vec2<f32>,
    @location(1) front: vec4<f32>,
    @location(2) back: vec4<f32>,
};

@fragment
fn fs_peel(in: Varyings) -> PeelOut {
    let n = near_key(in.clip.z);
    let prev = textureLoad(prev_depth, vec2<i32>(in.clip.xy), 0).xy;
    let near = -prev.x;
    let far = prev.y;
    if n < near || n > far {
        discard;
    }
    var o: PeelOut;
    o.depth = vec2<f32>(-BIG);
    o.front = vec4<f32>(0.0);
    o.back = vec4<f32>(0.0);
    let c = vec4<f32>(in.color.rgb * in.color.a, in.color.a);
    if n > near && n < far {
        o.depth = vec2<f32>(-n, n);
    } else if n == near {
        o.front = c;
    } else {
        o.back = c;
    }
    return o;
}

// ---- composite (after each peel pass) and combine (once) ----

@group(1) @binding(0) var in_depth: texture_2d<f32>;
@group(1) @binding(1) var out_depth: texture_2d<f32>;
@group(1) @binding(2) var front_layer: texture_2d<f32>;
@group(1) @binding(3) var back_layer: texture_2d<f32>;
@group(1) @binding(4) var<storage, read_write> front_acc: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read_write> back_acc: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read_write> counts: array<u32>;
// 0: pixels with fragments left to peel after this pass
@group(1) @binding(7) var<storage, read_write> remaining: array<atomic<u32>>;
@group(1) @binding(8) var<storage, read_write> out_image: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn composite(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let xy = vec2<i32>(id.xy);
    let i = id.y * w + id.x;
    let prev = textureLoad(in_depth, xy, 0).xy;
    let near = -prev.x;
    let far = prev.y;
    if near <= far {
        let f = textureLoad(front_layer, xy, 0);
        let fa = front_acc[i];
        front_acc[i] = fa + (1.0 - fa.a) * f;
        var c = counts[i] + 1u;
        if far != near {
            let b = textureLoad(back_layer, xy, 0);
            back_acc[i] = b + (1.0 - b.a) * back_acc[i];
            c = c + 1u;
        }
        counts[i] = c;
    }
    let next = textureLoad(out_depth, xy, 0).xy;
    if -next.x <= next.y {
        atomicAdd(&remaining[0], 1u);
    }
}

@compute @workgroup_size(8, 8)
fn combine(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let i = id.y * w + id.x;
    let f = front_acc[i];
    out_image[i] = f + (1.0 - f.a) * back_acc[i];
}
