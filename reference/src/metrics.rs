//! Error against the CPU reference: RMSE, PSNR, max abs error, bad-pixel fraction, non-finite
//! count, and layer-count accuracy. Images are premultiplied RGBA with A = 1 − transmittance.

/// Per-channel error above this marks a pixel bad (`bad_pixel_frac`): about 1/2 of an 8-bit step.
pub const BAD_PIXEL_TOL: f64 = 2.0e-3;

#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct ImageError {
    pub rmse: f64,
    /// 10·log10(1 / MSE) for a peak of 1; infinite when identical.
    pub psnr_db: f64,
    pub max_abs: f64,
    pub bad_pixel_frac: f64,
    /// Channels that were NaN or ±Inf in the GPU image (counted, and excluded from the other stats).
    pub non_finite: u64,
}

pub fn image_error(reference: &[[f64; 4]], got: &[[f32; 4]], tol: f64) -> ImageError {
    assert_eq!(reference.len(), got.len(), "image sizes differ");
    let mut se = 0.0;
    let mut n = 0u64;
    let mut max_abs: f64 = 0.0;
    let mut bad = 0u64;
    let mut non_finite = 0u64;
    for (r, g) in reference.iter().zip(got) {
        let mut pixel_bad = false;
        for c in 0..4 {
            let gv = g[c] as f64;
            if !gv.is_finite() {
                non_finite += 1;
                pixel_bad = true;
                continue;
            }
            let e = (gv - r[c]).abs();
            se += e * e;
            n += 1;
            max_abs = max_abs.max(e);
            pixel_bad |= e > tol;
        }
        bad += pixel_bad as u64;
    }
    let mse = if n > 0 { se / n as f64 } else { 0.0 };
    ImageError {
        rmse: mse.sqrt(),
        psnr_db: if mse > 0.0 {
            10.0 * (1.0 / mse).log10()
        } else {
            f64::INFINITY
        },
        max_abs,
        bad_pixel_frac: bad as f64 / reference.len().max(1) as f64,
        non_finite,
    }
}

/// Fraction of pixels whose captured fragment count equals the expected count.
pub fn layer_count_accuracy(expected: &[u32], captured: &[u32]) -> f64 {
    assert_eq!(expected.len(), captured.len());
    let ok = expected
        .iter()
        .zip(captured)
        .filter(|(e, c)| e == c)
        .count();
    ok as f64 / expected.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error_and_infinite_psnr() {
        let r = vec![[0.25, 0.5, 0.75, 1.0]; 4];
        let g = vec![[0.25f32, 0.5, 0.75, 1.0]; 4];
        let e = image_error(&r, &g, BAD_PIXEL_TOL);
        assert_eq!(e.rmse, 0.0);
        assert!(e.psnr_db.is_infinite());
        assert_eq!(e.bad_pixel_frac, 0.0);
    }

    #[test]
    fn one_bad_channel_is_measured_exactly() {
        let r = vec![[0.0; 4]; 4];
        let mut g = vec![[0.0f32; 4]; 4];
        g[1][2] = 0.5;
        let e = image_error(&r, &g, BAD_PIXEL_TOL);
        assert!((e.rmse - (0.25f64 / 16.0).sqrt()).abs() < 1e-12);
        assert_eq!(e.max_abs, 0.5);
        assert_eq!(e.bad_pixel_frac, 0.25);
    }

    #[test]
    fn nan_is_counted_not_hidden() {
        let r = vec![[0.0; 4]; 2];
        let g = vec![[f32::NAN, 0.0, 0.0, 0.0], [0.0; 4]];
        let e = image_error(&r, &g, BAD_PIXEL_TOL);
        assert_eq!(e.non_finite, 1);
        assert_eq!(e.bad_pixel_frac, 0.5);
    }
}
