//! mfx-flip: NVIDIA's perceptual image difference ꟻLIP (LDR) beside RMSE, and the difference
//! images of the worst points for the report.
//!
//! The metric itself is NVIDIA's C++ FLIP, compiled into the binary by the `nv-flip` crate
//! (BSD-3-Clause; its notice is in `THIRD-PARTY.md`, and binary distributions must carry it).
//! This crate only prepares the inputs the way a viewer of our PNGs sees them
//! ([`composite_srgb8`]), summarises the per-pixel map ([`FlipResult`]), colours it with FLIP's
//! magma map ([`magma_rgb8`]) and keeps the worst rows' images ([`WorstKeeper`]).
//!
//! Cost: NVIDIA's C++ runs single-threaded here (nv-flip-sys does not enable its OpenMP
//! pragmas), about 1 s for a 1024² pair on one core; [`flip_ldr`] splits the image into strips
//! on rayon's pool, bit-identically. `examples/flip_cost.rs` times it.

use std::io;
use std::path::Path;
use std::sync::OnceLock;

use rayon::prelude::*;

mod worst;
pub use worst::WorstKeeper;

/// FLIP's default viewing condition: 67 pixels per degree of visual angle, a 0.7 m wide
/// 3840-pixel monitor seen from 0.7 m (FLIP's README and `nv_flip::DEFAULT_PIXELS_PER_DEGREE`).
/// The value sets which spatial frequencies count as visible; a larger PPD forgives finer detail.
pub const PPD: f32 = 67.0;

/// Summary of one LDR-FLIP comparison. Every value is in [0, 1] (0 = indistinguishable).
#[derive(Clone, Debug, PartialEq)]
pub struct FlipResult {
    /// Per-pixel FLIP error, row-major from the top-left, `width * height` values.
    pub map: Vec<f32>,
    /// Mean over all pixels (FLIP's recommended single number), summed in f64.
    pub mean: f64,
    /// Percentiles over pixels, nearest-rank: the value at index `ceil(p * n) - 1` of the map
    /// sorted ascending (so each is a value some pixel actually has; not FLIP's histogram
    /// estimate, not weighted).
    pub p50: f64,
    pub p95: f64,
    pub p99: f64,
    /// Largest per-pixel error.
    pub max: f64,
}

/// A premultiplied RGBA image composited over `background` and quantised to RGB8, exactly as
/// `bench_core::image_io::write_png` does: the values are used as display values with no extra
/// transfer function, so the bytes are what a viewer of our PNGs sees (and FLIP, which reads
/// 8-bit input as sRGB, judges that view).
pub fn composite_srgb8(img: &[[f32; 4]], background: [f32; 3]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(img.len() * 3);
    for p in img {
        for c in 0..3 {
            let v = p[c] + (1.0 - p[3]) * background[c];
            bytes.push((v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
        }
    }
    bytes
}

/// LDR-FLIP of `test_rgb8` against `reference_rgb8` (both tightly packed RGB8, row-major from
/// the top-left, read as sRGB) at `ppd` pixels per degree ([`PPD`] by default).
///
/// Runs on rayon's pool in horizontal strips, each with [`halo_rows`] extra rows above and below:
/// every FLIP value depends only on the pixels within its filters' radius (FLIP clamps at the
/// image border, which a strip reaching the border shares), so the map is bit-identical to one
/// call on the whole image (tested), at a cost of `2 * halo` extra rows per strip.
///
/// # Panics
/// If either buffer is not `width * height * 3` bytes or the image is empty (a caller bug).
pub fn flip_ldr(
    reference_rgb8: &[u8],
    test_rgb8: &[u8],
    width: u32,
    height: u32,
    ppd: f32,
) -> FlipResult {
    // Identical inputs differ nowhere: FLIP is 0 at every pixel by its definition (no colour
    // difference, so no error whatever the features), and most exact rows of a sweep are
    // identical to their truth in 8 bits. Skipping the filters there is exact (tested against
    // the full computation) and saves most of a 1024² row's judging time.
    if reference_rgb8 == test_rgb8 {
        let n = width as usize * height as usize;
        assert!(n > 0, "flip_ldr: empty {width}x{height} image");
        assert_eq!(test_rgb8.len(), n * 3, "flip_ldr: test size");
        return summarise(vec![0.0; n]);
    }
    let halo = halo_rows(ppd);
    // Strips no shorter than 4 halos, so the halo overhead stays under 50 %.
    let rows = height
        .div_ceil(rayon::current_num_threads() as u32)
        .max(4 * halo);
    summarise(flip_map_strips(
        reference_rgb8,
        test_rgb8,
        width,
        height,
        ppd,
        rows,
    ))
}

/// Rows beyond a strip that FLIP's filters read at `ppd`: the larger of its spatial filter radius
/// `ceil(3 * sqrt(0.04 / (2 pi^2)) * ppd)` (its widest contrast-sensitivity Gaussian, b1.z) and
/// its feature filter radius `ceil(3 * 0.5 * 0.082 * ppd)`, plus 2 rows against float rounding in
/// those `ceil`s (the C++ computes them in f32).
pub fn halo_rows(ppd: f32) -> u32 {
    let ppd = ppd as f64;
    let spatial = (3.0 * (0.04 / (2.0 * std::f64::consts::PI.powi(2))).sqrt() * ppd).ceil();
    let feature = (3.0 * 0.5 * 0.082 * ppd).ceil();
    spatial.max(feature) as u32 + 2
}

/// The per-pixel map, computed in strips of `strip_rows` rows (see [`flip_ldr`]).
fn flip_map_strips(
    reference_rgb8: &[u8],
    test_rgb8: &[u8],
    width: u32,
    height: u32,
    ppd: f32,
    strip_rows: u32,
) -> Vec<f32> {
    let n = width as usize * height as usize;
    assert!(n > 0, "flip_ldr: empty {width}x{height} image");
    assert_eq!(reference_rgb8.len(), n * 3, "flip_ldr: reference size");
    assert_eq!(test_rgb8.len(), n * 3, "flip_ldr: test size");
    let halo = halo_rows(ppd);
    let strip_rows = strip_rows.max(1);
    let row_bytes = width as usize * 3;
    let strips: Vec<u32> = (0..height).step_by(strip_rows as usize).collect();
    let parts: Vec<Vec<f32>> = strips
        .par_iter()
        .map(|&y0| {
            let y1 = (y0 + strip_rows).min(height);
            let (a, b) = (y0.saturating_sub(halo), (y1 + halo).min(height));
            let bytes = a as usize * row_bytes..b as usize * row_bytes;
            let map = flip_map(
                &reference_rgb8[bytes.clone()],
                &test_rgb8[bytes],
                width,
                b - a,
                ppd,
            );
            let keep = (y0 - a) as usize * width as usize..(y1 - a) as usize * width as usize;
            map[keep].to_vec()
        })
        .collect();
    parts.concat()
}

/// One call of NVIDIA's FLIP on a whole (sub-)image.
fn flip_map(
    reference_rgb8: &[u8],
    test_rgb8: &[u8],
    width: u32,
    height: u32,
    ppd: f32,
) -> Vec<f32> {
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, reference_rgb8);
    let test = nv_flip::FlipImageRgb8::with_data(width, height, test_rgb8);
    nv_flip::flip(reference, test, ppd).to_vec()
}

fn summarise(map: Vec<f32>) -> FlipResult {
    let n = map.len();
    let mean = map.iter().map(|&v| v as f64).sum::<f64>() / n as f64;
    let mut sorted = map.clone();
    sorted.sort_unstable_by(f32::total_cmp);
    let rank = |p: f64| sorted[((p * n as f64).ceil() as usize).clamp(1, n) - 1] as f64;
    FlipResult {
        mean,
        p50: rank(0.50),
        p95: rank(0.95),
        p99: rank(0.99),
        max: sorted[n - 1] as f64,
        map,
    }
}

/// FLIP's 256-entry magma map as RGB8, read from the C++ library (the colours its CLI writes).
fn magma_lut() -> &'static [u8] {
    static LUT: OnceLock<Vec<u8>> = OnceLock::new();
    LUT.get_or_init(|| nv_flip::magma_lut().to_vec())
}

/// A FLIP map coloured with FLIP's magma map, RGB8 (0 → near-black, 1 → pale yellow). The
/// index is FLIP's own, `round(v * 255)`, with `v` clamped to [0, 1] first (NaN → 0).
pub fn magma_rgb8(map: &[f32]) -> Vec<u8> {
    let lut = magma_lut();
    let mut out = Vec::with_capacity(map.len() * 3);
    for &v in map {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        let i = (v * 255.0 + 0.5) as usize;
        out.extend_from_slice(&lut[i * 3..i * 3 + 3]);
    }
    out
}

/// Saves tightly packed RGB8 as a PNG.
pub fn save_rgb8_png(path: &Path, rgb8: &[u8], width: u32, height: u32) -> io::Result<()> {
    image::save_buffer(path, rgb8, width, height, image::ColorType::Rgb8)
        .map_err(|e| io::Error::other(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth 64x48 gradient with some structure, so FLIP's filters see edges.
    fn gradient(w: u32, h: u32) -> Vec<u8> {
        let mut v = Vec::new();
        for y in 0..h {
            for x in 0..w {
                v.extend_from_slice(&[
                    (x * 255 / (w - 1)) as u8,
                    (y * 255 / (h - 1)) as u8,
                    if (x / 8 + y / 8) % 2 == 0 { 40 } else { 200 },
                ]);
            }
        }
        v
    }

    #[test]
    fn identical_images_have_zero_error() {
        let img = gradient(64, 48);
        let r = flip_ldr(&img, &img, 64, 48, PPD);
        assert_eq!(r.map.len(), 64 * 48);
        assert_eq!(r.mean, 0.0);
        assert_eq!(r.max, 0.0);
        // The shortcut for identical inputs gives exactly what the filters give.
        let full = summarise(flip_map_strips(&img, &img, 64, 48, PPD, 48));
        assert_eq!(r, full);
    }

    #[test]
    fn one_pixel_difference_is_seen_and_local() {
        let (w, h) = (64u32, 48u32);
        let reference = gradient(w, h);
        let mut test = reference.clone();
        let at = ((20 * w + 30) * 3) as usize;
        test[at..at + 3].copy_from_slice(&[255, 0, 255]);
        let r = flip_ldr(&reference, &test, w, h, PPD);
        assert!(r.mean > 0.0, "mean {}", r.mean);
        // FLIP's filters spread one pixel's change over a small neighbourhood only, so most
        // pixels stay at 0: the median is 0 while the tail and the maximum are not.
        assert_eq!(r.p50, 0.0);
        assert!(r.p99 >= r.mean, "p99 {} < mean {}", r.p99, r.mean);
        assert!(r.max >= r.p99 && r.p99 >= r.p95 && r.p95 >= r.p50);
        assert!(
            r.max > 0.1,
            "a magenta pixel on a gradient is plainly visible: {}",
            r.max
        );
        let argmax = (0..r.map.len())
            .max_by(|&a, &b| r.map[a].total_cmp(&r.map[b]))
            .unwrap();
        let (x, y) = (argmax as u32 % w, argmax as u32 / w);
        assert!(
            x.abs_diff(30) <= 2 && y.abs_diff(20) <= 2,
            "peak at ({x}, {y})"
        );
    }

    #[test]
    fn strips_are_bit_identical_to_one_call() {
        // Includes strips of 1 row (all halo) and strips shorter than the halo, at three
        // viewing distances (halos of 7, 12 and 19 rows).
        let (w, h) = (40u32, 90u32);
        let reference = gradient(w, h);
        let test: Vec<u8> = reference
            .iter()
            .enumerate()
            .map(|(i, &v)| v.wrapping_add((i * 7919 % 61) as u8))
            .collect();
        for ppd in [30.0, PPD, 120.0] {
            let whole = flip_map(&reference, &test, w, h, ppd);
            assert!(whole.iter().any(|&v| v > 0.0));
            for rows in [1, 5, 13, 64, h] {
                let strips = flip_map_strips(&reference, &test, w, h, ppd, rows);
                assert!(
                    strips
                        .iter()
                        .zip(&whole)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "ppd {ppd}, strips of {rows} rows differ from one call"
                );
            }
        }
    }

    #[test]
    fn nearest_rank_percentiles() {
        // 100 values 0.01, 0.02, …, 1.00 in scrambled order: the p-th is exactly p.
        let map: Vec<f32> = (0..100)
            .map(|i| ((i * 37) % 100 + 1) as f32 / 100.0)
            .collect();
        let r = summarise(map);
        assert_eq!(r.p50, 0.5f32 as f64);
        assert_eq!(r.p95, 0.95f32 as f64);
        assert_eq!(r.p99, 0.99f32 as f64);
        assert_eq!(r.max, 1.0);
        // Mean of 0.01..=1.00 is 0.505; f32 inputs round each value by < 1e-8.
        assert!((r.mean - 0.505).abs() < 1e-7, "{}", r.mean);
        let one = summarise(vec![0.25]);
        assert_eq!((one.p50, one.p99, one.max), (0.25, 0.25, 0.25));
    }

    #[test]
    fn magma_endpoints_are_flips_table() {
        // FLIP's (= matplotlib's) magma starts at (0.001462, 0.000466, 0.013866) and ends at
        // (0.987053, 0.991438, 0.749504); ×255 rounded.
        assert_eq!(magma_rgb8(&[0.0, 1.0]), vec![0, 0, 4, 252, 253, 191]);
        // Out-of-range and NaN values are clamped, never index out of the table.
        assert_eq!(
            magma_rgb8(&[-1.0, f32::NAN, 7.0]),
            vec![0, 0, 4, 0, 0, 4, 252, 253, 191]
        );
        assert_eq!(magma_lut().len(), 256 * 3);
    }

    #[test]
    fn composite_matches_write_png_rule() {
        // Half-transparent red over white: 0.5 + 0.5 * 1 = 1 in red, 0.5 in green and blue.
        let px = [
            [0.5, 0.0, 0.0, 0.5],
            [0.0, 0.0, 0.0, 0.0],
            [2.0, -1.0, f32::NAN, 1.0],
        ];
        assert_eq!(
            composite_srgb8(&px, [1.0, 1.0, 1.0]),
            vec![255, 128, 128, 255, 255, 255, 255, 0, 0]
        );
    }
}
