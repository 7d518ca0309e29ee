//! Text on a chart: the embedded font (DejaVu Sans, so widths are known exactly and every
//! machine draws the same), sizes, widths, wrapping and title lines.

use std::sync::Once;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// DejaVu Sans, in the tree: the charts' one font (PNG, the SVG's measured widths, the PDF's
/// embedded font).
pub(super) const FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

pub(super) static FONT: Once = Once::new();

pub(super) fn ensure_font() {
    FONT.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            let _ = plotters::style::register_font("sans-serif", style, FONT_BYTES);
        }
    });
}

pub(super) const TITLE_PX: f64 = 20.0;
pub(super) const AXIS_PX: f64 = 15.0;
pub(super) const TICK_PX: f64 = 13.0;
pub(super) const LEGEND_PX: f64 = 13.0;
pub(super) const LEGEND_LINE: f64 = 18.0;
pub(super) const LEGEND_TEXT_MAX: f64 = 330.0;

pub(super) fn font(px: f64) -> FontDesc<'static> {
    ("sans-serif", px).into_font()
}

/// Width in pixels of `s` in the embedded font (DejaVu Sans) at `px`.
pub fn text_width(s: &str, px: f64) -> f64 {
    ensure_font();
    font(px)
        .box_size(s)
        .map(|(w, _)| w as f64)
        .unwrap_or(s.chars().count() as f64 * px * 0.6)
}

/// `s` broken at spaces (after commas first) into lines no wider than `max` px; a word longer
/// than a line stays whole. Nothing is cut.
pub fn wrap(s: &str, px: f64, max: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut cur = String::new();
    for word in s.split(' ') {
        let cand = if cur.is_empty() {
            word.to_string()
        } else {
            format!("{cur} {word}")
        };
        if !cur.is_empty() && text_width(&cand, px) > max {
            lines.push(std::mem::take(&mut cur));
            cur = word.to_string();
        } else {
            cur = cand;
        }
    }
    if !cur.is_empty() || lines.is_empty() {
        lines.push(cur);
    }
    lines
}

/// Title lines that fit `max` px (broken at " — " first, then at spaces).
pub(super) fn title_lines(t: &str, max: f64) -> Vec<String> {
    if text_width(t, TITLE_PX) <= max {
        return vec![t.to_string()];
    }
    if let Some((a, b)) = t.split_once(" — ") {
        let mut v = wrap(a, TITLE_PX, max);
        v.extend(wrap(&format!("— {b}"), TITLE_PX, max));
        return v;
    }
    wrap(t, TITLE_PX, max)
}

pub(super) fn text_style(px_size: f64, h: HPos, v: VPos, c: RGBColor) -> TextStyle<'static> {
    font(px_size).color(&c).pos(Pos::new(h, v))
}
