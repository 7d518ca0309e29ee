//! mfx-reference, the exact CPU reference: every fragment of every pixel, in f64, depth-sorted;
//! the error metrics images are judged by ([`metrics`]); and the CPU twins of the
//! order-dependent rules ([`oit`]); what only a sequence of views has, flicker and popping against
//! each view's truth ([`temporal`], for camera paths). GPU-free: no wgpu, tested without an adapter.
//!
//! It projects with the same f32 matrix the GPU receives (widened to f64), clips against the
//! depth range 0 ≤ z ≤ w like Vulkan, snaps screen positions to the GPU's 8 sub-pixel bits,
//! samples pixel centres with the top-left fill rule, interpolates depth linearly in screen space
//! and attributes perspective-correctly. Slow and obviously right on purpose; parallel over row
//! strips with rayon. Everything a GPU method outputs is judged against this. `multisample`
//! runs the same rasteriser at MSAA sample positions (and supersampled) for antialiased rows.

pub mod metrics;
pub mod multisample;
pub mod oit;
pub mod raster;
pub mod temporal;
pub mod volume;

pub use multisample::AaMode;
pub use raster::{rasterize, rasterize_with, RefFragment, Sampling, SUBPIXEL_BITS};

/// Per-pixel fragment lists in compressed-row form, each list sorted nearest first.
#[derive(Clone, Debug)]
pub struct FragmentLists {
    pub width: u32,
    pub height: u32,
    pub reversed_z: bool,
    /// Pixel p (row-major, top-left origin) owns `frags[offsets[p]..offsets[p + 1]]`.
    pub offsets: Vec<u32>,
    pub frags: Vec<RefFragment>,
}

impl FragmentLists {
    pub fn pixels(&self) -> usize {
        (self.width * self.height) as usize
    }

    /// Fragments of pixel `p`, nearest first.
    pub fn pixel(&self, p: usize) -> &[RefFragment] {
        &self.frags[self.offsets[p] as usize..self.offsets[p + 1] as usize]
    }

    pub fn at(&self, x: u32, y: u32) -> &[RefFragment] {
        self.pixel((y * self.width + x) as usize)
    }

    /// Fragments per pixel.
    pub fn depth_complexity(&self) -> Vec<u32> {
        self.offsets.windows(2).map(|w| w[1] - w[0]).collect()
    }

    pub fn max_depth_complexity(&self) -> u32 {
        self.offsets
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0)
    }

    pub fn total_fragments(&self) -> u64 {
        self.frags.len() as u64
    }

    /// Pixels where two consecutive fragments (nearest first) are within `ulps` f32 steps of
    /// each other in window depth: a method comparing f32 depths cannot order or separate them
    /// (intersecting or coplanar geometry).
    pub fn depth_tie_pixels(&self, ulps: u32) -> Vec<bool> {
        (0..self.pixels())
            .map(|p| {
                self.pixel(p).windows(2).any(|w| {
                    let (a, b) = (w[0].depth as f32, w[1].depth as f32);
                    (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs() <= ulps as u64
                })
            })
            .collect()
    }

    /// Front-to-back "under" compositing of at most `k` nearest fragments per pixel, as
    /// premultiplied RGBA with A = 1 − transmittance (no background).
    pub fn composite_first(&self, k: usize) -> Vec<[f64; 4]> {
        (0..self.pixels())
            .map(|p| composite(self.pixel(p).iter().take(k)))
            .collect()
    }

    /// The reference transparency image: all fragments composited.
    pub fn composite(&self) -> Vec<[f64; 4]> {
        self.composite_first(usize::MAX)
    }
}

/// Under-compositing of fragments given nearest first: C += (1 − A)·α·c; A += (1 − A)·α.
pub fn composite<'a>(frags: impl Iterator<Item = &'a RefFragment>) -> [f64; 4] {
    let mut acc = [0.0f64; 4];
    for f in frags {
        let a = f.color[3];
        let t = 1.0 - acc[3];
        for (c, fc) in acc.iter_mut().zip(&f.color).take(3) {
            *c += t * a * fc;
        }
        acc[3] += t * a;
    }
    acc
}

#[cfg(test)]
mod tests;
