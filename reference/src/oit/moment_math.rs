//! The reconstruction mathematics of moment-based OIT (Münstermann, Krumpen, Klein & Peters,
//! "Moment-Based Order-Independent Transparency", I3D 2018, §3 and its supplementary shader
//! code; the power-moment bounds go back to Peters & Klein's moment shadow mapping): given
//! normalised moments of a pixel's absorbance distribution over warped depth, the fraction of
//! absorbance in front of a depth z₀, from which T(z₀) = exp(−b₀ · fraction).
//!
//! Power moments b₁…b₂ₘ (m = 2, 3, 4: "4, 6, 8 power moments"): the Hankel matrix
//! B = (bᵢ₊ⱼ)ᵢⱼ (b₀ = 1) is solved for c = B⁻¹·(1, z₀, …, z₀ᵐ); the m real roots z₁…zₘ of
//! Σ cⱼ xʲ are, with z₀, the support of the canonical representation. Each support point gets
//! the weight factor 1 if it lies in front of z₀ (0 behind), z₀ itself `overestimation`; the
//! polynomial interpolating those factors at z₀…zₘ integrated against the moments (Σ pⱼbⱼ) is
//! the fraction. Roots: closed forms (quadratic, trigonometric cubic, Neumark's quartic), as
//! the paper's shaders; a GPU port should follow these functions.
//!
//! Trigonometric moments b₁…bₘ ∈ ℂ (m = 2, 3, 4): the same with the Hermitian Toeplitz
//! matrix (b_{i−j}), the unit-circle point e^{iφ₀} of the query depth, complex roots on the unit
//! circle, and a monotone circle parameter in place of depth order; roots in the wrapping zone
//! (the arc between the last depth's phase 2π − angle and 2π) get a linear ramp added.
//!
//! Everything is generic over [`Real`] so an f32 twin mirrors the GPU's arithmetic.

use std::ops::{Add, Div, Mul, Sub};

use super::Real;

/// A complex number over `T`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Complex<T> {
    pub re: T,
    pub im: T,
}

impl<T: Real> Complex<T> {
    pub fn new(re: T, im: T) -> Self {
        Complex { re, im }
    }
    pub fn real(re: T) -> Self {
        Complex { re, im: T::ZERO }
    }
    pub fn conj(self) -> Self {
        Complex::new(self.re, -self.im)
    }
    pub fn norm_sq(self) -> T {
        self.re * self.re + self.im * self.im
    }
    pub fn scale(self, s: T) -> Self {
        Complex::new(self.re * s, self.im * s)
    }
    pub fn recip(self) -> Self {
        Complex::real(T::ONE).div(self)
    }
    /// The principal square root.
    pub fn sqrt(self) -> Self {
        let r = self.norm_sq().sqrt();
        let re = ((r + self.re) * T::of(0.5)).max(T::ZERO).sqrt();
        let im = ((r - self.re) * T::of(0.5)).max(T::ZERO).sqrt();
        Complex::new(re, if self.im < T::ZERO { -im } else { im })
    }
    /// The principal cube root.
    pub fn cbrt(self) -> Self {
        let arg = self.im.atan2(self.re) / T::of(3.0);
        let r = self.norm_sq().powf(T::of(1.0 / 6.0));
        Complex::new(arg.cos() * r, arg.sin() * r)
    }
}

impl<T: Real> Add for Complex<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Complex::new(self.re + o.re, self.im + o.im)
    }
}

impl<T: Real> Sub for Complex<T> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Complex::new(self.re - o.re, self.im - o.im)
    }
}

impl<T: Real> Mul for Complex<T> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Complex::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

impl<T: Real> Div for Complex<T> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let d = o.norm_sq();
        Complex::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
}

/// The two real roots of a·x² + b·x + c (real by assumption), computed without cancellation.
pub fn quadratic_roots<T: Real>(a: T, b: T, c: T) -> [T; 2] {
    let h = b * T::of(0.5);
    let s = (h * h - a * c).max(T::ZERO).sqrt();
    if h >= T::ZERO {
        [-c / (h + s), (-h - s) / a]
    } else {
        [(-h + s) / a, c / (-h + s)]
    }
}

/// The real roots of x³ + a·x² + b·x + c: three by the trigonometric method when they are all
/// real (the case of a positive definite moment matrix), else the one real root (Cardano),
/// repeated. Sorted ascending in the three-root case.
pub fn cubic_roots<T: Real>(a: T, b: T, c: T) -> [T; 3] {
    let third = T::of(1.0 / 3.0);
    let shift = a * third;
    // Depressed cubic t³ + p·t + q with x = t − a/3.
    let p = b - a * shift;
    let q = T::of(2.0) * shift * shift * shift - b * shift + c;
    let disc = (q * T::of(0.5)) * (q * T::of(0.5)) + (p * third) * (p * third) * (p * third);
    if p < T::ZERO && disc <= T::ZERO {
        let m = T::of(2.0) * (-p * third).sqrt();
        let arg = (T::of(3.0) * q / (p * m)).clamp(-T::ONE, T::ONE);
        let theta = arg.acos() * third;
        let k = T::of(2.0 * std::f64::consts::PI / 3.0);
        let r0 = m * theta.cos() - shift;
        let r1 = m * (theta - k).cos() - shift;
        let r2 = m * (theta + k).cos() - shift;
        // cos θ ≥ cos(θ − 2π/3) ≥ cos(θ + 2π/3) for θ ∈ [0, π/3].
        [r2, r1, r0]
    } else {
        let s = disc.max(T::ZERO).sqrt();
        let cb = |x: T| {
            if x < T::ZERO {
                -(-x).powf(third)
            } else {
                x.powf(third)
            }
        };
        let t = cb(-q * T::of(0.5) + s) + cb(-q * T::of(0.5) - s);
        let r = t - shift;
        [r, r, r]
    }
}

/// The roots of x⁴ + b·x³ + c·x² + d·x + e (four real roots by assumption), by Neumark's
/// factorisation into two quadratics from the resolvent cubic's smallest root, choosing
/// between his two factorisations with Herbison-Evans' rule (as the paper's shader does).
pub fn quartic_roots<T: Real>(b: T, c: T, d: T, e: T) -> [T; 4] {
    let two = T::of(2.0);
    let four = T::of(4.0);
    let half = T::of(0.5);
    let y = cubic_roots(
        -two * c,
        c * c + b * d - four * e,
        d * d + b * b * e - b * c * d,
    )[0];
    let bb = b * b;
    let fy = four * y;
    let bb_fy = bb - fy;
    let z = c - y;
    let zz = z * z;
    let fe = four * e;
    let zz_fe = zz - fe;
    let (g1, g2, h1, h2);
    if y < T::ZERO || (zz + fe) * bb_fy > zz_fe * (bb + fy) {
        let s = bb_fy.max(T::ZERO).sqrt();
        g1 = (b + s) * half;
        g2 = (b - s) * half;
        let t = (b * z - two * d) / (two * s);
        h1 = z * half + t;
        h2 = z * half - t;
    } else {
        let s = zz_fe.max(T::ZERO).sqrt();
        h1 = (z + s) * half;
        h2 = (z - s) * half;
        let t = (b * z - two * d) / (two * s);
        g1 = b * half + t;
        g2 = b * half - t;
    }
    let [r0, r1] = quadratic_roots(T::ONE, g1, h1);
    let [r2, r3] = quadratic_roots(T::ONE, g2, h2);
    [r0, r1, r2, r3]
}

/// The real roots of Σ cⱼ xʲ of degree m = 2, 3, 4 (`c.len() == m + 1`).
pub fn real_roots<T: Real>(c: &[T]) -> Vec<T> {
    match c.len() {
        3 => quadratic_roots(c[2], c[1], c[0]).to_vec(),
        4 => cubic_roots(c[2] / c[3], c[1] / c[3], c[0] / c[3]).to_vec(),
        5 => quartic_roots(c[3] / c[4], c[2] / c[4], c[1] / c[4], c[0] / c[4]).to_vec(),
        n => panic!("polynomial of degree {} not supported", n as i64 - 1),
    }
}

/// Solves H·x = v for a symmetric positive definite H (row-major n×n) by an LDLᵀ
/// factorisation without pivoting, as the paper's unrolled Cholesky steps do.
pub fn solve_ldlt<T: Real>(h: &[T], v: &[T]) -> Vec<T> {
    let n = v.len();
    let mut l = vec![T::ZERO; n * n];
    let mut d = vec![T::ZERO; n];
    for i in 0..n {
        for j in 0..i {
            let mut s = h[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k] * d[k];
            }
            l[i * n + j] = s / d[j];
        }
        let mut s = h[i * n + i];
        for k in 0..i {
            s -= l[i * n + k] * l[i * n + k] * d[k];
        }
        d[i] = s;
    }
    let mut x = v.to_vec();
    for i in 0..n {
        for k in 0..i {
            let lx = l[i * n + k] * x[k];
            x[i] -= lx;
        }
    }
    for i in 0..n {
        x[i] /= d[i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            let lx = l[k * n + i] * x[k];
            x[i] -= lx;
        }
    }
    x
}

/// Monomial coefficients of the polynomial of degree `nodes.len() − 1` through
/// (nodesᵢ, valuesᵢ), by Newton's divided differences.
fn interpolate<T: Real>(nodes: &[T], values: &[T]) -> Vec<T> {
    let n = nodes.len();
    let mut dd = values.to_vec();
    for level in 1..n {
        for i in (level..n).rev() {
            dd[i] = (dd[i] - dd[i - 1]) / (nodes[i] - nodes[i - level]);
        }
    }
    // Horner on the Newton form: p = dd₀ + (x − z₀)(dd₁ + (x − z₁)(dd₂ + …)).
    let mut p = vec![T::ZERO; n];
    p[0] = dd[n - 1];
    for i in (0..n - 1).rev() {
        // p ← p·(x − zᵢ) + ddᵢ
        for j in (1..n).rev() {
            p[j] = p[j - 1] - p[j] * nodes[i];
        }
        p[0] = dd[i] - p[0] * nodes[i];
    }
    p
}

/// Fraction of the absorbance in front of `z0` from the normalised, biased power moments
/// `b` = [b₁, …, b₂ₘ] (b₀ = 1 implied), with `overestimation` the weight of z₀ itself.
pub fn power_fraction<T: Real>(b: &[T], z0: T, overestimation: T) -> T {
    let m = b.len() / 2;
    let n = m + 1;
    let moment = |k: usize| if k == 0 { T::ONE } else { b[k - 1] };
    let mut hankel = vec![T::ZERO; n * n];
    for i in 0..n {
        for j in 0..n {
            hankel[i * n + j] = moment(i + j);
        }
    }
    let mut powers = vec![T::ONE; n];
    for j in 1..n {
        powers[j] = powers[j - 1] * z0;
    }
    let c = solve_ldlt(&hankel, &powers);
    let mut nodes = vec![z0];
    nodes.extend(real_roots(&c));
    let values: Vec<T> = nodes
        .iter()
        .enumerate()
        .map(|(i, &z)| {
            if i == 0 {
                overestimation
            } else if z < z0 {
                T::ONE
            } else {
                T::ZERO
            }
        })
        .collect();
    let p = interpolate(&nodes, &values);
    (0..n).map(|j| p[j] * moment(j)).fold(T::ZERO, |s, x| s + x)
}

/// The four constants of the wrapping zone of `angle` radians (paper's code: usually π/10):
/// [angle, π − angle/2 (phase scale), slope and offset of the linear ramp in circle
/// parameter].
pub fn wrapping_zone(angle: f64) -> [f64; 4] {
    let scale = std::f64::consts::PI - 0.5 * angle;
    if angle <= 0.0 {
        return [angle, scale, 0.0, 0.0];
    }
    let end = 7.0;
    let a = std::f64::consts::TAU - angle;
    let begin = circle_parameter(a.cos(), a.sin());
    let slope = 1.0 / (end - begin);
    [angle, scale, slope, 1.0 - end * slope]
}

/// A parameter in [−1, 7] growing monotonically with the angle of the unit-circle point
/// (x, y) over [0, 2π) (not arc length; cheap).
pub fn circle_parameter<T: Real>(x: T, y: T) -> T {
    let r = y.abs() - x.abs();
    let r = if x < T::ZERO { T::of(2.0) - r } else { r };
    if y < T::ZERO {
        T::of(6.0) - r
    } else {
        r
    }
}

/// The unit-circle point of warped depth z ∈ [−1, 1]: phase (z + 1)·(π − angle/2).
pub fn circle_point<T: Real>(z: T, zone: &[T; 4]) -> Complex<T> {
    let phase = (z + T::ONE) * zone[1];
    Complex::new(phase.cos(), phase.sin())
}

/// Solves the Hermitian Toeplitz system M·x = v, M_{ij} = b_{i−j} (b₋ⱼ = conj bⱼ), by LDLᴴ.
fn solve_toeplitz<T: Real>(b: &[Complex<T>], v: &[Complex<T>]) -> Vec<Complex<T>> {
    let n = v.len();
    let m = |i: usize, j: usize| if i >= j { b[i - j] } else { b[j - i].conj() };
    let mut l = vec![Complex::real(T::ZERO); n * n];
    let mut d = vec![T::ZERO; n];
    for i in 0..n {
        for j in 0..i {
            let mut s = m(i, j);
            for k in 0..j {
                s = s.sub(l[i * n + k].mul(l[j * n + k].conj()).scale(d[k]));
            }
            l[i * n + j] = s.scale(T::ONE / d[j]);
        }
        let mut s = m(i, i).re;
        for k in 0..i {
            s -= l[i * n + k].norm_sq() * d[k];
        }
        d[i] = s;
    }
    let mut x = v.to_vec();
    for i in 0..n {
        for k in 0..i {
            x[i] = x[i].sub(l[i * n + k].mul(x[k]));
        }
    }
    for i in 0..n {
        x[i] = x[i].scale(T::ONE / d[i]);
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            x[i] = x[i].sub(l[k * n + i].conj().mul(x[k]));
        }
    }
    x
}

/// The roots of a·x² + b·x + c over ℂ.
pub fn complex_quadratic<T: Real>(a: Complex<T>, b: Complex<T>, c: Complex<T>) -> [Complex<T>; 2] {
    let inv = a.recip();
    let b = b.mul(inv).scale(T::of(0.5));
    let c = c.mul(inv);
    let s = b.mul(b).sub(c).sqrt();
    let nb = Complex::new(-b.re, -b.im);
    [nb.sub(s), nb.add(s)]
}

/// The roots of a·x³ + b·x² + c·x + d over ℂ (Blinn's formulation, as the paper's shader).
pub fn complex_cubic<T: Real>(
    a: Complex<T>,
    b: Complex<T>,
    c: Complex<T>,
    d: Complex<T>,
) -> [Complex<T>; 3] {
    let inv = a.recip();
    let third = T::of(1.0 / 3.0);
    let b = b.mul(inv).scale(third);
    let c = c.mul(inv).scale(third);
    let d = d.mul(inv);
    let delta00 = c.sub(b.mul(b));
    let delta01 = d.sub(c.mul(b));
    let delta11 = b.mul(d).sub(c.mul(c));
    let disc = delta00
        .mul(delta11)
        .scale(T::of(4.0))
        .sub(delta01.mul(delta01));
    let dep_d = delta01.sub(b.mul(delta00).scale(T::of(2.0)));
    let dep_c = delta00;
    let mut root = Complex::new(-disc.re, -disc.im).sqrt();
    // Face the root along the depressed constant term to avoid cancellation.
    if root.re * dep_d.re + root.im * dep_d.im < T::ZERO {
        root = Complex::new(-root.re, -root.im);
    }
    let first = root.sub(dep_d).scale(T::of(0.5)).cbrt();
    let h = T::of(0.5 * 3f64.sqrt());
    let w1 = Complex::new(T::of(-0.5), -h);
    let w2 = Complex::new(T::of(-0.5), h);
    let cubic = [first, w1.mul(first), w2.mul(first)];
    let inv_first = first.recip();
    let inv_cubic = [inv_first, w2.mul(inv_first), w1.mul(inv_first)];
    std::array::from_fn(|i| cubic[i].sub(dep_c.mul(inv_cubic[i])).sub(b))
}

/// The roots of a·x⁴ + b·x³ + c·x² + d·x + e over ℂ (Neumark, with a cubic-resolvent root
/// that is not the smallest, as the paper's shader).
pub fn complex_quartic<T: Real>(
    a: Complex<T>,
    b: Complex<T>,
    c: Complex<T>,
    d: Complex<T>,
    e: Complex<T>,
) -> [Complex<T>; 4] {
    let inv = a.recip();
    let (b, c, d, e) = (b.mul(inv), c.mul(inv), d.mul(inv), e.mul(inv));
    let p = c.scale(T::of(-2.0));
    let q = c.mul(c).add(b.mul(d)).sub(e.scale(T::of(4.0)));
    let r = d.mul(d).add(b.mul(b).mul(e)).sub(b.mul(c).mul(d));
    let cr = complex_cubic(Complex::real(T::ONE), p, q, r);
    let y = if cr[1].norm_sq() > cr[0].norm_sq() {
        cr[1]
    } else {
        cr[0]
    };
    let s = b.mul(b).sub(y.scale(T::of(4.0))).sqrt();
    let g1 = b.add(s).scale(T::of(0.5));
    let g2 = b.sub(s).scale(T::of(0.5));
    let z = c.sub(y);
    let t = b.mul(z).scale(T::of(0.5)).sub(d).div(s);
    let h1 = z.scale(T::of(0.5)).add(t);
    let h2 = z.scale(T::of(0.5)).sub(t);
    let one = Complex::real(T::ONE);
    let [r0, r1] = complex_quadratic(one, g1, h1);
    let [r2, r3] = complex_quadratic(one, g2, h2);
    [r0, r1, r2, r3]
}

/// Fraction of the absorbance in front of the unit-circle point `z0` from the normalised
/// trigonometric moments `b` = [b₁, …, bₘ] (already scaled by 1 − bias), with the wrapping
/// zone constants `zone` ([`wrapping_zone`]).
pub fn trig_fraction<T: Real>(
    b: &[Complex<T>],
    z0: Complex<T>,
    overestimation: T,
    zone: &[T; 4],
) -> T {
    let m = b.len();
    let n = m + 1;
    let mut moments = vec![Complex::real(T::ONE)];
    moments.extend_from_slice(b);
    let mut powers = vec![Complex::real(T::ONE)];
    for j in 1..n {
        powers.push(powers[j - 1].mul(z0));
    }
    let c = solve_toeplitz(&moments, &powers);
    // The kernel polynomial Σ conj(cⱼ) xʲ; its roots lie on the unit circle.
    let k: Vec<Complex<T>> = c.iter().map(|x| x.conj()).collect();
    let roots: Vec<Complex<T>> = match m {
        2 => complex_quadratic(k[2], k[1], k[0]).to_vec(),
        3 => complex_cubic(k[3], k[2], k[1], k[0]).to_vec(),
        4 => complex_quartic(k[4], k[3], k[2], k[1], k[0]).to_vec(),
        _ => panic!("{m} trigonometric moments not supported"),
    };
    let depth_param = circle_parameter(z0.re, z0.im);
    let mut nodes = vec![z0];
    let mut values = vec![Complex::real(overestimation)];
    for r in roots {
        let rp = circle_parameter(r.re, r.im);
        let binary = if rp < depth_param { T::ONE } else { T::ZERO };
        let ramp = (rp * zone[2] + zone[3]).clamp(T::ZERO, T::ONE);
        nodes.push(r);
        values.push(Complex::real(binary + ramp));
    }
    // Complex divided differences and Horner, as in `interpolate`.
    let mut dd = values;
    for level in 1..n {
        for i in (level..n).rev() {
            dd[i] = dd[i].sub(dd[i - 1]).div(nodes[i].sub(nodes[i - level]));
        }
    }
    let mut p = vec![Complex::real(T::ZERO); n];
    p[0] = dd[n - 1];
    for i in (0..n - 1).rev() {
        for j in (1..n).rev() {
            p[j] = p[j - 1].sub(p[j].mul(nodes[i]));
        }
        p[0] = dd[i].sub(p[0].mul(nodes[i]));
    }
    (0..n)
        .map(|j| moments[j].mul(p[j]).re)
        .fold(T::ZERO, |s, x| s + x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn real_root_solvers_recover_known_roots() {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(71);
        for _ in 0..500 {
            // Distinct roots in [−1, 1], at least 0.05 apart (moment supports are distinct).
            let mut r: Vec<f64> = Vec::new();
            while r.len() < 4 {
                let x: f64 = rng.random_range(-1.0..1.0);
                if r.iter().all(|y| (x - y).abs() > 0.05) {
                    r.push(x);
                }
            }
            for m in 2..=4 {
                // Σ cⱼ xʲ = s·Π (x − rᵢ) with a random scale s.
                let s: f64 =
                    rng.random_range(0.5..2.0) * if rng.random::<bool>() { 1.0 } else { -1.0 };
                let mut c = vec![s];
                for &ri in &r[..m] {
                    let mut next = vec![0.0; c.len() + 1];
                    for (j, cj) in c.iter().enumerate() {
                        next[j + 1] += cj;
                        next[j] -= cj * ri;
                    }
                    c = next;
                }
                let mut got = real_roots(&c);
                got.sort_by(f64::total_cmp);
                let mut want = r[..m].to_vec();
                want.sort_by(f64::total_cmp);
                for (g, w) in got.iter().zip(&want) {
                    // Closed forms lose a few digits near close roots; 0.05 spacing keeps 1e-9.
                    assert!((g - w).abs() < 1e-9, "m {m}: {got:?} vs {want:?}");
                }
            }
        }
    }

    #[test]
    fn complex_root_solvers_recover_unit_circle_roots() {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(72);
        for _ in 0..500 {
            let mut ang: Vec<f64> = Vec::new();
            while ang.len() < 4 {
                let x: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                if ang.iter().all(|y| (x - y).abs() > 0.05) {
                    ang.push(x);
                }
            }
            for m in 2..=4 {
                let roots: Vec<Complex<f64>> = ang[..m]
                    .iter()
                    .map(|a| Complex::new(a.cos(), a.sin()))
                    .collect();
                let mut c = vec![Complex::new(0.7, -0.3)];
                for &ri in &roots {
                    let mut next = vec![Complex::real(0.0); c.len() + 1];
                    for (j, cj) in c.iter().enumerate() {
                        next[j + 1] = next[j + 1].add(*cj);
                        next[j] = next[j].sub(cj.mul(ri));
                    }
                    c = next;
                }
                let got: Vec<Complex<f64>> = match m {
                    2 => complex_quadratic(c[2], c[1], c[0]).to_vec(),
                    3 => complex_cubic(c[3], c[2], c[1], c[0]).to_vec(),
                    _ => complex_quartic(c[4], c[3], c[2], c[1], c[0]).to_vec(),
                };
                for w in &roots {
                    let best = got
                        .iter()
                        .map(|g| g.sub(*w).norm_sq().sqrt())
                        .fold(f64::INFINITY, f64::min);
                    assert!(best < 1e-7, "m {m}: root {w:?} not found in {got:?}");
                }
            }
        }
    }

    #[test]
    fn ldlt_solves_a_hankel_system() {
        // Moments of three point masses: a positive definite 3×3 Hankel matrix.
        let pts = [(-0.5, 0.2), (0.1, 0.5), (0.7, 0.3)];
        let b = |k: i32| {
            pts.iter()
                .map(|(z, w): &(f64, f64)| w * z.powi(k))
                .sum::<f64>()
        };
        let h: Vec<f64> = (0..9).map(|i| b(i / 3 + i % 3)).collect();
        let v = [1.0, 0.3, 0.09];
        let x = solve_ldlt(&h, &v);
        for i in 0..3 {
            let hx: f64 = (0..3).map(|j| h[i * 3 + j] * x[j]).sum();
            assert!((hx - v[i]).abs() < 1e-12);
        }
    }
}
