//! Chart helpers over plotters: every chart is written as PNG and SVG, with title, axis labels
//! (units in them), legend and min–max whiskers. Log axes are drawn by plotting log10 values on
//! a linear axis with 10^v tick labels (one code path for PNG and SVG).

use std::path::Path;
use std::sync::Once;

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

static FONT: Once = Once::new();

fn ensure_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        for style in [FontStyle::Normal, FontStyle::Bold] {
            let _ = plotters::style::register_font("sans-serif", style, bytes);
        }
    });
}

/// A chart written to `<stem>.png` and `<stem>.svg` in the report folder.
#[derive(Clone, Debug)]
pub struct Figure {
    pub title: String,
    pub stem: String,
    pub caption: String,
}

#[derive(Clone, Copy, Debug)]
pub struct Pt {
    pub x: f64,
    pub y: f64,
    /// min and max of y (whisker), if measured.
    pub lo: Option<f64>,
    pub hi: Option<f64>,
}

impl Pt {
    pub fn new(x: f64, y: f64) -> Pt {
        Pt {
            x,
            y,
            lo: None,
            hi: None,
        }
    }
    pub fn spread(x: f64, y: f64, lo: Option<f64>, hi: Option<f64>) -> Pt {
        Pt { x, y, lo, hi }
    }
}

#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<Pt>,
}

/// Line or scatter chart.
#[derive(Clone, Debug)]
pub struct XY {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    /// Connect points of a series (false: scatter).
    pub lines: bool,
    pub series: Vec<Series>,
}

fn tick(v: f64, log: bool) -> String {
    let v = if log { 10f64.powf(v) } else { v };
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    // Two significant digits: log-axis ticks fall between round numbers.
    let digits = (2 - a.log10().floor() as i32 - 1).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn tr(v: f64, log: bool) -> Option<f64> {
    if log {
        (v > 0.0 && v.is_finite()).then(|| v.log10())
    } else {
        v.is_finite().then_some(v)
    }
}

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = (hi - lo) * 0.06;
    (lo - pad, hi + pad)
}

/// Fraction of the plot area (≈ 510 px high in both chart kinds) that a legend of `rows` entries
/// (≈ 16 px each plus its frame) covers; capped so some data always stays visible.
fn legend_fraction(rows: usize) -> f64 {
    ((20.0 + 16.0 * rows as f64) / 510.0).min(0.85)
}

fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("plotting: {e:?}")
}

impl XY {
    pub fn draw(&self, dir: &Path, stem: &str, caption: &str) -> Result<Figure> {
        ensure_font();
        let png = dir.join(format!("{stem}.png"));
        let svg = dir.join(format!("{stem}.svg"));
        self.render(BitMapBackend::new(&png, (960, 600)).into_drawing_area())?;
        self.render(SVGBackend::new(&svg, (960, 600)).into_drawing_area())?;
        Ok(Figure {
            title: self.title.clone(),
            stem: stem.into(),
            caption: caption.into(),
        })
    }

    /// The plot corner the legend hides least data in: points and samples along the drawn lines
    /// are counted in each corner's box (about the legend's size) and the emptiest corner wins.
    /// Returns the corner and how many samples it would hide.
    fn legend_corner(
        &self,
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
    ) -> (SeriesLabelPosition, usize) {
        let norm = |p: &Pt| {
            let (x, y) = (tr(p.x, self.log_x)?, tr(p.y, self.log_y)?);
            Some(((x - x0) / (x1 - x0), (y - y0) / (y1 - y0)))
        };
        let mut samples = Vec::new();
        for s in &self.series {
            let p: Vec<(f64, f64)> = s.points.iter().filter_map(norm).collect();
            samples.extend(p.iter().copied());
            if self.lines {
                for w in p.windows(2) {
                    samples.extend((1..16).map(|i| {
                        let t = i as f64 / 16.0;
                        (
                            w[0].0 + (w[1].0 - w[0].0) * t,
                            w[0].1 + (w[1].1 - w[0].1) * t,
                        )
                    }));
                }
            }
        }
        let count = |left: bool, top: bool| {
            samples
                .iter()
                .filter(|(x, y)| {
                    (if left { *x < 0.45 } else { *x > 0.55 })
                        && (if top { *y > 0.6 } else { *y < 0.4 })
                })
                .count()
        };
        [
            (SeriesLabelPosition::UpperLeft, count(true, true)),
            (SeriesLabelPosition::UpperRight, count(false, true)),
            (SeriesLabelPosition::LowerRight, count(false, false)),
            (SeriesLabelPosition::LowerLeft, count(true, false)),
        ]
        .into_iter()
        .min_by_key(|(_, n)| *n)
        .expect("four corners")
    }

    fn render<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let pts: Vec<(f64, f64)> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter())
            .flat_map(|p| {
                let mut v = vec![(p.x, p.y)];
                v.extend(p.lo.map(|l| (p.x, l)));
                v.extend(p.hi.map(|h| (p.x, h)));
                v
            })
            .filter_map(|(x, y)| Some((tr(x, self.log_x)?, tr(y, self.log_y)?)))
            .collect();
        let (x0, x1) = range(pts.iter().map(|p| p.0));
        let (y0, mut y1) = range(pts.iter().map(|p| p.1));
        // The legend goes in the emptiest corner; when every corner holds data, the y range
        // grows upwards by about the legend's height so it sits above the data instead.
        let (mut corner, hidden) = self.legend_corner((x0, x1), (y0, y1));
        if hidden > 0 {
            let f = legend_fraction(self.series.len());
            y1 += (y1 - y0) * f / (1.0 - f);
            corner = SeriesLabelPosition::UpperRight;
        }
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        let (lx, ly) = (self.log_x, self.log_y);
        chart
            .configure_mesh()
            .x_desc(if lx {
                format!("{} (log)", self.x_label)
            } else {
                self.x_label.clone()
            })
            .y_desc(if ly {
                format!("{} (log)", self.y_label)
            } else {
                self.y_label.clone()
            })
            .x_label_formatter(&|v| tick(*v, lx))
            .y_label_formatter(&|v| tick(*v, ly))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(err)?;
        for (i, s) in self.series.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let p: Vec<(f64, f64, Option<f64>, Option<f64>)> = s
                .points
                .iter()
                .filter_map(|p| {
                    Some((
                        tr(p.x, lx)?,
                        tr(p.y, ly)?,
                        p.lo.and_then(|l| tr(l, ly)),
                        p.hi.and_then(|h| tr(h, ly)),
                    ))
                })
                .collect();
            if self.lines && p.len() > 1 {
                chart
                    .draw_series(LineSeries::new(
                        p.iter().map(|q| (q.0, q.1)),
                        color.stroke_width(2),
                    ))
                    .map_err(err)?;
            }
            chart
                .draw_series(p.iter().map(|q| Circle::new((q.0, q.1), 4, color.filled())))
                .map_err(err)?
                .label(&s.name)
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, color.filled()));
            for q in &p {
                if let (Some(l), Some(h)) = (q.2, q.3) {
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            vec![(q.0, l), (q.0, h)],
                            color.stroke_width(1),
                        )))
                        .map_err(err)?;
                }
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(corner)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
        Ok(())
    }
}

/// Grouped bar chart: categories on x, one bar per series in each category.
#[derive(Clone, Debug)]
pub struct Bars {
    pub title: String,
    pub y_label: String,
    pub log_y: bool,
    pub categories: Vec<String>,
    /// (series name, one optional (value, min, max) per category)
    pub series: Vec<(String, Vec<Option<Pt>>)>,
    /// Draw a horizontal reference line at this y (e.g. 1 for speedups), if any.
    pub reference: Option<f64>,
}

impl Bars {
    pub fn draw(&self, dir: &Path, stem: &str, caption: &str) -> Result<Figure> {
        ensure_font();
        let png = dir.join(format!("{stem}.png"));
        let svg = dir.join(format!("{stem}.svg"));
        let w =
            (300 + 40 * self.categories.len() * self.series.len().max(1)).clamp(960, 2400) as u32;
        self.render(BitMapBackend::new(&png, (w, 760)).into_drawing_area())?;
        self.render(SVGBackend::new(&svg, (w, 760)).into_drawing_area())?;
        Ok(Figure {
            title: self.title.clone(),
            stem: stem.into(),
            caption: caption.into(),
        })
    }

    fn render<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let ly = self.log_y;
        let vals: Vec<f64> = self
            .series
            .iter()
            .flat_map(|(_, v)| v.iter().flatten())
            .flat_map(|p| [Some(p.y), p.lo, p.hi])
            .flatten()
            .chain(self.reference)
            .filter_map(|v| tr(v, ly))
            .collect();
        let (mut y0, mut y1) = range(vals.iter().copied());
        if !ly {
            y0 = y0.min(0.0);
        }
        let n = self.categories.len().max(1);
        let ns = self.series.len().max(1);
        // The legend sits top right; if a bar (or whisker) in the right part would be under it,
        // the y range grows so the legend clears the tallest of them.
        let f = legend_fraction(ns);
        let under_legend = self
            .series
            .iter()
            .flat_map(|(_, v)| v.iter().enumerate())
            .filter(|(c, _)| (*c as f64 + 0.5) / n as f64 > 0.55)
            .filter_map(|(_, p)| p.as_ref())
            .filter_map(|p| tr(p.hi.unwrap_or(p.y).max(p.y), ly))
            .fold(f64::NEG_INFINITY, f64::max);
        if under_legend > y1 - (y1 - y0) * f {
            y1 = y0 + (under_legend - y0) / (1.0 - f);
        }
        // Names that fit their category's width (≈ 7 px a character) are written across;
        // otherwise all are rotated and anchored at their start, hanging below their category.
        // (Axis labels in plotters are centred on their tick: a long rotated one would run up
        // into the bars, hence drawn by hand below.)
        let name = |c: &String| {
            if c.chars().count() > 28 {
                format!("{}…", c.chars().take(27).collect::<String>())
            } else {
                c.clone()
            }
        };
        let longest = self
            .categories
            .iter()
            .map(|c| name(c).chars().count())
            .max();
        let plot_w = root.dim_in_pixel().0 as i64 - 110;
        let across = (longest.unwrap_or(0) * 7) as i64 <= plot_w / n as i64 - 8;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(12)
            // Room for the category names: one line, or up to 28 characters rotated.
            .x_label_area_size(if across { 48 } else { 190 })
            .y_label_area_size(72)
            .build_cartesian_2d(0f64..n as f64, y0..y1)
            .map_err(err)?;
        // Category names are drawn below; the mesh only marks the category bounds.
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n + 1)
            .x_label_formatter(&|_| String::new())
            .y_desc(if ly {
                format!("{} (log)", self.y_label)
            } else {
                self.y_label.clone()
            })
            .y_label_formatter(&|v| tick(*v, ly))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(err)?;
        let base = if ly { y0 } else { 0.0 };
        let bw = 0.8 / ns as f64;
        for (si, (name, vals)) in self.series.iter().enumerate() {
            let color = Palette99::pick(si).to_rgba();
            let rects: Vec<Rectangle<(f64, f64)>> = vals
                .iter()
                .enumerate()
                .filter_map(|(ci, p)| {
                    let p = (*p)?;
                    let y = tr(p.y, ly)?;
                    let x = ci as f64 + 0.1 + si as f64 * bw;
                    Some(Rectangle::new(
                        [(x, base), (x + bw * 0.92, y)],
                        color.filled(),
                    ))
                })
                .collect();
            chart
                .draw_series(rects)
                .map_err(err)?
                .label(name)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled())
                });
            for (ci, p) in vals.iter().enumerate() {
                if let Some(p) = p {
                    if let (Some(l), Some(h)) =
                        (p.lo.and_then(|v| tr(v, ly)), p.hi.and_then(|v| tr(v, ly)))
                    {
                        let x = ci as f64 + 0.1 + si as f64 * bw + bw * 0.46;
                        chart
                            .draw_series(std::iter::once(PathElement::new(
                                vec![(x, l), (x, h)],
                                BLACK.stroke_width(1),
                            )))
                            .map_err(err)?;
                    }
                }
            }
        }
        if let Some(r) = self.reference.and_then(|v| tr(v, ly)) {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(0.0, r), (n as f64, r)],
                    BLACK.stroke_width(1),
                )))
                .map_err(err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
        let style = if across {
            TextStyle::from(("sans-serif", 13).into_font()).pos(Pos::new(HPos::Center, VPos::Top))
        } else {
            TextStyle::from(
                ("sans-serif", 12)
                    .into_font()
                    .transform(FontTransform::Rotate90),
            )
            .pos(Pos::new(HPos::Left, VPos::Center))
        };
        for (i, c) in self.categories.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(i as f64 + 0.5, y0));
            root.draw(&Text::new(name(c), (px, py + 8), style.clone()))
                .map_err(err)?;
        }
        root.present().map_err(err)?;
        Ok(())
    }
}
