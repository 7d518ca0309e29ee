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
//
// Effects (FX = true: translucency, Fresnel): the layers hold (linear view depth with the facing
// in its sign, normal) instead of colour, and the front and back accumulations are effects fold
// states (`effects/fold.wgsl`, four vec4 per pixel): the front fold sees fragments nearest first,
// the back fold farthest first. Both folds' quantities compose from the two ends: thickness
// Σ (exit − entry) is a sum in any order (the stable form's pair differences included, see
// `combine`), and the Fresnel transmittance a product.

const BIG: f32 = 3.0e38;
// Effects mode (set from Rust with the fold's overrides).
override FX: bool = false;

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
fn fs_peel(in: Varyings, @builtin(front_facing) facing: bool) -> PeelOut {
    let n = near_key(in.clip.z);
    let prev = textureLoad(prev_depth, vec2<i32>(in.clip.xy), 0).xy;
    let near = -prev.x;
    let far = prev.y;
    if n < near || n > far {
        discard;
    }
    var o: PeelOut;
    // −BIG loses every MAX: only the fragment at near (far) lands in the front (back) layer.
    o.depth = vec2<f32>(-BIG);
    o.front = vec4<f32>(-BIG);
    o.back = vec4<f32>(-BIG);
    var c = vec4<f32>(in.color.rgb * in.color.a, in.color.a);
    if FX {
        // Negative for front faces, as depth peeling's layers (view_z > 0 before the eye).
        c = vec4<f32>(select(in.view_z, -in.view_z, facing), in.normal);
    }
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

// Fold states in the accumulation buffers (FX): four vec4 per pixel, flags and count as floats
// (small integers, exact; a bitcast count would be a denormal a driver may flush).
fn fx_frag(l: vec4<f32>) -> Frag {
    return Frag(0.0, abs(l.x), vec4<f32>(0.0), l.yzw, 0u, l.x < 0.0);
}

fn unpack_state(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>, pixel: vec2<f32>) -> FoldState {
    let count = u32(d.y);
    if count == 0u {
        // Cleared memory (no fragment folded yet): a fresh state.
        return fold_init_at(pixel);
    }
    return FoldState(a, b, c, u32(d.x), count);
}

fn load_front(i: u32, pixel: vec2<f32>) -> FoldState {
    return unpack_state(front_acc[4u * i], front_acc[4u * i + 1u], front_acc[4u * i + 2u], front_acc[4u * i + 3u], pixel);
}

fn load_back(i: u32, pixel: vec2<f32>) -> FoldState {
    return unpack_state(back_acc[4u * i], back_acc[4u * i + 1u], back_acc[4u * i + 2u], back_acc[4u * i + 3u], pixel);
}

fn packed_tail(s: FoldState) -> vec4<f32> {
    return vec4<f32>(f32(s.flags), f32(s.count), 0.0, 0.0);
}

fn store_front(i: u32, s: FoldState) {
    front_acc[4u * i] = s.accum;
    front_acc[4u * i + 1u] = s.aux;
    front_acc[4u * i + 2u] = s.extra;
    front_acc[4u * i + 3u] = packed_tail(s);
}

fn store_back(i: u32, s: FoldState) {
    back_acc[4u * i] = s.accum;
    back_acc[4u * i + 1u] = s.aux;
    back_acc[4u * i + 2u] = s.extra;
    back_acc[4u * i + 3u] = packed_tail(s);
}

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
    if FX && near <= far {
        let pixel = vec2<f32>(id.xy) + 0.5;
        var sf = load_front(i, pixel);
        fold_step(&sf, fx_frag(textureLoad(front_layer, xy, 0)));
        store_front(i, sf);
        var c = counts[i] + 1u;
        if far != near {
            var sb = load_back(i, pixel);
            fold_step(&sb, fx_frag(textureLoad(back_layer, xy, 0)));
            store_back(i, sb);
            c = c + 1u;
        }
        counts[i] = c;
    } else if near <= far {
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
    if FX {
        out_image[i] = fold_finish(combined(i, vec2<f32>(id.xy) + 0.5));
        return;
    }
    let f = front_acc[i];
    out_image[i] = f + (1.0 - f.a) * back_acc[i];
}

// The front fold (nearest first) and the back fold (farthest first) as one state. Each fold's
// thickness is S − open·z_last (S its pair-difference sum, open its entries − exits, z_last the
// last depth it saw); the sum of both is S_f + S_b + open_f·(z_b − z_f) − (open_f + open_b)·z_b,
// so the only new term is again a difference of adjacent depths (the fragments where the two
// sweeps met) and the state below makes fold_thickness return exactly that.
fn combined(i: u32, pixel: vec2<f32>) -> FoldState {
    let sf = load_front(i, pixel);
    let sb = load_back(i, pixel);
    if sb.count == 0u {
        return sf;
    }
    var m = sf;
    if THICKNESS_STABLE {
        m.aux.x = (sf.aux.x - sf.aux.y) + (sb.aux.x - sb.aux.y) + sf.extra.w * (sb.aux.z - sf.aux.z);
        m.aux.y = 0.0;
        m.aux.z = sb.aux.z;
        m.extra.w = sf.extra.w + sb.extra.w;
    } else {
        m.aux.x = sf.aux.x + sb.aux.x;
    }
    m.aux.w = sf.aux.w * sb.aux.w;
    m.count = sf.count + sb.count;
    return m;
}
