//! Moment-based order-independent transparency (Münstermann, Krumpen, Klein & Peters, I3D
//! 2018), the two-pass scheme of its §3–4 and supplementary shaders:
//!
//! 1. Moments pass (additive): every fragment adds its absorbance A = −ln(1 − α) (clamped to 10,
//!    as the paper's code does, so α = 1 stays finite) to b₀ and A·φ(z) to the moments, with z
//!    the warped depth ([`Warp`], by default the paper's logarithmic warp of view distance into
//!    [−1, 1]). Power moments: φ(z) = (z, z², …, z²ᵐ), "4, 6, 8 power moments" for m = 2, 3, 4.
//!    Trigonometric moments: φ(z) = (e^{iφ}, …, e^{imφ}) with phase φ = (z + 1)·(π − w/2) (w the
//!    wrapping-zone angle, π/10), "2, 3, 4 trigonometric moments".
//! 2. Resolve pass (additive): each fragment reconstructs the transmittance in front of itself,
//!    T(z) = exp(−b₀·F(z)) with F the absorbance fraction of [`super::moment_math`] from the
//!    normalised moments bⱼ/b₀ after biasing, and adds T·α·c and T·α.
//! 3. Composite: A = 1 − exp(−b₀) (exact: b₀ is the sum of every absorbance), and colour either
//!    the resolve's sum ΣT·α·c as is, or with the total-absorbance normalisation the paper
//!    recommends: C = A·ΣT·α·c / ΣT·α, which makes a single layer exact whatever T(z) is.
//!
//! Bias (§3.5, the paper's recommended β per moment set and precision, in [`default_bias`]):
//! power moments are mixed with a fixed moment vector, b ← (1 − β)·b + β·b*, trigonometric ones
//! scaled by 1 − β, so the moment matrix stays positive definite in the precision used.
//!
//! Storage ([`MomentStorage`]): `F32` accumulates with additive blending into 32-bit floats (what
//! wgpu can do); `Unorm16` is the paper's 16-bit scheme, which stores the moments normalised by
//! b₀ and quantised (an affine transform onto [0, 1], unorm16) and therefore needs ordered
//! read-modify-write per fragment (rasterizer-ordered views) — the twin applies it in the order
//! given. `F64` keeps exact sums (the algorithm without storage error).
//!
//! Cut-offs of the paper's code kept here: fragments with α < 1e-7 are skipped in both passes, and
//! a pixel with b₀ < 0.00100050033 (total opacity below 0.001) resolves to nothing (0, 0, 0, 0).

use super::moment_math::{circle_point, power_fraction, trig_fraction, wrapping_zone, Complex};
use super::{to_f64, Frag, Real, Storage};
use crate::RefFragment;
use std::ops::Mul;

/// Power or trigonometric moments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MomentKind {
    Power,
    Trigonometric,
}

/// How the moments are stored between fragments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MomentStorage {
    /// Exact sums (no storage error).
    F64,
    /// 32-bit floats, additive blending (order-independent up to summation rounding).
    F32,
    /// The paper's 16-bit quantised, b₀-normalised storage (ordered read-modify-write); b₀ stays
    /// 32-bit float.
    Unorm16,
}

/// How view distance is mapped to the moments' depth in [−1, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Warp {
    /// The paper's: (ln z − ln near) / (ln far − ln near)·2 − 1.
    Log { near: f64, far: f64 },
    /// (z − near) / (far − near)·2 − 1.
    Linear { near: f64, far: f64 },
}

impl Warp {
    /// Warped depth of view distance `z`, clamped to [−1, 1].
    pub fn apply<T: Real>(&self, z: T) -> T {
        let w = match *self {
            Warp::Log { near, far } => {
                let (ln_near, ln_far) = (T::of(near.ln()), T::of(far.ln()));
                (z.ln() - ln_near) / (ln_far - ln_near)
            }
            Warp::Linear { near, far } => (z - T::of(near)) / (T::of(far) - T::of(near)),
        };
        (w * T::of(2.0) - T::ONE).clamp(-T::ONE, T::ONE)
    }
}

/// The absorbance clamp of the paper's code (α = 1 would be infinite).
pub const ABSORBANCE_MAX: f64 = 10.0;
/// Fragments more transparent than this are skipped (the paper's `clip(0.9999999 − T)`).
pub const ALPHA_MIN: f64 = 1e-7;
/// Pixels whose b₀ is below this (opacity < 0.001) resolve to nothing, as in the paper's code.
pub const B0_MIN: f64 = 0.00100050033;

/// The paper's recommended bias β for `count` moments of `kind` in `storage` (F64 uses F32's).
pub fn default_bias(kind: MomentKind, count: u32, storage: MomentStorage) -> Option<f64> {
    let sixteen = storage == MomentStorage::Unorm16;
    Some(match (kind, count, sixteen) {
        (MomentKind::Power, 4, false) => 5e-7,
        (MomentKind::Power, 4, true) => 6e-5,
        (MomentKind::Power, 6, false) => 5e-6,
        (MomentKind::Power, 6, true) => 6e-4,
        (MomentKind::Power, 8, false) => 5e-5,
        (MomentKind::Power, 8, true) => 2.5e-3,
        (MomentKind::Trigonometric, 2, false) => 4e-7,
        (MomentKind::Trigonometric, 2, true) => 4e-4,
        (MomentKind::Trigonometric, 3, false) => 8e-7,
        (MomentKind::Trigonometric, 3, true) => 6.5e-4,
        (MomentKind::Trigonometric, 4, false) => 1.5e-6,
        (MomentKind::Trigonometric, 4, true) => 8.5e-4,
        _ => return None,
    })
}

/// Everything that defines one moment-based OIT variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MomentConfig {
    pub kind: MomentKind,
    /// The paper's naming: 4, 6, 8 power moments or 2, 3, 4 trigonometric moments (b₀ extra).
    pub count: u32,
    pub storage: MomentStorage,
    pub bias: f64,
    /// Weight of the query depth itself in the reconstruction (the paper's code: 0.25); 0 is the
    /// lower bound of the absorbance in front, 1 the upper.
    pub overestimation: f64,
    /// The total-absorbance normalisation of the composite.
    pub normalize: bool,
    pub warp: Warp,
    /// Wrapping zone of trigonometric moments, radians (the paper's π/10).
    pub wrapping_zone_angle: f64,
    /// Storage of the resolve pass's colour sums.
    pub accum: Storage,
}

/// A moment configuration the paper does not define.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MomentConfigError {
    #[error(
        "{kind:?} moments come in counts 4, 6, 8 (power) or 2, 3, 4 (trigonometric), not {count}"
    )]
    Count { kind: MomentKind, count: u32 },
    #[error("warp range needs 0 < near < far, got {near}, {far}")]
    WarpRange { near: f64, far: f64 },
}

impl MomentConfig {
    /// The paper's defaults for `count` moments of `kind` in `storage`, normalised, log warp
    /// over [near, far]. Errors name a count the kind does not have.
    pub fn new(
        kind: MomentKind,
        count: u32,
        storage: MomentStorage,
        near: f64,
        far: f64,
    ) -> Result<Self, MomentConfigError> {
        let bias =
            default_bias(kind, count, storage).ok_or(MomentConfigError::Count { kind, count })?;
        if !(near > 0.0 && far > near) {
            return Err(MomentConfigError::WarpRange { near, far });
        }
        Ok(MomentConfig {
            kind,
            count,
            storage,
            bias,
            overestimation: 0.25,
            normalize: true,
            warp: Warp::Log { near, far },
            wrapping_zone_angle: 0.1 * std::f64::consts::PI,
            accum: Storage::Native,
        })
    }

    /// Stored reals besides b₀: 4, 6 or 8 for either kind.
    pub fn reals(&self) -> usize {
        match self.kind {
            MomentKind::Power => self.count as usize,
            MomentKind::Trigonometric => 2 * self.count as usize,
        }
    }

    /// Bytes per pixel of the moment buffers: b₀ (4 B) and the moments (4 B each, 2 B at 16
    /// bits). The resolve's accumulation target and the output image come on top.
    pub fn moment_bytes_per_pixel(&self) -> u32 {
        let per = if self.storage == MomentStorage::Unorm16 {
            2
        } else {
            4
        };
        4 + per * self.reals() as u32
    }

    fn store<T: Real>(&self, x: T) -> T {
        match self.storage {
            MomentStorage::F64 => x,
            MomentStorage::F32 => T::of(x.f64() as f32 as f64),
            MomentStorage::Unorm16 => T::of((x.f64().clamp(0.0, 1.0) * 65535.0).round() / 65535.0),
        }
    }
}

/// One pixel's moments after the moments pass.
#[derive(Clone, Debug, PartialEq)]
pub struct MomentState<T> {
    /// Total absorbance Σ −ln(1 − α).
    pub b0: T,
    /// Power, F64/F32: Σ A·zʲ for j = 1…2m. Power, Unorm16: the stored quantised normalised
    /// moments, odd ones then even ones. Trigonometric, F64/F32: Σ A·e^{ijφ} as (re, im) pairs,
    /// j = 1…m. Trigonometric, Unorm16: the stored 0.5 + 0.5·bⱼ/b₀ per real.
    pub values: Vec<T>,
}

/// The moments pass over `frags` in the order given (the order matters only through rounding,
/// and for `Unorm16` through its per-fragment quantisation).
pub fn accumulate<T: Real>(frags: &[Frag<T>], cfg: &MomentConfig) -> MomentState<T> {
    let n = cfg.reals();
    let mut st = MomentState {
        b0: T::ZERO,
        values: vec![T::ZERO; n],
    };
    let zone = zone::<T>(cfg);
    for f in frags {
        if f.alpha().f64() < ALPHA_MIN {
            continue;
        }
        let a = (-(T::ONE - f.alpha()).ln()).min(T::of(ABSORBANCE_MAX));
        let z = cfg.warp.apply(f.z);
        let phi = features(z, cfg, &zone);
        match cfg.storage {
            MomentStorage::F64 | MomentStorage::F32 => {
                st.b0 = cfg.store(st.b0 + a);
                for (v, p) in st.values.iter_mut().zip(&phi) {
                    *v = cfg.store(*v + a * *p);
                }
            }
            MomentStorage::Unorm16 => {
                let (offset, new) = match cfg.kind {
                    MomentKind::Power => (quant::offset(cfg.count), quant::quantize(&phi)),
                    // Trigonometric: stored as 0.5 + 0.5·b/b₀, so the feature itself scales by 0.5.
                    MomentKind::Trigonometric => {
                        (vec![0.5; n], phi.iter().map(|p| p.f64() * 0.5).collect())
                    }
                };
                let b0_new = st.b0 + a;
                for i in 0..n {
                    let old = (st.values[i] - T::of(offset[i])) * st.b0;
                    let q = (old + a * T::of(new[i])) / b0_new + T::of(offset[i]);
                    st.values[i] = cfg.store(q);
                }
                st.b0 = T::of(b0_new.f64() as f32 as f64);
            }
        }
    }
    st
}

/// The feature vector φ(z) of warped depth z: powers z¹…z²ᵐ, or (re, im) of e^{ijφ}.
fn features<T: Real>(z: T, cfg: &MomentConfig, zone: &[T; 4]) -> Vec<T> {
    match cfg.kind {
        MomentKind::Power => {
            let mut v = Vec::with_capacity(cfg.count as usize);
            let mut p = T::ONE;
            for _ in 0..cfg.count {
                p *= z;
                v.push(p);
            }
            v
        }
        MomentKind::Trigonometric => {
            let c = circle_point(z, zone);
            let mut p = Complex::real(T::ONE);
            let mut v = Vec::with_capacity(2 * cfg.count as usize);
            for _ in 0..cfg.count {
                p = p.mul(c);
                v.push(p.re);
                v.push(p.im);
            }
            v
        }
    }
}

fn zone<T: Real>(cfg: &MomentConfig) -> [T; 4] {
    wrapping_zone(cfg.wrapping_zone_angle).map(T::of)
}

/// The normalised moments bⱼ/b₀ (power: b₁…b₂ₘ; trigonometric: (re, im) pairs), before bias.
pub fn normalized<T: Real>(st: &MomentState<T>, cfg: &MomentConfig) -> Vec<T> {
    match (cfg.storage, cfg.kind) {
        (MomentStorage::Unorm16, MomentKind::Power) => {
            let off = quant::offset(cfg.count);
            let q: Vec<f64> = st
                .values
                .iter()
                .zip(&off)
                .map(|(v, o)| v.f64() - o)
                .collect();
            quant::dequantize(&q).into_iter().map(T::of).collect()
        }
        (MomentStorage::Unorm16, MomentKind::Trigonometric) => {
            st.values.iter().map(|v| *v * T::of(2.0) - T::ONE).collect()
        }
        _ => st.values.iter().map(|v| *v / st.b0).collect(),
    }
}

/// The transmittance in front of view distance `z`, reconstructed from `st` (1 where b₀ is 0).
/// A reconstruction that fails (a non-finite fraction: rounding pushed the stored moments out
/// of the positive definite cone, so the kernel polynomial has complex roots or the system is
/// singular; seen for ~1 % of single layers with 6 power moments in f32) gives T = 0, as the
/// paper's HLSL `saturate` turns its NaN into 0: the fragment is hidden. GPU builds count these.
pub fn transmittance_at<T: Real>(st: &MomentState<T>, z: T, cfg: &MomentConfig) -> T {
    if st.b0 <= T::ZERO {
        return T::ONE;
    }
    let b = normalized(st, cfg);
    let zw = cfg.warp.apply(z);
    let beta = T::of(cfg.bias);
    let over = T::of(cfg.overestimation);
    let fraction = match cfg.kind {
        MomentKind::Power => {
            let star = bias_vector(cfg.count, cfg.storage);
            let biased: Vec<T> = b
                .iter()
                .zip(&star)
                .map(|(x, s)| (T::ONE - beta) * *x + beta * T::of(*s))
                .collect();
            power_fraction(&biased, zw, over)
        }
        MomentKind::Trigonometric => {
            let zone = zone::<T>(cfg);
            let scale = T::ONE - beta;
            let tb: Vec<Complex<T>> = b
                .chunks(2)
                .map(|p| Complex::new(p[0] * scale, p[1] * scale))
                .collect();
            trig_fraction(&tb, circle_point(zw, &zone), over, &zone)
        }
    };
    if !fraction.is_finite() {
        return T::ZERO;
    }
    (-st.b0 * fraction).exp().clamp(T::ZERO, T::ONE)
}

/// The moment vector b* that power moments are biased towards (the paper's code, per count and
/// precision), in the order b₁…b₂ₘ.
pub fn bias_vector(count: u32, storage: MomentStorage) -> Vec<f64> {
    let sixteen = storage == MomentStorage::Unorm16;
    match (count, sixteen) {
        (4, false) => vec![0.0, 0.375, 0.0, 0.375],
        (4, true) => vec![0.0, 0.628, 0.0, 0.628],
        (6, false) => vec![0.0, 0.48, 0.0, 0.451, 0.0, 0.45],
        (6, true) => vec![0.0, 0.5566, 0.0, 0.489, 0.0, 0.47869382],
        (8, false) => vec![
            0.0,
            0.75,
            0.0,
            0.676_666_666_666_666_6,
            0.0,
            0.63,
            0.0,
            0.600_303_030_303_030_3,
        ],
        (8, true) => vec![
            0.0,
            0.424_749_163_879_598_66,
            0.0,
            0.224_078_026_755_852_84,
            0.0,
            0.153_692_307_692_307_68,
            0.0,
            0.129_004_405_290_891_2,
        ],
        _ => panic!("no bias vector for {count} power moments"),
    }
}

/// Result of a moment-based OIT pixel with its moments, for inspection.
#[derive(Clone, Debug, PartialEq)]
pub struct MomentPixel<T> {
    pub rgba: [T; 4],
    pub state: MomentState<T>,
}

/// Both passes over `frags` (in the order given) at precision `T`.
pub fn moments_t<T: Real>(frags: &[Frag<T>], cfg: &MomentConfig) -> MomentPixel<T> {
    let state = accumulate(frags, cfg);
    if state.b0.f64() < B0_MIN {
        return MomentPixel {
            rgba: [T::ZERO; 4],
            state,
        };
    }
    let mut sum = [T::ZERO; 4];
    for f in frags {
        let a = f.alpha();
        if a.f64() < ALPHA_MIN {
            continue;
        }
        let w = transmittance_at(&state, f.z, cfg) * a;
        let src = [w * f.color[0], w * f.color[1], w * f.color[2], w];
        for (s, v) in sum.iter_mut().zip(src) {
            *s = cfg.accum.round(*s + v);
        }
    }
    let alpha = T::ONE - (-state.b0).exp();
    let rgb = if cfg.normalize {
        if sum[3] > T::ZERO {
            [sum[0], sum[1], sum[2]].map(|s| alpha * s / sum[3])
        } else {
            [T::ZERO; 3]
        }
    } else {
        [sum[0], sum[1], sum[2]]
    };
    MomentPixel {
        rgba: [rgb[0], rgb[1], rgb[2], alpha],
        state,
    }
}

/// Moment-based OIT of one pixel in f64 (fragments in any order; `cfg.storage` decides the
/// stored precision).
pub fn moments(frags: &[RefFragment], cfg: &MomentConfig) -> [f64; 4] {
    let f: Vec<Frag<f64>> = frags.iter().map(Frag::of).collect();
    to_f64(moments_t(&f, cfg).rgba)
}

/// The warp range for `scene`: the view distances its vertices span, within the camera's
/// near/far (the paper's code warps over the scene's depth bounds, not the camera's range, which
/// can be far wider: e.g. `particles` fills 0.24–0.47 of [−1, 1] between its camera's planes).
/// A GPU method passes the same two numbers as uniforms.
pub fn depth_range(scene: &scenarios::Scene) -> (f64, f64) {
    let view = scene.camera.view().as_mat4();
    depth_range_of(
        &scene.mesh.positions,
        view,
        scene.camera.near,
        scene.camera.far,
    )
}

/// [`depth_range`] from vertex positions and the (f32) view matrix, as a GPU method has them
/// after uploading the scene (the same arithmetic, so both sides warp identically).
pub fn depth_range_of(positions: &[[f32; 3]], view: glam::Mat4, near: f64, far: f64) -> (f64, f64) {
    let view = view.as_dmat4();
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for p in positions {
        let z = -(view * glam::Vec3::from(*p).as_dvec3().extend(1.0)).z;
        lo = lo.min(z);
        hi = hi.max(z);
    }
    let lo = lo.clamp(near, far);
    let hi = hi.clamp(near, far);
    if hi > lo {
        (lo, hi)
    } else {
        (near, far)
    }
}

/// The paper's 16-bit quantisation of power moments (its `quantizeMoments` /
/// `offsetAndDequantizeMoments`): an affine map of (odd, even) moment vectors of depths in
/// [−1, 1] into [0, 1]. Layout here: odd moments b₁, b₃, … then even b₂, b₄, … (m each).
pub mod quant {
    const S3: f64 = 1.732_050_807_568_877_2;

    /// Matrices (row-major, y = M·x) per m = 2, 3, 4: (quantise odd, quantise even,
    /// dequantise odd, dequantise even).
    #[rustfmt::skip]
    pub fn matrices(m: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        match m {
            2 => (
                vec![1.5, -2.0, S3 * 0.5, -S3 * 2.0 / 9.0],
                vec![4.0, -4.0, 0.5, 0.5],
                vec![-1.0 / 3.0, S3, -0.75, 0.75 * S3],
                vec![0.125, 1.0, -0.125, 1.0],
            ),
            3 => (
                vec![2.5, -10.0, 8.0,
                     -1.87499864450, 4.20757543111, -1.83257678661,
                     1.26583039016, -1.47644882902, 0.71061660238],
                vec![4.0, -4.0, 0.0,
                     9.0, -24.0, 16.0,
                     -0.57759806484, 4.61936647543, -3.07953906655],
                vec![-0.02877789192, 0.47635550422, 1.55242808973,
                     0.09995235706, 0.84532580931, 1.05472570761,
                     0.25893353755, 0.90779616657, 0.83327335647],
                vec![0.00001253044, 0.16668494186, 0.86602540579,
                     -0.24998746956, 0.16668494186, 0.86602540579,
                     -0.37498825271, 0.21876713299, 0.81189881793],
            ),
            4 => (
                vec![3.48044635732474, -27.5760737514826, 55.1267384344761, -31.5311110403183,
                     1.26797185782836, -0.928755808743913, -2.07520453231032, 1.23598848322588,
                     -2.1671560004294, 6.17950199592966, -0.276515571579297, -4.23583042392097,
                     0.974332879165755, -0.443426830933027, -0.360491648368785, 0.310149466050223],
                vec![0.280504133158527, -0.757633844606942, 0.392179589334688, -0.887531871812237,
                     -2.01362265883247, 0.221551373038988, -1.06107954265125, 2.83887201588367,
                     -7.31010494985321, 13.9855979699139, -0.114305766176437, -7.4361899359832,
                     -15.8954215629556, 79.6186327084103, -127.457278992502, 63.7349456687829],
                vec![-0.00482399708502382, -0.423201508674231, 0.0348312382605129, 1.67179208266592,
                     -0.0233402218644408, -0.832829097046478, 0.0193406040499625, 1.21021509068975,
                     -0.010888537031885, -0.926393772997063, -0.11723394414779, 0.983723301818275,
                     -0.0308713357806732, -0.937989172670245, -0.218033377677099, 0.845991731322996],
                vec![-0.976220278891035, -0.456139260269401, -0.0504335521016742, 0.000838800390651085,
                     -1.04828341778299, -0.229726640510149, 0.0259608334616091, -0.00133632693205861,
                     -1.03115268628604, -0.077844420809897, 0.00443408851014257, -0.0103744938457406,
                     -0.996038443434636, 0.0175438624416783, -0.0361414253243963, -0.00317839994022725],
            ),
            _ => panic!("no quantisation for {} power moments", 2 * m),
        }
    }

    fn apply(mat: &[f64], x: &[f64]) -> Vec<f64> {
        let n = x.len();
        (0..n)
            .map(|i| (0..n).map(|j| mat[i * n + j] * x[j]).sum())
            .collect()
    }

    /// The offset added after quantising (odd then even), per power-moment count.
    pub fn offset(count: u32) -> Vec<f64> {
        let m = count as usize / 2;
        let mut o = vec![0.5; m];
        o.extend(match m {
            2 => vec![0.0, 0.0],
            3 => vec![0.0, 0.0, 0.018888946],
            _ => vec![0.972481993925964, 1.0, 0.999179192513328, 0.991778293073131],
        });
        o
    }

    /// Quantised (not offset) moments, odd then even, of moments b₁…b₂ₘ given in natural order.
    pub fn quantize<T: super::Real>(b: &[T]) -> Vec<f64> {
        let m = b.len() / 2;
        let odd: Vec<f64> = (0..m).map(|i| b[2 * i].f64()).collect();
        let even: Vec<f64> = (0..m).map(|i| b[2 * i + 1].f64()).collect();
        let (qo, qe, _, _) = matrices(m);
        let mut q = apply(&qo, &odd);
        q.extend(apply(&qe, &even));
        q
    }

    /// Moments b₁…b₂ₘ in natural order from quantised ones (offset already removed).
    pub fn dequantize(q: &[f64]) -> Vec<f64> {
        let m = q.len() / 2;
        let (_, _, dqo, dqe) = matrices(m);
        let odd = apply(&dqo, &q[..m]);
        let even = apply(&dqe, &q[m..]);
        (0..2 * m)
            .map(|j| if j % 2 == 0 { odd[j / 2] } else { even[j / 2] })
            .collect()
    }
}

#[cfg(test)]
mod tests;
