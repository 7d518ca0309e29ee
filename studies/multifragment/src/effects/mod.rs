//! Effects computed from captured fragments, their f64 CPU references, and what each reads.
//!
//! A method that resolves fragments nearest-first runs the WGSL fold in `methods/effects.wgsl`
//! with the override constants of [`EffectConfig::constants`]; this file is its CPU twin, run on
//! the exact fragment lists of [`mfx_reference`]. Every effect's output is a premultiplied-
//! RGBA image compared channel by channel (RMSE, max abs, bad pixels, non-finite):
//!
//! | `effect`       | payload read            | compared image (per pixel)                                          |
//! |----------------|-------------------------|---------------------------------------------------------------------|
//! | `transparency` | colour (+ window depth) | under-composite (C, A), A = 1 − transmittance                       |
//! | `translucency` | view_z + facing         | (T, T, T, 1 − T), T = exp(−σ·l), l = Σ(exit − entry) ≥ 0 in linear view depth; 1 − T to full relative precision for small σ·l |
//! | `fresnel`      | view_z + facing + normal| as translucency with T × Π_i (1 − (1 − cos θ_i)^5)                   |
//! | `csg_and/or/sub` | window depth + object id | (depth, 1 if A, 1 if B, 1) of the first fragment where A∩B / A∪B / A−B becomes true; 0 if never |
//! | `dof`          | colour + view_z         | three images (foreground, midground, background) one after another: the nearest fragment of view depth in [0, n), [n, f), [f, ∞) as (rgb·a, a); 0 if none |
//! | `volume`       | colour (scalar s = red) + view_z | Bavoil 2007 §6.3.2: the ray segments between consecutive fragments composited front to back, opacity 1 − exp(−σ·(s₁ + s₂)/2·Δz), colour the transfer ramp at the mean s (`mfx_reference::volume`) |
//! | `isosurface`   | colour (scalar s = red) + view_z | §6.3.1: (view depth of the nearest crossing of `iso_value` between consecutive fragments, interpolated linearly, 0, 0, 1); 0 if none |
//!
//! Thickness uses front faces as entries and back faces as exits (Σ ±z by facing: the seed
//! alternates by index, which is the same for disjoint closed objects), so `variant=naive` (the
//! seed's f32 running sum of ±z) and `variant=stable` (per-pair differences of adjacent depths,
//! Kahan-summed) compute the same quantity and differ only in arithmetic.

/// The effects fold (`fold_init_at` / `fold_step` / `fold_finish_image`, override `EFFECT`):
/// prepend it to a method's WGSL and set `effects::EffectConfig::constants` on the pipelines
/// that call the fold.
pub const FOLD_WGSL: &str = include_str!("fold.wgsl");

/// Bytes of one `FoldState` in `effects.wgsl` (three vec4 + two u32, padded to 16): methods that
/// keep fold states in a per-pixel buffer between passes size it with this.
pub const FOLD_STATE_BYTES: u64 = 64;

use glam::{DMat4, DVec3};
use rayon::prelude::*;
use scenarios::Scene;

use crate::method::Expected;
use bench_core::axes::{Axis, Point};
use bench_core::record::cols;
use bench_core::study::InvalidPoint;
use mfx_reference::{FragmentLists, RefFragment};

/// Known effect names (the `effect` CSV column).
pub const EFFECTS: &[&str] = &[
    "transparency",
    "translucency",
    "fresnel",
    "csg_and",
    "csg_or",
    "csg_sub",
    "dof",
    "volume",
    "isosurface",
];
/// The effect a point computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    Transparency,
    Translucency,
    Fresnel,
    /// 0 = A ∩ B, 1 = A ∪ B, 2 = A − B (the WGSL CSG_OP).
    Csg(u32),
    Dof,
    /// §6.3.2 direct volume rendering of the ray segments between consecutive fragments.
    Volume,
    /// §6.3.1 the nearest iso-value crossing between consecutive fragments.
    Isosurface,
}

impl Effect {
    pub fn parse(s: &str) -> Result<Effect, InvalidPoint> {
        Ok(match s {
            "transparency" => Effect::Transparency,
            "translucency" => Effect::Translucency,
            "fresnel" => Effect::Fresnel,
            "csg_and" => Effect::Csg(0),
            "csg_or" => Effect::Csg(1),
            "csg_sub" => Effect::Csg(2),
            "dof" => Effect::Dof,
            "volume" => Effect::Volume,
            "isosurface" => Effect::Isosurface,
            other => {
                return Err(InvalidPoint::value(
                    EFFECT.name(),
                    format!("'{other}'"),
                    format!("is not one of {}", EFFECTS.join(", ")),
                ))
            }
        })
    }
    /// The WGSL `EFFECT` value.
    pub fn code(self) -> u32 {
        match self {
            Effect::Transparency => 0,
            Effect::Translucency => 1,
            Effect::Fresnel => 2,
            Effect::Csg(_) => 3,
            Effect::Dof => 4,
            Effect::Volume => 5,
            Effect::Isosurface => 6,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Effect::Transparency => "transparency",
            Effect::Translucency => "translucency",
            Effect::Fresnel => "fresnel",
            Effect::Csg(0) => "csg_and",
            Effect::Csg(1) => "csg_or",
            Effect::Csg(_) => "csg_sub",
            Effect::Dof => "dof",
            Effect::Volume => "volume",
            Effect::Isosurface => "isosurface",
        }
    }
    /// What a fragment must carry for this effect (window depth is always available).
    pub fn payload(self) -> Payload {
        match self {
            Effect::Transparency => Payload::RGBA,
            Effect::Translucency => Payload::DEPTH,
            Effect::Fresnel => Payload::DEPTH_NORMAL,
            Effect::Csg(_) => Payload::DEPTH_ID,
            // The scalar rides in the colour (the thesis stores "a depth value and a scalar
            // value with each fragment": 8 B; mfx's colour payload keeps 16 B of colour).
            Effect::Dof | Effect::Volume | Effect::Isosurface => Payload::RGBA_VIEWZ,
        }
    }
    /// Images the effect outputs (concatenated in `Capture.image`).
    pub fn image_count(self) -> usize {
        if self == Effect::Dof {
            3
        } else {
            1
        }
    }
}

/// What is stored per captured fragment besides its window depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Payload {
    pub color: bool,
    /// Linear view depth with the facing in its sign.
    pub view_z: bool,
    pub normal: bool,
    pub object_id: bool,
}

impl Payload {
    pub const RGBA: Payload = Payload {
        color: true,
        view_z: false,
        normal: false,
        object_id: false,
    };
    pub const DEPTH: Payload = Payload {
        color: false,
        view_z: true,
        normal: false,
        object_id: false,
    };
    pub const DEPTH_NORMAL: Payload = Payload {
        color: false,
        view_z: true,
        normal: true,
        object_id: false,
    };
    pub const DEPTH_ID: Payload = Payload {
        color: false,
        view_z: false,
        normal: false,
        object_id: true,
    };
    pub const RGBA_VIEWZ: Payload = Payload {
        color: true,
        view_z: true,
        normal: false,
        object_id: false,
    };
    /// The "uber" configuration: everything stored.
    pub const ALL: Payload = Payload {
        color: true,
        view_z: true,
        normal: true,
        object_id: true,
    };

    /// The `payload` column value.
    pub fn name(self) -> &'static str {
        match self {
            Payload::RGBA => "rgba_depth",
            Payload::DEPTH => "depth",
            Payload::DEPTH_NORMAL => "depth_normal",
            Payload::DEPTH_ID => "depth_id",
            Payload::RGBA_VIEWZ => "rgba_viewz",
            Payload::ALL => "all",
            _ => "custom",
        }
    }
    /// True if every field `need` reads is stored.
    pub fn covers(self, need: Payload) -> bool {
        (self.color || !need.color)
            && (self.view_z || !need.view_z)
            && (self.normal || !need.normal)
            && (self.object_id || !need.object_id)
    }
}

/// One effect with its parameters, read from a point's axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EffectConfig {
    pub effect: Effect,
    pub sigma: f64,
    /// Thickness arithmetic: per-pair differences + Kahan (true) or the seed's ±z sum (false).
    pub stable_thickness: bool,
    pub csg_a: u32,
    pub csg_b: u32,
    pub dof_near: f64,
    pub dof_far: f64,
    pub iso_value: f64,
}

impl Default for EffectConfig {
    fn default() -> Self {
        EffectConfig {
            effect: Effect::Transparency,
            sigma: 1.0,
            stable_thickness: true,
            csg_a: 0,
            csg_b: 1,
            dof_near: 1.0,
            dof_far: 10.0,
            iso_value: 0.3,
        }
    }
}

/// The effect axis alone: every method of the `methods` study sweeps it (a method that folds no
/// effects gets a `skipped` row for each effect but transparency, never a silent gap).
pub const EFFECT: Axis = Axis::choice(
    cols::EFFECT,
    "the effect computed on the captured fragments",
    "transparency",
    EFFECTS,
);
pub const SIGMA: Axis = Axis::float(
    cols::SIGMA,
    "translucency/fresnel: extinction coefficient per world unit; volume: σ·s per unit of view depth",
    1.0,
    0.0,
    f64::MAX,
)
.only_when(&EFFECT, &["translucency", "fresnel", "volume"]);
pub const CSG_A: Axis = Axis::int(
    cols::CSG_A,
    "csg_*: object id of operand A",
    0,
    0,
    u32::MAX as i64,
)
.only_when(&EFFECT, &["csg_and", "csg_or", "csg_sub"]);
pub const CSG_B: Axis = Axis::int(
    cols::CSG_B,
    "csg_*: object id of operand B",
    1,
    0,
    u32::MAX as i64,
)
.only_when(&EFFECT, &["csg_and", "csg_or", "csg_sub"]);
pub const DOF_NEAR: Axis = Axis::float(
    cols::DOF_NEAR,
    "dof: view depth between foreground and midground (≤ dof_far)",
    1.0,
    0.0,
    f64::MAX,
)
.only_when(&EFFECT, &["dof"]);
pub const DOF_FAR: Axis = Axis::float(
    cols::DOF_FAR,
    "dof: view depth between midground and background (≥ dof_near)",
    10.0,
    0.0,
    f64::MAX,
)
.only_when(&EFFECT, &["dof"]);
pub const ISO_VALUE: Axis = Axis::float(
    cols::ISO_VALUE,
    "isosurface: the iso-value cut on the scalar (the colour's red channel)",
    0.3,
    f64::MIN,
    f64::MAX,
)
.only_when(&EFFECT, &["isosurface"]);
pub const THICKNESS: Axis = Axis::choice(
    cols::THICKNESS,
    "translucency/fresnel thickness arithmetic: naive (running ±z sum) or stable (Kahan pair differences)",
    "stable",
    &["naive", "stable"],
)
.only_when(&EFFECT, &["translucency", "fresnel"]);

/// Axes every effect-capable method reads: list them in its `axes()`, validate with
/// [`EffectConfig::from_point`].
pub const AXES: &[Axis] = &[
    EFFECT, SIGMA, CSG_A, CSG_B, DOF_NEAR, DOF_FAR, ISO_VALUE, THICKNESS,
];

impl EffectConfig {
    /// Reads the effect axes of a resolved point; the one rule a range cannot say
    /// (`dof_near ≤ dof_far`) is an error naming both values.
    pub fn from_point(point: &Point) -> Result<EffectConfig, InvalidPoint> {
        let effect = Effect::parse(&point.choice(&EFFECT))?;
        let (dof_near, dof_far) = (point.float(&DOF_NEAR), point.float(&DOF_FAR));
        if dof_near > dof_far {
            return Err(InvalidPoint::combination(format!(
                "dof bounds must satisfy dof_near ≤ dof_far, got {dof_near}, {dof_far}"
            )));
        }
        Ok(EffectConfig {
            effect,
            sigma: point.float(&SIGMA),
            stable_thickness: point.choice(&THICKNESS) == "stable",
            csg_a: point.int(&CSG_A) as u32,
            csg_b: point.int(&CSG_B) as u32,
            dof_near,
            dof_far,
            iso_value: point.float(&ISO_VALUE),
        })
    }

    /// The WGSL override constants of `methods/effects.wgsl` for this configuration.
    pub fn constants(&self) -> Vec<(&'static str, f64)> {
        let op = match self.effect {
            Effect::Csg(op) => op,
            _ => 0,
        };
        vec![
            ("EFFECT", self.effect.code() as f64),
            (
                "THICKNESS_STABLE",
                if self.stable_thickness { 1.0 } else { 0.0 },
            ),
            // f32 overrides: a σ beyond the f32 range is clamped to the largest f32 (σ·l then
            // saturates and T = 0, as the reference gives).
            ("SIGMA", self.sigma.min(f32::MAX as f64)),
            ("CSG_OP", op as f64),
            ("CSG_A", self.csg_a as f64),
            ("CSG_B", self.csg_b as f64),
            ("DOF_NEAR", self.dof_near.min(f32::MAX as f64)),
            ("DOF_FAR", self.dof_far.min(f32::MAX as f64)),
            (
                "ISO_VALUE",
                self.iso_value.clamp(f32::MIN as f64, f32::MAX as f64),
            ),
        ]
    }

    /// The f64 reference image(s) of this effect, judged against `expected` (all fragments or
    /// the k nearest); `image_count` images of `lists.pixels()` pixels, one after another.
    pub fn reference(
        &self,
        scene: &Scene,
        lists: &FragmentLists,
        expected: Expected,
    ) -> Vec<[f64; 4]> {
        let k = match expected {
            Expected::All => usize::MAX,
            Expected::FirstK(k) => k as usize,
        };
        let n = lists.pixels();
        let frags = |p: usize| lists.pixel(p).iter().take(k);
        match self.effect {
            // Per pixel, independent: in parallel (a 1024² truth of 16 layers is ~0.1 s on one core).
            Effect::Transparency => (0..n)
                .into_par_iter()
                .map(|p| mfx_reference::composite(frags(p)))
                .collect(),
            Effect::Translucency | Effect::Fresnel => {
                let dirs = (self.effect == Effect::Fresnel)
                    .then(|| view_dirs(scene, lists.width, lists.height));
                (0..n)
                    .into_par_iter()
                    .map(|p| {
                        let l: f64 = frags(p).map(signed_view_z).sum();
                        let x = (self.sigma * l).max(0.0);
                        let mut t = (-x).exp();
                        let mut a = -(-x).exp_m1();
                        if let Some(dirs) = &dirs {
                            t *= frags(p)
                                .map(|f| schlick_t(f.normal, dirs[p]))
                                .product::<f64>();
                            a = 1.0 - t;
                        }
                        [t, t, t, a]
                    })
                    .collect()
            }
            Effect::Csg(op) => (0..n)
                .into_par_iter()
                .map(|p| csg(frags(p), op, self.csg_a, self.csg_b))
                .collect(),
            Effect::Dof => {
                let mut out = vec![[0.0; 4]; 3 * n];
                for p in 0..n {
                    let mut filled = [false; 3];
                    for f in frags(p) {
                        let part = if f.view_z < self.dof_near {
                            0
                        } else if f.view_z < self.dof_far {
                            1
                        } else {
                            2
                        };
                        if !filled[part] {
                            filled[part] = true;
                            let a = f.color[3];
                            out[part * n + p] = [f.color[0] * a, f.color[1] * a, f.color[2] * a, a];
                        }
                    }
                }
                out
            }
            Effect::Volume => (0..n)
                .map(|p| mfx_reference::volume::volume(frags(p), self.sigma))
                .collect(),
            Effect::Isosurface => (0..n)
                .map(|p| mfx_reference::volume::isosurface(frags(p), self.iso_value))
                .collect(),
        }
    }
}

/// Entering (front face) subtracts the linear depth, leaving adds it.
pub fn signed_view_z(f: &RefFragment) -> f64 {
    if f.front_facing {
        -f.view_z
    } else {
        f.view_z
    }
}

/// Schlick transmittance at one interface (the WGSL `fold_schlick_t`; a zero normal → 1).
pub fn schlick_t(n: [f64; 3], dir: DVec3) -> f64 {
    let n = DVec3::from(n);
    let len2 = n.length_squared();
    if len2 <= 0.0 {
        return 1.0;
    }
    let c = (n.dot(dir).abs() / len2.sqrt()).min(1.0);
    1.0 - (1.0 - c).powi(5)
}

/// The world-space view ray direction through every pixel centre, computed like the WGSL
/// `fold_view_dir` (from the same f32 matrices, in f64).
pub fn view_dirs(scene: &Scene, width: u32, height: u32) -> Vec<DVec3> {
    let aspect = width as f64 / height as f64;
    let clip: DMat4 = scene.camera.clip_from_world_gpu(aspect).as_dmat4();
    let view: DMat4 = scene.camera.view().as_mat4().as_dmat4();
    let r = glam::DMat3::from_mat4(view);
    let rt = r.transpose();
    let p00 = (clip * rt.x_axis.extend(0.0)).x;
    let p11 = (clip * rt.y_axis.extend(0.0)).y;
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let ndc_x = (x as f64 + 0.5) / width as f64 * 2.0 - 1.0;
            let ndc_y = 1.0 - (y as f64 + 0.5) / height as f64 * 2.0;
            out.push((rt * DVec3::new(ndc_x / p00, ndc_y / p11, -1.0)).normalize());
        }
    }
    out
}

/// CPU twin of the WGSL fold's thickness arithmetic in f32, for fragments (linear depth,
/// front-facing) given nearest first: the seed's running sum of ±z (`stable = false`) or
/// per-pair differences of adjacent depths weighted by the objects open, Kahan-summed.
pub fn thickness_f32(frags: &[(f32, bool)], stable: bool) -> f32 {
    if !stable {
        return frags
            .iter()
            .map(|&(z, front)| if front { -z } else { z })
            .fold(0.0f32, |s, t| s + t);
    }
    let (mut sum, mut comp, mut last, mut open) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for (i, &(z, front)) in frags.iter().enumerate() {
        if i > 0 {
            let y = open * (z - last) - comp;
            let t = sum + y;
            comp = (t - sum) - y;
            sum = t;
        }
        last = z;
        open += if front { 1.0 } else { -1.0 };
    }
    sum - comp - open * last
}

fn csg_holds(bits: u32, op: u32) -> bool {
    let (a, b) = (bits & 1 != 0, bits & 2 != 0);
    match op {
        0 => a && b,
        1 => a || b,
        _ => a && !b,
    }
}

/// Front-to-back traversal toggling inside A / inside B; the first fragment at which the
/// boolean becomes true is the visible surface of the CSG result.
fn csg<'a>(frags: impl Iterator<Item = &'a RefFragment>, op: u32, a: u32, b: u32) -> [f64; 4] {
    let mut bits = 0u32;
    for f in frags {
        let before = csg_holds(bits, op);
        if f.object_id == a {
            bits ^= 1;
        }
        if f.object_id == b {
            bits ^= 2;
        }
        if !before && csg_holds(bits, op) {
            return [
                f.depth,
                (f.object_id == a) as u32 as f64,
                (f.object_id == b) as u32 as f64,
                1.0,
            ];
        }
    }
    [0.0; 4]
}

/// The reference image of `effect` with default parameters (kept for callers that only need
/// transparency); `None` for an unknown name or an effect that needs the scene (fresnel).
pub fn reference_image(
    effect: &str,
    lists: &FragmentLists,
    expected: Expected,
) -> Option<Vec<[f64; 4]>> {
    match effect {
        "transparency" => Some(match expected {
            Expected::All => lists.composite(),
            Expected::FirstK(k) => lists.composite_first(k as usize),
        }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scenarios::{ParamValue, Params};

    fn frag(z: f64, front: bool, id: u32) -> RefFragment {
        RefFragment {
            depth: z / 100.0,
            view_z: z,
            color: [0.5, 0.5, 0.5, 0.5],
            normal: [0.0, 0.0, 1.0],
            object_id: id,
            front_facing: front,
            prim: 0,
            depth_slope: 0.0,
        }
    }

    #[test]
    fn thickness_is_exit_minus_entry_for_nested_objects() {
        // Two nested objects: [1, 4] and [2, 3] → 3 + 1 = 4.
        let f = [
            frag(1.0, true, 0),
            frag(2.0, true, 1),
            frag(3.0, false, 1),
            frag(4.0, false, 0),
        ];
        assert_eq!(f.iter().map(signed_view_z).sum::<f64>(), 4.0);
    }

    #[test]
    fn thickness_arithmetic_stable_form_keeps_thin_nested_shells_far_away_the_naive_does_not() {
        // 64 nested shells at distance 1e6 with walls 0.1·k: the naive running sum reaches
        // 64e6 (ulp 4), the per-pair differences are exact (adjacent depths within a factor 2:
        // Sterbenz) and the Kahan sum of ≤ 128 positive terms stays within a few f32 ulps of l.
        let (n, d) = (64, 1e6f32);
        let mut frags: Vec<(f32, bool)> =
            (0..n).map(|k| (d - 0.1 * (n - k) as f32, true)).collect();
        frags.extend((0..n).rev().map(|k| (d + 0.1 * (n - k) as f32, false)));
        let exact: f64 = frags
            .iter()
            .map(|&(z, f)| if f { -(z as f64) } else { z as f64 })
            .sum();
        let stable = thickness_f32(&frags, true) as f64;
        let naive = thickness_f32(&frags, false) as f64;
        let bound = 4.0 * f32::EPSILON as f64 * exact;
        assert!(
            (stable - exact).abs() <= bound,
            "stable {stable} vs {exact}"
        );
        assert!(
            (naive - exact).abs() > 100.0 * bound,
            "naive {naive} vs {exact}: no cancellation shown"
        );
        // Unbalanced (the eye inside an object): both forms compute the same Σ ±z.
        let open = [(5.0f32, false), (6.0, true), (7.0, false)];
        assert_eq!(thickness_f32(&open, true), thickness_f32(&open, false));
    }

    #[test]
    fn csg_operations_pick_the_first_surface_of_the_result() {
        // A = [1, 3], B = [2, 4] along the ray.
        let f = [
            frag(1.0, true, 0),
            frag(2.0, true, 1),
            frag(3.0, false, 0),
            frag(4.0, false, 1),
        ];
        assert_eq!(
            csg(f.iter(), 0, 0, 1)[0],
            0.02,
            "A∩B starts where B is entered"
        );
        assert_eq!(csg(f.iter(), 1, 0, 1)[0], 0.01, "A∪B starts at A's front");
        assert_eq!(csg(f.iter(), 2, 0, 1)[0], 0.01, "A−B starts at A's front");
        // B first: A − B starts where B is left.
        let g = [
            frag(1.0, true, 1),
            frag(2.0, true, 0),
            frag(3.0, false, 1),
            frag(4.0, false, 0),
        ];
        assert_eq!(csg(g.iter(), 2, 0, 1), [0.03, 0.0, 1.0, 1.0]);
    }

    #[test]
    fn bad_effect_parameters_are_named() {
        let resolve = |p: Params| Point::resolve(AXES, &p);
        let e = resolve(Params::new().with("effect", ParamValue::Str("glow".into()))).unwrap_err();
        assert!(e[0].contains("glow"), "{e:?}");
        let e = resolve(Params::new().with("sigma", ParamValue::Float(-1.0))).unwrap_err();
        assert!(e[0].contains("sigma"), "{e:?}");
        let p = resolve(
            Params::new()
                .with("dof_near", ParamValue::Float(5.0))
                .with("dof_far", ParamValue::Float(1.0)),
        )
        .unwrap();
        let e = EffectConfig::from_point(&p).unwrap_err().to_string();
        assert!(e.contains("dof_near ≤ dof_far"), "{e}");
    }
}
