//! mfx-shading, on the harness (`bench-core`): the shading studies' kinds ([`studies`]) and
//! the one light model of the shading studies (`deferred`, issue 6; `prepass`, issue 10), its
//! GPU twin (`light.wgsl`), the f64 brute-force reference (`reference.rs`), the G-buffer pass
//! (`gbuffer.rs`), the GPU shading paths (`gpu_paths.rs`), the BF3-style CPU tile path
//! (`cpu_tiled.rs`), the sun shadow map with its 8-tap filter (`sun_shadow.rs`) and the 2×MSAA
//! G-buffer's sample read-back and edge class (`msaa.rs`).
//!
//! Model (all in view space): lights have a finite range r; attenuation
//! att(d) = (1 − (d/r)²)² for d < r, else 0 (monotone in d, so a culling sphere is a proof);
//! spot lights multiply by saturate((cos∠ − cos_outer)/(1 − cos_outer))²; line (capsule) lights
//! use the segment's nearest point. Blinn-Phong, specular power p = 2^(1 + 10·smoothness) with
//! the (p + 8)/8 normalisation. Pixel = albedo·(Σ diffuse + ambient) + specular·Σ specular,
//! where the sun (if any) is one more light with att = 1 (with a sun shadow map: att = the
//! sun's visibility, `sun_shadow::ShadowMap::visibility`); sky pixels are the sky colour.
//! A light flagged *diffuse-only* (BF3) has a specular term of exactly 0 everywhere: it adds
//! to Σ diffuse only (`GpuLight::extra[1]` = 1 on the GPU and the CPU path,
//! `ViewLight::diffuse_only` in the reference); [`ShadeSetup::with_diffuse_only`] flags a
//! fraction of a scene's lights.
//!
//! Culling with an attenuation threshold τ: a light of peak channel intensity I is dropped
//! where I·att ≤ τ, i.e. beyond d_τ = r·sqrt(1 − sqrt(τ/I)); its culling sphere has that radius
//! (plus half the segment for a line light, around the segment's midpoint). τ = 0 culls only
//! where att is exactly 0, so the culled paths equal the unculled ones up to rounding.

pub mod cpu_tiled;
pub mod debug;
pub mod gbuffer;
pub mod gpu_paths;
pub mod msaa;
pub mod prepass;
pub mod reference;
pub mod studies;
pub mod sun_shadow;
#[cfg(test)]
mod tests;

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec3, DVec4, Mat4, Vec3};
use scenarios::{Light, LightKind, Scene};

pub const LIGHT_WGSL: &str = include_str!("light.wgsl");

/// Radiance of sky pixels (nothing rasterised there).
pub const SKY: [f32; 3] = [0.40, 0.55, 0.85];
/// Constant ambient term, times albedo.
pub const AMBIENT: [f32; 3] = [0.03, 0.03, 0.035];
/// Material id written where no geometry was rasterised (the sky mark).
pub const SKY_MATERIAL: u32 = u32::MAX;
/// Rec. 709 luminance: the light pre-pass stores specular as luminance only.
pub const LUM: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Light as the GPU reads it (matches `struct Light` in light.wgsl), in view space.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, Default)]
pub struct GpuLight {
    pub pos_range: [f32; 4],
    pub dir_kind: [f32; 4],
    pub color_cos: [f32; 4],
    pub cull: [f32; 4],
    /// Line length, diffuse-only flag (1: no specular term), 0, 0.
    pub extra: [f32; 4],
}

impl GpuLight {
    pub fn diffuse_only(&self) -> bool {
        self.extra[1] > 0.5
    }
}

/// Matches `struct Shade` in light.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug)]
pub struct ShadeUniform {
    pub view_from_clip: [[f32; 4]; 4],
    pub clip_from_view: [[f32; 4]; 4],
    pub viewport: [f32; 4],
    pub sun_dir: [f32; 4],
    pub sun_color: [f32; 4],
    pub sky: [f32; 4],
    pub ambient: [f32; 4],
    pub counts: [u32; 4],
    pub misc: [f32; 4],
    /// Sun shadow: view space → the map's clip space (orthographic).
    pub shadow_from_view: [[f32; 4]; 4],
    /// Map side in texels, compare bias, 1 when on, 0.
    pub shadow: [f32; 4],
}

/// A light transformed to view space, f64 (the reference's input; the GPU gets it as f32).
#[derive(Clone, Copy, Debug)]
pub struct ViewLight {
    pub kind: LightKind,
    pub pos: DVec3,
    pub dir: DVec3,
    pub color: DVec3,
    pub range: f64,
    pub cos_outer: f64,
    pub length: f64,
    /// No specular term (it is exactly 0): the light adds to Σ diffuse only.
    pub diffuse_only: bool,
}

impl ViewLight {
    /// Peak channel intensity I (the culling threshold compares I·att with τ).
    pub fn intensity(&self) -> f64 {
        self.color.max_element()
    }
    /// Radius beyond which I·att ≤ τ; `None` when the light is below τ everywhere.
    pub fn threshold_distance(&self, tau: f64) -> Option<f64> {
        if tau <= 0.0 {
            return Some(self.range);
        }
        let a = tau / self.intensity().max(1e-30);
        if a >= 1.0 {
            return None;
        }
        Some(self.range * (1.0 - a.sqrt()).max(0.0).sqrt())
    }
    /// Bounding sphere of the region where I·att > τ: (centre, radius), or `None` (nowhere).
    pub fn cull_sphere(&self, tau: f64) -> Option<(DVec3, f64)> {
        let d = self.threshold_distance(tau)?;
        Some(match self.kind {
            LightKind::Line => (
                self.pos + self.dir * (0.5 * self.length),
                d + 0.5 * self.length,
            ),
            _ => (self.pos, d),
        })
    }
}

/// Everything the shading paths and the reference share about one scene at one resolution.
#[derive(Clone, Debug)]
pub struct ShadeSetup {
    pub width: u32,
    pub height: u32,
    pub lights: Vec<ViewLight>,
    /// View-space direction to the sun and its colour.
    pub sun: Option<(DVec3, DVec3)>,
    /// Inverse of the projection (clip from view) in f64.
    pub view_from_clip: DMat4,
    pub clip_from_view: DMat4,
    pub clear_depth: f32,
    pub reversed_z: bool,
    /// The sun's shadow map (read back from the GPU), when the point shades with one.
    pub sun_shadow: Option<Arc<sun_shadow::ShadowMap>>,
}

fn v3(a: [f32; 3]) -> DVec3 {
    DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64)
}

impl ShadeSetup {
    pub fn new(scene: &Scene, width: u32, height: u32) -> ShadeSetup {
        let cam = &scene.camera;
        let aspect = width as f64 / height as f64;
        // The GPU rasterises with the f32 view matrix; the lights go through the same one.
        let view = cam.view().as_mat4().as_dmat4();
        let proj = cam.proj(aspect);
        let lights = scene
            .lights
            .iter()
            .map(|l: &Light| ViewLight {
                kind: l.kind,
                pos: view.transform_point3(v3(l.position)),
                dir: view.transform_vector3(v3(l.direction)).normalize_or_zero(),
                color: v3(l.color),
                range: l.range as f64,
                cos_outer: l.cos_outer as f64,
                length: l.length as f64,
                diffuse_only: false,
            })
            .collect();
        let sun = scene.sun.map(|s| {
            (
                view.transform_vector3(v3(s.direction)).normalize(),
                v3(s.color),
            )
        });
        ShadeSetup {
            width,
            height,
            lights,
            sun,
            view_from_clip: proj.inverse(),
            clip_from_view: proj,
            clear_depth: cam.clear_depth(),
            reversed_z: cam.reversed_z,
            sun_shadow: None,
        }
    }

    /// Flags `frac` (0..=1) of the lights diffuse-only, spread evenly over the light order:
    /// light i is flagged when ⌊(i+1)·frac⌋ > ⌊i·frac⌋ (0.5: every second light).
    pub fn with_diffuse_only(mut self, frac: f64) -> ShadeSetup {
        for (i, l) in self.lights.iter_mut().enumerate() {
            l.diffuse_only = ((i + 1) as f64 * frac).floor() > (i as f64 * frac).floor();
        }
        self
    }

    /// The sun shaded through `map` (its visibility scales the sun term).
    pub fn with_sun_shadow(mut self, map: Option<Arc<sun_shadow::ShadowMap>>) -> ShadeSetup {
        self.sun_shadow = map;
        self
    }

    /// View-space position of pixel (x, y) at depth `d` (f64).
    pub fn view_pos(&self, x: u32, y: u32, d: f32) -> DVec3 {
        let ndc_x = (x as f64 + 0.5) / self.width as f64 * 2.0 - 1.0;
        let ndc_y = 1.0 - (y as f64 + 0.5) / self.height as f64 * 2.0;
        let v = self.view_from_clip * DVec4::new(ndc_x, ndc_y, d as f64, 1.0);
        v.truncate() / v.w
    }

    /// The lights as the GPU reads them, with culling spheres for threshold `tau`.
    pub fn gpu_lights(&self, tau: f64) -> Vec<GpuLight> {
        self.lights
            .iter()
            .map(|l| {
                let kind = match l.kind {
                    LightKind::Point => 0.0,
                    LightKind::Spot => 1.0,
                    LightKind::Line => 2.0,
                };
                // Widen the sphere by a hair so f32 rounding in the cull never drops a light
                // the model says reaches the tile (the proof is about the f64 model).
                let cull = match l.cull_sphere(tau) {
                    Some((c, r)) => [
                        c.x as f32,
                        c.y as f32,
                        c.z as f32,
                        (r * 1.0001 + 1e-4) as f32,
                    ],
                    None => [0.0, 0.0, 0.0, -1.0],
                };
                GpuLight {
                    pos_range: [
                        l.pos.x as f32,
                        l.pos.y as f32,
                        l.pos.z as f32,
                        l.range as f32,
                    ],
                    dir_kind: [l.dir.x as f32, l.dir.y as f32, l.dir.z as f32, kind],
                    color_cos: [
                        l.color.x as f32,
                        l.color.y as f32,
                        l.color.z as f32,
                        l.cos_outer as f32,
                    ],
                    cull,
                    extra: [
                        l.length as f32,
                        if l.diffuse_only { 1.0 } else { 0.0 },
                        0.0,
                        0.0,
                    ],
                }
            })
            .collect()
    }

    pub fn uniform(&self, tau: f64, tiles: (u32, u32), tile_size: u32) -> ShadeUniform {
        let (sd, sc, has) = match self.sun {
            Some((d, c)) => (d.as_vec3(), c.as_vec3(), 1.0),
            None => (Vec3::ZERO, Vec3::ZERO, 0.0),
        };
        ShadeUniform {
            view_from_clip: self.view_from_clip.as_mat4().to_cols_array_2d(),
            clip_from_view: self.clip_from_view.as_mat4().to_cols_array_2d(),
            viewport: [
                self.width as f32,
                self.height as f32,
                1.0 / self.width as f32,
                1.0 / self.height as f32,
            ],
            sun_dir: [sd.x, sd.y, sd.z, has],
            sun_color: [sc.x, sc.y, sc.z, 0.0],
            sky: [SKY[0], SKY[1], SKY[2], 1.0],
            ambient: [AMBIENT[0], AMBIENT[1], AMBIENT[2], 0.0],
            counts: [self.lights.len() as u32, tiles.0, tiles.1, tile_size],
            misc: [
                tau as f32,
                self.clear_depth,
                if self.reversed_z { 1.0 } else { 0.0 },
                0.0,
            ],
            shadow_from_view: match &self.sun_shadow {
                Some(m) => m.shadow_from_view.as_mat4().to_cols_array_2d(),
                None => Mat4::IDENTITY.to_cols_array_2d(),
            },
            shadow: match &self.sun_shadow {
                Some(m) => [m.size as f32, sun_shadow::COMPARE_BIAS as f32, 1.0, 0.0],
                None => [1.0, 0.0, 0.0, 0.0],
            },
        }
    }

    /// f32 view_from_clip as the GPU and the CPU tile path use it.
    pub fn view_from_clip_f32(&self) -> Mat4 {
        self.view_from_clip.as_mat4()
    }
}

/// A G-buffer read back from the GPU, decoded to f32 exactly as the shaders see it.
#[derive(Clone, Debug)]
pub struct GBuffer {
    pub width: u32,
    pub height: u32,
    pub depth: Vec<f32>,
    /// View-space normal xyz, smoothness in w.
    pub normal: Vec<[f32; 4]>,
    pub albedo: Vec<[f32; 3]>,
    pub spec: Vec<[f32; 3]>,
    pub material: Vec<u32>,
}

impl GBuffer {
    pub fn is_sky(&self, i: usize) -> bool {
        self.material[i] == SKY_MATERIAL
    }
    pub fn pixels(&self) -> usize {
        (self.width * self.height) as usize
    }
}

/// Specular power and its normalisation for a smoothness.
pub fn spec_power(smoothness: f64) -> (f64, f64) {
    let p = (1.0 + 10.0 * smoothness).exp2();
    (p, (p + 8.0) / 8.0)
}

/// Per-pixel classification feature bits (Split/Second style; see `gpu_paths` and the study).
pub mod class {
    pub const SKY: u32 = 1;
    pub const GEOM: u32 = 2;
    pub const SUN: u32 = 4;
    pub const SPEC: u32 = 8;
    /// Sun shadow fade (penumbra): some sun-facing pixel's 8-tap footprint straddles a shadow
    /// edge, so the tile's shader runs the filter (`sun_shadow`); set only with a shadow map.
    pub const FADE: u32 = 16;
    /// MSAA edge (2×MSAA G-buffer only): some pixel's samples differ in what the shading reads
    /// (depth, normal + smoothness, albedo, specular, material), so the tile's shader shades
    /// every sample and averages; elsewhere one sample is the pixel (`msaa`).
    pub const EDGE: u32 = 32;
    /// Classification ids: every OR of the bits above.
    pub const IDS: u32 = 64;
    pub const TILE: u32 = 4;
    /// Ids a tile can have: sky and/or geometry; sun and specular only with geometry; fade
    /// only with sun; edge only with geometry (two sky samples are equal).
    pub fn valid(id: u32) -> bool {
        id & (SKY | GEOM) != 0
            && (id & (SUN | SPEC) == 0 || id & GEOM != 0)
            && (id & FADE == 0 || id & SUN != 0)
            && (id & EDGE == 0 || id & GEOM != 0)
    }
    pub fn names(id: u32) -> String {
        let mut v = vec![];
        for (b, n) in [
            (SKY, "sky"),
            (GEOM, "geom"),
            (SUN, "sun"),
            (SPEC, "spec"),
            (FADE, "fade"),
            (EDGE, "edge"),
        ] {
            if id & b != 0 {
                v.push(n);
            }
        }
        if v.is_empty() {
            "empty".into()
        } else {
            v.join("+")
        }
    }
}

/// The feature bits of one pixel of a G-buffer (the CPU twin of `classify` in the GPU path).
pub fn pixel_class(setup: &ShadeSetup, gb: &GBuffer, i: usize) -> u32 {
    pixel_class_margin(setup, gb, i).0
}

/// [`pixel_class`] and how far its fade decision is from a tie (infinite without one): within
/// `sun_shadow::TIE_EPS` the f32 GPU may decide the other way.
pub fn pixel_class_margin(setup: &ShadeSetup, gb: &GBuffer, i: usize) -> (u32, f64) {
    if gb.is_sky(i) {
        return (class::SKY, f64::INFINITY);
    }
    let mut bits = class::GEOM;
    let mut margin = f64::INFINITY;
    if let Some((d, _)) = setup.sun {
        let n = gb.normal[i];
        if (n[0] * d.x as f32 + n[1] * d.y as f32 + n[2] * d.z as f32) > 0.0 {
            bits |= class::SUN;
            if let Some(m) = &setup.sun_shadow {
                let x = (i % gb.width as usize) as u32;
                let y = (i / gb.width as usize) as u32;
                let f = m.fade(m.coord(setup.view_pos(x, y, gb.depth[i])));
                margin = f.margin;
                if f.value > 0.5 {
                    bits |= class::FADE;
                }
            }
        }
    }
    if gb.spec[i].iter().any(|&s| s > 0.0) {
        bits |= class::SPEC;
    }
    (bits, margin)
}

/// The six planes (inward normals, n·x + w ≥ 0 inside) of the frustum through the pixel
/// rectangle [x0,x1]×[y0,y1] between view distances zmin..zmax; f32 like the GPU's.
pub fn tile_planes(
    vfc: &Mat4,
    size: (u32, u32),
    rect: [f32; 4],
    zmin: f32,
    zmax: f32,
) -> [[f32; 4]; 6] {
    let ray = |x: f32, y: f32| -> Vec3 {
        let ndc_x = x / size.0 as f32 * 2.0 - 1.0;
        let ndc_y = 1.0 - y / size.1 as f32 * 2.0;
        let v = *vfc * glam::Vec4::new(ndc_x, ndc_y, 0.5, 1.0);
        v.truncate() / v.w
    };
    let c = [
        ray(rect[0], rect[1]),
        ray(rect[2], rect[1]),
        ray(rect[2], rect[3]),
        ray(rect[0], rect[3]),
    ];
    let mid = c[0] + c[1] + c[2] + c[3];
    let mut out = [[0.0f32; 4]; 6];
    for i in 0..4 {
        let mut n = c[i].cross(c[(i + 1) % 4]).normalize();
        if n.dot(mid) < 0.0 {
            n = -n;
        }
        out[i] = [n.x, n.y, n.z, 0.0];
    }
    out[4] = [0.0, 0.0, -1.0, -zmin];
    out[5] = [0.0, 0.0, 1.0, zmax];
    out
}

/// True when the sphere `cull` (centre xyz, radius w; w < 0: nowhere) misses the region.
pub fn sphere_outside(planes: &[[f32; 4]; 6], cull: [f32; 4]) -> bool {
    if cull[3] < 0.0 {
        return true;
    }
    planes
        .iter()
        .any(|p| p[0] * cull[0] + p[1] * cull[1] + p[2] * cull[2] + p[3] < -cull[3])
}

/// This crate's study kinds (the binary's table, `mfx::STUDIES`, lists them with the others).
pub const STUDIES: &[&dyn bench_core::study::Study] = &[
    &studies::deferred::DeferredStudy,
    &studies::prepass::PrepassStudy,
];
