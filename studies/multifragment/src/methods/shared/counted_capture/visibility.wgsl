// Visibility-buffer re-derivation, shared by compute_abuffer and linked_list's compact nodes: a
// stored fragment is only (window depth, primitive | front << 31); its attributes are derived
// again at the pixel centre from the primitive's three vertices. The including shader gives the
// mesh accessors `position`, `vertex_normal`, `vertex_color`, `vertex_object` and `tri_indices`
// (mesh.wgsl over the scene's own buffers, or compute_abuffer's packed vertices) and the camera.

// Bits of a stored tag that hold the primitive (below them: nothing else; above: a coverage
// mask under MSAA, then bit 31 front facing). 31 unless a method packs a mask (23: 8 samples).
override TAG_PRIM_BITS: u32 = 31u;

// Weights of a point outside its triangle are extrapolated instead of clamped: a fragment that
// covers some MSAA samples but not the pixel centre is shaded at the centre, as a GPU shades a
// pixel-rate fragment (and as the coverage reference does).
override EXTRAPOLATE: bool = false;

fn tag_prim(tag: u32) -> u32 {
    return tag & ((1u << TAG_PRIM_BITS) - 1u);
}

fn clip_of(i: u32) -> vec4<f32> {
    return camera.clip_from_world * vec4<f32>(position(i), 1.0);
}

// Perspective-correct weights of a triangle's three vertices at NDC point `ndc` (2D homogeneous
// rasterisation, Olano & Greer 1997): solve [v0 v1 v2]·λ ∝ (x, y, 1) over the clip-space
// (x, y, w) columns, each scaled to unit size first so vertices at 1e20 neither overflow nor
// cancel; valid for vertices behind the eye too. A covered point lies inside the triangle, so
// its weights are in [0, 1]: they are clamped there (rounding), and a triangle degenerate in clip
// space (collinear vertices that snapping turned into a covering sliver: λ ≈ 0/0) gets equal
// weights instead of NaN.
fn persp_weights(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, ndc: vec2<f32>) -> vec3<f32> {
    let s = 1.0 / max(vec3<f32>(
        max(max(abs(c0.x), abs(c0.y)), abs(c0.w)),
        max(max(abs(c1.x), abs(c1.y)), abs(c1.w)),
        max(max(abs(c2.x), abs(c2.y)), abs(c2.w)),
    ), vec3<f32>(1e-30));
    let a = c0.xyw * s.x;
    let b = c1.xyw * s.y;
    let c = c2.xyw * s.z;
    let q = vec3<f32>(ndc, 1.0);
    let l = vec3<f32>(dot(cross(b, c), q), dot(cross(c, a), q), dot(cross(a, b), q)) * s;
    let sum = l.x + l.y + l.z;
    if !(abs(sum) > 1e-6 * (abs(l.x) + abs(l.y) + abs(l.z))) {
        return vec3<f32>(1.0 / 3.0);
    }
    if EXTRAPOLATE {
        return l / sum;
    }
    let w = clamp(l / sum, vec3<f32>(0.0), vec3<f32>(1.0));
    let t = w.x + w.y + w.z;
    if !(t > 0.0) {
        return vec3<f32>(1.0 / 3.0);
    }
    return w / t;
}

// The fragment of primitive `tag_prim(tag)` (vertices `i`, clip positions `c0..c2`) at NDC
// point `ndc`. Attributes an effect does not read are dead code once EFFECT is fixed.
fn frag_from(depth: f32, tag: u32, ndc: vec2<f32>, i: vec3<u32>, c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>) -> Frag {
    return frag_weighted(depth, tag, i, persp_weights(c0, c1, c2, ndc));
}

// The fragment of primitive `tag_prim(tag)` (vertices `i`) with vertex weights `b`.
fn frag_weighted(depth: f32, tag: u32, i: vec3<u32>, b: vec3<f32>) -> Frag {
    let v = camera.view_from_world;
    let vz = -vec3<f32>(
        (v * vec4<f32>(position(i.x), 1.0)).z,
        (v * vec4<f32>(position(i.y), 1.0)).z,
        (v * vec4<f32>(position(i.z), 1.0)).z,
    );
    return Frag(
        depth,
        dot(b, vz),
        b.x * vertex_color(i.x) + b.y * vertex_color(i.y) + b.z * vertex_color(i.z),
        b.x * vertex_normal(i.x) + b.y * vertex_normal(i.y) + b.z * vertex_normal(i.z),
        vertex_object(i.x),
        (tag >> 31u) != 0u,
    );
}

// NDC of pixel `id`'s centre.
fn pixel_ndc(id: vec2<u32>) -> vec2<f32> {
    let centre = vec2<f32>(id) + 0.5;
    return vec2<f32>(centre.x * camera.viewport.z * 2.0 - 1.0, 1.0 - centre.y * camera.viewport.w * 2.0);
}

// (depth, primitive) of a nearer than of b: ties keep submission order, as the reference.
fn before(da: f32, pa: u32, db: f32, pb: u32) -> bool {
    return nearer(da, db) || (da == db && tag_prim(pa) < tag_prim(pb));
}
