//! CPU twins of the approximate (bounded-memory) transparency methods: each is the method's
//! per-pixel rule, written plainly, applied to one pixel's fragments. A GPU method is judged
//! against the f64 reference ([`crate::reference`]); its twin says what the *algorithm* gives on
//! the same fragments, so a test can separate the algorithm's error from the implementation's
//! (races, precision). Every twin returns premultiplied RGBA with A = 1 − transmittance, like
//! [`crate::composite`] (no background).
//!
//! | twin | paper | what it keeps per pixel | exact when |
//! |------|-------|-------------------------|------------|
//! | [`mlab`] | Salvi & Vaidyanathan 2014 | k blend layers, two farthest merged on overflow (order-dependent) | n ≤ k |
//! | [`adaptive`] | Salvi et al. 2011 | k visibility nodes, least-area node removed on overflow | n ≤ k |
//! | [`moments`] | Münstermann et al. 2018 | b₀ + 4/6/8 power or 2/3/4 trigonometric moments | n = 1 (normalised resolve) |
//! | [`hybrid`] | Maule et al. 2013 | k nearest exact + weighted-average tail | n ≤ k |
//! | [`tail`] | NVIDIA's OIT sample, Bevy's TODO | k nearest or first exact + blended (or dropped) tail | n ≤ k |
//! | [`wboit`] | McGuire & Bavoil 2013 | weighted sums + revealage | n = 1 |
//!
//! Fragments: [`Frag`] holds a depth key `z` (view distance, increasing away from the eye in
//! both depth conventions) and straight RGBA. [`frags`] converts a reference list, in arrival
//! (primitive) order or depth order. Each twin is generic over [`Real`] (`mlab::mlab_t::<f32>`,
//! …) so a GPU test can run it in the GPU's f32 arithmetic and compare at 1e-5; the plain names
//! (`mlab`, `adaptive`, `moments`, …) are f64 conveniences over `&[RefFragment]`. [`image`]
//! applies one to every pixel of a [`FragmentLists`].
//!
//! Tail axes: a bounded capture's `tail = drop | blend` and `keep = nearest | first` are
//! [`tail_blend`]. MLAB with its merge replaced by `tail = drop` or `blend` never merges, so it
//! keeps the k nearest and equals `tail_blend(.., Keep::Nearest, ..)`.
//!
//! Arrival order: on a GPU, fragments of one draw reach a pixel in primitive order only under
//! ordering hardware (rasterizer-ordered views); wgpu has none, so an unguarded GPU build of an
//! order-dependent method sees some other order. The ideal-order twins replay primitive order,
//! which is what the method would produce with ordering hardware.

pub mod adaptive;
pub mod hybrid;
pub mod mlab;
pub mod moment_math;
pub mod moments;
pub mod tail;
pub mod wboit;

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

use rayon::prelude::*;

use crate::{FragmentLists, RefFragment};

pub use adaptive::adaptive;
pub use hybrid::hybrid;
pub use mlab::{mlab, mlab_merges};
pub use moments::{moments, MomentConfig, MomentConfigError, MomentKind, MomentStorage, Warp};
pub use tail::{tail_blend, Bounded, Keep, TailMode};
pub use wboit::wboit;

/// The float type a twin computes in: f64 for the reference-side answer, f32 to mirror a GPU.
pub trait Real:
    Copy
    + PartialOrd
    + Debug
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
{
    const ZERO: Self;
    const ONE: Self;
    /// Rounds an f64 to this type.
    fn of(x: f64) -> Self;
    fn f64(self) -> f64;
    fn sqrt(self) -> Self;
    fn exp(self) -> Self;
    fn ln(self) -> Self;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    fn acos(self) -> Self;
    fn atan2(self, x: Self) -> Self;
    fn abs(self) -> Self;
    fn powf(self, e: Self) -> Self;
    fn is_finite(self) -> bool;
    fn min(self, o: Self) -> Self {
        if o < self {
            o
        } else {
            self
        }
    }
    fn max(self, o: Self) -> Self {
        if o > self {
            o
        } else {
            self
        }
    }
    fn clamp(self, lo: Self, hi: Self) -> Self {
        self.max(lo).min(hi)
    }
}

macro_rules! real {
    ($t:ty) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            fn of(x: f64) -> Self {
                x as $t
            }
            fn f64(self) -> f64 {
                self as f64
            }
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            fn ln(self) -> Self {
                <$t>::ln(self)
            }
            fn sin(self) -> Self {
                <$t>::sin(self)
            }
            fn cos(self) -> Self {
                <$t>::cos(self)
            }
            fn acos(self) -> Self {
                <$t>::acos(self)
            }
            fn atan2(self, x: Self) -> Self {
                <$t>::atan2(self, x)
            }
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            fn powf(self, e: Self) -> Self {
                <$t>::powf(self, e)
            }
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
        }
    };
}
real!(f32);
real!(f64);

/// Where an accumulator is stored between fragments (a render target or buffer format): after
/// every update the value is rounded to it, as a blend unit writing that format does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// Kept at the twin's own precision `T` (an f32 target when `T = f32`).
    Native,
    /// IEEE half (RGBA16F / R16F targets).
    F16,
}

impl Storage {
    pub fn round<T: Real>(self, x: T) -> T {
        match self {
            Storage::Native => x,
            Storage::F16 => T::of(half::f16::from_f64(x.f64()).to_f64()),
        }
    }
}

/// One fragment as the twins see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frag<T> {
    /// Depth key: larger is farther. The twins use view distance ([`RefFragment::view_z`]).
    pub z: T,
    /// Straight RGBA; `color[3]` is opacity.
    pub color: [T; 4],
}

impl<T: Real> Frag<T> {
    pub fn of(f: &RefFragment) -> Self {
        Frag {
            z: T::of(f.view_z),
            color: f.color.map(T::of),
        }
    }
    pub fn alpha(&self) -> T {
        self.color[3]
    }
}

/// Fragment order handed to a twin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// By primitive id: submission order, what ordering hardware would deliver.
    Arrival,
    /// Nearest first, as [`FragmentLists`] stores them.
    Depth,
}

/// `list` (one pixel's reference fragments, nearest first) as twin fragments in `order`.
pub fn frags<T: Real>(list: &[RefFragment], order: Order) -> Vec<Frag<T>> {
    match order {
        Order::Depth => list.iter().map(Frag::of).collect(),
        Order::Arrival => {
            let mut v: Vec<&RefFragment> = list.iter().collect();
            // One triangle covers a pixel centre at most once, so prim ids are unique per pixel.
            v.sort_by_key(|f| f.prim);
            v.into_iter().map(Frag::of).collect()
        }
    }
}

/// Applies `f` to every pixel of `lists`, handing it the pixel's fragments in arrival
/// (primitive-id) order when `arrival_order`, else nearest first. Row-major like a capture.
pub fn image<F>(lists: &FragmentLists, arrival_order: bool, f: F) -> Vec<[f64; 4]>
where
    F: Fn(&[RefFragment]) -> [f64; 4] + Sync,
{
    (0..lists.pixels())
        .into_par_iter()
        .map(|p| {
            let list = lists.pixel(p);
            if arrival_order {
                let mut v = list.to_vec();
                v.sort_by_key(|f| f.prim);
                f(&v)
            } else {
                f(list)
            }
        })
        .collect()
}

/// Front-to-back "under" compositing of fragments already in depth order (nearest first):
/// C += T·α·c, T *= 1 − α. Returns premultiplied RGB, A = 1 − T, and T.
pub fn composite_sorted<'a, T: Real + 'a>(frags: impl Iterator<Item = &'a Frag<T>>) -> ([T; 4], T) {
    let mut c = [T::ZERO; 3];
    let mut t = T::ONE;
    for f in frags {
        let a = f.alpha();
        for (ci, fc) in c.iter_mut().zip(&f.color) {
            *ci += t * a * *fc;
        }
        t *= T::ONE - a;
    }
    ([c[0], c[1], c[2], T::ONE - t], t)
}

/// `v` widened to f64.
pub fn to_f64<T: Real>(v: [T; 4]) -> [f64; 4] {
    v.map(Real::f64)
}

/// Indices of `frags` sorted nearest first; ties keep arrival order (a stable sort).
pub(crate) fn depth_order<T: Real>(frags: &[Frag<T>]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..frags.len()).collect();
    idx.sort_by(|&a, &b| {
        frags[a]
            .z
            .partial_cmp(&frags[b].z)
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    idx
}

/// Random fragment piles for tests (this crate's, and through the `testing` feature other
/// crates' that hold a GPU rule to its twin).
#[cfg(any(test, feature = "testing"))]
pub mod testing;
