// The reconstruction of moment-based OIT (Münstermann et al. 2018), ported line for line from the
// CPU twin `oit::moment_math` (which follows the paper's supplementary shaders): the fraction of
// a pixel's absorbance in front of a depth, from its normalised, biased moments. Every function
// has the twin's name and operation order, so the f32 twin predicts this code's rounding.
// Arrays are sized for the largest set (m = 4: 5×5 systems); loops run to n = m + 1.

// ---- complex numbers as vec2 (re, im) ----

fn cmul(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

fn cdiv(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    let d = b.x * b.x + b.y * b.y;
    return vec2<f32>((a.x * b.x + a.y * b.y) / d, (a.y * b.x - a.x * b.y) / d);
}

fn conj(a: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(a.x, -a.y);
}

fn crecip(a: vec2<f32>) -> vec2<f32> {
    return cdiv(vec2<f32>(1.0, 0.0), a);
}

fn norm_sq(a: vec2<f32>) -> f32 {
    return a.x * a.x + a.y * a.y;
}

fn csqrt(a: vec2<f32>) -> vec2<f32> {
    let r = sqrt(norm_sq(a));
    let re = sqrt(max((r + a.x) * 0.5, 0.0));
    let im = sqrt(max((r - a.x) * 0.5, 0.0));
    return vec2<f32>(re, select(im, -im, a.y < 0.0));
}

// pow(0, y) is undefined in WGSL: 0 stays 0.
fn pow_pos(x: f32, e: f32) -> f32 {
    if x <= 0.0 {
        return 0.0;
    }
    return pow(x, e);
}

fn ccbrt(a: vec2<f32>) -> vec2<f32> {
    let arg = atan2(a.y, a.x) / 3.0;
    let r = pow_pos(norm_sq(a), 1.0 / 6.0);
    return vec2<f32>(cos(arg) * r, sin(arg) * r);
}

// ---- real roots (power moments) ----

fn quadratic_roots(a: f32, b: f32, c: f32) -> vec2<f32> {
    let h = b * 0.5;
    let s = sqrt(max(h * h - a * c, 0.0));
    if h >= 0.0 {
        return vec2<f32>(-c / (h + s), (-h - s) / a);
    }
    return vec2<f32>((-h + s) / a, c / (-h + s));
}

fn cube_root(x: f32) -> f32 {
    if x < 0.0 {
        return -pow_pos(-x, 1.0 / 3.0);
    }
    return pow_pos(x, 1.0 / 3.0);
}

fn cubic_roots(a: f32, b: f32, c: f32) -> vec3<f32> {
    let third = 1.0 / 3.0;
    let shift = a * third;
    let p = b - a * shift;
    let q = 2.0 * shift * shift * shift - b * shift + c;
    let disc = (q * 0.5) * (q * 0.5) + (p * third) * (p * third) * (p * third);
    if p < 0.0 && disc <= 0.0 {
        let m = 2.0 * sqrt(-p * third);
        let arg = clamp(3.0 * q / (p * m), -1.0, 1.0);
        let theta = acos(arg) * third;
        let k = 2.0 * 3.14159265358979 / 3.0;
        let r0 = m * cos(theta) - shift;
        let r1 = m * cos(theta - k) - shift;
        let r2 = m * cos(theta + k) - shift;
        return vec3<f32>(r2, r1, r0);
    }
    let s = sqrt(max(disc, 0.0));
    let t = cube_root(-q * 0.5 + s) + cube_root(-q * 0.5 - s);
    let r = t - shift;
    return vec3<f32>(r, r, r);
}

fn quartic_roots(b: f32, c: f32, d: f32, e: f32) -> vec4<f32> {
    let y = cubic_roots(-2.0 * c, c * c + b * d - 4.0 * e, d * d + b * b * e - b * c * d).x;
    let bb = b * b;
    let fy = 4.0 * y;
    let bb_fy = bb - fy;
    let z = c - y;
    let zz = z * z;
    let fe = 4.0 * e;
    let zz_fe = zz - fe;
    var g1: f32;
    var g2: f32;
    var h1: f32;
    var h2: f32;
    if y < 0.0 || (zz + fe) * bb_fy > zz_fe * (bb + fy) {
        let s = sqrt(max(bb_fy, 0.0));
        g1 = (b + s) * 0.5;
        g2 = (b - s) * 0.5;
        let t = (b * z - 2.0 * d) / (2.0 * s);
        h1 = z * 0.5 + t;
        h2 = z * 0.5 - t;
    } else {
        let s = sqrt(max(zz_fe, 0.0));
        h1 = (z + s) * 0.5;
        h2 = (z - s) * 0.5;
        let t = (b * z - 2.0 * d) / (2.0 * s);
        g1 = b * 0.5 + t;
        g2 = b * 0.5 - t;
    }
    let r01 = quadratic_roots(1.0, g1, h1);
    let r23 = quadratic_roots(1.0, g2, h2);
    return vec4<f32>(r01, r23);
}

// ---- power moments ----

// Fraction of the absorbance in front of warped depth z0 from the biased, normalised power
// moments b[0..2m] (b₀ = 1 implied), m = COUNT / 2.
fn power_fraction(b: array<f32, 8>, z0: f32, overestimation: f32) -> f32 {
    // max: a trigonometric build folds COUNT into this unused function (see trig_fraction).
    let m = max(COUNT / 2u, 2u);
    let n = m + 1u;
    var mom: array<f32, 9>;
    mom[0] = 1.0;
    for (var k = 1u; k <= 2u * m; k = k + 1u) {
        mom[k] = b[k - 1u];
    }
    // Hankel system H·c = (1, z0, …, z0ᵐ) by LDLᵀ without pivoting (solve_ldlt).
    var l: array<f32, 25>;
    var d: array<f32, 5>;
    for (var i = 0u; i < n; i = i + 1u) {
        for (var j = 0u; j < i; j = j + 1u) {
            var s = mom[i + j];
            for (var k = 0u; k < j; k = k + 1u) {
                s = s - l[i * n + k] * l[j * n + k] * d[k];
            }
            l[i * n + j] = s / d[j];
        }
        var s = mom[2u * i];
        for (var k = 0u; k < i; k = k + 1u) {
            s = s - l[i * n + k] * l[i * n + k] * d[k];
        }
        d[i] = s;
    }
    var x: array<f32, 5>;
    x[0] = 1.0;
    for (var j = 1u; j < n; j = j + 1u) {
        x[j] = x[j - 1u] * z0;
    }
    for (var i = 0u; i < n; i = i + 1u) {
        for (var k = 0u; k < i; k = k + 1u) {
            x[i] = x[i] - l[i * n + k] * x[k];
        }
    }
    for (var i = 0u; i < n; i = i + 1u) {
        x[i] = x[i] / d[i];
    }
    for (var ii = 0u; ii < n; ii = ii + 1u) {
        let i = n - 1u - ii;
        for (var k = i + 1u; k < n; k = k + 1u) {
            x[i] = x[i] - l[k * n + i] * x[k];
        }
    }
    // Support: z0 and the real roots of Σ xⱼ zʲ (real_roots). One difference from the twin:
    // where f32 rounding makes the leading coefficient exactly 0 (e.g. one layer queried at its
    // own depth: the right-hand side then lies in the span of the nearly singular system), one
    // root is at infinity, where its weight in the canonical representation vanishes; the
    // limit is the interpolant over the other nodes, so the degree drops by one instead of
    // dividing by zero (the twin's f32 arithmetic returns NaN there, its f64 arithmetic never
    // meets an exact 0).
    var deg = m;
    if x[m] == 0.0 {
        deg = m - 1u;
    }
    var nodes: array<f32, 5>;
    nodes[0] = z0;
    if deg == 1u {
        nodes[1] = -x[0] / x[1];
    } else if deg == 2u {
        let r = quadratic_roots(x[2], x[1], x[0]);
        nodes[1] = r.x;
        nodes[2] = r.y;
    } else if deg == 3u {
        let r = cubic_roots(x[2] / x[3], x[1] / x[3], x[0] / x[3]);
        nodes[1] = r.x;
        nodes[2] = r.y;
        nodes[3] = r.z;
    } else {
        let r = quartic_roots(x[3] / x[4], x[2] / x[4], x[1] / x[4], x[0] / x[4]);
        nodes[1] = r.x;
        nodes[2] = r.y;
        nodes[3] = r.z;
        nodes[4] = r.w;
    }
    let nn = deg + 1u;
    var dd: array<f32, 5>;
    dd[0] = overestimation;
    for (var i = 1u; i < nn; i = i + 1u) {
        dd[i] = select(0.0, 1.0, nodes[i] < z0);
    }
    // Newton's divided differences, then Horner into monomial coefficients (interpolate).
    for (var level = 1u; level < nn; level = level + 1u) {
        for (var ii = 0u; ii + level < nn; ii = ii + 1u) {
            let i = nn - 1u - ii;
            dd[i] = (dd[i] - dd[i - 1u]) / (nodes[i] - nodes[i - level]);
        }
    }
    var p: array<f32, 5>;
    p[0] = dd[nn - 1u];
    for (var ii = 1u; ii < nn; ii = ii + 1u) {
        let i = nn - 1u - ii;
        for (var jj = 0u; jj + 1u < nn; jj = jj + 1u) {
            let j = nn - 1u - jj;
            p[j] = p[j - 1u] - p[j] * nodes[i];
        }
        p[0] = dd[i] - p[0] * nodes[i];
    }
    var f = 0.0;
    for (var j = 0u; j < nn; j = j + 1u) {
        f = f + p[j] * mom[j];
    }
    return f;
}

// ---- trigonometric moments ----

// A parameter growing monotonically with the angle of the unit-circle point (x, y).
fn circle_parameter(x: f32, y: f32) -> f32 {
    var r = abs(y) - abs(x);
    if x < 0.0 {
        r = 2.0 - r;
    }
    if y < 0.0 {
        return 6.0 - r;
    }
    return r;
}

// The unit-circle point of warped depth z: phase (z + 1)·(π − angle/2).
fn circle_point(z: f32, zone: vec4<f32>) -> vec2<f32> {
    let phase = (z + 1.0) * zone.y;
    return vec2<f32>(cos(phase), sin(phase));
}

fn complex_quadratic(a: vec2<f32>, b0: vec2<f32>, c0: vec2<f32>) -> array<vec2<f32>, 2> {
    let inv = crecip(a);
    let b = cmul(b0, inv) * 0.5;
    let c = cmul(c0, inv);
    let s = csqrt(cmul(b, b) - c);
    let nb = -b;
    return array<vec2<f32>, 2>(nb - s, nb + s);
}

fn complex_cubic(a: vec2<f32>, b0: vec2<f32>, c0: vec2<f32>, d0: vec2<f32>) -> array<vec2<f32>, 3> {
    let inv = crecip(a);
    let third = 1.0 / 3.0;
    let b = cmul(b0, inv) * third;
    let c = cmul(c0, inv) * third;
    let d = cmul(d0, inv);
    let delta00 = c - cmul(b, b);
    let delta01 = d - cmul(c, b);
    let delta11 = cmul(b, d) - cmul(c, c);
    let disc = cmul(delta00, delta11) * 4.0 - cmul(delta01, delta01);
    let dep_d = delta01 - cmul(b, delta00) * 2.0;
    let dep_c = delta00;
    var root = csqrt(-disc);
    if root.x * dep_d.x + root.y * dep_d.y < 0.0 {
        root = -root;
    }
    let first = ccbrt((root - dep_d) * 0.5);
    let h = 0.5 * sqrt(3.0);
    let w1 = vec2<f32>(-0.5, -h);
    let w2 = vec2<f32>(-0.5, h);
    let inv_first = crecip(first);
    let c1 = cmul(w1, first);
    let c2 = cmul(w2, first);
    let i1 = cmul(w2, inv_first);
    let i2 = cmul(w1, inv_first);
    return array<vec2<f32>, 3>(
        first - cmul(dep_c, inv_first) - b,
        c1 - cmul(dep_c, i1) - b,
        c2 - cmul(dep_c, i2) - b,
    );
}

fn complex_quartic(a: vec2<f32>, b0: vec2<f32>, c0: vec2<f32>, d0: vec2<f32>, e0: vec2<f32>) -> array<vec2<f32>, 4> {
    let inv = crecip(a);
    let b = cmul(b0, inv);
    let c = cmul(c0, inv);
    let d = cmul(d0, inv);
    let e = cmul(e0, inv);
    let p = c * -2.0;
    let q = cmul(c, c) + cmul(b, d) - e * 4.0;
    let r = cmul(d, d) + cmul(cmul(b, b), e) - cmul(cmul(b, c), d);
    let cr = complex_cubic(vec2<f32>(1.0, 0.0), p, q, r);
    var y = cr[0];
    if norm_sq(cr[1]) > norm_sq(cr[0]) {
        y = cr[1];
    }
    let s = csqrt(cmul(b, b) - y * 4.0);
    let g1 = (b + s) * 0.5;
    let g2 = (b - s) * 0.5;
    let z = c - y;
    let t = cdiv(cmul(b, z) * 0.5 - d, s);
    let h1 = z * 0.5 + t;
    let h2 = z * 0.5 - t;
    let one = vec2<f32>(1.0, 0.0);
    let r01 = complex_quadratic(one, g1, h1);
    let r23 = complex_quadratic(one, g2, h2);
    return array<vec2<f32>, 4>(r01[0], r01[1], r23[0], r23[1]);
}

// Fraction of the absorbance in front of the unit-circle point z0 from the normalised
// trigonometric moments b[0..m] (scaled by 1 − bias), m = COUNT (trig_fraction).
fn trig_fraction(b: array<vec2<f32>, 4>, z0: vec2<f32>, overestimation: f32, zone: vec4<f32>) -> f32 {
    // min: a power build folds COUNT into this unused function, whose constant indices must
    // stay inside the arrays.
    let m = min(COUNT, 4u);
    let n = m + 1u;
    var mom: array<vec2<f32>, 5>;
    mom[0] = vec2<f32>(1.0, 0.0);
    for (var k = 1u; k < n; k = k + 1u) {
        mom[k] = b[k - 1u];
    }
    // Hermitian Toeplitz system by LDLᴴ (solve_toeplitz): M_ij = b_{i−j}, b_{−j} = conj b_j.
    var l: array<vec2<f32>, 25>;
    var d: array<f32, 5>;
    for (var i = 0u; i < n; i = i + 1u) {
        for (var j = 0u; j < i; j = j + 1u) {
            var s = mom[i - j];
            for (var k = 0u; k < j; k = k + 1u) {
                s = s - cmul(l[i * n + k], conj(l[j * n + k])) * d[k];
            }
            l[i * n + j] = s * (1.0 / d[j]);
        }
        var s = mom[0].x;
        for (var k = 0u; k < i; k = k + 1u) {
            s = s - norm_sq(l[i * n + k]) * d[k];
        }
        d[i] = s;
    }
    var x: array<vec2<f32>, 5>;
    x[0] = vec2<f32>(1.0, 0.0);
    for (var j = 1u; j < n; j = j + 1u) {
        x[j] = cmul(x[j - 1u], z0);
    }
    for (var i = 0u; i < n; i = i + 1u) {
        for (var k = 0u; k < i; k = k + 1u) {
            x[i] = x[i] - cmul(l[i * n + k], x[k]);
        }
    }
    for (var i = 0u; i < n; i = i + 1u) {
        x[i] = x[i] * (1.0 / d[i]);
    }
    for (var ii = 0u; ii < n; ii = ii + 1u) {
        let i = n - 1u - ii;
        for (var k = i + 1u; k < n; k = k + 1u) {
            x[i] = x[i] - cmul(conj(l[k * n + i]), x[k]);
        }
    }
    // Roots of the kernel polynomial Σ conj(xⱼ) zʲ (on the unit circle).
    var kp: array<vec2<f32>, 5>;
    for (var j = 0u; j < n; j = j + 1u) {
        kp[j] = conj(x[j]);
    }
    var nodes: array<vec2<f32>, 5>;
    nodes[0] = z0;
    if m == 2u {
        let r = complex_quadratic(kp[2], kp[1], kp[0]);
        nodes[1] = r[0];
        nodes[2] = r[1];
    } else if m == 3u {
        let r = complex_cubic(kp[3], kp[2], kp[1], kp[0]);
        nodes[1] = r[0];
        nodes[2] = r[1];
        nodes[3] = r[2];
    } else {
        let r = complex_quartic(kp[4], kp[3], kp[2], kp[1], kp[0]);
        nodes[1] = r[0];
        nodes[2] = r[1];
        nodes[3] = r[2];
        nodes[4] = r[3];
    }
    let depth_param = circle_parameter(z0.x, z0.y);
    var dd: array<vec2<f32>, 5>;
    dd[0] = vec2<f32>(overestimation, 0.0);
    for (var i = 1u; i < n; i = i + 1u) {
        let rp = circle_parameter(nodes[i].x, nodes[i].y);
        let binary = select(0.0, 1.0, rp < depth_param);
        let ramp = clamp(rp * zone.z + zone.w, 0.0, 1.0);
        dd[i] = vec2<f32>(binary + ramp, 0.0);
    }
    for (var level = 1u; level < n; level = level + 1u) {
        for (var ii = 0u; ii + level < n; ii = ii + 1u) {
            let i = n - 1u - ii;
            dd[i] = cdiv(dd[i] - dd[i - 1u], nodes[i] - nodes[i - level]);
        }
    }
    var p: array<vec2<f32>, 5>;
    p[0] = dd[n - 1u];
    for (var ii = 1u; ii < n; ii = ii + 1u) {
        let i = n - 1u - ii;
        for (var jj = 0u; jj + 1u < n; jj = jj + 1u) {
            let j = n - 1u - jj;
            p[j] = p[j - 1u] - cmul(p[j], nodes[i]);
        }
        p[0] = dd[i] - cmul(p[0], nodes[i]);
    }
    var f = 0.0;
    for (var j = 0u; j < n; j = j + 1u) {
        f = f + cmul(mom[j], p[j]).x;
    }
    return f;
}
