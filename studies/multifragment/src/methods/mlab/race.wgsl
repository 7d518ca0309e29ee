// MLAB as a GPU without rasterizer-ordered views can build it: every fragment reads its pixel's
// K layers from storage, inserts itself (mlab.wgsl) and writes them back, with plain loads and
// stores. Two fragments of one pixel in flight at once read the same layers and one write wins:
// the other fragment is lost or its layers mixed (the race; judged against the ideal-order twin,
// whose image is the method's definition). With TAIL_MODE 2 the layer that falls out of a full
// pixel is returned to the blended tail targets (tail.wgsl).

// Per pixel K × (z, r, g, b, t) as f32 bits; only the first min(arrivals, K) are meaningful.
// `layers` (binding 1, with further parts where one storage binding is too small) and its
// `layers_load(i)` / `layers_store(i, v)` are prepended by mod.rs (limits::Split::wgsl).
// Per pixel: fragments seen (cleared every frame).
@group(0) @binding(7) var<storage, read_write> arrived: array<u32>;
@group(0) @binding(2) var<storage, read_write> out_image: array<vec4<f32>>;
// 0: pixels with more than K arrivals, 1: arrivals beyond K (merged, dropped or tailed)
@group(0) @binding(3) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(4) var tail_sums: texture_2d<f32>;
@group(0) @binding(5) var tail_trans: texture_2d<f32>;
@group(0) @binding(6) var tail_count: texture_2d<f32>;

fn pixel_base(p: u32) -> u32 {
    return p * 5u * K;
}

fn load_blend(base: u32, n: u32) -> Blend {
    var s: Blend;
    s.n = n;
    for (var i = 0u; i < n; i = i + 1u) {
        let b = base + 5u * i;
        s.z[i] = bitcast<f32>(layers_load(b));
        s.rgb[i] = vec3<f32>(bitcast<f32>(layers_load(b + 1u)), bitcast<f32>(layers_load(b + 2u)), bitcast<f32>(layers_load(b + 3u)));
        s.t[i] = bitcast<f32>(layers_load(b + 4u));
    }
    return s;
}

fn mlab_rmw(in: Varyings) -> Inserted {
    let p = u32(in.clip.y) * u32(camera.viewport.x) + u32(in.clip.x);
    let base = pixel_base(p);
    let arrivals = arrived[p];
    var s = load_blend(base, min(arrivals, K));
    let r = mlab_insert(&s, in.view_z, in.color);
    for (var i = r.first; i < s.n; i = i + 1u) {
        let b = base + 5u * i;
        layers_store(b, bitcast<u32>(s.z[i]));
        layers_store(b + 1u, bitcast<u32>(s.rgb[i].r));
        layers_store(b + 2u, bitcast<u32>(s.rgb[i].g));
        layers_store(b + 3u, bitcast<u32>(s.rgb[i].b));
        layers_store(b + 4u, bitcast<u32>(s.t[i]));
    }
    arrived[p] = arrivals + 1u;
    return r;
}

@fragment
fn fs_mlab(in: Varyings) {
    _ = mlab_rmw(in);
}

@fragment
fn fs_mlab_tail(in: Varyings) -> TailOut {
    let r = mlab_rmw(in);
    if r.fell {
        return tail_of(r.rgb, r.a);
    }
    return tail_none();
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    let base = pixel_base(p);
    let arrivals = arrived[p];
    var s = load_blend(base, min(arrivals, K));
    let c = mlab_resolve(&s);
    var o = vec4<f32>(c.rgb, 1.0 - c.w);
    if TAIL_MODE == 2u {
        let xy = vec2<i32>(id.xy);
        o = tail_behind(c.rgb, c.w, textureLoad(tail_sums, xy, 0), textureLoad(tail_trans, xy, 0).x, textureLoad(tail_count, xy, 0).x, false);
    }
    out_image[p] = o;
    if arrivals > K {
        atomicAdd(&counters[0], 1u);
        atomicAdd(&counters[1], arrivals - K);
    }
}
