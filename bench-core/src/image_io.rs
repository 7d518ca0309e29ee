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

/// 16 hex digits naming a point's saved image: FNV-1a 64 of `point_key|adapter|backend`
/// (stable across machines and Rust versions, unlike `DefaultHasher`).
pub fn point_hash(point_key: &str, adapter: &str, backend: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in [point_key, adapter, backend].join("|").bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

fn npy_err(path: &Path, e: impl std::fmt::Display) -> CoreError {
    CoreError::Io(format!("{}: {e}", path.display()))
}

/// Writes `data` as a C-order `.npy` array of `shape` (dtype from `T`: `<f4`, `<u2`, …).
pub fn write_npy<T: npyz::AutoSerialize + Copy>(
    path: &Path,
    shape: &[u64],
    data: &[T],
) -> Result<()> {
    use npyz::WriterBuilder;
    let n: u64 = shape.iter().product();
    if n != data.len() as u64 {
        return Err(npy_err(
            path,
            format!("{} values for shape {shape:?}", data.len()),
        ));
    }
    let file = std::fs::File::create(path).map_err(|e| npy_err(path, e))?;
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(std::io::BufWriter::new(file))
        .begin_nd()
        .map_err(|e| npy_err(path, e))?;
    w.extend(data.iter().copied())
        .map_err(|e| npy_err(path, e))?;
    w.finish().map_err(|e| npy_err(path, e))
}

/// A premultiplied RGBA image as float32 `(height, width, 4)`, row 0 at the top.
pub fn write_npy_rgba(path: &Path, width: u32, height: u32, img: &[[f32; 4]]) -> Result<()> {
    let flat: &[f32] = bytemuck::cast_slice(img);
    write_npy(path, &[height as u64, width as u64, 4], flat)
}

/// Reads a float32 `(height, width, 4)` `.npy` back: (width, height, pixels).
pub fn read_npy_rgba(path: &Path) -> Result<(u32, u32, Vec<[f32; 4]>)> {
    let bytes = std::fs::read(path).map_err(|e| npy_err(path, e))?;
    let npy = npyz::NpyFile::new(&bytes[..]).map_err(|e| npy_err(path, e))?;
    let shape = npy.shape().to_vec();
    if shape.len() != 3 || shape[2] != 4 {
        return Err(npy_err(
            path,
            format!("shape {shape:?} is not (height, width, 4)"),
        ));
    }
    let v: Vec<f32> = npy.into_vec().map_err(|e| npy_err(path, e))?;
    let px = v
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    Ok((shape[1] as u32, shape[0] as u32, px))
}

/// Writes exact counts as a 16-bit greyscale PNG (value = count, not rescaled).
pub fn write_png16(path: &Path, width: u32, height: u32, values: &[u16]) -> Result<()> {
    let img =
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(width, height, values.to_vec())
            .ok_or_else(|| npy_err(path, "size does not match width × height"))?;
    img.save(path).map_err(|e| npy_err(path, e))
}
