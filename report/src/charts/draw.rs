//! Drawing shared by every chart kind: numeric axes, frames, markers, legends and titles.

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::layout::{AxisRecord, Rect};
use super::style::{FRAME, SHAPES};
use super::text::{
    text_style, text_width, wrap, LEGEND_LINE, LEGEND_PX, LEGEND_TEXT_MAX, TITLE_PX,
};
use super::ticks;

pub(super) fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("plotting: {e:?}")
}

/// A numeric axis: range, ticks, and the map from values to pixels.
#[derive(Clone, Debug)]
pub(super) struct Axis {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) log: bool,
    pub(super) ticks: Vec<f64>,
    pub(super) labels: Vec<String>,
}

impl Axis {
    pub(super) fn new((lo, hi): (f64, f64), log: bool) -> Axis {
        let ticks = if log {
            ticks::log_ticks(lo, hi)
        } else {
            ticks::linear_ticks(lo, hi, 6)
        };
        let labels = ticks::tick_labels(&ticks);
        Axis {
            lo,
            hi,
            log,
            ticks,
            labels,
        }
    }
    pub(super) fn t(&self, v: f64) -> f64 {
        if self.log {
            v.log10()
        } else {
            v
        }
    }
    /// 0 at `lo`, 1 at `hi`.
    pub(super) fn frac(&self, v: f64) -> f64 {
        (self.t(v) - self.t(self.lo)) / (self.t(self.hi) - self.t(self.lo))
    }
    pub(super) fn record(&self, title: &str, data: Option<[f64; 2]>) -> AxisRecord {
        AxisRecord {
            title: title.to_string(),
            log: self.log,
            categorical: false,
            data,
            range: [self.lo, self.hi],
            ticks: self.labels.clone(),
            off_scale: 0,
        }
    }
}

pub(super) fn minmax(v: impl Iterator<Item = f64>) -> Option<[f64; 2]> {
    let mut r: Option<[f64; 2]> = None;
    for x in v {
        r = Some(match r {
            None => [x, x],
            Some([a, b]) => [a.min(x), b.max(x)],
        });
    }
    r
}

pub(super) fn px(v: f64) -> i32 {
    v.round() as i32
}

/// The thin grey outline of `r` (plot areas, legend boxes).
pub(super) fn draw_frame<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, r: &Rect) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.draw(&Rectangle::new(
        [(px(r.x), px(r.y)), (px(r.right()), px(r.bottom()))],
        FRAME.stroke_width(1),
    ))
    .map_err(err)
}

/// An axis title, saying so when the axis is logarithmic.
pub(super) fn axis_title(label: &str, log: bool) -> String {
    if log {
        format!("{label} (log scale)")
    } else {
        label.to_string()
    }
}

pub(super) fn draw_marker<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    (x, y): (f64, f64),
    family: usize,
    c: RGBColor,
    hollow: bool,
    r: f64,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (n, rot) = SHAPES[family % SHAPES.len()];
    if n == 0 {
        if hollow {
            root.draw(&Circle::new((px(x), px(y)), px(r), WHITE.filled()))
                .map_err(err)?;
            root.draw(&Circle::new((px(x), px(y)), px(r), c.stroke_width(2)))
                .map_err(err)?;
        } else {
            root.draw(&Circle::new((px(x), px(y)), px(r), c.filled()))
                .map_err(err)?;
        }
        return Ok(());
    }
    // Polygons a little larger than the circle so their areas look alike.
    let rr = r * if n == 3 { 1.35 } else { 1.2 };
    let pts: Vec<(i32, i32)> = (0..n)
        .map(|i| {
            let a = rot + i as f64 * std::f64::consts::TAU / n as f64;
            (px(x + rr * a.cos()), px(y + rr * a.sin()))
        })
        .collect();
    if hollow {
        root.draw(&Polygon::new(pts.clone(), WHITE.filled()))
            .map_err(err)?;
        let mut closed = pts.clone();
        closed.push(pts[0]);
        root.draw(&PathElement::new(closed, c.stroke_width(2)))
            .map_err(err)?;
    } else {
        root.draw(&Polygon::new(pts, c.filled())).map_err(err)?;
    }
    Ok(())
}

/// One legend entry: what its swatch shows and its (wrapped) text.
#[derive(Clone, Debug)]
pub(super) enum Swatch {
    Marker {
        family: usize,
        color: RGBColor,
        hollow: bool,
    },
    Line {
        color: RGBColor,
        dashed: bool,
    },
    Bar {
        color: RGBColor,
    },
}

#[derive(Clone, Debug)]
pub(super) struct Entry {
    pub(super) swatch: Swatch,
    pub(super) lines: Vec<String>,
}

pub(super) fn entry(swatch: Swatch, text: &str) -> Entry {
    Entry {
        swatch,
        lines: wrap(text, LEGEND_PX, LEGEND_TEXT_MAX),
    }
}

pub(super) fn legend_size(entries: &[Entry]) -> (f64, f64) {
    let tw = entries
        .iter()
        .flat_map(|e| e.lines.iter())
        .map(|l| text_width(l, LEGEND_PX))
        .fold(0.0, f64::max);
    let rows: usize = entries.iter().map(|e| e.lines.len()).sum();
    (tw + 44.0, rows as f64 * LEGEND_LINE + 14.0)
}

pub(super) fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    r: &Rect,
    entries: &[Entry],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.draw(&Rectangle::new(
        [(px(r.x), px(r.y)), (px(r.right()), px(r.bottom()))],
        WHITE.filled(),
    ))
    .map_err(err)?;
    draw_frame(root, r)?;
    let mut y = r.y + 7.0 + LEGEND_LINE / 2.0;
    for e in entries {
        let sx = r.x + 18.0;
        match &e.swatch {
            Swatch::Marker {
                family,
                color,
                hollow,
            } => draw_marker(root, (sx, y), *family, *color, *hollow, 5.0)?,
            Swatch::Line { color, dashed } => {
                let seg = vec![(px(sx - 11.0), px(y)), (px(sx + 11.0), px(y))];
                if *dashed {
                    root.draw(&DashedPathElement::new(seg, 5, 3, color.stroke_width(2)))
                        .map_err(err)?;
                } else {
                    root.draw(&PathElement::new(seg, color.stroke_width(2)))
                        .map_err(err)?;
                }
            }
            Swatch::Bar { color } => {
                root.draw(&Rectangle::new(
                    [(px(sx - 8.0), px(y - 5.0)), (px(sx + 8.0), px(y + 5.0))],
                    color.filled(),
                ))
                .map_err(err)?;
            }
        }
        for l in &e.lines {
            root.draw(&Text::new(
                l.clone(),
                (px(r.x + 36.0), px(y)),
                text_style(LEGEND_PX, HPos::Left, VPos::Center, BLACK),
            ))
            .map_err(err)?;
            y += LEGEND_LINE;
        }
    }
    Ok(())
}

pub(super) fn draw_title<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    lines: &[String],
    cx: f64,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    for (i, l) in lines.iter().enumerate() {
        root.draw(&Text::new(
            l.clone(),
            (px(cx), px(12.0 + i as f64 * 26.0)),
            text_style(TITLE_PX, HPos::Center, VPos::Top, BLACK),
        ))
        .map_err(err)?;
    }
    Ok(())
}
