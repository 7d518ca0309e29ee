// `bindings = packed` (and `auto` under fewer than ten storage buffers per stage, as WebGPU's
// default eight): the mesh packed at prepare into one vertex buffer (`pack_mesh`, three 16 B
// words a vertex: position and object id, normal, colour), and the work counters after the
// per-pixel offsets in one buffer (from word `sizes.work_base`). Six storage buffers with the
// fragments unsplit, so they may take three bindings of their own.

@group(0) @binding(1) var<storage, read> verts: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> indices: array<u32>;
// Per pixel: count → first slot → one past the last slot; then the work counters.
@group(0) @binding(6) var<storage, read_write> offs: array<atomic<u32>>;

fn offs_add(i: u32, v: u32) -> u32 {
    return atomicAdd(&offs[i], v);
}

fn offs_load(i: u32) -> u32 {
    return atomicLoad(&offs[i]);
}

fn offs_store(i: u32, v: u32) {
    atomicStore(&offs[i], v);
}

fn work_add(k: u32, v: u32) -> u32 {
    return atomicAdd(&offs[sizes.work_base + k], v);
}

fn work_load(k: u32) -> u32 {
    return atomicLoad(&offs[sizes.work_base + k]);
}

fn work_store(k: u32, v: u32) {
    atomicStore(&offs[sizes.work_base + k], v);
}

fn position(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(verts[3u * i].xyz);
}

fn vertex_object(i: u32) -> u32 {
    return verts[3u * i].w;
}

fn vertex_normal(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(verts[3u * i + 1u].xyz);
}

fn vertex_color(i: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(verts[3u * i + 2u]);
}

fn tri_indices(prim: u32) -> vec3<u32> {
    return vec3<u32>(indices[3u * prim], indices[3u * prim + 1u], indices[3u * prim + 2u]);
}
