// Classic depth peeling (Everitt 2001). Pass i keeps, per pixel, the nearest fragment strictly
// behind layer i−1's depth: the fragment stage discards what is not behind, the depth test keeps
// the nearest of the rest. A compute pass then feeds the layer's fragment to the effects fold
// (effects.wgsl, prepended), whose per-pixel FoldState lives in a storage buffer between passes.
// Strict comparison means a fragment at exactly the previous layer's depth (coplanar) is lost:
// the classic method's known failure. TIEBREAK peels on (depth, object id) pairs instead: a
// fragment at the previous depth survives when its id is larger, and the depth test (Less)
// keeps the first submitted of equal depths, so ids that grow with submission order are peeled
// one by one.
//
// Payload variants ("leave out what the scene does not need"): one vertex entry per attribute
// set (vs_full binds all four) and one fragment/resolve entry pair per payload, so a pipeline
// fetches, writes and reads only what its effect uses.

override PEEL: bool = true;
override TIEBREAK: bool = false;
// MSAA (aa = msaa*, sample shading): samples per pixel. The Rust side then compiles this file
// with every texture multisampled (`texture_2d` → `texture_multisampled_2d`) and each fragment
// entry per sample (`gpu_util::per_sample_source`, which sets SAMPLE to the sample index); the
// resolve runs one invocation per (pixel, sample) with SAMPLE = global_invocation_id.z and keeps
// one fold state per sample; fold_end averages the samples' images. With one sample SAMPLE is 0,
// the textureLoad level, and every index below is the pixel's.
override SAMPLES: u32 = 1u;
var<private> SAMPLE: i32 = 0;

@group(0) @binding(1) var prev_depth: texture_depth_2d;
// The previous layer's object ids (TIEBREAK only; a 1×1 dummy otherwise).
@group(0) @binding(2) var prev_id: texture_2d<u32>;

// ---- vertex stages that fetch only some attributes ----

struct PosIn {
    @location(0) position: vec3<f32>,
};
struct PosColorIn {
    @location(0) position: vec3<f32>,
    @location(2) color: vec4<f32>,
};
struct PosNormalIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
};
struct PosIdIn {
    @location(0) position: vec3<f32>,
    @location(3) object_id: u32,
};

fn varyings(p: vec3<f32>, color: vec4<f32>, normal: vec3<f32>, id: u32) -> Varyings {
    let q = vec4<f32>(p, 1.0);
    var out: Varyings;
    out.clip = camera.clip_from_world * q;
    out.color = color;
    out.normal = normal;
    out.view_z = -(camera.view_from_world * q).z;
    out.object_id = id;
    return out;
}

@vertex
fn vs_p(v: PosIn) -> Varyings {
    return varyings(v.position, vec4<f32>(0.0), vec3<f32>(0.0), 0u);
}
@vertex
fn vs_pc(v: PosColorIn) -> Varyings {
    return varyings(v.position, v.color, vec3<f32>(0.0), 0u);
}
@vertex
fn vs_pn(v: PosNormalIn) -> Varyings {
    return varyings(v.position, vec4<f32>(0.0), v.normal, 0u);
}
@vertex
fn vs_pi(v: PosIdIn) -> Varyings {
    return varyings(v.position, vec4<f32>(0.0), vec3<f32>(0.0), v.object_id);
}

// ---- peel: keep only what lies behind the previous layer ----

// The fragment's depth as the keep test reads it: under MSAA every entry also writes it as
// frag_depth (`ms_depth_source`), so the depth buffer holds exactly what the next pass compares.
var<private> FRAG_Z: f32 = 0.0;

fn peel_keep(pos: vec4<f32>, id: u32) -> bool {
    FRAG_Z = pos.z;
    if !PEEL {
        return true;
    }
    let px = vec2<i32>(pos.xy);
    let prev = textureLoad(prev_depth, px, SAMPLE);
    if TIEBREAK {
        return nearer(prev, pos.z) || (pos.z == prev && id > textureLoad(prev_id, px, SAMPLE).x);
    }
    return nearer(prev, pos.z);
}

// Linear view depth with the facing in its sign (view_z > 0 in front of the eye): negative for
// front faces (entries), positive for back faces (exits).
fn signed_z(view_z: f32, front: bool) -> f32 {
    return select(view_z, -view_z, front);
}

@fragment
fn fs_rgba(@builtin(position) pos: vec4<f32>, @location(0) color: vec4<f32>) -> @location(0) vec4<f32> {
    if !peel_keep(pos, 0u) {
        discard;
    }
    return color;
}

@fragment
fn fs_z(@builtin(position) pos: vec4<f32>, @builtin(front_facing) front: bool, @location(2) view_z: f32) -> @location(0) f32 {
    if !peel_keep(pos, 0u) {
        discard;
    }
    return signed_z(view_z, front);
}

@fragment
fn fs_zn(@builtin(position) pos: vec4<f32>, @builtin(front_facing) front: bool, @location(1) normal: vec3<f32>, @location(2) view_z: f32) -> @location(0) vec4<f32> {
    if !peel_keep(pos, 0u) {
        discard;
    }
    return vec4<f32>(normal, signed_z(view_z, front));
}

@fragment
fn fs_id(@builtin(position) pos: vec4<f32>, @location(3) @interpolate(flat) id: u32) -> @location(0) u32 {
    if !peel_keep(pos, id) {
        discard;
    }
    return id;
}

struct RgbaZOut {
    @location(0) color: vec4<f32>,
    @location(1) z: f32,
};

@fragment
fn fs_rgbaz(@builtin(position) pos: vec4<f32>, @builtin(front_facing) front: bool, @location(0) color: vec4<f32>, @location(2) view_z: f32) -> RgbaZOut {
    if !peel_keep(pos, 0u) {
        discard;
    }
    return RgbaZOut(color, signed_z(view_z, front));
}

struct AllOut {
    @location(0) color: vec4<f32>,
    @location(1) normal_z: vec4<f32>,
    @location(2) id: u32,
};

@fragment
fn fs_all(in: Varyings, @builtin(front_facing) front: bool) -> AllOut {
    if !peel_keep(in.clip, in.object_id) {
        discard;
    }
    return AllOut(in.color, vec4<f32>(in.normal, signed_z(in.view_z, front)), in.object_id);
}

// ---- resolve: feed each pixel's layer fragment to the fold ----

@group(1) @binding(0) var layer_color: texture_2d<f32>;
@group(1) @binding(1) var layer_depth: texture_depth_2d;
@group(1) @binding(2) var layer_z: texture_2d<f32>;
@group(1) @binding(3) var layer_zn: texture_2d<f32>;
@group(1) @binding(4) var layer_id: texture_2d<u32>;
@group(1) @binding(5) var<storage, read_write> fold: array<FoldState>;
@group(1) @binding(6) var<storage, read_write> counts: array<u32>;
@group(1) @binding(7) var<storage, read_write> image: array<vec4<f32>>;

// The fold slot of invocation `id`: its pixel's (one sample), or its (pixel, sample)'s; -1
// outside the image. Sets SAMPLE for the texture loads.
fn pixel_index(id: vec3<u32>) -> i32 {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return -1;
    }
    SAMPLE = i32(id.z);
    return i32((id.y * w + id.x) * SAMPLES + id.z);
}

// The layer's window depth at `id`, or a negative value where the layer is empty (the depth
// buffer still holds its clear value).
fn layer_at(id: vec3<u32>) -> f32 {
    let d = textureLoad(layer_depth, vec2<i32>(id.xy), SAMPLE);
    if d == camera.near_far.w {
        return -1.0;
    }
    return d;
}

fn step_pixel(i: i32, f: Frag) {
    var s = fold[i];
    fold_step(&s, f);
    fold[i] = s;
    counts[i] = counts[i] + 1u;
}

fn frag(depth: f32, signed_view_z: f32, color: vec4<f32>, normal: vec3<f32>, id: u32) -> Frag {
    return Frag(depth, abs(signed_view_z), color, normal, id, signed_view_z < 0.0);
}

@compute @workgroup_size(8, 8)
fn resolve_rgba(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 { return; }
    let d = layer_at(id);
    if d < 0.0 { return; }
    let c = textureLoad(layer_color, vec2<i32>(id.xy), SAMPLE);
    step_pixel(i, frag(d, 0.0, c, vec3<f32>(0.0), 0u));
}

@compute @workgroup_size(8, 8)
fn resolve_z(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 { return; }
    let d = layer_at(id);
    if d < 0.0 { return; }
    let z = textureLoad(layer_z, vec2<i32>(id.xy), SAMPLE).x;
    step_pixel(i, frag(d, z, vec4<f32>(0.0), vec3<f32>(0.0), 0u));
}

@compute @workgroup_size(8, 8)
fn resolve_zn(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 { return; }
    let d = layer_at(id);
    if d < 0.0 { return; }
    let nz = textureLoad(layer_zn, vec2<i32>(id.xy), SAMPLE);
    step_pixel(i, frag(d, nz.w, vec4<f32>(0.0), nz.xyz, 0u));
}

@compute @workgroup_size(8, 8)
fn resolve_id(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 { return; }
    let d = layer_at(id);
    if d < 0.0 { return; }
    let o = textureLoad(layer_id, vec2<i32>(id.xy), SAMPLE).x;
    step_pixel(i, frag(d, 0.0, vec4<f32>(0.0), vec3<f32>(0.0), o));
}

@compute @workgroup_size(8, 8)
fn resolve_rgbaz(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 { return; }
    let d = layer_at(id);
    if d < 0.0 { return; }
    let c = textureLoad(layer_color, vec2<i32>(id.xy), SAMPLE);
    let z = textureLoad(layer_z, vec2<i32>(id.xy), SAMPLE).x;
    step_pixel(i, frag(d, z, c, vec3<f32>(0.0), 0u));
}

@compute @workgroup_size(8, 8)
fn resolve_all(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 { return; }
    let d = layer_at(id);
    if d < 0.0 { return; }
    let c = textureLoad(layer_color, vec2<i32>(id.xy), SAMPLE);
    let nz = textureLoad(layer_zn, vec2<i32>(id.xy), SAMPLE);
    let o = textureLoad(layer_id, vec2<i32>(id.xy), SAMPLE).x;
    step_pixel(i, frag(d, nz.w, c, nz.xyz, o));
}

// ---- init and finish: once per frame ----

// Dispatched over pixels only (z = 0): each invocation covers its pixel's samples.
@compute @workgroup_size(8, 8)
fn fold_begin(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 { return; }
    // Every sample's view ray is the pixel centre's (as the reference's effects take it).
    let init = fold_init_at(vec2<f32>(id.xy) + 0.5);
    for (var s = 0u; s < SAMPLES; s = s + 1u) {
        fold[u32(i) + s] = init;
        counts[u32(i) + s] = 0u;
    }
}

@compute @workgroup_size(8, 8)
fn fold_end(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = pixel_index(id);
    if i < 0 { return; }
    let n = u32(camera.viewport.x) * u32(camera.viewport.y);
    let p = u32(i) / SAMPLES;
    for (var k = 0u; k < fold_image_count(); k = k + 1u) {
        if SAMPLES == 1u {
            image[k * n + p] = fold_finish_image(fold[i], k);
        } else {
            // The resolve: the mean of the samples' images.
            var sum = vec4<f32>(0.0);
            for (var s = 0u; s < SAMPLES; s = s + 1u) {
                sum = sum + fold_finish_image(fold[u32(i) + s], k);
            }
            image[k * n + p] = sum / f32(SAMPLES);
        }
    }
}
