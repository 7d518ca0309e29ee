// The effects fold: every method that resolves per-pixel fragments in depth order (nearest
// first) feeds them through fold_step and writes fold_finish. Which effect is computed is the
// override EFFECT, so each variant compiles with only its own code (the "leave out what the
// scene does not need" rule). Keep FoldState small: it may live in a per-pixel storage buffer
// between passes (depth peeling).
//
// EFFECT: 0 = transparency (front-to-back "under" compositing, premultiplied RGBA, A = 1 − T).
// Further effects (translucency, Fresnel, CSG, depth-of-field partitions) extend this file.

override EFFECT: u32 = 0u;

// What a captured fragment offers to effects; a method fills what its payload stores.
struct Frag {
    depth: f32,
    view_z: f32,
    color: vec4<f32>,
    normal: vec3<f32>,
    object_id: u32,
    front_facing: bool,
};

struct FoldState {
    // transparency: premultiplied RGBA accumulated under.
    accum: vec4<f32>,
    // effect scratch (e.g. thickness sum and its compensation, entry depth, inside bitmask).
    aux: vec4<f32>,
    flags: u32,
    count: u32,
};

fn fold_init() -> FoldState {
    return FoldState(vec4<f32>(0.0), vec4<f32>(0.0), 0u, 0u);
}

fn fold_step(s: ptr<function, FoldState>, f: Frag) {
    (*s).count = (*s).count + 1u;
    if EFFECT == 0u {
        let t = 1.0 - (*s).accum.a;
        (*s).accum = vec4<f32>((*s).accum.rgb + t * f.color.a * f.color.rgb, (*s).accum.a + t * f.color.a);
    }
}

fn fold_finish(s: FoldState) -> vec4<f32> {
    return s.accum;
}
