// Weighted blended order-independent transparency (McGuire & Bavoil 2013). One geometry pass,
// no sorting: target 0 sums premultiplied colour and alpha, each weighted by w(z, α) (the
// paper's eq. 7, of view depth); target 1 multiplies the revealage Π(1 − α). The resolve
// divides the weighted sum by the summed weighted alpha and scales by 1 − revealage. Exact when
// a pixel has one layer, or all its layers share one colour; otherwise approximate.

// Set per sample by the sample-rate form of this module (`gpu_util::per_sample_source`).
var<private> SAMPLE: i32 = 0;

struct WbOut {
    @location(0) accum: vec4<f32>,
    @location(1) reveal: f32,
};

fn weight(view_z: f32, alpha: f32) -> f32 {
    let z = abs(view_z);
    return alpha * clamp(10.0 / (1e-5 + pow(z / 5.0, 2.0) + pow(z / 200.0, 6.0)), 1e-2, 3e3);
}

@fragment
fn fs_accum(in: Varyings) -> WbOut {
    let a = in.color.a;
    let w = weight(in.view_z, a);
    var o: WbOut;
    o.accum = vec4<f32>(in.color.rgb * a, a) * w;
    o.reveal = a;
    return o;
}

@group(0) @binding(1) var accum_tex: texture_2d<f32>;
@group(0) @binding(2) var reveal_tex: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> out_image: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let acc = textureLoad(accum_tex, vec2<i32>(id.xy), 0);
    let r = textureLoad(reveal_tex, vec2<i32>(id.xy), 0).r;
    let a = 1.0 - r;
    let c = acc.rgb / max(acc.a, 1e-5);
    out_image[id.y * w + id.x] = vec4<f32>(c * a, a);
}

// ---- MSAA (aa = msaa*): the sums and revealage are blended per sample (a fragment reaches the
// samples it covers; with aa_capture = sample it is shaded at each). The resolve composites each
// sample as above and averages: the multisampled image of the same per-sample definition. ----

@group(0) @binding(4) var accum_ms: texture_multisampled_2d<f32>;
@group(0) @binding(5) var reveal_ms: texture_multisampled_2d<f32>;

@compute @workgroup_size(8, 8)
fn resolve_ms(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let n = textureNumSamples(accum_ms);
    var sum = vec4<f32>(0.0);
    for (var s = 0u; s < n; s = s + 1u) {
        let acc = textureLoad(accum_ms, vec2<i32>(id.xy), i32(s));
        let a = 1.0 - textureLoad(reveal_ms, vec2<i32>(id.xy), i32(s)).r;
        sum = sum + vec4<f32>(acc.rgb / max(acc.a, 1e-5) * a, a);
    }
    out_image[id.y * w + id.x] = sum / f32(n);
}
