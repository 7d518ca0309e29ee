//! Bar and dot charts (`Bars`), horizontal: categories down the left, never cut.

use std::path::Path;

use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::draw::{
    axis_title, draw_frame, draw_legend, draw_marker, draw_title, entry, err, legend_size, minmax,
    px, Axis, Entry, Swatch,
};
use super::layout::{AxisRecord, Layout, Rect};
use super::output::write_all;
use super::style::{color, style_key, GRID, MUTED};
use super::text::{ensure_font, text_style, text_width, title_lines, wrap, AXIS_PX, TICK_PX};
use super::{ticks, Figure, Pt};

/// Grouped bars: one row per category, one bar (or dot) per series in each row. Values are
/// drawn as bars from zero on a linear axis, or, when `log_y` allows it and they span more than
/// a decade, as dots on a log axis (a bar's length on a log axis would mean nothing).
#[derive(Clone, Debug, Default)]
pub struct Bars {
    pub title: String,
    /// The value axis's title.
    pub y_label: String,
    pub log_y: bool,
    pub categories: Vec<String>,
    /// (series name, one optional value per category; lo/hi draw a whisker)
    pub series: Vec<(String, Vec<Option<Pt>>)>,
    /// A reference value drawn as a line (e.g. 1 for speedups).
    pub reference: Option<f64>,
}

const BAR_PLOT_W: f64 = 600.0;
const CAT_LABEL_MAX: f64 = 430.0;

struct BarPlan {
    layout: Layout,
    title: Vec<String>,
    v: Axis,
    dots: bool,
    /// Per category: (top y, height, label lines).
    rows: Vec<(f64, f64, Vec<String>)>,
    slot: f64,
    entries: Vec<Entry>,
    ticks_on_top: bool,
}

impl Bars {
    fn values(&self) -> Vec<f64> {
        self.series
            .iter()
            .flat_map(|(_, v)| v.iter().flatten())
            .flat_map(|p| [Some(p.y), p.lo, p.hi])
            .flatten()
            .filter(|v| v.is_finite())
            .collect()
    }

    fn plan(&self, stem: &str) -> Option<BarPlan> {
        let vals = self.values();
        let [lo, hi] = minmax(vals.iter().copied())?;
        let ref_ok = self.reference.filter(|r| r.is_finite());
        let dots = self.log_y && lo > 0.0 && hi / lo >= 10.0 && ref_ok.is_none_or(|r| r > 0.0);
        let all = minmax(vals.iter().copied().chain(ref_ok))?;
        let (v, data) = if dots {
            (
                Axis::new(ticks::axis_range(all[0], all[1], true), true),
                all,
            )
        } else {
            let d = [all[0].min(0.0), all[1].max(0.0)];
            let mut a = Axis::new(ticks::zero_based_range(d[0], d[1]), false);
            if d[1] - d[0] == 0.0 {
                a = Axis::new((0.0, 1.0), false);
            }
            (a, d)
        };
        let ns = self.series.len().max(1);
        let slot = if dots { 10.0 } else { 12.0 };
        let label_w = self
            .categories
            .iter()
            .flat_map(|c| wrap(c, TICK_PX, CAT_LABEL_MAX))
            .map(|l| text_width(&l, TICK_PX))
            .fold(0.0, f64::max);
        let mut entries = Vec::new();
        if ns > 1 || self.series.iter().any(|(n, _)| !n.is_empty()) {
            for (i, (n, _)) in self.series.iter().enumerate() {
                entries.push(entry(
                    if dots {
                        Swatch::Marker {
                            family: 0,
                            color: color(i),
                            hollow: false,
                        }
                    } else {
                        Swatch::Bar { color: color(i) }
                    },
                    n,
                ));
            }
        }
        if self
            .series
            .iter()
            .flat_map(|(_, v)| v.iter().flatten())
            .any(|p| p.flagged)
        {
            entries.push(entry(
                Swatch::Marker {
                    family: 0,
                    color: MUTED,
                    hollow: true,
                },
                "hollow: flagged (see table)",
            ));
        }
        let (lw, lh) = legend_size(&entries);
        let left = 16.0 + label_w + 12.0;
        let last = v
            .labels
            .last()
            .map(|l| text_width(l, TICK_PX))
            .unwrap_or(0.0);
        let legend_x = left + BAR_PLOT_W + (last / 2.0 + 12.0).max(24.0);
        let width = if entries.is_empty() {
            legend_x
        } else {
            legend_x + lw + 14.0
        };
        let title = title_lines(&self.title, width - 24.0);
        let mut rows = Vec::new();
        let body: f64 = self
            .categories
            .iter()
            .map(|c| {
                let lines = wrap(c, TICK_PX, CAT_LABEL_MAX);
                (ns as f64 * slot + 10.0).max(lines.len() as f64 * 16.0 + 8.0)
            })
            .sum();
        let ticks_on_top = body > 560.0;
        let top = 12.0 + title.len() as f64 * 26.0 + 12.0 + if ticks_on_top { 24.0 } else { 0.0 };
        let mut y = top;
        for c in &self.categories {
            let lines = wrap(c, TICK_PX, CAT_LABEL_MAX);
            let h = (ns as f64 * slot + 10.0).max(lines.len() as f64 * 16.0 + 8.0);
            rows.push((y, h, lines));
            y += h;
        }
        let plot = Rect::new(left, top, BAR_PLOT_W, (y - top).max(20.0));
        let legend = (!entries.is_empty()).then(|| Rect::new(legend_x, top, lw, lh));
        let height = (plot.bottom() + 60.0).max(top + lh + 14.0).ceil();
        let layout = Layout {
            stem: stem.into(),
            kind: if dots { "dots" } else { "bars" }.into(),
            width: width.ceil(),
            height,
            plot,
            legend,
            x: v.record(&self.y_label, Some(data)),
            y: AxisRecord {
                title: String::new(),
                log: false,
                categorical: true,
                data: None,
                range: [0.0, self.categories.len() as f64],
                ticks: self.categories.clone(),
                off_scale: 0,
            },
            series: self.series.len(),
            zero_band: 0.0,
            styles: (0..self.series.len())
                .map(|i| {
                    if dots {
                        style_key(color(i), 0)
                    } else {
                        let c = color(i);
                        format!("#{:02x}{:02x}{:02x} bar", c.0, c.1, c.2)
                    }
                })
                .collect(),
            labels: Vec::new(),
            marks: Vec::new(),
        };
        Some(BarPlan {
            layout,
            title,
            v,
            dots,
            rows,
            slot,
            entries,
            ticks_on_top,
        })
    }

    /// Draws the chart, or returns a note when there is no value to draw. Categories without
    /// any value are left out (and counted in the caption).
    pub fn draw(&self, dir: &Path, stem: &str, caption: &str) -> Result<Figure> {
        ensure_font();
        let keep: Vec<bool> = (0..self.categories.len())
            .map(|c| {
                self.series
                    .iter()
                    .any(|(_, v)| v.get(c).is_some_and(|p| p.is_some_and(|p| p.y.is_finite())))
            })
            .collect();
        let empty = keep.iter().filter(|k| !**k).count();
        if empty > 0 {
            let pick = |v: &[Option<Pt>]| -> Vec<Option<Pt>> {
                v.iter()
                    .zip(&keep)
                    .filter(|(_, k)| **k)
                    .map(|(p, _)| *p)
                    .collect()
            };
            let mut b = self.clone();
            b.categories = self
                .categories
                .iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(c, _)| c.clone())
                .collect();
            b.series = self
                .series
                .iter()
                .map(|(n, v)| (n.clone(), pick(v)))
                .collect();
            let mut f = b.draw(dir, stem, caption)?;
            f.caption.push_str(&format!(
                " {empty} categor{} without a value left out.",
                if empty == 1 { "y" } else { "ies" }
            ));
            return Ok(f);
        }
        let Some(plan) = self.plan(stem) else {
            return Ok(Figure::note(&self.title, "not drawn: no value to show."));
        };
        write_all(dir, stem, &plan.layout, &|r| self.render(r, &plan), &|r| {
            self.render(r, &plan)
        })?;
        let how = if plan.dots {
            " Values span more than a decade: dots on a log axis."
        } else {
            " Bars start at zero on a linear axis."
        };
        Ok(Figure {
            title: self.title.clone(),
            stem: stem.into(),
            caption: format!("{caption}{how}"),
            ..Default::default()
        })
    }

    fn render<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, p: &BarPlan) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let l = &p.layout;
        let plot = l.plot;
        draw_title(root, &p.title, l.width / 2.0)?;
        let fx = |v: f64| plot.x + p.v.frac(v) * plot.w;
        // Row shading, then the value grid.
        for (i, (y, h, _)) in p.rows.iter().enumerate() {
            if i % 2 == 1 {
                root.draw(&Rectangle::new(
                    [(px(plot.x), px(*y)), (px(plot.right()), px(y + h))],
                    RGBColor(246, 246, 246).filled(),
                ))
                .map_err(err)?;
            }
        }
        for (v, lab) in p.v.ticks.iter().zip(&p.v.labels) {
            let x = fx(*v);
            root.draw(&PathElement::new(
                vec![(px(x), px(plot.y)), (px(x), px(plot.bottom()))],
                GRID.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&Text::new(
                lab.clone(),
                (px(x), px(plot.bottom() + 8.0)),
                text_style(TICK_PX, HPos::Center, VPos::Top, BLACK),
            ))
            .map_err(err)?;
            if p.ticks_on_top {
                root.draw(&Text::new(
                    lab.clone(),
                    (px(x), px(plot.y - 6.0)),
                    text_style(TICK_PX, HPos::Center, VPos::Bottom, BLACK),
                ))
                .map_err(err)?;
            }
        }
        draw_frame(root, &plot)?;
        let vt = axis_title(&self.y_label, p.dots);
        root.draw(&Text::new(
            vt,
            (px(plot.x + plot.w / 2.0), px(plot.bottom() + 30.0)),
            text_style(AXIS_PX, HPos::Center, VPos::Top, BLACK),
        ))
        .map_err(err)?;
        let ns = self.series.len().max(1);
        for (ci, (y, h, lines)) in p.rows.iter().enumerate() {
            let n = lines.len() as f64;
            for (k, line) in lines.iter().enumerate() {
                root.draw(&Text::new(
                    line.clone(),
                    (
                        px(plot.x - 8.0),
                        px(y + h / 2.0 - (n - 1.0) * 8.0 + k as f64 * 16.0),
                    ),
                    text_style(TICK_PX, HPos::Right, VPos::Center, BLACK),
                ))
                .map_err(err)?;
            }
            let y0 = y + (h - ns as f64 * p.slot) / 2.0;
            for (si, (_, vals)) in self.series.iter().enumerate() {
                let Some(Some(q)) = vals.get(ci) else {
                    continue;
                };
                if !q.y.is_finite() || (p.dots && q.y <= 0.0) {
                    continue;
                }
                let c = color(si);
                let cy = y0 + (si as f64 + 0.5) * p.slot;
                if !p.dots {
                    let (a, b) = (fx(0.0), fx(q.y));
                    let (a, b) = (a.min(b), a.max(b));
                    let r = [
                        (px(a), px(cy - p.slot * 0.42)),
                        (px(b), px(cy + p.slot * 0.42)),
                    ];
                    if q.flagged {
                        root.draw(&Rectangle::new(r, WHITE.filled())).map_err(err)?;
                        root.draw(&Rectangle::new(r, c.stroke_width(2)))
                            .map_err(err)?;
                    } else {
                        root.draw(&Rectangle::new(r, c.filled())).map_err(err)?;
                    }
                }
                if let (Some(lo), Some(hi)) = (q.lo, q.hi) {
                    if lo.is_finite() && hi.is_finite() && (!p.dots || lo > 0.0) {
                        let (a, b) = (fx(lo), fx(hi));
                        for seg in [
                            vec![(px(a), px(cy)), (px(b), px(cy))],
                            vec![(px(a), px(cy - 3.0)), (px(a), px(cy + 3.0))],
                            vec![(px(b), px(cy - 3.0)), (px(b), px(cy + 3.0))],
                        ] {
                            root.draw(&PathElement::new(seg, BLACK.stroke_width(1)))
                                .map_err(err)?;
                        }
                    }
                }
                if p.dots {
                    draw_marker(root, (fx(q.y), cy), 0, c, q.flagged, 4.0)?;
                }
            }
        }
        if let Some(r) = self
            .reference
            .filter(|r| r.is_finite() && (!p.dots || *r > 0.0))
        {
            let x = fx(r);
            root.draw(&PathElement::new(
                vec![(px(x), px(plot.y)), (px(x), px(plot.bottom()))],
                BLACK.stroke_width(1),
            ))
            .map_err(err)?;
        }
        if let Some(g) = &l.legend {
            draw_legend(root, g, &p.entries)?;
        }
        Ok(())
    }
}
