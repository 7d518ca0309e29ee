// `bindings = packed`: the scene's mesh buffers packed into one vertex buffer at prepare (three
// 16 B words a vertex: position and object id, normal, colour; read by packed.wgsl).

@group(0) @binding(0) var<storage, read> positions: array<f32>;
@group(0) @binding(1) var<storage, read> normals: array<f32>;
@group(0) @binding(2) var<storage, read> colors: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> object_ids: array<u32>;
@group(0) @binding(4) var<storage, read_write> verts: array<vec4<u32>>;

@compute @workgroup_size(64)
fn pack_mesh(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let n = min(arrayLength(&object_ids), arrayLength(&verts) / 3u);
    for (var i = gid.x; i < n; i = i + nw.x * 64u) {
        let p = vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
        let m = vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
        verts[3u * i] = vec4<u32>(bitcast<vec3<u32>>(p), object_ids[i]);
        verts[3u * i + 1u] = vec4<u32>(bitcast<vec3<u32>>(m), 0u);
        verts[3u * i + 2u] = bitcast<vec4<u32>>(colors[i]);
    }
}
