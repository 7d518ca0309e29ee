// `bindings = native` (and `auto` where ten storage buffers per stage are allowed): the scene's
// five mesh buffers as they are, the per-pixel offsets and the work counters in buffers of their
// own (mesh.wgsl's accessors follow this file).

@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> colors: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> object_ids: array<u32>;
@group(0) @binding(5) var<storage, read> indices: array<u32>;
// Per pixel: count (after Count) → first slot (after Scan) → one past the last slot (after Fill).
@group(0) @binding(6) var<storage, read_write> offs: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> work: array<atomic<u32>>;

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
    return atomicAdd(&work[k], v);
}

fn work_load(k: u32) -> u32 {
    return atomicLoad(&work[k]);
}

fn work_store(k: u32, v: u32) {
    atomicStore(&work[k], v);
}
