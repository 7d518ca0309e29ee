//! The CPU twin of `shade_point` in shadows.wgsl (vello's habit): the same rule, in the
//! shader's shape and in f32, run on the maps the GPU built. A test compares the two pixel by
//! pixel, so an implementation slip (region, stride, bias, backprojection) is told apart from
//! the algorithm's own error against the ray tracer.

use glam::{Mat4, Vec2, Vec4};

use bytemuck::{Pod, Zeroable};

const FAR: f32 = 1.0e30;

/// Matches `struct Light` in shadows.wgsl: the GPU pass (layered.rs) fills it, the twin reads
/// it back (here, so the twin does not import the pass that imports the twin).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct LightUniform {
    pub view_from_world: [[f32; 4]; 4],
    pub map: [f32; 4],
    pub cfg: [u32; 4],
    pub bias: [f32; 4],
    pub level_offset: [[u32; 4]; 4],
}

/// The GPU's shading inputs after a frame: the light uniform, the packed depth and slope
/// texels (row-major, r×r) and the min pyramid (all levels, as the GPU stores them).
pub struct Maps {
    pub light: LightUniform,
    pub depth: Vec<[f32; 4]>,
    pub slope: Vec<[f32; 4]>,
    pub pyramid: Vec<f32>,
}

impl Maps {
    fn level_offset(&self, l: u32) -> u32 {
        self.light.level_offset[(l / 4) as usize][(l % 4) as usize]
    }

    fn level_size(&self, l: u32) -> u32 {
        let r = self.light.map[0] as u32;
        (r + (1 << l) - 1) >> l
    }

    fn hsm_min(&self, lo: Vec2, hi: Vec2) -> f32 {
        let top = self.light.bias[2] as u32;
        let w = (hi.x - lo.x).max(hi.y - lo.y);
        let lvl = (w.max(1.0).log2().ceil().max(0.0) as u32).min(top);
        let size = self.level_size(lvl) as i32;
        let scale = (1u32 << lvl) as f32;
        let a = (lo / scale).floor().as_ivec2();
        let b = (hi / scale).floor().as_ivec2();
        let mut m = FAR;
        for y in a.y..=b.y.min(a.y + 1) {
            for x in a.x..=b.x.min(a.x + 1) {
                if x >= 0 && y >= 0 && x < size && y < size {
                    m = m.min(
                        self.pyramid[(self.level_offset(lvl) + (y * size + x) as u32) as usize],
                    );
                }
            }
        }
        m
    }

    fn layer_bias(&self, d: [f32; 4], s: [f32; 4], j: usize) -> f32 {
        let (gscale, gmax) = (self.light.bias[0], self.light.bias[1]);
        let mut mid = gmax;
        if j + 1 < self.light.cfg[0] as usize && d[j + 1] < FAR * 0.5 {
            mid = 0.5 * (d[j + 1] - d[j]);
        }
        if self.light.bias[3] > 0.0 {
            mid = mid.min(self.light.bias[3]);
        }
        let slope = (gscale * s[j]).min(gmax);
        match self.light.cfg[2] {
            0 => mid,
            1 => slope,
            _ => mid.max(slope),
        }
    }

    /// The width in texels of the region `shade_point` samples for `g` (0 where it returns lit
    /// before sampling), or None where it cannot be evaluated: what the HSM shrinks (§5.3.2).
    pub fn search_width(&self, g: [f32; 4]) -> Option<f32> {
        if g[3] == 0.0 {
            return None;
        }
        let [r, n, f, l] = self.light.map;
        let pv = Mat4::from_cols_array_2d(&self.light.view_from_world)
            * Vec4::new(g[0], g[1], g[2], 1.0);
        let p = Vec2::new(pv.x, pv.y);
        let z = -pv.z;
        let ndc = p * f / z;
        if z <= n || ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 {
            return None;
        }
        let c = Vec2::new((ndc.x * 0.5 + 0.5) * r, (0.5 - ndc.y * 0.5) * r);
        let kscale = r * l * f * 0.5;
        let mut zmin = n;
        if self.light.cfg[3] & 2 != 0 {
            zmin = self.pyramid[self.level_offset(self.light.bias[2] as u32) as usize];
        }
        if self.light.cfg[3] & 1 != 0 {
            for _ in 0..2 {
                if zmin >= z {
                    break;
                }
                let kr = (kscale * (1.0 / zmin - 1.0 / z)).min(2.0 * r);
                zmin = zmin.max(self.hsm_min(c - 0.5 * kr, c + 0.5 * kr));
            }
        }
        if zmin >= z {
            return Some(0.0);
        }
        Some((kscale * (1.0 / zmin - 1.0 / z)).min(2.0 * r))
    }

    /// Visibility of the light from G-buffer point `g` (w = 0: no surface), or −1.
    pub fn shade_point(&self, g: [f32; 4]) -> f32 {
        if g[3] == 0.0 {
            return -1.0;
        }
        let [r, n, f, l] = self.light.map;
        let pv = Mat4::from_cols_array_2d(&self.light.view_from_world)
            * Vec4::new(g[0], g[1], g[2], 1.0);
        let p = Vec2::new(pv.x, pv.y);
        let z = -pv.z;
        if z <= n {
            return -1.0;
        }
        let ndc = p * f / z;
        if ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 {
            return -1.0;
        }
        let c = Vec2::new((ndc.x * 0.5 + 0.5) * r, (0.5 - ndc.y * 0.5) * r);
        let kscale = r * l * f * 0.5;
        let mut zmin = n;
        if self.light.cfg[3] & 2 != 0 {
            zmin = self.pyramid[self.level_offset(self.light.bias[2] as u32) as usize];
            if zmin >= z {
                return 1.0;
            }
        }
        if self.light.cfg[3] & 1 != 0 {
            for _ in 0..2 {
                let kr = (kscale * (1.0 / zmin - 1.0 / z)).min(2.0 * r);
                zmin = zmin.max(self.hsm_min(c - 0.5 * kr, c + 0.5 * kr));
                if zmin >= z {
                    return 1.0;
                }
            }
        }
        let kr = (kscale * (1.0 / zmin - 1.0 / z)).min(2.0 * r);
        let x0 = (c - 0.5 * kr).floor().as_ivec2();
        let x1 = (c + 0.5 * kr).ceil().as_ivec2();
        let count = (x1 - x0).max(glam::IVec2::ONE);
        let m = self.light.cfg[1] as i32;
        let s = 1.max((count.x.max(count.y) + m - 1) / m);
        let nb = (count + glam::IVec2::splat(s - 1)) / s;
        let ri = r as i32;
        let k = self.light.cfg[0] as usize;
        let texel_ndc = 2.0 / r;
        let mut occluded = 0.0f32;
        for a in 0..nb.y {
            for b in 0..nb.x {
                let blk = x0 + glam::IVec2::new(b, a) * s;
                let t = blk + glam::IVec2::splat(s / 2);
                if t.x < 0 || t.y < 0 || t.x >= ri || t.y >= ri {
                    continue;
                }
                let ti = (t.y * ri + t.x) as usize;
                let d = self.depth[ti];
                if d[0] >= z {
                    continue;
                }
                let s4 = if self.light.cfg[2] != 0 {
                    self.slope[ti]
                } else {
                    [0.0; 4]
                };
                for j in (0..k).rev() {
                    let zj = d[j];
                    if zj >= FAR * 0.5 {
                        continue;
                    }
                    if zj + self.layer_bias(d, s4, j) < z {
                        let nlo = Vec2::new(
                            blk.x as f32 * texel_ndc - 1.0,
                            1.0 - (blk.y + s) as f32 * texel_ndc,
                        );
                        let nhi = Vec2::new(
                            (blk.x + s) as f32 * texel_ndc - 1.0,
                            1.0 - blk.y as f32 * texel_ndc,
                        );
                        let wlo = nlo * zj / f;
                        let whi = nhi * zj / f;
                        let gk = z / (z - zj);
                        let llo =
                            ((p + (wlo - p) * gk) / l).clamp(Vec2::splat(-0.5), Vec2::splat(0.5));
                        let lhi =
                            ((p + (whi - p) * gk) / l).clamp(Vec2::splat(-0.5), Vec2::splat(0.5));
                        let e = (lhi - llo).max(Vec2::ZERO);
                        occluded += e.x * e.y;
                        break;
                    }
                }
            }
        }
        (1.0 - occluded).clamp(0.0, 1.0)
    }
}
