//! What tells series apart: the palette, the marker shapes, the greys of grids and frames.

use plotters::style::RGBColor;

/// Series colours: category10's first eight, extended to 32 by greedy max–min CIELAB distance
/// (Glasbey et al. 2007) over an sRGB grid with L* in 30–68 so every colour reads on white; no
/// two of the first 24 are closer than ΔE76 ≈ 27 (tested).
pub const PALETTE: [u32; 32] = [
    0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf, 0x0000ff,
    0xff1eff, 0xb4a500, 0x1e5a3c, 0x690fb4, 0xff0078, 0xa5a569, 0x0078ff, 0x960f4b, 0x965a00,
    0x00b487, 0xb496b4, 0xc300a5, 0xff7887, 0x4b6900, 0x3c4b5a, 0xd269ff, 0x004bff, 0xf0875a,
    0xa51eff, 0x693c69, 0x004ba5, 0x789696, 0x5a4b0f,
];

pub fn color(i: usize) -> RGBColor {
    let c = PALETTE[i % PALETTE.len()];
    RGBColor((c >> 16) as u8, (c >> 8) as u8, c as u8)
}

/// How many marker shapes there are (`Series::family` is taken modulo this).
pub const MARKERS: usize = SHAPES.len();

/// Marker shapes, one per method family; all closed, so a hollow (flagged) one reads as such.
pub(super) const SHAPES: [(usize, f64); 8] = [
    (0, 0.0),                          // circle
    (4, std::f64::consts::FRAC_PI_4),  // square
    (3, -std::f64::consts::FRAC_PI_2), // triangle up
    (4, 0.0),                          // diamond
    (3, std::f64::consts::FRAC_PI_2),  // triangle down
    (6, 0.0),                          // hexagon
    (5, -std::f64::consts::FRAC_PI_2), // pentagon
    (3, 0.0),                          // triangle right
];
pub(super) const SHAPE_NAMES: [&str; 8] = [
    "circle",
    "square",
    "triangle-up",
    "diamond",
    "triangle-down",
    "hexagon",
    "pentagon",
    "triangle-right",
];

pub(super) const GRID: RGBColor = RGBColor(228, 228, 228);
pub(super) const FRAME: RGBColor = RGBColor(120, 120, 120);
pub(super) const MUTED: RGBColor = RGBColor(110, 110, 110);
pub(super) const CONTEXT: RGBColor = RGBColor(200, 200, 200);

/// What tells a series apart in the layout record: its colour and marker.
pub(super) fn style_key(c: RGBColor, family: usize) -> String {
    format!(
        "#{:02x}{:02x}{:02x} {}",
        c.0,
        c.1,
        c.2,
        SHAPE_NAMES[family % SHAPE_NAMES.len()]
    )
}
