// Layered soft shadow maps (Bavoil 2007, thesis ch. 5; Bavoil, Callahan & Silva, "Robust soft
// shadow mapping with backprojection and depth peeling", JGT 2008).
//
// 1. fs_peel: k depth-peeling passes from the light's centre (the `camera` uniform is the light's
//    camera here). Each layer stores the world-space distance to the light plane (view_z) and its
//    screen-space slope max(|ddx|, |ddy|), for the slope bias.
// 2. pack: the k layers into one RGBA32F texel (one fetch per sample) plus their slopes, and
//    level 0 of the min-depth pyramid (HSM) over the first layer.
// 3. hsm_reduce: each pyramid level is the 2×2 min of the one below.
// 4. fs_gbuffer: the eye's visible surface, world position per pixel.
// 5. shade: per pixel, the conservative search region, HSM refinement, and the backprojection of
//    every occluding sample onto the light square.

// Empty shadow-map texel (no surface at that layer): far beyond any scene.
const FAR: f32 = 1.0e30;

override PEEL: bool = true;

@group(1) @binding(0) var prev_layer: texture_2d<f32>;

@fragment
fn fs_peel(in: Varyings) -> @location(0) vec2<f32> {
    let z = in.view_z;
    // Derivatives before any discard: they need the whole quad.
    let slope = max(abs(dpdx(z)), abs(dpdy(z)));
    if PEEL {
        let prev = textureLoad(prev_layer, vec2<i32>(in.clip.xy), 0).x;
        // Strictly behind the previous layer: the same fragment interpolates the same z, so it
        // is peeled away; a coplanar twin is lost (the classic method's known limit).
        if !(z > prev) {
            discard;
        }
    }
    return vec2<f32>(z, slope);
}

// ---- pack + pyramid ----

struct Light {
    view_from_world: mat4x4<f32>,
    // shadow-map resolution r, light near plane n, f = 1/tan(fovy/2), light side l
    map: vec4<f32>,
    // layers k, samples per axis floor(sqrt(max_nspp)), bias mode (0 midpoint, 1 slope,
    // 2 hybrid), hsm (0|1)
    cfg: vec4<u32>,
    // gscale, gmax, top pyramid level, unused
    bias: vec4<f32>,
    // word offset of pyramid level L in `pyramid` (16 levels)
    level_offset: array<vec4<u32>, 4>,
};

@group(1) @binding(1) var<uniform> light: Light;
@group(2) @binding(0) var layer0: texture_2d<f32>;
@group(2) @binding(1) var layer1: texture_2d<f32>;
@group(2) @binding(2) var layer2: texture_2d<f32>;
@group(2) @binding(3) var layer3: texture_2d<f32>;
@group(2) @binding(4) var packed_depth: texture_storage_2d<rgba32float, write>;
@group(2) @binding(5) var packed_slope: texture_storage_2d<rgba32float, write>;
@group(1) @binding(2) var<storage, read_write> pyramid: array<f32>;

fn level_offset(l: u32) -> u32 {
    return light.level_offset[l / 4u][l % 4u];
}

fn level_size(l: u32) -> u32 {
    let r = u32(light.map.x);
    return (r + (1u << l) - 1u) >> l;
}

@compute @workgroup_size(8, 8)
fn pack(@builtin(global_invocation_id) id: vec3<u32>) {
    let r = u32(light.map.x);
    if id.x >= r || id.y >= r {
        return;
    }
    let t = vec2<i32>(id.xy);
    let k = light.cfg.x;
    var d = vec4<f32>(FAR);
    var s = vec4<f32>(0.0);
    let l0 = textureLoad(layer0, t, 0);
    d.x = l0.x;
    s.x = l0.y;
    if k > 1u {
        let l1 = textureLoad(layer1, t, 0);
        d.y = l1.x;
        s.y = l1.y;
    }
    if k > 2u {
        let l2 = textureLoad(layer2, t, 0);
        d.z = l2.x;
        s.z = l2.y;
    }
    if k > 3u {
        let l3 = textureLoad(layer3, t, 0);
        d.w = l3.x;
        s.w = l3.y;
    }
    textureStore(packed_depth, t, d);
    textureStore(packed_slope, t, s);
    pyramid[level_offset(0u) + id.y * r + id.x] = d.x;
}

struct Reduce {
    // level written; its size; the size of the level below
    level: u32,
    size: u32,
    src_size: u32,
    pad: u32,
};

@group(2) @binding(6) var<uniform> reduce: Reduce;

@compute @workgroup_size(8, 8)
fn hsm_reduce(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= reduce.size || id.y >= reduce.size {
        return;
    }
    let src = level_offset(reduce.level - 1u);
    var m = FAR;
    for (var dy = 0u; dy < 2u; dy++) {
        for (var dx = 0u; dx < 2u; dx++) {
            let x = id.x * 2u + dx;
            let y = id.y * 2u + dy;
            if x < reduce.src_size && y < reduce.src_size {
                m = min(m, pyramid[src + y * reduce.src_size + x]);
            }
        }
    }
    pyramid[level_offset(reduce.level) + id.y * reduce.size + id.x] = m;
}

// ---- eye G-buffer ----

struct GVaryings {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

@vertex
fn vs_world(v: PositionIn) -> GVaryings {
    var out: GVaryings;
    out.clip = camera.clip_from_world * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    return out;
}

@fragment
fn fs_gbuffer(in: GVaryings) -> @location(0) vec4<f32> {
    return vec4<f32>(in.world, 1.0);
}

// ---- shade ----

@group(2) @binding(7) var gbuffer: texture_2d<f32>;
@group(2) @binding(8) var depth_map: texture_2d<f32>;
@group(2) @binding(9) var slope_map: texture_2d<f32>;
@group(2) @binding(10) var<storage, read_write> visibility: array<f32>;
@group(2) @binding(11) var<storage, read_write> points: array<vec4<f32>>;

// Min depth of the first layer over the texel interval [lo, hi] (continuous texel coordinates),
// from the pyramid level whose texels are at least as wide as the interval: ≤ 2×2 fetches.
fn hsm_min(lo: vec2<f32>, hi: vec2<f32>) -> f32 {
    let top = u32(light.bias.z);
    let w = max(hi.x - lo.x, hi.y - lo.y);
    let lvl = min(u32(max(ceil(log2(max(w, 1.0))), 0.0)), top);
    let size = i32(level_size(lvl));
    let scale = f32(1u << lvl);
    let a = vec2<i32>(floor(lo / scale));
    let b = vec2<i32>(floor(hi / scale));
    var m = FAR;
    for (var y = a.y; y <= min(b.y, a.y + 1); y++) {
        for (var x = a.x; x <= min(b.x, a.x + 1); x++) {
            if x >= 0 && y >= 0 && x < size && y < size {
                m = min(m, pyramid[level_offset(lvl) + u32(y * size + x)]);
            }
        }
    }
    return m;
}

// Bias of layer j at a sample: midpoint to the next captured layer (the last captured layer
// has none and falls back to gmax), slope gscale·max(|ddx|,|ddy|) clamped by gmax, or the
// larger of the two (hybrid).
fn layer_bias(d: vec4<f32>, s: vec4<f32>, j: u32) -> f32 {
    let gscale = light.bias.x;
    let gmax = light.bias.y;
    var mid = gmax;
    if j + 1u < light.cfg.x && d[j + 1u] < FAR * 0.5 {
        mid = 0.5 * (d[j + 1u] - d[j]);
    }
    // bias_max (light.bias.w > 0): §5.2.2's maximum depth bias on the midpoint.
    if light.bias.w > 0.0 {
        mid = min(mid, light.bias.w);
    }
    let slope = min(gscale * s[j], gmax);
    switch light.cfg.z {
        case 0u: {
            return mid;
        }
        case 1u: {
            return slope;
        }
        default: {
            return max(mid, slope);
        }
    }
}

@compute @workgroup_size(8, 8)
fn shade(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let i = id.y * w + id.x;
    visibility[i] = shade_point(textureLoad(gbuffer, vec2<i32>(id.xy), 0));
}

// Visibility in [0, 1] of the light from a G-buffer point, or −1 where it cannot be evaluated
// (no surface, behind the light's near plane, or outside its frustum).
fn shade_point(g: vec4<f32>) -> f32 {
    if g.w == 0.0 {
        return -1.0;
    }
    let r = light.map.x;
    let n = light.map.y;
    let f = light.map.z;
    let l = light.map.w;
    let pv = light.view_from_world * vec4<f32>(g.xyz, 1.0);
    // Receiver: lateral position in the light's frame and distance to the light plane.
    let p = pv.xy;
    let z = -pv.z;
    if z <= n {
        return -1.0;
    }
    let ndc = p * f / z;
    if abs(ndc.x) > 1.0 || abs(ndc.y) > 1.0 {
        return -1.0;
    }
    let c = vec2<f32>((ndc.x * 0.5 + 0.5) * r, (0.5 - ndc.y * 0.5) * r);
    // kr(z_min) = r·l·(n/w)·(1/z_min − 1/z) texels, with n/w = f/2: the light square seen from
    // the receiver, cut at depth z_min and projected onto the near plane.
    let kscale = r * l * f * 0.5;
    // §5.3.2: the initial region is kr(n), from the light's near plane; search_start =
    // global_min (cfg.w bit 1) starts from the pyramid's top instead, lit when it is behind z.
    var zmin = n;
    if (light.cfg.w & 2u) != 0u {
        zmin = pyramid[level_offset(u32(light.bias.z))];
        if zmin >= z {
            return 1.0;
        }
    }
    if (light.cfg.w & 1u) != 0u {
        // HSM: the min over a smaller region raises z_min, which shrinks the region (twice).
        for (var it = 0; it < 2; it++) {
            let kr = min(kscale * (1.0 / zmin - 1.0 / z), 2.0 * r);
            zmin = max(zmin, hsm_min(c - 0.5 * kr, c + 0.5 * kr));
            if zmin >= z {
                return 1.0;
            }
        }
    }
    let kr = min(kscale * (1.0 / zmin - 1.0 / z), 2.0 * r);
    let x0 = vec2<i32>(floor(c - 0.5 * kr));
    let x1 = vec2<i32>(ceil(c + 0.5 * kr));
    let count = max(x1 - x0, vec2<i32>(1));
    // Adaptive stride: at most m×m samples; each stands for an s×s block of texels.
    let m = i32(light.cfg.y);
    let s = max(1, (max(count.x, count.y) + m - 1) / m);
    let nb = (count + vec2<i32>(s - 1)) / s;
    let ri = i32(r);
    let k = light.cfg.x;
    let texel_ndc = 2.0 / r;
    var occluded = 0.0;
    for (var a = 0; a < nb.y; a++) {
        for (var b = 0; b < nb.x; b++) {
            let blk = x0 + vec2<i32>(b, a) * s;
            let t = blk + vec2<i32>(s / 2);
            if t.x < 0 || t.y < 0 || t.x >= ri || t.y >= ri {
                continue;
            }
            let d = textureLoad(depth_map, t, 0);
            if d.x >= z {
                // The nearest layer is already behind the receiver: nothing here occludes.
                continue;
            }
            var s4 = vec4<f32>(0.0);
            if light.cfg.z != 0u {
                s4 = textureLoad(slope_map, t, 0);
            }
            // From the deepest layer: the occluder nearest the receiver has the largest
            // backprojection, which fills the gaps between first-layer micro-patches.
            for (var jj = 0; jj < i32(k); jj++) {
                let j = k - 1u - u32(jj);
                let zj = d[j];
                if zj >= FAR * 0.5 {
                    continue;
                }
                if zj + layer_bias(d, s4, j) < z {
                    // The block's micro-patch at depth zj, in the light's frame.
                    let nlo = vec2<f32>(f32(blk.x) * texel_ndc - 1.0, 1.0 - f32(blk.y + s) * texel_ndc);
                    let nhi = vec2<f32>(f32(blk.x + s) * texel_ndc - 1.0, 1.0 - f32(blk.y) * texel_ndc);
                    let wlo = nlo * zj / f;
                    let whi = nhi * zj / f;
                    // Backprojection from the receiver onto the light plane (depth 0), in units
                    // of the light's side, clamped to the square [−0.5, 0.5]².
                    let g = z / (z - zj);
                    let llo = clamp((p + (wlo - p) * g) / l, vec2<f32>(-0.5), vec2<f32>(0.5));
                    let lhi = clamp((p + (whi - p) * g) / l, vec2<f32>(-0.5), vec2<f32>(0.5));
                    let e = max(lhi - llo, vec2<f32>(0.0));
                    occluded += e.x * e.y;
                    break;
                }
            }
        }
    }
    return clamp(1.0 - occluded, 0.0, 1.0);
}

// Untimed: the G-buffer points, for the ray-traced reference to start from the same surfaces.
@compute @workgroup_size(8, 8)
fn export_points(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    points[id.y * w + id.x] = textureLoad(gbuffer, vec2<i32>(id.xy), 0);
}
