// Double-f32 arithmetic: a value hi + lo (vec2: x = hi, y = lo), about 48 bits. Error-free
// transformations (Knuth's TwoSum, Dekker's TwoProd) need correctly rounded f32 adds and
// multiplies, kept as written. Two things stand in the way, and are dealt with here:
// - Shader compilers simplify float algebra that SPIR-V does not mark exact (naga cannot mark
//   it): Mesa rewrites (a + b) − a to b, which zeroes TwoSum's error term. Multiplying by
//   `df_one()` — 1.0, but read from a buffer, so the compiler cannot see it — keeps the
//   subtraction (exactly: the product is the value itself). The including shader defines it.
// - `fma` may be computed unfused (Vulkan allows it; lavapipe does), so TwoProd splits by masking
//   (12 + 12 mantissa bits): every partial product is exact, and a driver that contracts a
//   multiply and an add into an fma changes nothing.
// `double_f32_*` tests check both on the adapter they run on.
fn split12(a: f32) -> vec2<f32> {
    let h = bitcast<f32>(bitcast<u32>(a) & 0xfffff000u);
    return vec2<f32>(h, a - h);
}

fn two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = a + b;
    let bb = s * df_one() - a;
    return vec2<f32>(s, (a - (s - bb)) + (b - bb));
}

// TwoSum for |a| ≥ |b|.
fn quick_two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = a + b;
    return vec2<f32>(s, b - (s * df_one() - a));
}

fn two_prod(a: f32, b: f32) -> vec2<f32> {
    let p = a * b;
    let x = split12(a);
    let y = split12(b);
    return vec2<f32>(p, ((x.x * y.x - p) + x.x * y.y + x.y * y.x) + x.y * y.y);
}

fn df_add(x: vec2<f32>, y: vec2<f32>) -> vec2<f32> {
    let s = two_sum(x.x, y.x);
    return quick_two_sum(s.x, s.y + (x.y + y.y));
}

fn df_mul_f(x: vec2<f32>, b: f32) -> vec2<f32> {
    let p = two_prod(x.x, b);
    return quick_two_sum(p.x, x.y * b + p.y);
}

fn df_mul(x: vec2<f32>, y: vec2<f32>) -> vec2<f32> {
    let p = two_prod(x.x, y.x);
    return quick_two_sum(p.x, p.y + (x.x * y.y + x.y * y.x));
}

// x / y by two corrections of the f32 quotient (f32 division itself is only within 2.5 ulp).
// Each quotient goes through `df_one()`: NVIDIA's compiler (H200, driver 580) otherwise folds
// y · (x / y) back to x, the remainder becomes 0 and the result is only f32-accurate (5.8e-8
// relative, 40 of 70 000 grass vertices snapped 1/256 px off: `double_f32_*` tests there).
fn df_div(x: vec2<f32>, y: vec2<f32>) -> vec2<f32> {
    let q1 = (x.x / y.x) * df_one();
    let r1 = df_add(x, -df_mul_f(y, q1));
    let q2 = (r1.x / y.x) * df_one();
    let r2 = df_add(r1, -df_mul_f(y, q2));
    let q3 = (r2.x / y.x) * df_one();
    return df_add(quick_two_sum(q1, q2), vec2<f32>(q3, 0.0));
}

// Row `r` of m · (p, 1).
fn df_clip(m: mat4x4<f32>, r: u32, p: vec3<f32>) -> vec2<f32> {
    var acc = two_prod(m[0][r], p.x);
    acc = df_add(acc, two_prod(m[1][r], p.y));
    acc = df_add(acc, two_prod(m[2][r], p.z));
    return df_add(acc, vec2<f32>(m[3][r], 0.0));
}

// Rounds half away from zero to 1/256 px (the reference's `snap`, f64::round), of a double-f32.
fn df_snap(v: vec2<f32>) -> f32 {
    let neg = v.x < 0.0;
    let t = select(v, -v, neg) * 256.0;
    let f = floor(t.x);
    let up = (t.x - f) + t.y >= 0.5;
    let n = (f + select(0.0, 1.0, up)) / 256.0;
    return select(n, -n, neg);
}

// The snapped screen position of world point `p` in a `vp`-sized viewport, as the f64 reference
// computes it: ((x/w)·½ + ½)·width and (½ − (y/w)·½)·height, each rounded once. In f32 the
// transform and viewport mapping err by ~1e-7 of the coordinate, so a vertex within that of a
// 1/512-px rounding boundary would snap to the other 1/256 step than the reference's and a pixel
// centre within a step of its edges flip (2 of 10 000 grass blades' fragments at 128²).
fn df_screen(m: mat4x4<f32>, p: vec3<f32>, vp: vec2<f32>) -> vec2<f32> {
    let x = df_clip(m, 0u, p);
    let y = df_clip(m, 1u, p);
    let w = df_clip(m, 3u, p);
    let sx = df_div(df_mul_f(df_add(x, w), 0.5 * vp.x), w);
    let sy = df_div(df_mul_f(df_add(w, -y), 0.5 * vp.y), w);
    return vec2<f32>(df_snap(sx), df_snap(sy));
}
