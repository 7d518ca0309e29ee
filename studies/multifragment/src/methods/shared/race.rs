//! Judging a race build against its ideal-order twin (`mlab`, `adaptive`): unguarded
//! read-modify-write of a pixel's state races, and the pixels whose image differs from the twin
//! run in primitive order are its hazards.

use crate::methods::Capture;
use bench_core::record::Flag;

/// A pixel whose image differs from the ideal-order twin by more than this is a hazard: ten
/// times what f32 arithmetic alone gives over 300 fragments (the twin's `mlab_f32_twin_follows_
/// f64_to_1e5`), plus the GPU's f32 attribute interpolation.
pub const HAZARD_TOL: f64 = 1e-4;

/// Pixels whose image differs from `definition` by more than [`HAZARD_TOL`] in some channel,
/// and the first one.
pub fn hazards(image: &[[f32; 4]], definition: &[[f64; 4]]) -> (u64, Option<usize>) {
    let mut n = 0;
    let mut first = None;
    for (p, (g, d)) in image.iter().zip(definition).enumerate() {
        if (0..4).any(|c| {
            let e = (g[c] as f64 - d[c]).abs();
            e.is_nan() || e > HAZARD_TOL
        }) {
            n += 1;
            first.get_or_insert(p);
        }
    }
    (n, first)
}

/// The race build's judgement: its ideal-order twin `def` becomes the capture's definition and
/// the pixels that differ from it its hazards (flagged, the first named in the notes).
pub fn judge_race(cap: &mut Capture, def: Vec<[f64; 4]>, width: u32) {
    if let Some(img) = &cap.image {
        let (n, first) = hazards(img, &def);
        cap.hazard_pixels = Some(n);
        if let Some(p) = first {
            cap.flag.add(Flag::Hazard);
            let (x, y) = (p as u32 % width, p as u32 / width);
            cap.notes = format!(
                "{}; {n} pixels differ from the ideal-order twin by more than {HAZARD_TOL:e} (first ({x},{y}))",
                cap.notes
            );
        }
    }
    cap.definition = Some(def);
}
