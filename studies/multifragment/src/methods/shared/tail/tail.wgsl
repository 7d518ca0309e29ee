// The out-of-order tail of a bounded capture (`tail = blend`; CPU twin `oit::tail`): fragments
// that do not fit are blended, in any order, into three sums a blend unit keeps exactly up to f32
// rounding: (Σ α·c, Σ α) additively, Π(1 − α) multiplicatively and the count n additively. The
// resolve composites the tail behind the kept fragments' transmittance T_kept:
//   C = C_kept + T_kept·o·Σαc/Σα,   A = 1 − T_kept·(1 − o),
// with o the tail's opacity: exact, 1 − Π(1 − α) (`tail = blend`), or Bavoil & Myers' mean-alpha
// estimate 1 − (1 − Σα/n)ⁿ (hybrid transparency).

struct TailOut {
    @location(0) sums: vec4<f32>,
    @location(1) trans: vec4<f32>,
    @location(2) count: vec4<f32>,
};

// Nothing to the tail (additive 0, multiplicative × (1 − 0)).
fn tail_none() -> TailOut {
    return TailOut(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
}

// One fragment of premultiplied colour `rgb` (α·c) and opacity `a` to the tail.
fn tail_of(rgb: vec3<f32>, a: f32) -> TailOut {
    return TailOut(vec4<f32>(rgb, a), vec4<f32>(a), vec4<f32>(1.0));
}

// The kept fragments' composite (premultiplied `rgb`, transmittance `t_kept`) with the tail
// (`sums` = (Σαc, Σα), `trans` = Π(1 − α), `count` = n) behind it.
fn tail_behind(rgb: vec3<f32>, t_kept: f32, sums: vec4<f32>, trans: f32, count: f32, mean_alpha: bool) -> vec4<f32> {
    var o = 1.0 - trans;
    if mean_alpha {
        o = 0.0;
        if count > 0.0 {
            let base = 1.0 - sums.w / count;
            // pow(0, n) is undefined in WGSL: a tail of opaque fragments is opaque.
            o = 1.0 - select(0.0, pow(base, count), base > 0.0);
        }
    }
    var tail = vec3<f32>(0.0);
    if sums.w > 0.0 {
        tail = sums.rgb * (o / sums.w);
    }
    return vec4<f32>(rgb + t_kept * tail, 1.0 - t_kept * (1.0 - o));
}
