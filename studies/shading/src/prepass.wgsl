// Light pre-pass, second geometry pass (prepended: common.wgsl). Each material combines the
// light buffer (Σ diffuse RGB, Σ lum·spec in A) with its own colours, its own way:
//   model 0 (dielectric: albedo > 0): albedo·(D + ambient) + specular·A   (monochrome specular)
//   model 1 (metal: albedo = 0):       specular·A·D/lum(D)                 (specular colour from
//                                      the diffuse light's chroma, Engel's reconstruction)

struct Material {
    albedo_smooth: vec4<f32>,
    spec: vec4<f32>,
};

@group(1) @binding(0) var<storage, read> materials: array<Material>;
@group(1) @binding(1) var lb0: texture_2d<f32>;
@group(1) @binding(2) var lb1: texture_2d<f32>;

// RG11B10 + R16F: the specular term is in the second texture.
override SPLIT: bool = false;
// Light buffer decode factor (RGBA8 stores light / 8).
override LB_DECODE: f32 = 1.0;
// = shading::AMBIENT
const AMBIENT: vec3<f32> = vec3<f32>(0.03, 0.03, 0.035);

const LUM_W: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

fn unorm8(c: vec3<f32>) -> vec3<f32> {
    return round(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)) * 255.0) / 255.0;
}

@fragment
fn fs_material(v: Varyings) -> @location(0) vec4<f32> {
    let p = vec2<u32>(v.clip.xy);
    let t0 = textureLoad(lb0, p, 0);
    var a = t0.w;
    if SPLIT {
        a = textureLoad(lb1, p, 0).x;
    }
    let d = t0.xyz * LB_DECODE;
    a = a * LB_DECODE;
    let m = materials[v.object_id];
    // The colours the full G-buffer stores (Rgba8Unorm), so that both renderers shade the same
    // material inputs and the one f64 reference (built from the read-back G-buffer) serves both.
    let albedo = unorm8(m.albedo_smooth.xyz);
    let spec = unorm8(m.spec.xyz);
    if all(albedo == vec3<f32>(0.0)) {
        let l = dot(d, LUM_W);
        var chroma = vec3<f32>(0.0);
        if l > 1e-6 {
            chroma = d / l;
        }
        return vec4<f32>(spec * a * chroma, 1.0);
    }
    return vec4<f32>(albedo * (d + AMBIENT) + spec * a, 1.0);
}
