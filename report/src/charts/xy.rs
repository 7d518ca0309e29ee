//! Line and scatter charts (`XY`): log or linear axes from the data alone, a band under a log
//! axis for zeros, whiskers, a named Pareto front, floors as named verticals, grey context lines
//! for small multiples, and markers of different series moved apart where they would hide each
//! other.

use std::path::Path;

use anyhow::Result;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::draw::{
    axis_title, draw_frame, draw_legend, draw_marker, draw_title, entry, err, legend_size, minmax,
    px, Axis, Entry, Swatch,
};
use super::layout::{Layout, Mark, Rect, TextBox};
use super::output::write_all;
use super::style::{color, style_key, CONTEXT, FRAME, GRID, MUTED};
use super::text::{ensure_font, font, text_style, text_width, title_lines, AXIS_PX, TICK_PX};
use super::{ticks, Figure, Named, Pt, Series};

/// Line or scatter chart.
#[derive(Clone, Debug, Default)]
pub struct XY {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    /// Connect points of a series (false: scatter).
    pub lines: bool,
    pub series: Vec<Series>,
    /// Points joined by a dashed line and named (a Pareto front), with the line's legend name.
    pub front: Vec<Named>,
    pub front_name: String,
    /// Vertical reference lines (x, name), e.g. the floors on a time axis, and their legend
    /// entry (default "floors (named above the plot)").
    pub vlines: Vec<(f64, String)>,
    pub vlines_name: String,
    /// Name of the band under a log y axis where y = 0 is drawn (default "0").
    pub zero_label: String,
    /// Other configurations drawn as thin grey lines behind the series (small multiples: the
    /// rest of the field), with their one legend name.
    pub context: Vec<Vec<Pt>>,
    pub context_name: String,
}

const PLOT_W: f64 = 640.0;
const PLOT_H: f64 = 440.0;
const ZERO_BAND: f64 = 30.0;
/// A front with more members is numbered on the chart and named in the caption.
const FRONT_NAMED_MAX: usize = 6;
/// Markers of different series closer than this (px) are moved apart so each shows.
pub(super) const DODGE_PX: f64 = 9.0;
/// The sideways step between spread markers (px): a marker's width less a little.
const DODGE_STEP: f64 = 10.0;
const FLOOR_PX: f64 = 11.0;
const FLOOR_ROW: f64 = 15.0;
const FRONT_PX: f64 = 12.0;

/// A front member as placed: where its point is, and its label with an optional leader line.
struct FrontPlace {
    at: (f64, f64),
    label: Option<TextBox>,
    leader: bool,
}

/// Everything an XY chart needs to draw, computed before any drawing.
struct XyPlan {
    layout: Layout,
    title: Vec<String>,
    x: Axis,
    y: Axis,
    /// The plot's log (or linear) part: the plot minus the zero band.
    main: Rect,
    entries: Vec<Entry>,
    /// Points not drawable on the axes (≤ 0 on a log axis, not finite).
    dropped: usize,
    /// Per series, per point: where its marker goes (after spreading coincident ones).
    pos: Vec<Vec<Option<(f64, f64)>>>,
    /// Markers moved sideways because another series' marker sat on the same spot.
    dodged: usize,
    /// The reference lines: pixel x and their label (above the plot).
    floors: Vec<(f64, TextBox)>,
    front: Vec<FrontPlace>,
    /// Front members without room for their name on the chart (named in the caption).
    unnamed: Vec<String>,
}

/// Moves a marker that would sit on (nearly) the same spot as an earlier one of another series
/// to the nearest free spot of a `DODGE_STEP` grid around it (sideways first), inside the plot
/// (`inside`, for marker centres), so none hides another and each stays by its value; returns how many moved.
/// A `level` marker (a value that is exactly 0 on a linear axis: a rate that never happened)
/// moves sideways only, so it stays on its line.
fn dodge(pos: &mut [Vec<Option<(f64, f64)>>], level: &[Vec<bool>], inside: Rect) -> usize {
    let mut grid: Vec<(f64, f64)> = (-8..=8)
        .flat_map(|i| (-8..=8).map(move |j| (f64::from(i), f64::from(j))))
        .collect();
    grid.sort_by(|a, b| {
        a.0.hypot(a.1)
            .total_cmp(&b.0.hypot(b.1))
            .then(a.1.abs().total_cmp(&b.1.abs()))
    });
    let mut placed: Vec<(usize, f64, f64)> = Vec::new();
    let mut moved = 0;
    for (i, s) in pos.iter_mut().enumerate() {
        for (j, p) in s.iter_mut().enumerate() {
            let Some((x, y)) = *p else { continue };
            let sideways = level
                .get(i)
                .and_then(|l| l.get(j))
                .copied()
                .unwrap_or(false);
            let clash = |cx: f64, cy: f64| {
                placed
                    .iter()
                    .any(|(k, ox, oy)| *k != i && (cx - ox).hypot(cy - oy) < DODGE_PX)
            };
            let free = |only_sideways: bool| {
                grid.iter()
                    .filter(|(_, b)| !only_sideways || *b == 0.0)
                    .map(|(a, b)| (x + a * DODGE_STEP, y + b * DODGE_STEP))
                    .filter(|(cx, cy)| {
                        (*cx, *cy) == (x, y)
                            || (inside.x..=inside.right()).contains(cx)
                                && (inside.y..=inside.bottom()).contains(cy)
                    })
                    .find(|(cx, cy)| !clash(*cx, *cy))
            };
            // Off its line only when the line itself is full (the caption counts every move).
            let (nx, ny) = free(sideways)
                .or_else(|| free(false).filter(|_| sideways))
                .unwrap_or((x, y));
            if (nx, ny) != (x, y) {
                moved += 1;
                *p = Some((nx, ny));
            }
            placed.push((i, nx, ny));
        }
    }
    moved
}

/// Whether a leader line from `at` to the label `r` crosses no marker or front ring but the
/// one at `at`.
fn leader_clear(at: (f64, f64), r: &Rect, marks: &[Mark], rings: &[Rect]) -> bool {
    let (cx, cy) = (at.0.clamp(r.x, r.right()), at.1.clamp(r.y, r.bottom()));
    let len = (cx - at.0).hypot(cy - at.1);
    let own = |o: &Rect| o.x <= at.0 && at.0 <= o.right() && o.y <= at.1 && at.1 <= o.bottom();
    let n = (len / 2.0).ceil().max(1.0) as usize;
    (0..=n).all(|k| {
        let t = k as f64 / n as f64;
        let p = Rect::new(at.0 + (cx - at.0) * t, at.1 + (cy - at.1) * t, 0.1, 0.1);
        marks
            .iter()
            .map(|m| &m.rect)
            .chain(rings)
            .all(|o| own(o) || !o.intersects(&p))
    })
}

impl XY {
    fn x_ok(&self, x: f64) -> bool {
        x.is_finite() && (!self.log_x || x > 0.0)
    }
    /// Where a y value goes: Some(true) on the axis, Some(false) in the zero band, None nowhere.
    fn y_place(&self, y: f64) -> Option<bool> {
        if !y.is_finite() {
            None
        } else if !self.log_y || y > 0.0 {
            Some(true)
        } else if y == 0.0 {
            Some(false)
        } else {
            None
        }
    }

    fn plan(&self, stem: &str) -> Option<XyPlan> {
        let pts: Vec<&Pt> = self.series.iter().flat_map(|s| s.points.iter()).collect();
        let ok = |p: &Pt| self.x_ok(p.x) && self.y_place(p.y).is_some();
        let drawn: Vec<&Pt> = pts.iter().copied().filter(|p| ok(p)).collect();
        let dropped = pts.len() - drawn.len();
        if drawn.len() < 2 {
            return None;
        }
        let context: Vec<&Pt> = self.context.iter().flatten().filter(|p| ok(p)).collect();
        let front: Vec<&Named> = self
            .front
            .iter()
            .filter(|n| self.x_ok(n.x) && self.y_place(n.y).is_some())
            .collect();
        let xs = drawn
            .iter()
            .flat_map(|p| [Some(p.x), p.xlo, p.xhi])
            .flatten()
            .filter(|x| self.x_ok(*x))
            .chain(context.iter().map(|p| p.x))
            .chain(front.iter().map(|n| n.x))
            .chain(self.vlines.iter().map(|v| v.0).filter(|x| self.x_ok(*x)));
        let x_data = minmax(xs)?;
        let on_axis = |y: f64| self.y_place(y) == Some(true);
        let ys = drawn
            .iter()
            .flat_map(|p| [Some(p.y), p.lo, p.hi])
            .flatten()
            .chain(context.iter().map(|p| p.y))
            .chain(front.iter().map(|n| n.y))
            .filter(|y| on_axis(*y));
        let y_data = minmax(ys);
        let zero = self.log_y && drawn.iter().chain(&context).any(|p| p.y == 0.0);
        let x = Axis::new(
            ticks::axis_range(x_data[0], x_data[1], self.log_x),
            self.log_x,
        );
        // Only zeros on a log axis: the axis around them is arbitrary; show one decade.
        let y = match y_data {
            Some(d) => Axis::new(ticks::axis_range(d[0], d[1], self.log_y), self.log_y),
            None => Axis::new((1e-3, 1e-2), true),
        };
        let ytw = y
            .labels
            .iter()
            .map(|l| text_width(l, TICK_PX))
            .chain(zero.then(|| text_width(self.zero_label_text(), TICK_PX)))
            .fold(0.0, f64::max);
        let mut entries: Vec<Entry> = self
            .series
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.name.is_empty())
            .map(|(i, s)| {
                entry(
                    Swatch::Marker {
                        family: s.family,
                        color: color(s.color.unwrap_or(i)),
                        hollow: false,
                    },
                    &s.name,
                )
            })
            .collect();
        if !context.is_empty() {
            entries.push(entry(
                Swatch::Line {
                    color: CONTEXT,
                    dashed: false,
                },
                &self.context_name,
            ));
        }
        if drawn.iter().any(|p| p.flagged) {
            entries.push(entry(
                Swatch::Marker {
                    family: 0,
                    color: MUTED,
                    hollow: true,
                },
                "hollow: flagged (see table)",
            ));
        }
        if front.len() > 1 {
            entries.push(entry(
                Swatch::Line {
                    color: BLACK,
                    dashed: true,
                },
                &self.front_name,
            ));
        }
        if !self.vlines.is_empty() {
            entries.push(entry(
                Swatch::Line {
                    color: MUTED,
                    dashed: true,
                },
                if self.vlines_name.is_empty() {
                    "floors (named above the plot)"
                } else {
                    &self.vlines_name
                },
            ));
        }
        let left = 16.0 + AXIS_PX + 12.0 + ytw + 10.0;
        let last_x = x
            .labels
            .last()
            .map(|l| text_width(l, TICK_PX))
            .unwrap_or(0.0);
        let (lw, lh) = legend_size(&entries);
        let legend_x = left + PLOT_W + (last_x / 2.0 + 12.0).max(24.0);
        let width = if entries.is_empty() {
            legend_x
        } else {
            legend_x + lw + 14.0
        };
        let title = title_lines(&self.title, width - 24.0);
        // The floors' names, level above the plot, each over its line; names that would touch
        // go to the next row up (no rotated text crossing its neighbour or a marker).
        let label_top = 12.0 + title.len() as f64 * 26.0 + 4.0;
        let mut vl: Vec<(f64, String)> = self
            .vlines
            .iter()
            .filter(|(v, _)| self.x_ok(*v))
            .map(|(v, n)| (left + x.frac(*v) * PLOT_W, n.clone()))
            .collect();
        vl.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut rows: Vec<Vec<Rect>> = Vec::new();
        let mut floors_at: Vec<(f64, String, Rect, usize)> = Vec::new();
        for (xp, name) in vl {
            let w = text_width(&name, FLOOR_PX) + 4.0;
            let rx = (xp - w / 2.0).clamp(2.0, width - w - 2.0);
            let r = Rect::new(rx - 3.0, 0.0, w + 6.0, FLOOR_ROW - 1.0);
            let row = match rows
                .iter()
                .position(|row| !row.iter().any(|o| o.intersects(&r)))
            {
                Some(k) => k,
                None => {
                    rows.push(Vec::new());
                    rows.len() - 1
                }
            };
            rows[row].push(r);
            floors_at.push((xp, name, Rect::new(rx, 0.0, w, FLOOR_ROW - 1.0), row));
        }
        let nrows = rows.len() as f64;
        // Row 0 sits just above the plot; later rows stack upwards.
        let top = if rows.is_empty() {
            12.0 + title.len() as f64 * 26.0 + 12.0
        } else {
            label_top + nrows * FLOOR_ROW + 6.0
        };
        let floors: Vec<(f64, TextBox)> = floors_at
            .into_iter()
            .map(|(xp, text, mut r, row)| {
                r.y = top - 6.0 - (row as f64 + 1.0) * FLOOR_ROW;
                (xp, TextBox { text, rect: r })
            })
            .collect();
        // A long legend gets a taller plot beside it rather than white space.
        let plot_h = lh.clamp(PLOT_H, 1.5 * PLOT_H);
        let plot = Rect::new(left, top, PLOT_W, plot_h);
        let legend = (!entries.is_empty()).then(|| Rect::new(legend_x, top, lw, lh));
        let height = (top + plot_h + 60.0).max(top + lh + 14.0).ceil();
        let main = if zero {
            Rect::new(left, top, PLOT_W, plot_h - ZERO_BAND)
        } else {
            plot
        };
        let fx = |v: f64| plot.x + x.frac(v) * plot.w;
        let zero_y = plot.bottom() - ZERO_BAND / 2.0 + 2.0;
        let fy = |v: f64| {
            if self.log_y && v == 0.0 {
                zero_y
            } else {
                main.bottom() - y.frac(v) * main.h
            }
        };
        let mut pos: Vec<Vec<Option<(f64, f64)>>> = self
            .series
            .iter()
            .map(|s| {
                s.points
                    .iter()
                    .map(|q| ok(q).then(|| (fx(q.x), fy(q.y))))
                    .collect()
            })
            .collect();
        let level: Vec<Vec<bool>> = self
            .series
            .iter()
            .map(|s| s.points.iter().map(|q| !self.log_y && q.y == 0.0).collect())
            .collect();
        let dodged = dodge(
            &mut pos,
            &level,
            Rect::new(plot.x + 6.0, plot.y + 6.0, plot.w - 12.0, plot.h - 12.0),
        );
        let marks: Vec<Mark> = pos
            .iter()
            .enumerate()
            .flat_map(|(i, s)| {
                s.iter().flatten().map(move |(mx, my)| Mark {
                    series: i,
                    rect: Rect::new(mx - 6.0, my - 6.0, 12.0, 12.0),
                })
            })
            .collect();
        // The front: each member named where its name covers no marker, no front ring and no
        // other name, nearest first (a leader line when not beside its point); else in the
        // caption.
        let mut fr: Vec<(f64, f64, &str)> = front
            .iter()
            .map(|n| (fx(n.x), fy(n.y), n.text.as_str()))
            .collect();
        fr.sort_by(|a, b| a.0.total_cmp(&b.0));
        let numbered = fr.len() > FRONT_NAMED_MAX;
        let rings: Vec<Rect> = fr
            .iter()
            .map(|(a, b, _)| Rect::new(a - 9.0, b - 9.0, 18.0, 18.0))
            .collect();
        let mut placed: Vec<Rect> = Vec::new();
        let mut front_places = Vec::new();
        let mut unnamed = Vec::new();
        for (i, (fxp, fyp, text)) in fr.iter().enumerate() {
            let text = if numbered {
                (i + 1).to_string()
            } else {
                text.to_string()
            };
            let (w, h) = (text_width(&text, FRONT_PX) + 4.0, 15.0);
            // Nearest first: rings 8 px apart, 16 directions each (right and left first).
            let spot = (0..20).map(|k| 10.0 + 8.0 * k as f64).find_map(|d| {
                [0, 8, 14, 2, 10, 6, 12, 4, 15, 1, 9, 7, 13, 3, 11, 5]
                    .iter()
                    .map(|k| {
                        let a = *k as f64 * std::f64::consts::TAU / 16.0;
                        let (cx, cy) =
                            (fxp + a.cos() * (d + w / 2.0), fyp + a.sin() * (d + h / 2.0));
                        Rect::new(cx - w / 2.0, cy - h / 2.0, w, h)
                    })
                    .find(|r| {
                        plot.contains(r)
                            && !placed.iter().any(|o| o.intersects(r))
                            && !marks.iter().any(|m| m.rect.intersects(r))
                            && !rings.iter().any(|o| o.intersects(r))
                            && (d <= 10.0 || leader_clear((*fxp, *fyp), r, &marks, &rings))
                    })
                    .map(|r| (r, d > 10.0))
            });
            match spot {
                Some((r, leader)) => {
                    placed.push(r);
                    front_places.push(FrontPlace {
                        at: (*fxp, *fyp),
                        label: Some(TextBox { text, rect: r }),
                        leader,
                    });
                }
                None => {
                    if !numbered {
                        unnamed.push(text);
                    }
                    front_places.push(FrontPlace {
                        at: (*fxp, *fyp),
                        label: None,
                        leader: false,
                    });
                }
            }
        }
        let mut labels: Vec<TextBox> = floors.iter().map(|(_, t)| t.clone()).collect();
        labels.extend(front_places.iter().filter_map(|f| f.label.clone()));
        let styles = self
            .series
            .iter()
            .enumerate()
            .map(|(i, s)| {
                if s.name.is_empty() {
                    String::new()
                } else {
                    style_key(color(s.color.unwrap_or(i)), s.family)
                }
            })
            .collect();
        let layout = Layout {
            stem: stem.to_string(),
            kind: "xy".into(),
            width: width.ceil(),
            height,
            plot,
            legend,
            x: x.record(&self.x_label, Some(x_data)),
            y: y.record(&self.y_label, y_data),
            series: self.series.len(),
            zero_band: if zero { ZERO_BAND } else { 0.0 },
            styles,
            labels,
            marks,
        };
        Some(XyPlan {
            layout,
            title,
            x,
            y,
            main,
            entries,
            dropped,
            pos,
            dodged,
            floors,
            front: front_places,
            unnamed,
        })
    }

    fn zero_label_text(&self) -> &str {
        if self.zero_label.is_empty() {
            "0"
        } else {
            &self.zero_label
        }
    }

    /// Draws the chart, or returns a note when fewer than two points can be drawn.
    pub fn draw(&self, dir: &Path, stem: &str, caption: &str) -> Result<Figure> {
        ensure_font();
        let Some(plan) = self.plan(stem) else {
            let n: usize = self.series.iter().map(|s| s.points.len()).sum();
            return Ok(Figure::note(
                &self.title,
                format!(
                    "not drawn: {} to show ({} configuration{}).",
                    match n {
                        0 => "no point".to_string(),
                        1 => "one point".to_string(),
                        n => format!("{n} points, fewer than two drawable"),
                    },
                    self.series.len(),
                    if self.series.len() == 1 { "" } else { "s" }
                ),
            ));
        };
        write_all(dir, stem, &plan.layout, &|r| self.render(r, &plan), &|r| {
            self.render(r, &plan)
        })?;
        let mut caption = caption.to_string();
        let mut front: Vec<&Named> = self
            .front
            .iter()
            .filter(|n| self.x_ok(n.x) && self.y_place(n.y).is_some())
            .collect();
        if front.len() > FRONT_NAMED_MAX {
            front.sort_by(|a, b| a.x.total_cmp(&b.x));
            let names: Vec<String> = front
                .iter()
                .enumerate()
                .map(|(i, n)| format!("{} {}", i + 1, n.text))
                .collect();
            caption.push_str(&format!(" Front, left to right: {}.", names.join("; ")));
        }
        if !plan.unnamed.is_empty() {
            caption.push_str(&format!(
                " Front members without room for their name on the chart: {}.",
                plan.unnamed.join("; ")
            ));
        }
        if plan.dodged > 0 {
            caption.push_str(&format!(
                " {} markers of different configurations at the same spot are moved apart ({} px steps, to the nearest free spot) so each shows.",
                plan.dodged, DODGE_STEP
            ));
        }
        if plan.dropped > 0 {
            caption.push_str(&format!(
                " {} point{} not drawn (not finite, or ≤ 0 on a log axis).",
                plan.dropped,
                if plan.dropped == 1 { "" } else { "s" }
            ));
        }
        Ok(Figure {
            title: self.title.clone(),
            stem: stem.into(),
            caption,
            ..Default::default()
        })
    }

    fn render<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, p: &XyPlan) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let l = &p.layout;
        let (plot, main) = (l.plot, p.main);
        draw_title(root, &p.title, l.width / 2.0)?;
        let fx = |v: f64| plot.x + p.x.frac(v) * plot.w;
        let zero_y = plot.bottom() - ZERO_BAND / 2.0 + 2.0;
        let fy = |v: f64| {
            if self.log_y && v == 0.0 {
                zero_y
            } else {
                main.bottom() - p.y.frac(v) * main.h
            }
        };
        // Grid, ticks and tick labels.
        for (v, lab) in p.x.ticks.iter().zip(&p.x.labels) {
            let x = fx(*v);
            root.draw(&PathElement::new(
                vec![(px(x), px(plot.y)), (px(x), px(plot.bottom()))],
                GRID.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&PathElement::new(
                vec![(px(x), px(plot.bottom())), (px(x), px(plot.bottom() + 5.0))],
                FRAME.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&Text::new(
                lab.clone(),
                (px(x), px(plot.bottom() + 8.0)),
                text_style(TICK_PX, HPos::Center, VPos::Top, BLACK),
            ))
            .map_err(err)?;
        }
        for (v, lab) in p.y.ticks.iter().zip(&p.y.labels) {
            let y = main.bottom() - p.y.frac(*v) * main.h;
            root.draw(&PathElement::new(
                vec![(px(plot.x), px(y)), (px(plot.right()), px(y))],
                GRID.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&PathElement::new(
                vec![(px(plot.x - 5.0), px(y)), (px(plot.x), px(y))],
                FRAME.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&Text::new(
                lab.clone(),
                (px(plot.x - 8.0), px(y)),
                text_style(TICK_PX, HPos::Right, VPos::Center, BLACK),
            ))
            .map_err(err)?;
        }
        if l.zero_band > 0.0 {
            root.draw(&DashedPathElement::new(
                vec![
                    (px(plot.x), px(main.bottom())),
                    (px(plot.right()), px(main.bottom())),
                ],
                4,
                3,
                FRAME.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&Text::new(
                self.zero_label_text().to_string(),
                (px(plot.x - 8.0), px(zero_y)),
                text_style(TICK_PX, HPos::Right, VPos::Center, BLACK),
            ))
            .map_err(err)?;
        }
        draw_frame(root, &plot)?;
        // Axis titles.
        let xt = axis_title(&self.x_label, self.log_x);
        let yt = axis_title(&self.y_label, self.log_y);
        root.draw(&Text::new(
            xt,
            (px(plot.x + plot.w / 2.0), px(plot.bottom() + 30.0)),
            text_style(AXIS_PX, HPos::Center, VPos::Top, BLACK),
        ))
        .map_err(err)?;
        root.draw(&Text::new(
            yt,
            (px(16.0), px(plot.y + plot.h / 2.0)),
            font(AXIS_PX)
                .transform(FontTransform::Rotate270)
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Top)),
        ))
        .map_err(err)?;
        // Reference lines, each continued up (dotted) to its name above the plot.
        for (xp, t) in &p.floors {
            root.draw(&DashedPathElement::new(
                vec![(px(*xp), px(plot.y)), (px(*xp), px(plot.bottom()))],
                5,
                4,
                MUTED.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&DashedPathElement::new(
                vec![(px(*xp), px(t.rect.bottom())), (px(*xp), px(plot.y))],
                1,
                2,
                MUTED.stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&Text::new(
                t.text.clone(),
                (px(t.rect.x + 2.0), px(t.rect.y + t.rect.h / 2.0)),
                text_style(FLOOR_PX, HPos::Left, VPos::Center, MUTED),
            ))
            .map_err(err)?;
        }
        // Other configurations, for context: thin grey lines under everything.
        for c in &self.context {
            let mut line: Vec<(f64, f64)> = c
                .iter()
                .filter(|q| self.x_ok(q.x) && self.y_place(q.y).is_some())
                .map(|q| (fx(q.x), fy(q.y)))
                .collect();
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            for w in line.windows(2) {
                root.draw(&PathElement::new(
                    vec![(px(w[0].0), px(w[0].1)), (px(w[1].0), px(w[1].1))],
                    CONTEXT.stroke_width(1),
                ))
                .map_err(err)?;
            }
        }
        // Lines, whiskers, then markers on top.
        for (i, s) in self.series.iter().enumerate() {
            let c = color(s.color.unwrap_or(i));
            let mut line: Vec<(f64, f64)> = p.pos[i].iter().flatten().copied().collect();
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            if self.lines {
                // Segment by segment: a 2 px polyline's miter join at a sharp turn draws a long
                // spike out of the plot in the bitmap backend.
                for w in line.windows(2) {
                    let (a, b) = (w[0], w[1]);
                    root.draw(&PathElement::new(
                        vec![(px(a.0), px(a.1)), (px(b.0), px(b.1))],
                        c.mix(0.8).stroke_width(2),
                    ))
                    .map_err(err)?;
                }
            }
            for (q, at) in s.points.iter().zip(&p.pos[i]) {
                let Some((x, y)) = *at else { continue };
                if let (Some(lo), Some(hi)) = (q.xlo, q.xhi) {
                    if self.x_ok(lo) && self.x_ok(hi) {
                        let (a, b) = (fx(lo), fx(hi));
                        for seg in [
                            vec![(px(a), px(y)), (px(b), px(y))],
                            vec![(px(a), px(y - 3.0)), (px(a), px(y + 3.0))],
                            vec![(px(b), px(y - 3.0)), (px(b), px(y + 3.0))],
                        ] {
                            root.draw(&PathElement::new(seg, c.stroke_width(1)))
                                .map_err(err)?;
                        }
                    }
                }
                if let (Some(lo), Some(hi)) = (q.lo, q.hi) {
                    if self.y_place(lo) == Some(true) && self.y_place(hi) == Some(true) {
                        let (a, b) = (fy(lo), fy(hi));
                        for seg in [
                            vec![(px(x), px(a)), (px(x), px(b))],
                            vec![(px(x - 3.0), px(a)), (px(x + 3.0), px(a))],
                            vec![(px(x - 3.0), px(b)), (px(x + 3.0), px(b))],
                        ] {
                            root.draw(&PathElement::new(seg, c.stroke_width(1)))
                                .map_err(err)?;
                        }
                    }
                }
            }
        }
        for (i, s) in self.series.iter().enumerate() {
            for (q, at) in s.points.iter().zip(&p.pos[i]) {
                let Some(at) = *at else { continue };
                draw_marker(
                    root,
                    at,
                    s.family,
                    color(s.color.unwrap_or(i)),
                    q.flagged,
                    5.0,
                )?;
            }
        }
        // The front: a dashed line through its members, each named where there is room.
        if p.front.len() > 1 {
            root.draw(&DashedPathElement::new(
                p.front
                    .iter()
                    .map(|f| (px(f.at.0), px(f.at.1)))
                    .collect::<Vec<_>>(),
                6,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(err)?;
        }
        for f in &p.front {
            let (x, y) = f.at;
            root.draw(&Circle::new((px(x), px(y)), 8, BLACK.stroke_width(1)))
                .map_err(err)?;
            let Some(t) = &f.label else { continue };
            let r = t.rect;
            if f.leader {
                let cx = x.clamp(r.x, r.right());
                let cy = y.clamp(r.y, r.bottom());
                let d = (cx - x).hypot(cy - y).max(1.0);
                root.draw(&PathElement::new(
                    vec![
                        (px(x + (cx - x) * 9.0 / d), px(y + (cy - y) * 9.0 / d)),
                        (px(cx), px(cy)),
                    ],
                    MUTED.stroke_width(1),
                ))
                .map_err(err)?;
            }
            root.draw(&Rectangle::new(
                [(px(r.x), px(r.y)), (px(r.right()), px(r.bottom()))],
                WHITE.mix(0.6).filled(),
            ))
            .map_err(err)?;
            root.draw(&Text::new(
                t.text.clone(),
                (px(r.x + 2.0), px(r.y + r.h / 2.0)),
                text_style(FRONT_PX, HPos::Left, VPos::Center, BLACK),
            ))
            .map_err(err)?;
        }
        if let Some(g) = &l.legend {
            draw_legend(root, g, &p.entries)?;
        }
        Ok(())
    }
}
