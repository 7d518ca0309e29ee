// G-buffer pass of the shading studies (prepended: common.wgsl). Normals go to view space
// (the camera's view matrix is rigid) and face the eye; material by object id.

struct Material {
    albedo_smooth: vec4<f32>,
    spec: vec4<f32>,
};

@group(1) @binding(0) var<storage, read> materials: array<Material>;

struct GOut {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) spec: vec4<f32>,
    @location(3) mat: u32,
};

// The scene generator gives normals facing where the camera can be (outward boxes, inward room).
fn view_normal(v: Varyings) -> vec3<f32> {
    return normalize((camera.view_from_world * vec4<f32>(v.normal, 0.0)).xyz);
}

fn gbuffer_out(v: Varyings) -> GOut {
    let m = materials[v.object_id];
    var o: GOut;
    o.normal = vec4<f32>(view_normal(v), m.albedo_smooth.w);
    o.albedo = vec4<f32>(m.albedo_smooth.xyz, 1.0);
    o.spec = vec4<f32>(m.spec.xyz, 0.0);
    o.mat = v.object_id;
    return o;
}

@fragment
fn fs_gbuffer(v: Varyings) -> GOut {
    return gbuffer_out(v);
}

// The MSAA G-buffer (msaa.rs): the same outputs and the depth at the pixel centre, so every
// sample the triangle covers holds the same depth too (no sample-rate shading: one fragment per
// pixel, its outputs written to each covered sample).
struct GOutMs {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) spec: vec4<f32>,
    @location(3) mat: u32,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_gbuffer_ms(v: Varyings) -> GOutMs {
    let g = gbuffer_out(v);
    return GOutMs(g.normal, g.albedo, g.spec, g.mat, v.clip.z);
}

@fragment
fn fs_prepass(v: Varyings) -> @location(0) vec4<f32> {
    let m = materials[v.object_id];
    return vec4<f32>(view_normal(v), m.albedo_smooth.w);
}
