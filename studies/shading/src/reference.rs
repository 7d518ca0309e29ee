//! The brute-force f64 reference of the shading studies: every light at every pixel of a
//! G-buffer read back from the GPU (no culling, no threshold; a light contributes exactly 0
//! beyond its range, which is the model, not an approximation). Rows run in parallel (rayon);
//! the result does not depend on the thread count (each pixel sums its lights in index order).

use glam::DVec3;
use rayon::prelude::*;
use scenarios::LightKind;

use super::{spec_power, GBuffer, ShadeSetup, ViewLight, AMBIENT, LUM, SKY};

/// The sums of one pixel: what a deferred path composes and a light pre-pass stores.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Terms {
    pub diffuse: DVec3,
    pub specular: DVec3,
    /// Σ lum(contrib)·spec_term: the light pre-pass's alpha channel.
    pub spec_lum: f64,
}

/// Surface inputs of one pixel in f64.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub pos: DVec3,
    pub n: DVec3,
    pub smoothness: f64,
}

pub fn surface(setup: &ShadeSetup, gb: &GBuffer, i: usize) -> Surface {
    let x = (i % gb.width as usize) as u32;
    let y = (i / gb.width as usize) as u32;
    let n = gb.normal[i];
    Surface {
        pos: setup.view_pos(x, y, gb.depth[i]),
        n: DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64),
        smoothness: n[3] as f64,
    }
}

/// I·att of light `l` at point `p` (the quantity the culling threshold bounds), f64.
pub fn intensity_att(l: &ViewLight, p: DVec3) -> f64 {
    let (_, att) = light_vector(l, p);
    l.intensity() * att
}

/// (unit vector to the light, attenuation incl. spot factor) at `p`.
fn light_vector(l: &ViewLight, p: DVec3) -> (DVec3, f64) {
    let mut q = l.pos;
    if l.kind == LightKind::Line {
        let t = (p - q).dot(l.dir).clamp(0.0, l.length);
        q += l.dir * t;
    }
    let lv = q - p;
    let d2 = lv.length_squared();
    let r2 = l.range * l.range;
    if d2 >= r2 || d2 < 1e-12 {
        return (DVec3::ZERO, 0.0);
    }
    let d = d2.sqrt();
    let ld = lv / d;
    let x = 1.0 - d2 / r2;
    let mut att = x * x;
    if l.kind == LightKind::Spot {
        let c = l.cos_outer;
        let sf = ((-ld.dot(l.dir) - c) / (1.0 - c)).clamp(0.0, 1.0);
        att *= sf * sf;
    }
    (ld, att)
}

/// Adds one light; `diffuse_only`: its specular term is 0 (the model's diffuse-only flag).
fn add(
    t: &mut Terms,
    s: &Surface,
    v: DVec3,
    ld: DVec3,
    color: DVec3,
    att: f64,
    diffuse_only: bool,
) {
    let ndl = s.n.dot(ld);
    if ndl <= 0.0 || att <= 0.0 {
        return;
    }
    let contrib = color * (att * ndl);
    t.diffuse += contrib;
    if diffuse_only {
        return;
    }
    let (p, norm) = spec_power(s.smoothness);
    let h = (ld + v).normalize();
    let ndh = s.n.dot(h).max(0.0);
    let st = if ndh > 0.0 { norm * ndh.powf(p) } else { 0.0 };
    t.specular += contrib * st;
    t.spec_lum += (contrib.x * LUM[0] + contrib.y * LUM[1] + contrib.z * LUM[2]) * st;
}

/// All lights (and the sun) at one non-sky pixel.
pub fn terms(setup: &ShadeSetup, s: &Surface) -> Terms {
    let mut t = Terms::default();
    let v = (-s.pos).normalize();
    for l in &setup.lights {
        let (ld, att) = light_vector(l, s.pos);
        if att > 0.0 {
            add(&mut t, s, v, ld, l.color, att, l.diffuse_only);
        }
    }
    if let Some((d, c)) = setup.sun {
        // The shadow is looked up only where the sun faces the surface (as the GPU paths do);
        // its visibility is the sun's attenuation.
        let vis = match &setup.sun_shadow {
            Some(m) if s.n.dot(d) > 0.0 => m.visibility(s.pos).value,
            _ => 1.0,
        };
        add(&mut t, s, v, d, c, vis, false);
    }
    t
}

/// Pixels whose sun shadow look-up has a compare within `sun_shadow::TIE_EPS` of a tie (the
/// f32 GPU may decide it the other way; none without a shadow map).
pub fn sun_shadow_ties(setup: &ShadeSetup, gb: &GBuffer) -> Vec<bool> {
    (0..gb.pixels())
        .into_par_iter()
        .map(|i| match (&setup.sun_shadow, setup.sun) {
            (Some(m), Some((d, _))) if !gb.is_sky(i) => {
                let s = surface(setup, gb, i);
                s.n.dot(d) > 0.0 && m.visibility(s.pos).margin < super::sun_shadow::TIE_EPS
            }
            _ => false,
        })
        .collect()
}

/// The final pixel from its terms: albedo·(diffuse + ambient) + specular·Σspecular.
pub fn compose(gb: &GBuffer, i: usize, t: &Terms) -> [f64; 4] {
    if gb.is_sky(i) {
        return [SKY[0] as f64, SKY[1] as f64, SKY[2] as f64, 1.0];
    }
    let a = gb.albedo[i];
    let s = gb.spec[i];
    let mut out = [0.0; 4];
    for c in 0..3 {
        out[c] = a[c] as f64 * (t.diffuse[c] + AMBIENT[c] as f64) + s[c] as f64 * t.specular[c];
    }
    out[3] = 1.0;
    out
}

/// Per-pixel terms of the whole image (sky pixels: zero terms).
pub fn all_terms(setup: &ShadeSetup, gb: &GBuffer) -> Vec<Terms> {
    (0..gb.pixels())
        .into_par_iter()
        .map(|i| {
            if gb.is_sky(i) {
                Terms::default()
            } else {
                terms(setup, &surface(setup, gb, i))
            }
        })
        .collect()
}

/// The reference image (RGBA, A = 1).
pub fn shade(setup: &ShadeSetup, gb: &GBuffer) -> Vec<[f64; 4]> {
    let t = all_terms(setup, gb);
    image_from_terms(gb, &t)
}

pub fn image_from_terms(gb: &GBuffer, t: &[Terms]) -> Vec<[f64; 4]> {
    (0..gb.pixels()).map(|i| compose(gb, i, &t[i])).collect()
}

/// The light pre-pass image in f64 from the same terms: the light buffer keeps Σ diffuse RGB
/// and only the luminance of the specular sum (A); dielectrics use albedo·(D + ambient) +
/// specular·A, metals (albedo 0) specular·A·D/lum(D). Its distance from [`compose`] is the
/// specular colour the RGB+A packing loses, before any light-buffer format rounding.
pub fn prepass_compose(gb: &GBuffer, i: usize, t: &Terms) -> [f64; 4] {
    if gb.is_sky(i) {
        return [SKY[0] as f64, SKY[1] as f64, SKY[2] as f64, 1.0];
    }
    let a = gb.albedo[i];
    let s = gb.spec[i];
    let mut out = [0.0, 0.0, 0.0, 1.0];
    if a == [0.0; 3] {
        let l = t.diffuse.x * LUM[0] + t.diffuse.y * LUM[1] + t.diffuse.z * LUM[2];
        for c in 0..3 {
            let chroma = if l > 1e-6 { t.diffuse[c] / l } else { 0.0 };
            out[c] = s[c] as f64 * t.spec_lum * chroma;
        }
    } else {
        for c in 0..3 {
            out[c] = a[c] as f64 * (t.diffuse[c] + AMBIENT[c] as f64) + s[c] as f64 * t.spec_lum;
        }
    }
    out
}

pub fn prepass_image(gb: &GBuffer, t: &[Terms]) -> Vec<[f64; 4]> {
    (0..gb.pixels())
        .map(|i| prepass_compose(gb, i, &t[i]))
        .collect()
}
