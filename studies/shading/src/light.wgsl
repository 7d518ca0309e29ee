// The light model of the shading studies (issues 6 and 10); the same model as
// bench-core/src/shading/mod.rs (f32 CPU path) and reference.rs (f64). Everything is in view
// space (right-handed, looking down −z). No bindings here: each path declares its own.
//
// Per light: q = the light's nearest point to P (the segment's for a line light), d = |q − P|,
// att = (1 − (d/range)²)² for d < range, else 0; a spot multiplies by
// saturate((cos∠ − cos_outer) / (1 − cos_outer))². Blinn-Phong with specular power
// p = 2^(1 + 10·smoothness) normalised by (p + 8)/8 (BF3). contrib = colour·att·N·L;
// diffuse += contrib, specular += contrib·spec_term, spec_lum += lum(contrib)·spec_term.
// Pixel = albedo·(diffuse + ambient) + specular_colour·specular; sky pixels = sky colour.
// A diffuse-only light (extra.y = 1) adds to diffuse only: its specular term is 0.

struct Light {
    // view-space position (segment start for a line light), range
    pos_range: vec4<f32>,
    // view-space unit direction (spot axis / segment direction), kind (0 point, 1 spot, 2 line)
    dir_kind: vec4<f32>,
    // colour (linear, intensity folded in), spot cos_outer
    color_cos: vec4<f32>,
    // culling sphere: centre, radius at the attenuation threshold (< 0: culled everywhere)
    cull: vec4<f32>,
    // line length, diffuse-only flag (1: the light has no specular term), 0, 0
    extra: vec4<f32>,
};

struct Shade {
    view_from_clip: mat4x4<f32>,
    clip_from_view: mat4x4<f32>,
    // width, height, 1/width, 1/height
    viewport: vec4<f32>,
    // view-space direction to the sun, w = 1 when the scene has a sun
    sun_dir: vec4<f32>,
    sun_color: vec4<f32>,
    sky: vec4<f32>,
    ambient: vec4<f32>,
    // light_count, tiles_x, tiles_y, tile_size
    counts: vec4<u32>,
    // attenuation threshold, clear depth, reversed_z, 0
    misc: vec4<f32>,
    // sun shadow (sun_shadow.wgsl): view space -> the map's clip space
    shadow_from_view: mat4x4<f32>,
    // map side in texels, compare bias, 1 when on, 0
    shadow: vec4<f32>,
};

struct GPixel {
    pos: vec3<f32>,
    n: vec3<f32>,
    smoothness: f32,
    albedo: vec3<f32>,
    spec: vec3<f32>,
    mat: u32,
    sky: bool,
};

struct Acc {
    diffuse: vec3<f32>,
    specular: vec3<f32>,
    spec_lum: f32,
};

const SKY_MATERIAL: u32 = 0xffffffffu;
const LUM: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

fn acc_zero() -> Acc {
    return Acc(vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
}

// View-space position of pixel `p` (integer coordinates, sampled at its centre) at depth `d`.
fn view_pos(sh: Shade, p: vec2<u32>, d: f32) -> vec3<f32> {
    let ndc = vec2<f32>(
        (f32(p.x) + 0.5) * sh.viewport.z * 2.0 - 1.0,
        1.0 - (f32(p.y) + 0.5) * sh.viewport.w * 2.0,
    );
    let v = sh.view_from_clip * vec4<f32>(ndc, d, 1.0);
    return v.xyz / v.w;
}

fn spec_power(smoothness: f32) -> f32 {
    return exp2(1.0 + 10.0 * smoothness);
}

// Adds light `l` to `acc`; `with_spec` false compiles out the specular work.
fn acc_light(acc: ptr<function, Acc>, l: Light, g: GPixel, v: vec3<f32>, p: f32, norm: f32, with_spec: bool) {
    var q = l.pos_range.xyz;
    let kind = u32(l.dir_kind.w);
    if kind == 2u {
        let t = clamp(dot(g.pos - q, l.dir_kind.xyz), 0.0, l.extra.x);
        q = q + l.dir_kind.xyz * t;
    }
    let lv = q - g.pos;
    let d2 = dot(lv, lv);
    let r2 = l.pos_range.w * l.pos_range.w;
    if d2 >= r2 || d2 < 1e-12 {
        return;
    }
    let d = sqrt(d2);
    let ld = lv / d;
    let x = 1.0 - d2 / r2;
    var att = x * x;
    if kind == 1u {
        let c = l.color_cos.w;
        let sf = saturate((dot(-ld, l.dir_kind.xyz) - c) / (1.0 - c));
        att = att * sf * sf;
    }
    let ndl = dot(g.n, ld);
    if ndl <= 0.0 || att <= 0.0 {
        return;
    }
    let contrib = l.color_cos.xyz * (att * ndl);
    (*acc).diffuse += contrib;
    if with_spec && l.extra.y < 0.5 {
        let h = normalize(ld + v);
        let ndh = max(dot(g.n, h), 0.0);
        var st = 0.0;
        if ndh > 0.0 {
            st = norm * pow(ndh, p);
        }
        (*acc).specular += contrib * st;
        (*acc).spec_lum += dot(contrib, LUM) * st;
    }
}

fn acc_sun(acc: ptr<function, Acc>, sh: Shade, g: GPixel, v: vec3<f32>, p: f32, norm: f32, with_spec: bool) {
    acc_sun_vis(acc, sh, g, v, p, norm, with_spec, 1.0);
}

// The sun times its visibility `vis` (the shadow map's, 1 without one).
fn acc_sun_vis(acc: ptr<function, Acc>, sh: Shade, g: GPixel, v: vec3<f32>, p: f32, norm: f32, with_spec: bool, vis: f32) {
    let ld = sh.sun_dir.xyz;
    let ndl = dot(g.n, ld);
    if sh.sun_dir.w < 0.5 || ndl <= 0.0 {
        return;
    }
    let contrib = sh.sun_color.xyz * (vis * ndl);
    (*acc).diffuse += contrib;
    if with_spec {
        let h = normalize(ld + v);
        let ndh = max(dot(g.n, h), 0.0);
        var st = 0.0;
        if ndh > 0.0 {
            st = norm * pow(ndh, p);
        }
        (*acc).specular += contrib * st;
        (*acc).spec_lum += dot(contrib, LUM) * st;
    }
}

fn compose(sh: Shade, g: GPixel, acc: Acc) -> vec4<f32> {
    if g.sky {
        return vec4<f32>(sh.sky.xyz, 1.0);
    }
    return vec4<f32>(g.albedo * (acc.diffuse + sh.ambient.xyz) + g.spec * acc.specular, 1.0);
}

// Sphere (c, r) is entirely outside the convex region of `planes` (inward normals, dot(n,x)+w >= 0 inside).
fn sphere_outside(planes: array<vec4<f32>, 6>, c: vec3<f32>, r: f32) -> bool {
    if r < 0.0 {
        return true;
    }
    for (var i = 0u; i < 6u; i++) {
        if dot(planes[i].xyz, c) + planes[i].w < -r {
            return true;
        }
    }
    return false;
}

// A point on the view ray through the pixel-space corner (x, y) (pixel edges, not centres).
fn corner_ray(sh: Shade, x: f32, y: f32) -> vec3<f32> {
    let ndc = vec2<f32>(x * sh.viewport.z * 2.0 - 1.0, 1.0 - y * sh.viewport.w * 2.0);
    let v = sh.view_from_clip * vec4<f32>(ndc, 0.5, 1.0);
    return v.xyz / v.w;
}

// The frustum of the pixel rectangle [x0,x1]×[y0,y1] between view distances zmin and zmax.
fn tile_planes(sh: Shade, x0: f32, y0: f32, x1: f32, y1: f32, zmin: f32, zmax: f32) -> array<vec4<f32>, 6> {
    let a = corner_ray(sh, x0, y0);
    let b = corner_ray(sh, x1, y0);
    let c = corner_ray(sh, x1, y1);
    let d = corner_ray(sh, x0, y1);
    let mid = a + b + c + d;
    var out: array<vec4<f32>, 6>;
    let corners = array<vec3<f32>, 4>(a, b, c, d);
    for (var i = 0u; i < 4u; i++) {
        var n = normalize(cross(corners[i], corners[(i + 1u) % 4u]));
        if dot(n, mid) < 0.0 {
            n = -n;
        }
        out[i] = vec4<f32>(n, 0.0);
    }
    out[4] = vec4<f32>(0.0, 0.0, -1.0, -zmin);
    out[5] = vec4<f32>(0.0, 0.0, 1.0, zmax);
    return out;
}
