// The mesh accessors visibility.wgsl reads, over the scene's own buffers (one per attribute, as
// the raster methods draw them): the including shader declares `positions`, `normals`, `colors`,
// `object_ids` and `indices`.

fn position(i: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

fn vertex_normal(i: u32) -> vec3<f32> {
    return vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
}

fn vertex_color(i: u32) -> vec4<f32> {
    return colors[i];
}

fn vertex_object(i: u32) -> u32 {
    return object_ids[i];
}

fn tri_indices(prim: u32) -> vec3<u32> {
    return vec3<u32>(indices[3u * prim], indices[3u * prim + 1u], indices[3u * prim + 2u]);
}
