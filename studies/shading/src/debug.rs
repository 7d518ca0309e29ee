//! Debug views of the deferred paths (the seeds call them essential): 4×4 tiles coloured by
//! classification id, a lights-per-tile heat map of the GPU tiled culling, and the shaded image
//! (tone-mapped x/(1+x)), written as PNGs (`mfx shading-views --out <run folder>`).

use std::path::{Path as FsPath, PathBuf};

use scenarios::Scene;

use super::gpu_paths::{Deferred, Path};
use super::{class, ShadeSetup};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::timed::Timed;
use bench_core::timing::GpuTimer;
use bench_core::{CoreError, Result};

fn save(path: &FsPath, w: u32, h: u32, rgb: &[[u8; 3]]) -> Result<()> {
    let bytes: Vec<u8> = rgb.iter().flatten().copied().collect();
    image::save_buffer(path, &bytes, w, h, image::ColorType::Rgb8)
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))
}

/// Colour of a classification id (distinct, fixed: the legend is `class::names`).
pub fn id_color(id: u32) -> [u8; 3] {
    const C: [[u8; 3]; 16] = [
        [0, 0, 0],
        [90, 140, 255],
        [120, 120, 120],
        [150, 120, 255],
        [230, 200, 60],
        [255, 0, 255],
        [240, 150, 40],
        [255, 220, 150],
        [0, 255, 255],
        [0, 200, 200],
        [60, 200, 90],
        [120, 255, 200],
        [255, 80, 80],
        [255, 0, 128],
        [255, 255, 255],
        [200, 255, 120],
    ];
    C[(id & 15) as usize]
}

/// Black → red → yellow → white for 0..1.
pub fn heat(t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0) * 3.0;
    let c = |x: f64| (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    [c(t), c(t - 1.0), c(t - 2.0)]
}

/// Writes `classes.png`, `lights_per_tile.png` and `image.png` into `out`; returns the paths
/// and a one-line legend.
pub fn write_views(
    gpu: &Gpu,
    scene: &Scene,
    width: u32,
    height: u32,
    tile: u32,
    tau: f64,
    out: &FsPath,
) -> Result<(Vec<PathBuf>, String)> {
    std::fs::create_dir_all(out).map_err(|e| CoreError::Io(format!("{}: {e}", out.display())))?;
    let gs = GpuScene::upload(gpu, scene, width, height);
    let mut timer = GpuTimer::new(gpu);
    let mut run = |path: Path| -> Result<Deferred> {
        let mut d = Deferred::new(gpu, scene, &gs, path, tau, false)?;
        timer.begin_frame();
        d.frame(gpu, &gs, &mut timer)?;
        gpu.wait()?;
        Ok(d)
    };
    let classified = run(Path::Classified { uber: false })?;
    let tiled = run(Path::Tiled { tile, levels: 1 })?;
    let img = tiled.read_image(gpu)?;
    let n = (width * height) as usize;
    let lum: Vec<f64> = img
        .iter()
        .map(|p| {
            let l = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            l / (1.0 + l)
        })
        .collect();
    let mut files = Vec::new();
    // Classification ids, modulated by the image so the scene stays readable.
    let (ids, counts, _, _) = classified.classification(gpu)?.expect("classified path");
    let (tx, _) = classified.class_tiles().expect("classified path");
    let mut rgb = vec![[0u8; 3]; n];
    for (i, px) in rgb.iter_mut().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        let id = ids[((y / class::TILE) * tx + x / class::TILE) as usize];
        let k = 0.45 + 0.55 * lum[i];
        *px = id_color(id).map(|c| (c as f64 * k) as u8);
    }
    let p = out.join("classes.png");
    save(&p, width, height, &rgb)?;
    files.push(p);
    // Lights per tile.
    let tc = tiled.tile_counts(gpu)?.expect("tiled path");
    let ttx = width.div_ceil(tile);
    let max = tc.iter().copied().max().unwrap_or(0).max(1) as f64;
    for (i, px) in rgb.iter_mut().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        let c = tc[((y / tile) * ttx + x / tile) as usize] as f64;
        let edge = x % tile == 0 || y % tile == 0;
        *px = if edge { [40, 40, 40] } else { heat(c / max) };
    }
    let p = out.join("lights_per_tile.png");
    save(&p, width, height, &rgb)?;
    files.push(p);
    for (i, px) in rgb.iter_mut().enumerate() {
        *px = img[i].map(|v| {
            let v = v.max(0.0) as f64;
            ((v / (1.0 + v)).powf(1.0 / 2.2) * 255.0 + 0.5) as u8
        })[..3]
            .try_into()
            .unwrap();
    }
    let p = out.join("image.png");
    save(&p, width, height, &rgb)?;
    files.push(p);
    let legend = (0..16u32)
        .filter(|&id| counts[id as usize] > 0)
        .map(|id| {
            format!(
                "{}={:?}:{} tiles",
                class::names(id),
                id_color(id),
                counts[id as usize]
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    let _ = ShadeSetup::new(scene, width, height);
    Ok((
        files,
        format!("classes: {legend}; lights per {tile}² tile: max {max}"),
    ))
}
