// The effects fold: every method that resolves per-pixel fragments in depth order (nearest
// first) feeds them through fold_step and writes fold_finish. Which effect is computed is the
// override EFFECT, so each variant compiles with only its own code (the "leave out what the
// scene does not need" rule): the branches below test override constants, which the pipeline
// fixes, so the driver folds the unused ones away. FoldState is 64 bytes: it may live in a
// per-pixel storage buffer between passes (depth peeling).
//
// The Rust side (bench-core/src/effects.rs, `EffectConfig::constants`) sets these overrides
// and holds the f64 CPU reference of every effect; the output images are documented there.
//
// EFFECT  name          reads (payload)          output (premultiplied RGBA, per image)
// 0       transparency  colour                   front-to-back "under" composite, A = 1 − T
// 1       translucency  view_z + facing          (T, T, T, 1 − T), T = exp(−SIGMA·thickness)
// 2       fresnel       view_z + facing + normal translucency × Π Schlick transmittance
// 3       csg           depth + object id        (depth, is A, is B, 1) of the first fragment
//                                                 where the boolean CSG_OP(A, B) holds
// 4       dof           colour + view_z          3 images: the nearest fragment of each view-depth
//                                                 partition [0, DOF_NEAR), [DOF_NEAR, DOF_FAR),
//                                                 [DOF_FAR, ∞), as (rgb·a, a)
// 5       volume        colour.r (scalar) +      Bavoil 2007 §6.3.2: each ray segment between
//                       view_z                   consecutive fragments, opacity
//                                                 1 − exp(−SIGMA·(s1 + s2)/2·Δz), colour
//                                                 fold_transfer(mean s), composited front to back
// 6       isosurface    colour.r (scalar) +      §6.3.1: (view_z of the nearest ISO_VALUE
//                       view_z                   crossing between consecutive fragments, 0, 0, 1)
//
// Contract for callers: FoldState s = fold_init_at(pixel centre) (or fold_init() when the
// effect needs no view direction: all but fresnel); fold_step(&s, Frag(...)) per fragment,
// nearest first; then fold_finish(s) (image 0) and, for i < fold_image_count(),
// fold_finish_image(s, i).

override EFFECT: u32 = 0u;
// Thickness arithmetic: false = the seed's naive ±z running sum, true = per-pair differences of
// adjacent linear depths with Kahan summation.
override THICKNESS_STABLE: bool = true;
// Extinction coefficient per world unit (Beer–Lambert).
override SIGMA: f32 = 1.0;
// CSG boolean: 0 = A ∩ B, 1 = A ∪ B, 2 = A − B; A and B are object ids.
override CSG_OP: u32 = 0u;
override CSG_A: u32 = 0u;
override CSG_B: u32 = 1u;
// Depth-of-field partition bounds in linear view depth (world units).
override DOF_NEAR: f32 = 1.0;
override DOF_FAR: f32 = 10.0;
// The iso-value of the isosurface effect.
override ISO_VALUE: f32 = 0.3;

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
    // transparency: premultiplied RGBA accumulated under; csg: the result; dof: image 0.
    accum: vec4<f32>,
    // translucency/fresnel: x thickness sum, y Kahan compensation, z previous view_z,
    // w product of Fresnel transmittances; dof: image 1; volume/isosurface: x previous scalar,
    // z previous view_z.
    aux: vec4<f32>,
    // translucency/fresnel: xyz world-space view direction (0 = unknown: the view axis),
    // w = objects open (entries − exits so far); dof: image 2.
    extra: vec4<f32>,
    // csg: bit 0 inside A, bit 1 inside B, bit 2 done; dof: bit i = image i filled;
    // isosurface: bit 2 done.
    flags: u32,
    count: u32,
};

fn fold_init() -> FoldState {
    return FoldState(vec4<f32>(0.0), vec4<f32>(0.0, 0.0, 0.0, 1.0), vec4<f32>(0.0), 0u, 0u);
}

// The world-space direction of the view ray through window position `pixel` (pixel centre,
// top-left origin). Derived from the camera uniform: view_from_world is rigid, so the projection's
// x and y scales are clip_from_world applied to the rows of its rotation.
fn fold_view_dir(pixel: vec2<f32>) -> vec3<f32> {
    let v = camera.view_from_world;
    let r = mat3x3<f32>(v[0].xyz, v[1].xyz, v[2].xyz);
    let rt = transpose(r);
    let p00 = (camera.clip_from_world * vec4<f32>(rt[0], 0.0)).x;
    let p11 = (camera.clip_from_world * vec4<f32>(rt[1], 0.0)).y;
    let ndc = vec2<f32>(pixel.x * camera.viewport.z * 2.0 - 1.0, 1.0 - pixel.y * camera.viewport.w * 2.0);
    let d_view = vec3<f32>(ndc.x / p00, ndc.y / p11, -1.0);
    return normalize(rt * d_view);
}

fn fold_init_at(pixel: vec2<f32>) -> FoldState {
    var s = fold_init();
    if EFFECT == 2u {
        s.extra = vec4<f32>(fold_view_dir(pixel), 0.0);
    }
    return s;
}

fn fold_image_count() -> u32 {
    if EFFECT == 4u {
        return 3u;
    }
    return 1u;
}

fn fold_csg(bits: u32) -> bool {
    let a = (bits & 1u) != 0u;
    let b = (bits & 2u) != 0u;
    if CSG_OP == 0u {
        return a && b;
    } else if CSG_OP == 1u {
        return a || b;
    }
    return a && !b;
}

// Schlick's transmittance 1 − (1 − cos θ)^5 at one interface; a zero normal counts as normal
// incidence (transmittance 1) rather than producing NaN.
fn fold_schlick_t(n: vec3<f32>, dir: vec3<f32>) -> f32 {
    let len2 = dot(n, n);
    if !(len2 > 0.0) {
        return 1.0;
    }
    var d = dir;
    if dot(d, d) == 0.0 {
        // No pixel given: the view axis (−z in view space) in world space.
        let v = camera.view_from_world;
        d = -vec3<f32>(v[0].z, v[1].z, v[2].z);
    }
    let c = min(abs(dot(n, d)) / sqrt(len2), 1.0);
    let m = 1.0 - c;
    let m2 = m * m;
    return 1.0 - m2 * m2 * m;
}

// The volume effect's transfer function: a ramp from blue through green to red over s ∈ [0, 1]
// (mfx_reference::volume::transfer).
fn fold_transfer(s: f32) -> vec3<f32> {
    return vec3<f32>(s, 4.0 * s * (1.0 - s), 1.0 - s);
}

fn fold_step(s: ptr<function, FoldState>, f: Frag) {
    let first = (*s).count == 0u;
    (*s).count = (*s).count + 1u;
    if EFFECT == 0u {
        let t = 1.0 - (*s).accum.a;
        (*s).accum = vec4<f32>((*s).accum.rgb + t * f.color.a * f.color.rgb, (*s).accum.a + t * f.color.a);
    } else if EFFECT == 1u || EFFECT == 2u {
        // Entering an object (front face) subtracts its depth, leaving adds it: Σ (exit − entry).
        if THICKNESS_STABLE {
            // Σ s_i z_i = Σ_j open_{j−1} (z_j − z_{j−1}) + (unbalanced rest, added at the end):
            // each term is a difference of adjacent depths (exact by Sterbenz when they are
            // within a factor 2), so the large common distance never enters the sum.
            if !first {
                let seg = (*s).extra.w * (f.view_z - (*s).aux.z);
                let y = seg - (*s).aux.y;
                let t = (*s).aux.x + y;
                (*s).aux.y = (t - (*s).aux.x) - y;
                (*s).aux.x = t;
            }
            (*s).aux.z = f.view_z;
            (*s).extra.w = (*s).extra.w + select(-1.0, 1.0, f.front_facing);
        } else {
            (*s).aux.x = (*s).aux.x + select(f.view_z, -f.view_z, f.front_facing);
        }
        if EFFECT == 2u {
            (*s).aux.w = (*s).aux.w * fold_schlick_t(f.normal, (*s).extra.xyz);
        }
    } else if EFFECT == 3u {
        if ((*s).flags & 4u) != 0u {
            return;
        }
        let before = fold_csg((*s).flags);
        var bits = (*s).flags;
        if f.object_id == CSG_A {
            bits = bits ^ 1u;
        }
        if f.object_id == CSG_B {
            bits = bits ^ 2u;
        }
        if !before && fold_csg(bits) {
            (*s).accum = vec4<f32>(f.depth, select(0.0, 1.0, f.object_id == CSG_A), select(0.0, 1.0, f.object_id == CSG_B), 1.0);
            bits = bits | 4u;
        }
        (*s).flags = bits;
    } else if EFFECT == 4u {
        var part = 2u;
        if f.view_z < DOF_NEAR {
            part = 0u;
        } else if f.view_z < DOF_FAR {
            part = 1u;
        }
        let bit = 1u << part;
        if ((*s).flags & bit) == 0u {
            (*s).flags = (*s).flags | bit;
            let c = vec4<f32>(f.color.rgb * f.color.a, f.color.a);
            if part == 0u {
                (*s).accum = c;
            } else if part == 1u {
                (*s).aux = c;
            } else {
                (*s).extra = c;
            }
        }
    } else if EFFECT == 5u {
        // §6.3.2: the segment from the previous fragment to this one. The thesis looks its
        // colour up in a pre-integrated table of (s_f, s_b, distance); with extinction linear in
        // s the table's entry is this closed form (the reference's, in f64).
        if !first {
            let mean = 0.5 * ((*s).aux.x + f.color.r);
            let x = max(SIGMA * mean * (f.view_z - (*s).aux.z), 0.0);
            let a = select(1.0 - exp(-x), x * (1.0 - 0.5 * x * (1.0 - x / 3.0)), x < 1e-2);
            let t = 1.0 - (*s).accum.a;
            (*s).accum = vec4<f32>((*s).accum.rgb + t * a * fold_transfer(mean), (*s).accum.a + t * a);
        }
        (*s).aux.x = f.color.r;
        (*s).aux.z = f.view_z;
    } else if EFFECT == 6u {
        // §6.3.1: the first segment whose scalars bracket the iso-value; its depth by linear
        // interpolation (the thesis then depth-tests it against one k-buffer entry: the first
        // crossing front to back is that test's winner).
        if ((*s).flags & 4u) != 0u {
            return;
        }
        let s1 = (*s).aux.x;
        let s2 = f.color.r;
        if !first && (s1 - ISO_VALUE) * (s2 - ISO_VALUE) <= 0.0 && s1 != s2 {
            let t = (ISO_VALUE - s1) / (s2 - s1);
            (*s).accum = vec4<f32>((*s).aux.z + t * (f.view_z - (*s).aux.z), 0.0, 0.0, 1.0);
            (*s).flags = (*s).flags | 4u;
        }
        (*s).aux.x = s2;
        (*s).aux.z = f.view_z;
    }
}

fn fold_thickness(s: FoldState) -> f32 {
    if THICKNESS_STABLE {
        // Objects still open at the end (the eye inside one, or a lost exit) contribute
        // −open·z_last, so both forms compute the same quantity Σ ±z.
        return s.aux.x - s.aux.y - s.extra.w * s.aux.z;
    }
    return s.aux.x;
}

fn fold_finish_image(s: FoldState, image: u32) -> vec4<f32> {
    if EFFECT == 1u || EFFECT == 2u {
        // exp(−x) underflows to 0 for large x; the explicit cut keeps σ·l = ∞ (or σ = 0 with
        // l = ∞) from producing NaN: the output is 0, never NaN.
        let x = max(SIGMA * fold_thickness(s), 0.0);
        var t = select(0.0, exp(-x), x < 87.0);
        // 1 − T for small σ·l by its series (1 − exp(−x) in f32 would keep ~1e-7 absolute,
        // losing a thickness with σ·l ≈ 1e-6 to 6% error); error ≤ x⁴/24.
        var a = select(1.0 - t, x * (1.0 - 0.5 * x * (1.0 - x / 3.0)), x < 1e-2);
        if EFFECT == 2u {
            t = t * s.aux.w;
            a = 1.0 - t;
        }
        return vec4<f32>(t, t, t, a);
    } else if EFFECT == 4u {
        if (s.flags & (1u << image)) == 0u {
            return vec4<f32>(0.0);
        }
        if image == 1u {
            return s.aux;
        } else if image == 2u {
            return s.extra;
        }
        return s.accum;
    }
    return s.accum;
}

fn fold_finish(s: FoldState) -> vec4<f32> {
    return fold_finish_image(s, 0u);
}
