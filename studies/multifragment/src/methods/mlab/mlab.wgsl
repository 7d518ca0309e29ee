// Multi-layer alpha blending (Salvi & Vaidyanathan 2014), the rule of the CPU twin
// `oit::mlab::blend_layers`: K blend layers (depth, premultiplied colour, transmittance) sorted
// nearest first; a fragment (z, c, α) becomes the layer (z, α·c, 1 − α), inserted behind every
// layer of smaller or equal depth; with K + 1 layers the two farthest merge at the nearer's depth
// (TAIL_MODE 0), or the farthest falls out (1: dropped, 2: blended into the tail), which keeps
// the K nearest (`oit::tail_blend` with keep = nearest).

override K: u32 = 4u;
override TAIL_MODE: u32 = 0u;
// Largest K (the layers axis' maximum); arrays hold one layer more during an insertion.
const KMAX: u32 = 16u;

struct Blend {
    z: array<f32, 17>,
    rgb: array<vec3<f32>, 17>,
    t: array<f32, 17>,
    n: u32,
};

// What an insertion did: the first layer index it changed, and the layer that fell out.
struct Inserted {
    first: u32,
    fell: bool,
    rgb: vec3<f32>,
    a: f32,
};

fn mlab_insert(s: ptr<function, Blend>, z: f32, c: vec4<f32>) -> Inserted {
    let a = c.a;
    var j = (*s).n;
    loop {
        if j == 0u || (*s).z[j - 1u] <= z {
            break;
        }
        (*s).z[j] = (*s).z[j - 1u];
        (*s).rgb[j] = (*s).rgb[j - 1u];
        (*s).t[j] = (*s).t[j - 1u];
        j = j - 1u;
    }
    (*s).z[j] = z;
    (*s).rgb[j] = vec3<f32>(a * c.r, a * c.g, a * c.b);
    (*s).t[j] = 1.0 - a;
    (*s).n = (*s).n + 1u;
    var r = Inserted(j, false, vec3<f32>(0.0), 0.0);
    if (*s).n > K {
        let far = K;
        if TAIL_MODE == 0u {
            (*s).rgb[far - 1u] = (*s).rgb[far - 1u] + (*s).t[far - 1u] * (*s).rgb[far];
            (*s).t[far - 1u] = (*s).t[far - 1u] * (*s).t[far];
            r.first = min(j, far - 1u);
        } else {
            r.fell = true;
            r.rgb = (*s).rgb[far];
            r.a = 1.0 - (*s).t[far];
        }
        (*s).n = K;
    }
    return r;
}

// The layers composited nearest first: (premultiplied rgb, transmittance).
fn mlab_resolve(s: ptr<function, Blend>) -> vec4<f32> {
    var c = vec3<f32>(0.0);
    var t = 1.0;
    for (var i = 0u; i < (*s).n; i = i + 1u) {
        c = c + t * (*s).rgb[i];
        t = t * (*s).t[i];
    }
    return vec4<f32>(c, t);
}
