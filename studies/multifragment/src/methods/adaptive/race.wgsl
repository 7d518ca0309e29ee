// Adaptive transparency as a GPU without rasterizer-ordered views builds it: pass 1, every
// fragment reads its pixel's nodes from storage, inserts itself (adaptive.wgsl) and writes them
// back with plain loads and stores (concurrent fragments of one pixel race: lost insertions);
// pass 2 (the paper's resolve), every fragment adds vis(z)·α·c through the final nodes with
// additive blending; a compute composite sets A = 1 − the last node's transmittance.

// Per pixel K × (z, t) as f32 bits; the first min(arrivals, K) are meaningful.
@group(0) @binding(1) var<storage, read_write> nodes: array<u32>;
// Per pixel: fragments seen (cleared every frame).
@group(0) @binding(2) var<storage, read_write> arrived: array<u32>;
@group(0) @binding(3) var<storage, read_write> out_image: array<vec4<f32>>;
// 0: pixels with more than K arrivals, 1: node removals (arrivals beyond K)
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(5) var accum_tex: texture_2d<f32>;

fn load_nodes(p: u32) -> Nodes {
    var s: Nodes;
    s.n = min(arrived[p], K);
    let base = p * 2u * K;
    for (var i = 0u; i < s.n; i = i + 1u) {
        s.z[i] = bitcast<f32>(nodes[base + 2u * i]);
        s.t[i] = bitcast<f32>(nodes[base + 2u * i + 1u]);
    }
    return s;
}

fn pixel_of(clip: vec4<f32>) -> u32 {
    return u32(clip.y) * u32(camera.viewport.x) + u32(clip.x);
}

@fragment
fn fs_nodes(in: Varyings) {
    let p = pixel_of(in.clip);
    let arrivals = arrived[p];
    var s = load_nodes(p);
    let first = at_insert(&s, in.view_z, in.color.a);
    let base = p * 2u * K;
    for (var i = first; i < s.n; i = i + 1u) {
        nodes[base + 2u * i] = bitcast<u32>(s.z[i]);
        nodes[base + 2u * i + 1u] = bitcast<u32>(s.t[i]);
    }
    arrived[p] = arrivals + 1u;
}

@fragment
fn fs_shade(in: Varyings) -> @location(0) vec4<f32> {
    var s = load_nodes(pixel_of(in.clip));
    let w = visibility(&s, in.view_z) * in.color.a;
    return vec4<f32>(in.color.rgb * w, 0.0);
}

@compute @workgroup_size(8, 8)
fn composite(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    var s = load_nodes(p);
    let c = textureLoad(accum_tex, vec2<i32>(id.xy), 0).rgb;
    out_image[p] = vec4<f32>(c, 1.0 - total_transmittance(&s));
    let arrivals = arrived[p];
    if arrivals > K {
        atomicAdd(&counters[0], 1u);
        atomicAdd(&counters[1], arrivals - K);
    }
}
