// Shared by every raster method: the camera and the standard vertex stage.
// Vertex inputs: 0 position (Float32x3), 1 normal (Float32x3), 2 colour (Float32x4, straight
// RGBA), 3 object id (Uint32). A pipeline binds only the attributes its entry point reads.

struct Camera {
    clip_from_world: mat4x4<f32>,
    view_from_world: mat4x4<f32>,
    // width, height, 1/width, 1/height
    viewport: vec4<f32>,
    // near, far, reversed_z (0|1), clear depth
    near_far: vec4<f32>,
};

@group(0) @binding(0) var<uniform> camera: Camera;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
    @location(3) object_id: u32,
};

struct Varyings {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
    @location(1) normal: vec3<f32>,
    // Linear view-space distance (positive in front of the eye).
    @location(2) view_z: f32,
    @location(3) @interpolate(flat) object_id: u32,
};

@vertex
fn vs_full(v: VertexIn) -> Varyings {
    let p = vec4<f32>(v.position, 1.0);
    var out: Varyings;
    out.clip = camera.clip_from_world * p;
    out.color = v.color;
    out.normal = v.normal;
    out.view_z = -(camera.view_from_world * p).z;
    out.object_id = v.object_id;
    return out;
}

struct PositionIn {
    @location(0) position: vec3<f32>,
};

@vertex
fn vs_position(v: PositionIn) -> @builtin(position) vec4<f32> {
    return camera.clip_from_world * vec4<f32>(v.position, 1.0);
}

// True if window depth `a` is strictly nearer than `b` under the camera's depth convention.
fn nearer(a: f32, b: f32) -> bool {
    return select((a < b), (a > b), camera.near_far.z > 0.5);
}
