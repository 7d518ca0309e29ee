// The GPU shading paths of the deferred study (prepended: light.wgsl; appended:
// sun_shadow.wgsl). Group 0: the shading uniform, the lights, the depth/normal targets and the
// sun shadow map with its per-texel neighbourhood min/max; group 1: albedo, specular, material id; group 2:
// per-path buffers. With a 2×MSAA G-buffer (msaa.rs) gpu_paths::paths_source makes the five
// G-buffer textures multisampled and SAMPLES 2 (textureLoad's last argument is then the sample).

@group(0) @binding(0) var<uniform> sh: Shade;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var t_depth: texture_depth_2d;
@group(0) @binding(3) var t_normal: texture_2d<f32>;
@group(0) @binding(4) var t_shadow: texture_depth_2d;
@group(0) @binding(5) var<storage, read> shadow_range: array<vec2<f32>>;
@group(1) @binding(0) var t_albedo: texture_2d<f32>;
@group(1) @binding(1) var t_spec: texture_2d<f32>;
@group(1) @binding(2) var t_mat: texture_2d<u32>;

// Shader permutation: which features this pipeline contains (the uber-shader has all).
override F_SKY: bool = true;
override F_GEOM: bool = true;
override F_SUN: bool = true;
override F_SPEC: bool = true;
override F_LIGHTS: bool = true;
// Sun shadow (when the uniform turns it on): the 8-tap filter, else one compare (exact in tiles
// without the fade bit).
override F_SHADOW_FADE: bool = true;
// Light pre-pass: write the light buffer (Σ diffuse RGB, Σ lum·spec in A, times LB_SCALE).
override LIGHT_BUFFER: bool = false;
override LB_SCALE: f32 = 1.0;
// Samples per G-buffer pixel (a constant of the source: 2 in the MSAA variant).
const SAMPLES: u32 = 1u;
// MSAA: shade every sample and average (naive, the uber-shader and the edge class); without it
// the pixel is its sample 0 (exact where the samples are equal).
override F_EDGE: bool = true;

fn light_buffer_value(g: GPixel, acc: Acc) -> vec4<f32> {
    if g.sky {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(acc.diffuse, acc.spec_lum) * LB_SCALE;
}

fn load_pixel(p: vec2<u32>) -> GPixel {
    return load_sample(p, 0u);
}

// Sample s of pixel p (s = 0 without MSAA: the third argument is then the mip level).
fn load_sample(p: vec2<u32>, s: u32) -> GPixel {
    var g: GPixel;
    g.mat = textureLoad(t_mat, p, s).x;
    let d = textureLoad(t_depth, p, s);
    // Sky = nothing rasterised: the clear depth (the material id marks the same pixels; the
    // light pre-pass has only depth and normals).
    g.sky = d == sh.misc.y;
    g.pos = view_pos(sh, p, d);
    let n = textureLoad(t_normal, p, s);
    g.n = n.xyz;
    g.smoothness = n.w;
    g.albedo = textureLoad(t_albedo, p, s).xyz;
    g.spec = textureLoad(t_spec, p, s).xyz;
    return g;
}

// MSAA edge (as shading::msaa::samples_differ): some sample differs from sample 0 in what the
// shading reads.
fn samples_differ(p: vec2<u32>) -> bool {
    for (var s = 1u; s < SAMPLES; s++) {
        if textureLoad(t_depth, p, 0u) != textureLoad(t_depth, p, s)
            || any(textureLoad(t_normal, p, 0u) != textureLoad(t_normal, p, s))
            || any(textureLoad(t_albedo, p, 0u).xyz != textureLoad(t_albedo, p, s).xyz)
            || any(textureLoad(t_spec, p, 0u).xyz != textureLoad(t_spec, p, s).xyz)
            || textureLoad(t_mat, p, 0u).x != textureLoad(t_mat, p, s).x {
            return true;
        }
    }
    return false;
}

// The class bits of pixel p: every sample's, and EDGE (32) where they differ.
fn pixel_bits_ms(p: vec2<u32>) -> u32 {
    var b = pixel_bits(load_sample(p, 0u));
    for (var s = 1u; s < SAMPLES; s++) {
        b |= pixel_bits(load_sample(p, s));
    }
    if SAMPLES > 1u && samples_differ(p) {
        b |= 32u;
    }
    return b;
}

// The pixel's colour: the average over its samples (MSAA with F_EDGE), else its sample 0.
fn shade_pixel(p: vec2<u32>) -> vec4<f32> {
    if SAMPLES > 1u && F_EDGE {
        var c = vec4<f32>(0.0);
        for (var s = 0u; s < SAMPLES; s++) {
            c += shade_all(load_sample(p, s));
        }
        return c / f32(SAMPLES);
    }
    return shade_all(load_pixel(p));
}

// Feature bits of one pixel (SKY 1, GEOM 2, SUN 4, SPEC 8, FADE 16), as shading::pixel_class.
fn pixel_bits(g: GPixel) -> u32 {
    if g.sky {
        return 1u;
    }
    var b = 2u;
    if sh.sun_dir.w > 0.5 && dot(g.n, sh.sun_dir.xyz) > 0.0 {
        b |= 4u;
        if shadow_on() && shadow_fade(shadow_coord(g.pos)) {
            b |= 16u;
        }
    }
    if any(g.spec > vec3<f32>(0.0)) {
        b |= 8u;
    }
    return b;
}

// Every light at this pixel, with only the features of this permutation.
fn shade_all(g: GPixel) -> vec4<f32> {
    if g.sky && LIGHT_BUFFER {
        return vec4<f32>(0.0);
    }
    if g.sky {
        if F_SKY {
            return vec4<f32>(sh.sky.xyz, 1.0);
        }
        return vec4<f32>(0.0);
    }
    if !F_GEOM {
        return vec4<f32>(0.0);
    }
    var acc = acc_zero();
    let v = normalize(-g.pos);
    let p = spec_power(g.smoothness);
    let norm = (p + 8.0) / 8.0;
    if F_LIGHTS {
        let n = sh.counts.x;
        for (var i = 0u; i < n; i++) {
            acc_light(&acc, lights[i], g, v, p, norm, F_SPEC);
        }
    }
    if F_SUN {
        var vis = 1.0;
        if shadow_on() && sh.sun_dir.w > 0.5 && dot(g.n, sh.sun_dir.xyz) > 0.0 {
            let c = shadow_coord(g.pos);
            if F_SHADOW_FADE {
                vis = shadow_filter8(c);
            } else {
                vis = shadow_hard(c);
            }
        }
        acc_sun_vis(&acc, sh, g, v, p, norm, F_SPEC, vis);
    }
    if LIGHT_BUFFER {
        return light_buffer_value(g, acc);
    }
    return compose(sh, g, acc);
}

struct FsOut {
    @builtin(position) clip: vec4<f32>,
};

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> FsOut {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var o: FsOut;
    o.clip = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    return o;
}

@fragment
fn fs_shade(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return shade_pixel(vec2<u32>(frag.xy));
}

struct SplitOut {
    @location(0) diffuse: vec4<f32>,
    @location(1) spec: vec4<f32>,
};

// Light pre-pass into two targets (RG11B10 diffuse has no alpha: the specular term goes to R16F).
@fragment
fn fs_shade_split(@builtin(position) frag: vec4<f32>) -> SplitOut {
    let v = shade_all(load_pixel(vec2<u32>(frag.xy)));
    return SplitOut(vec4<f32>(v.xyz, 1.0), vec4<f32>(v.w, 0.0, 0.0, 1.0));
}

// ---- classified (Split/Second): 4×4 tiles, ids, per-id lists, one draw per id ----

override CLASS_ID: u32 = 0u;
// Classification ids (shading::class::IDS): every OR of the 6 bits; CLASS_ID = CLASS_IDS is
// the uber-shader drawing every tile.
const CLASS_IDS: u32 = 64u;

@group(2) @binding(0) var<storage, read_write> tile_class: array<u32>;
@group(2) @binding(1) var<storage, read_write> class_count: array<atomic<u32>, CLASS_IDS>;
@group(2) @binding(2) var<storage, read_write> class_offset: array<u32, CLASS_IDS>;
@group(2) @binding(3) var<storage, read_write> class_cursor: array<atomic<u32>, CLASS_IDS>;
@group(2) @binding(4) var<storage, read_write> draw_args: array<u32>;
@group(2) @binding(5) var<storage, read_write> tile_list: array<u32>;

@group(2) @binding(10) var<storage, read> tile_list_ro: array<u32>;
@group(2) @binding(11) var<storage, read> class_offset_ro: array<u32, CLASS_IDS>;

fn class_tiles() -> vec2<u32> {
    return (vec2<u32>(sh.viewport.xy) + 3u) / 4u;
}

@compute @workgroup_size(8, 8)
fn cs_classify(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nt = class_tiles();
    if gid.x >= nt.x || gid.y >= nt.y {
        return;
    }
    let size = vec2<u32>(sh.viewport.xy);
    var bits = 0u;
    for (var y = 0u; y < 4u; y++) {
        for (var x = 0u; x < 4u; x++) {
            let p = gid.xy * 4u + vec2<u32>(x, y);
            if p.x < size.x && p.y < size.y {
                bits |= pixel_bits_ms(p);
            }
        }
    }
    let t = gid.y * nt.x + gid.x;
    tile_class[t] = bits;
    atomicAdd(&class_count[bits], 1u);
}

@compute @workgroup_size(1)
fn cs_offsets() {
    var o = 0u;
    for (var id = 0u; id < CLASS_IDS; id++) {
        let c = atomicLoad(&class_count[id]);
        class_offset[id] = o;
        draw_args[id * 4u + 0u] = 6u;
        draw_args[id * 4u + 1u] = c;
        draw_args[id * 4u + 2u] = 0u;
        draw_args[id * 4u + 3u] = 0u;
        o += c;
    }
}

@compute @workgroup_size(64)
fn cs_scatter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nt = class_tiles();
    let t = gid.x;
    if t >= nt.x * nt.y {
        return;
    }
    let id = tile_class[t];
    let k = atomicAdd(&class_cursor[id], 1u);
    tile_list[class_offset[id] + k] = t;
}

@vertex
fn vs_tile(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> FsOut {
    let nt = class_tiles();
    // CLASS_ID CLASS_IDS: the uber-shader drawing every tile in one draw (the list from 0).
    var t = tile_list_ro[ii];
    if CLASS_ID < CLASS_IDS {
        t = tile_list_ro[class_offset_ro[min(CLASS_ID, CLASS_IDS - 1u)] + ii];
    }
    let corner = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    );
    let px = (vec2<f32>(f32(t % nt.x), f32(t / nt.x)) + corner[vi]) * 4.0;
    var o: FsOut;
    o.clip = vec4<f32>(px.x * sh.viewport.z * 2.0 - 1.0, 1.0 - px.y * sh.viewport.w * 2.0, 0.0, 1.0);
    return o;
}

// ---- GPU compute tiled: per-tile depth bounds, light culling, shading (BF3 on a GPU) ----
// Lights are culled in batches of BATCH (the shared list's size), so no list can overflow at
// any light count: each batch is culled into the tile list (and, two-level, from there into
// the sub-tile lists), then every thread adds the batch's kept lights to its pixels' sums.

override TILE: u32 = 16u;
override WG: u32 = 16u;
override PPT: u32 = 1u;
override STORE_LISTS: bool = false;
override LIST_CAP: u32 = 1u;
const BATCH: u32 = 256u;

@group(2) @binding(0) var out_tex: texture_storage_2d<rgba32float, write>;
@group(2) @binding(1) var<storage, read_write> tile_counts: array<u32>;
@group(2) @binding(2) var<storage, read_write> tile_lists: array<u32>;

var<workgroup> zmin_u: atomic<u32>;
var<workgroup> zmax_u: atomic<u32>;
var<workgroup> n_lights: atomic<u32>;
var<workgroup> kept_total: u32;
var<workgroup> tile_lights: array<u32, BATCH>;
var<workgroup> planes: array<vec4<f32>, 6>;
var<workgroup> sub_zmin: array<atomic<u32>, 8>;
var<workgroup> sub_zmax: array<atomic<u32>, 8>;
var<workgroup> sub_n: array<atomic<u32>, 8>;
var<workgroup> sub_planes: array<array<vec4<f32>, 6>, 8>;
var<workgroup> sub_lights: array<u32, 2048>;

fn tile_init(li: u32) {
    if li == 0u {
        atomicStore(&zmin_u, 0x7f7fffffu);
        atomicStore(&zmax_u, 0u);
        kept_total = 0u;
    }
    if li < 8u {
        atomicStore(&sub_zmin[li], 0x7f7fffffu);
        atomicStore(&sub_zmax[li], 0u);
    }
}

// Culls lights [base, end) against the tile frustum into tile_lights; returns how many.
fn cull_batch(li: u32, t: u32, base: u32, end: u32, all_sky: bool) -> u32 {
    workgroupBarrier();
    if li == 0u {
        atomicStore(&n_lights, 0u);
    }
    if li < 8u {
        atomicStore(&sub_n[li], 0u);
    }
    workgroupBarrier();
    for (var i = base + li; i < end; i += WG * WG) {
        if !all_sky && !sphere_outside(planes, lights[i].cull.xyz, lights[i].cull.w) {
            tile_lights[atomicAdd(&n_lights, 1u)] = i;
        }
    }
    workgroupBarrier();
    let m = atomicLoad(&n_lights);
    if STORE_LISTS {
        for (var k = li; k < m; k += WG * WG) {
            let o = kept_total + k;
            if o < LIST_CAP {
                tile_lists[t * LIST_CAP + o] = tile_lights[k];
            }
        }
    }
    return m;
}

fn end_batch(li: u32, m: u32) {
    workgroupBarrier();
    if li == 0u {
        kept_total += m;
    }
}

fn add_lights(acc: ptr<function, Acc>, g: GPixel, base: u32, m: u32, sub: bool) {
    let v = normalize(-g.pos);
    let p = spec_power(g.smoothness);
    let norm = (p + 8.0) / 8.0;
    for (var k = 0u; k < m; k++) {
        var li: u32;
        if sub {
            li = sub_lights[base + k];
        } else {
            li = tile_lights[k];
        }
        acc_light(acc, lights[li], g, v, p, norm, true);
    }
}

fn finish_pixel(g: GPixel, acc_in: Acc) -> vec4<f32> {
    var acc = acc_in;
    if !g.sky {
        let v = normalize(-g.pos);
        let p = spec_power(g.smoothness);
        acc_sun(&acc, sh, g, v, p, (p + 8.0) / 8.0, true);
    }
    if LIGHT_BUFFER {
        return light_buffer_value(g, acc);
    }
    return compose(sh, g, acc);
}

fn z_bits(p: vec2<u32>) -> u32 {
    // View distance > 0: its f32 bits order like the value.
    return bitcast<u32>(-view_pos(sh, p, textureLoad(t_depth, p, 0)).z);
}

fn in_screen(p: vec2<u32>) -> bool {
    return p.x < u32(sh.viewport.x) && p.y < u32(sh.viewport.y);
}

@compute @workgroup_size(WG, WG)
fn cs_tiled(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(num_workgroups) nwg: vec3<u32>) {
    tile_init(li);
    workgroupBarrier();
    let size = vec2<u32>(sh.viewport.xy);
    let origin = wid.xy * TILE;
    let t = wid.y * nwg.x + wid.x;
    let npx = PPT * PPT;
    for (var k = 0u; k < npx; k++) {
        let p = origin + lid.xy * PPT + vec2<u32>(k % PPT, k / PPT);
        if in_screen(p) && textureLoad(t_depth, p, 0) != sh.misc.y {
            let z = z_bits(p);
            atomicMin(&zmin_u, z);
            atomicMax(&zmax_u, z);
        }
    }
    workgroupBarrier();
    if li == 0u {
        let hi = min(origin + vec2<u32>(TILE), size);
        planes = tile_planes(sh, f32(origin.x), f32(origin.y), f32(hi.x), f32(hi.y), bitcast<f32>(atomicLoad(&zmin_u)), bitcast<f32>(atomicLoad(&zmax_u)));
    }
    let all_sky = atomicLoad(&zmin_u) > atomicLoad(&zmax_u);
    var acc: array<Acc, 16>;
    for (var k = 0u; k < npx; k++) {
        acc[k] = acc_zero();
    }
    let n = sh.counts.x;
    for (var base = 0u; base < n; base += BATCH) {
        let m = cull_batch(li, t, base, min(base + BATCH, n), all_sky);
        for (var k = 0u; k < npx; k++) {
            let p = origin + lid.xy * PPT + vec2<u32>(k % PPT, k / PPT);
            if in_screen(p) {
                let g = load_pixel(p);
                if !g.sky {
                    var a = acc[k];
                    add_lights(&a, g, 0u, m, false);
                    acc[k] = a;
                }
            }
        }
        end_batch(li, m);
    }
    if li == 0u {
        tile_counts[t] = kept_total;
    }
    for (var k = 0u; k < npx; k++) {
        let p = origin + lid.xy * PPT + vec2<u32>(k % PPT, k / PPT);
        if in_screen(p) {
            textureStore(out_tex, p, finish_pixel(load_pixel(p), acc[k]));
        }
    }
}

// Two levels (BF3): a 64×64 tile culled, then each 32×16 sub-tile culled from the tile's list.
// One thread per 4×4 quad (16×16 threads); sub-tile s = (quad.y / 4) * 2 + quad.x / 8.
@compute @workgroup_size(16, 16)
fn cs_tiled2(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(num_workgroups) nwg: vec3<u32>) {
    tile_init(li);
    workgroupBarrier();
    let size = vec2<u32>(sh.viewport.xy);
    let origin = wid.xy * 64u;
    let t = wid.y * nwg.x + wid.x;
    let s = (lid.y / 4u) * 2u + lid.x / 8u;
    for (var k = 0u; k < 16u; k++) {
        let p = origin + lid.xy * 4u + vec2<u32>(k % 4u, k / 4u);
        if in_screen(p) && textureLoad(t_depth, p, 0) != sh.misc.y {
            let z = z_bits(p);
            atomicMin(&zmin_u, z);
            atomicMax(&zmax_u, z);
            atomicMin(&sub_zmin[s], z);
            atomicMax(&sub_zmax[s], z);
        }
    }
    workgroupBarrier();
    if li == 0u {
        let hi = min(origin + vec2<u32>(64u), size);
        planes = tile_planes(sh, f32(origin.x), f32(origin.y), f32(hi.x), f32(hi.y), bitcast<f32>(atomicLoad(&zmin_u)), bitcast<f32>(atomicLoad(&zmax_u)));
    }
    if li < 8u {
        let so = origin + vec2<u32>((li % 2u) * 32u, (li / 2u) * 16u);
        let hi = min(so + vec2<u32>(32u, 16u), size);
        sub_planes[li] = tile_planes(sh, f32(so.x), f32(so.y), f32(hi.x), f32(hi.y), bitcast<f32>(atomicLoad(&sub_zmin[li])), bitcast<f32>(atomicLoad(&sub_zmax[li])));
    }
    let all_sky = atomicLoad(&zmin_u) > atomicLoad(&zmax_u);
    let sub_sky = atomicLoad(&sub_zmin[s]) > atomicLoad(&sub_zmax[s]);
    let j = (lid.x % 8u) + (lid.y % 4u) * 8u;
    var acc: array<Acc, 16>;
    for (var k = 0u; k < 16u; k++) {
        acc[k] = acc_zero();
    }
    let n = sh.counts.x;
    for (var base = 0u; base < n; base += BATCH) {
        let m = cull_batch(li, t, base, min(base + BATCH, n), all_sky);
        for (var k = j; k < m; k += 32u) {
            let i = tile_lights[k];
            if !sub_sky && !sphere_outside(sub_planes[s], lights[i].cull.xyz, lights[i].cull.w) {
                sub_lights[s * BATCH + atomicAdd(&sub_n[s], 1u)] = i;
            }
        }
        workgroupBarrier();
        let m2 = atomicLoad(&sub_n[s]);
        for (var k = 0u; k < 16u; k++) {
            let p = origin + lid.xy * 4u + vec2<u32>(k % 4u, k / 4u);
            if in_screen(p) {
                let g = load_pixel(p);
                if !g.sky {
                    var a = acc[k];
                    add_lights(&a, g, s * BATCH, m2, true);
                    acc[k] = a;
                }
            }
        }
        end_batch(li, m);
    }
    if li == 0u {
        tile_counts[t] = kept_total;
    }
    for (var k = 0u; k < 16u; k++) {
        let p = origin + lid.xy * 4u + vec2<u32>(k % 4u, k / 4u);
        if in_screen(p) {
            textureStore(out_tex, p, finish_pixel(load_pixel(p), acc[k]));
        }
    }
}

// ---- light volumes: one instanced cube per light, additive, back faces only ----

struct VolOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) light: u32,
};

const CUBE: array<u32, 36> = array<u32, 36>(
    0u, 4u, 6u, 0u, 6u, 2u, 1u, 3u, 7u, 1u, 7u, 5u, 0u, 1u, 5u, 0u, 5u, 4u,
    2u, 6u, 7u, 2u, 7u, 3u, 0u, 2u, 3u, 0u, 3u, 1u, 4u, 5u, 7u, 4u, 7u, 6u,
);

@vertex
fn vs_volume(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VolOut {
    let l = lights[ii];
    let c = CUBE[vi];
    let corner = vec3<f32>(f32(c & 1u), f32((c >> 1u) & 1u), f32((c >> 2u) & 1u)) * 2.0 - 1.0;
    var o: VolOut;
    o.light = ii;
    if l.cull.w < 0.0 {
        o.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0); // outside the clip volume: nothing drawn
        return o;
    }
    let p = l.cull.xyz + corner * l.cull.w;
    o.clip = sh.clip_from_view * vec4<f32>(p, 1.0);
    return o;
}

@fragment
fn fs_volume(v: VolOut) -> @location(0) vec4<f32> {
    let g = load_pixel(vec2<u32>(v.clip.xy));
    if g.sky {
        discard;
    }
    var acc = acc_zero();
    let vv = normalize(-g.pos);
    let p = spec_power(g.smoothness);
    acc_light(&acc, lights[v.light], g, vv, p, (p + 8.0) / 8.0, true);
    return vec4<f32>(g.albedo * acc.diffuse + g.spec * acc.specular, 0.0);
}
