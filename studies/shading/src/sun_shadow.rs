//! The sun shadow of the deferred study (`sun_shadow = taps8`, issue 30): Split/Second's
//! expensive soft-shadow class (GEG2 ch. 4, the seed's `CascadeShadowMap_8Taps`). One
//! orthographic depth map of the scene from the sun (square, [`map_size`] texels, fitted to the
//! scene's bounding sphere), read with an 8-tap filter (each tap a bilinear blend of 4 texel
//! compares: 32 loads) on the sun term only. The *fade* class bit marks a pixel where the depths
//! within ±[`REACH`] texels of its own texel (a square holding every texel the filter reads) lie
//! on both sides of its depth: only there can the compares disagree; elsewhere one compare gives
//! exactly the filter's 0 or 1. Classifying costs one load of that texel's precomputed range.
//! The uber-shader runs the filter on every sun-facing pixel; the classified path only in fade
//! tiles. The map's slope-scaled raster bias ([`SLOPE_BIAS`]) covers a plane's depth change over
//! the reach, so a lit plane is fully lit (not fade) and free of acne.
//!
//! The map and its range map are built once per prepare (a static sun and scene: a cached
//! shadow map), outside the timed frame, and are the same for every path; the ranges are
//! computed here on the CPU from the read-back map, so the GPU and the CPU classify against the
//! same numbers. [`ShadowMap`] is the f64 twin of `sun_shadow.wgsl` the reference shades with.

use std::sync::Arc;

use glam::{DMat4, DVec3};
use scenarios::Scene;
use wgpu::util::DeviceExt;

use bench_core::gpu::{read_texture, Gpu};
use bench_core::gpu_scene::{camera_uniform, AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::shader;
use bench_core::study::InvalidPoint;
use bench_core::Result;

pub const WGSL: &str = include_str!("sun_shadow.wgsl");
/// Half-side of the square whose depth range decides the fade class (`SHADOW_REACH` in the
/// WGSL): the filter reads texels floor(c) − 2 ..= floor(c) + 2; one more for f32 rounding.
pub const REACH: i64 = 3;
/// The map's slope-scaled raster bias, in multiples of the largest depth slope per texel: a
/// plane's depth changes by at most 2·REACH slopes across the reach square, and by half a
/// texel's worth more between the receiver and its texel centre.
pub const SLOPE_BIAS: f32 = 8.0;
/// Texel offsets of the 8 taps (`SHADOW_TAPS` in the WGSL).
pub const TAPS: [[f64; 2]; 8] = [
    [-1.5, -0.5],
    [1.5, 0.5],
    [-0.5, 1.5],
    [0.5, -1.5],
    [-1.5, 0.5],
    [1.5, -0.5],
    [0.5, 1.5],
    [-0.5, -1.5],
];
/// Subtracted from the receiver's shadow depth before comparing (map depth spans the scene's
/// bounding-sphere diameter; with the map's slope-scaled raster bias it keeps lit faces free of
/// self-shadowing acne).
pub const COMPARE_BIAS: f64 = 2e-3;
/// A compare whose two sides are closer than this (map depth units) or a receiver within this
/// many texels of a texel edge is a *tie*: f32 and f64 position reconstruction may decide it
/// differently (relative f32 error ~1e-7 on coordinates of order 1–2000).
pub const TIE_EPS: f64 = 2e-5;
pub const TIE_TEXELS: f64 = 2e-3;

/// Whether a deferred point shades the sun with a shadow map (axis `sun_shadow`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Mode {
    #[default]
    Off,
    Taps8,
}

impl Mode {
    pub const NAMES: &'static [&'static str] = &["off", "taps8"];
    pub fn parse(s: &str) -> std::result::Result<Mode, InvalidPoint> {
        match s {
            "off" => Ok(Mode::Off),
            "taps8" => Ok(Mode::Taps8),
            o => Err(InvalidPoint::value(
                "sun_shadow",
                format!("'{o}'"),
                "is not one of off, taps8",
            )),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Mode::Off => "off",
            Mode::Taps8 => "taps8",
        }
    }
}

/// Shadow map side for an image: the next power of two of its larger side, 256..=2048 (about
/// one texel per pixel across the scene; 2048² at 1280×720).
pub fn map_size(width: u32, height: u32) -> u32 {
    width.max(height).next_power_of_two().clamp(256, 2048)
}

/// The sun's clip from world: orthographic, looking along −(direction to the sun), its box the
/// scene's bounding sphere (depth 0 nearest the sun). `None` without a sun.
pub fn sun_clip_from_world(scene: &Scene) -> Option<DMat4> {
    let sun = scene.sun?;
    let (lo, hi) = scene.mesh.bounds();
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let c = (lo + hi) * 0.5;
    let r = ((hi - lo).length() * 0.5).max(1e-3);
    let d = DVec3::from(sun.direction.map(|x| x as f64)).normalize();
    let up = if d.y.abs() > 0.99 { DVec3::X } else { DVec3::Y };
    let view = DMat4::look_at_rh(c + d * (2.0 * r), c, up);
    Some(DMat4::orthographic_rh(-r, r, -r, r, r, 3.0 * r) * view)
}

/// The read-back sun depth map, its block min/max and the view-to-shadow transform: everything
/// the CPU twin needs, f64 arithmetic on the map's f32 depths.
#[derive(Clone, Debug)]
pub struct ShadowMap {
    pub size: u32,
    pub depth: Vec<f32>,
    /// Per texel, (min, max) depth of the texels within ±REACH (clamped to the map), row-major.
    pub range: Vec<[f32; 2]>,
    pub shadow_from_view: DMat4,
}

/// A filtered look-up and the smallest distance of any of its compares from a tie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookup {
    pub value: f64,
    pub margin: f64,
}

impl ShadowMap {
    pub fn new(size: u32, depth: Vec<f32>, shadow_from_view: DMat4) -> ShadowMap {
        let range = range_of(&depth, size);
        ShadowMap {
            size,
            depth,
            range,
            shadow_from_view,
        }
    }

    /// Texel coordinates and compare depth of a view-space point (`shadow_coord`).
    pub fn coord(&self, pos: DVec3) -> DVec3 {
        let s = self.shadow_from_view.project_point3(pos);
        let n = self.size as f64;
        DVec3::new(
            (s.x * 0.5 + 0.5) * n,
            (0.5 - s.y * 0.5) * n,
            s.z - COMPARE_BIAS,
        )
    }

    fn texel_of(&self, v: f64) -> i64 {
        v.floor().clamp(-16.0, self.size as f64 + 16.0) as i64
    }

    fn texel(&self, x: i64, y: i64) -> f64 {
        let n = self.size as i64 - 1;
        let (x, y) = (x.clamp(0, n), y.clamp(0, n));
        self.depth[(y * self.size as i64 + x) as usize] as f64
    }

    fn lit(&self, x: i64, y: i64, z: f64, margin: &mut f64) -> f64 {
        let d = self.texel(x, y);
        *margin = margin.min((z - d).abs());
        if z <= d {
            1.0
        } else {
            0.0
        }
    }

    /// One compare at the receiver's texel (`shadow_hard`).
    pub fn hard(&self, c: DVec3) -> Lookup {
        let mut margin = f64::INFINITY;
        let value = self.lit(self.texel_of(c.x), self.texel_of(c.y), c.z, &mut margin);
        Lookup { value, margin }
    }

    /// The 8-tap bilinear filter (`shadow_filter8`), in [0, 1].
    pub fn filter8(&self, c: DVec3) -> Lookup {
        let mut margin = f64::INFINITY;
        let mut sum = 0.0;
        for t in TAPS {
            let (tx, ty) = (c.x + t[0] - 0.5, c.y + t[1] - 0.5);
            let (ix, iy) = (tx.floor(), ty.floor());
            let (fx, fy) = (tx - ix, ty - iy);
            let (ix, iy) = (self.texel_of(ix), self.texel_of(iy));
            let a = self.lit(ix, iy, c.z, &mut margin);
            let b = self.lit(ix + 1, iy, c.z, &mut margin);
            let d = self.lit(ix, iy + 1, c.z, &mut margin);
            let e = self.lit(ix + 1, iy + 1, c.z, &mut margin);
            let top = a + (b - a) * fx;
            let bottom = d + (e - d) * fx;
            sum += top + (bottom - top) * fy;
        }
        Lookup {
            value: sum * 0.125,
            margin,
        }
    }

    /// The fade class rule (`shadow_fade`): value 1 when the depths around the receiver's texel
    /// straddle c.z. Margin 0 also where the receiver is within TIE_TEXELS of a texel edge and
    /// the texel across it decides otherwise (f32 may pick that texel).
    pub fn fade(&self, c: DVec3) -> Lookup {
        let n = self.size as i64 - 1;
        let (ix, iy) = (
            self.texel_of(c.x).clamp(0, n),
            self.texel_of(c.y).clamp(0, n),
        );
        let straddles = |x: i64, y: i64| {
            let m = self.range[(y.clamp(0, n) * self.size as i64 + x.clamp(0, n)) as usize];
            !(c.z <= m[0] as f64 || c.z > m[1] as f64)
        };
        let m = self.range[(iy * self.size as i64 + ix) as usize];
        let mut margin = (c.z - m[0] as f64).abs().min((c.z - m[1] as f64).abs());
        let fade = straddles(ix, iy);
        // The texel across a near edge: −1 just above an integer, +1 just below, 0 far from one.
        let across = |v: f64| {
            let r = v - v.round();
            match () {
                _ if r.abs() >= TIE_TEXELS => 0,
                _ if r >= 0.0 => -1,
                _ => 1,
            }
        };
        let (ax, ay) = (across(c.x), across(c.y));
        for (dx, dy) in [(ax, 0), (0, ay), (ax, ay)] {
            if (dx, dy) != (0, 0) && straddles(ix + dx, iy + dy) != fade {
                margin = 0.0;
            }
        }
        Lookup {
            value: if fade { 1.0 } else { 0.0 },
            margin,
        }
    }

    /// The sun's visibility at a view-space point as a path shades it: the filter where the
    /// fade class says the compares can disagree, else the one compare (they are equal there).
    pub fn visibility(&self, pos: DVec3) -> Lookup {
        let c = self.coord(pos);
        let f = self.fade(c);
        let v = if f.value > 0.5 {
            self.filter8(c)
        } else {
            self.hard(c)
        };
        Lookup {
            value: v.value,
            margin: v.margin.min(f.margin),
        }
    }
}

/// Per texel of a `size`² map, (min, max) depth within ±REACH texels (clamped to the map):
/// a box filter of min and max, separable (rows, then columns).
pub fn range_of(depth: &[f32], size: u32) -> Vec<[f32; 2]> {
    let n = size as i64;
    let at = |x: i64, y: i64| (y * n + x) as usize;
    let mut rows = vec![[0.0f32; 2]; depth.len()];
    for y in 0..n {
        for x in 0..n {
            let (mut mn, mut mx) = (f32::INFINITY, f32::NEG_INFINITY);
            for k in (x - REACH).max(0)..=(x + REACH).min(n - 1) {
                mn = mn.min(depth[at(k, y)]);
                mx = mx.max(depth[at(k, y)]);
            }
            rows[at(x, y)] = [mn, mx];
        }
    }
    let mut out = vec![[0.0f32; 2]; depth.len()];
    for y in 0..n {
        for x in 0..n {
            let (mut mn, mut mx) = (f32::INFINITY, f32::NEG_INFINITY);
            for k in (y - REACH).max(0)..=(y + REACH).min(n - 1) {
                mn = mn.min(rows[at(x, k)][0]);
                mx = mx.max(rows[at(x, k)][1]);
            }
            out[at(x, y)] = [mn, mx];
        }
    }
    out
}

/// The GPU side: the map texture, its per-texel range, and the read-back twin.
pub struct SunShadow {
    pub texture: wgpu::Texture,
    pub range: wgpu::Buffer,
    pub map: Arc<ShadowMap>,
}

impl SunShadow {
    /// Renders the sun's depth map of `gscene` (untimed), reads it back and uploads its block
    /// ranges. `None` when the scene has no sun.
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        gscene: &GpuScene,
        alloc: &mut AllocCounter,
    ) -> Result<Option<SunShadow>> {
        let Some(clip_from_world) = sun_clip_from_world(scene) else {
            return Ok(None);
        };
        let d = &gpu.device;
        let size = map_size(gscene.width, gscene.height);
        let texture = alloc.texture(
            gpu,
            "sun shadow map",
            size,
            size,
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let mut cam = camera_uniform(scene, size, size);
        cam.clip_from_world = clip_from_world.as_mat4().to_cols_array_2d();
        let camera = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sun camera"),
            contents: bytemuck::bytes_of(&cam),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let module = shader(gpu, "sun shadow map", "");
        let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("sun camera"),
            entries: &[bench_core::gpu_util::camera_entry(0)],
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sun camera"),
            layout: &bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            }],
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("sun shadow map"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let layouts = GpuScene::layouts(Attrs::POSITION_ONLY);
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("sun shadow map"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_position"),
                compilation_options: Default::default(),
                buffers: &layouts.iter().map(|l| Some(l.clone())).collect::<Vec<_>>(),
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                // Slope-scaled: a lit face stays nearer the sun than its map over the reach.
                bias: wgpu::DepthBiasState {
                    constant: 2,
                    slope_scale: SLOPE_BIAS,
                    clamp: 0.0,
                },
            }),
            multisample: Default::default(),
            fragment: None,
            multiview_mask: None,
            cache: None,
        });
        let view = texture.create_view(&Default::default());
        let mut enc = d.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("sun shadow map"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            gscene.draw(&mut pass, Attrs::POSITION_ONLY);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.wait()?;
        let bytes = read_texture(gpu, &texture, 4, wgpu::TextureAspect::DepthOnly)?;
        let depth: Vec<f32> = bytemuck::cast_slice(&bytes).to_vec();
        // The paths shade in the camera's view space (the f32 view matrix the G-buffer used).
        let view_from_world = scene.camera.view().as_mat4().as_dmat4();
        let map = ShadowMap::new(size, depth, clip_from_world * view_from_world.inverse());
        let range = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sun shadow range"),
            contents: bytemuck::cast_slice(&map.range),
            usage: wgpu::BufferUsages::STORAGE,
        });
        alloc.bytes += range.size();
        Ok(Some(SunShadow {
            texture,
            range,
            map: Arc::new(map),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16² map, left half at depth 0.2 (an occluder), right half 1.0 (nothing).
    fn step_map() -> ShadowMap {
        let depth = (0..256)
            .map(|i| if i % 16 < 8 { 0.2 } else { 1.0 })
            .collect();
        ShadowMap::new(16, depth, DMat4::IDENTITY)
    }

    #[test]
    fn filter_is_exact_away_from_the_edge_and_fractional_on_it() {
        let m = step_map();
        let z = 0.5;
        // Texel 2 and 13: the footprint (±3 texels) stays on one side of the edge at x = 8.
        assert_eq!(m.filter8(DVec3::new(2.5, 8.5, z)).value, 0.0);
        assert_eq!(m.filter8(DVec3::new(13.5, 8.5, z)).value, 1.0);
        assert_eq!(m.fade(DVec3::new(13.5, 8.5, z)).value, 0.0);
        let on_edge = DVec3::new(8.0, 8.5, z);
        let f = m.filter8(on_edge).value;
        assert!(f > 0.0 && f < 1.0, "penumbra {f}");
        assert_eq!(m.fade(on_edge).value, 1.0);
    }

    #[test]
    fn range_holds_min_and_max_within_reach() {
        let m = step_map();
        // Column 4: columns 1..=7, all occluder; column 5: 2..=8, across the edge at 8.
        assert_eq!(m.range[8 * 16 + 4], [0.2, 0.2]);
        assert_eq!(m.range[8 * 16 + 5], [0.2, 1.0]);
        assert_eq!(m.range[8 * 16 + 11], [1.0, 1.0]);
        assert_eq!(m.range[0], [0.2, 0.2]);
    }
}
