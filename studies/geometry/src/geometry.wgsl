// Geometry feeding (Bavoil 2007, ch. 3). Appended to common.wgsl (camera at binding 0) and to a
// generated prelude that declares `struct FeedIn` (location 0 = position, then the other
// attributes in slot order), `fn decode_position(v: FeedIn, batch: u32) -> vec3<f32>` and
// `fn attribute_check(v: FeedIn) -> vec3<f32>` (every non-position attribute, decoded, folded
// into one vec3 with distinct weights: studies/geometry/prep.rs `check_value` is its twin).

// Per-batch bounding box of the quantised positions: p = centre + half · q.
struct BatchBox {
    centre: vec4<f32>,
    half: vec4<f32>,
};

@group(0) @binding(1) var<storage, read> boxes: array<BatchBox>;

// touch.x is 0 in every run. The vertex shader adds touch.x · (every attribute) to the clip
// position, so no compiler can prove an attribute unused and skip its fetch, while the result
// stays bit-exact (attributes are finite).
struct Feed {
    touch: vec4<f32>,
};

@group(0) @binding(2) var<uniform> feed: Feed;

struct FeedOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) check: vec3<f32>,
};

@vertex
fn vs_feed(v: FeedIn, @builtin(instance_index) batch: u32) -> FeedOut {
    let p = decode_position(v, batch);
    let check = attribute_check(v);
    var out: FeedOut;
    out.clip = camera.clip_from_world * vec4<f32>(p, 1.0);
    out.clip.x += feed.touch.x * (check.x + check.y + check.z);
    out.check = check;
    return out;
}

// The benchmark's fragment stage: one constant colour (the thesis's method), so the time is
// the geometry's, not shading's.
@fragment
fn fs_constant() -> @location(0) vec4<f32> {
    return vec4<f32>(0.8, 0.8, 0.8, 1.0);
}

// Tests only: the decoded attributes and the window depth, to compare with the CPU twin.
@fragment
fn fs_check(in: FeedOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.check, in.clip.z);
}
