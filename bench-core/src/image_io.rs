//! PNG output of premultiplied images (composited over a background for viewing).

use std::path::Path;

use crate::{CoreError, Result};

/// Writes a premultiplied RGBA image composited over `background`, 8-bit sRGB-agnostic.
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    img: &[[f32; 4]],
    background: [f32; 3],
) -> Result<()> {
    let mut bytes = Vec::with_capacity(img.len() * 4);
    for p in img {
        for c in 0..3 {
            let v = p[c] + (1.0 - p[3]) * background[c];
            bytes.push((v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
        }
        bytes.push(255);
    }
    image::save_buffer(path, &bytes, width, height, image::ColorType::Rgba8)
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))
}

/// Writes a single-channel heat map (0 → black, max → white) as 8-bit grey.
pub fn write_gray_png(path: &Path, width: u32, height: u32, values: &[f64]) -> Result<()> {
    let max = values.iter().cloned().fold(0.0f64, f64::max).max(1e-30);
    let bytes: Vec<u8> = values
        .iter()
        .map(|v| ((v / max).clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
        .collect();
    image::save_buffer(path, &bytes, width, height, image::ColorType::L8)
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))
}
