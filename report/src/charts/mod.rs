//! Charts over plotters, laid out by hand so the layout is known exactly: every chart is written
//! as `<stem>.png`, `<stem>.svg` and `<stem>.layout.json` (the rectangles and ranges that
//! `layout::check` and `scripts/check-report.sh` test). Legends sit outside the plot, axis ranges
//! come from the data alone, log axes carry decade or 1-2-5 ticks, bars start at zero on linear
//! axes and values that span decades become dot plots. A chart that cannot say anything is not
//! drawn: `Figure::note` says so in one line instead.

pub mod layout;
pub mod ticks;

use std::path::Path;
use std::sync::Once;

use anyhow::{anyhow, Context, Result};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

pub use layout::{AxisRecord, Layout, Mark, Rect, TextBox};

static FONT: Once = Once::new();

fn ensure_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/DejaVuSans.ttf");
        for style in [FontStyle::Normal, FontStyle::Bold] {
            let _ = plotters::style::register_font("sans-serif", style, bytes);
        }
    });
}

/// One item of a report section: a chart (`<stem>.svg`/`.png`), a one-line note standing in for
/// a chart that would say nothing, or a block of HTML (a table).
#[derive(Clone, Debug, Default)]
pub struct Figure {
    pub title: String,
    pub stem: String,
    pub caption: String,
    /// Set when no chart was drawn: the line that says why.
    pub note: Option<String>,
    /// Set for a table or other HTML block (no chart).
    pub html: Option<String>,
}

impl Figure {
    pub fn note(title: impl Into<String>, note: impl Into<String>) -> Figure {
        Figure {
            title: title.into(),
            note: Some(note.into()),
            ..Default::default()
        }
    }
    pub fn html(title: impl Into<String>, html: impl Into<String>) -> Figure {
        Figure {
            title: title.into(),
            html: Some(html.into()),
            ..Default::default()
        }
    }
    /// A drawn chart (not a note or a table).
    pub fn is_chart(&self) -> bool {
        self.note.is_none() && self.html.is_none()
    }
}

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
const SHAPES: [(usize, f64); 8] = [
    (0, 0.0),                          // circle
    (4, std::f64::consts::FRAC_PI_4),  // square
    (3, -std::f64::consts::FRAC_PI_2), // triangle up
    (4, 0.0),                          // diamond
    (3, std::f64::consts::FRAC_PI_2),  // triangle down
    (6, 0.0),                          // hexagon
    (5, -std::f64::consts::FRAC_PI_2), // pentagon
    (3, 0.0),                          // triangle right
];
const SHAPE_NAMES: [&str; 8] = [
    "circle",
    "square",
    "triangle-up",
    "diamond",
    "triangle-down",
    "hexagon",
    "pentagon",
    "triangle-right",
];

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pt {
    pub x: f64,
    pub y: f64,
    /// The ends of a whisker on y (a confidence interval), when measured.
    pub lo: Option<f64>,
    pub hi: Option<f64>,
    /// The ends of a whisker on x, when measured.
    pub xlo: Option<f64>,
    pub xhi: Option<f64>,
    /// Drawn hollow: the row carries a flag (overflow, hazard, noisy, …).
    pub flagged: bool,
}

impl Pt {
    pub fn new(x: f64, y: f64) -> Pt {
        Pt {
            x,
            y,
            ..Default::default()
        }
    }
    pub fn spread(x: f64, y: f64, lo: Option<f64>, hi: Option<f64>) -> Pt {
        Pt {
            x,
            y,
            lo,
            hi,
            ..Default::default()
        }
    }
    pub fn flagged(mut self, f: bool) -> Pt {
        self.flagged = f;
        self
    }
}

#[derive(Clone, Debug, Default)]
pub struct Series {
    pub name: String,
    /// Marker shape index: one per method family.
    pub family: usize,
    /// Palette index (default: the series' position), so a configuration keeps its colour
    /// across charts.
    pub color: Option<usize>,
    pub points: Vec<Pt>,
}

impl Series {
    pub fn new(name: impl Into<String>, points: Vec<Pt>) -> Series {
        Series {
            name: name.into(),
            family: 0,
            color: None,
            points,
        }
    }
}

/// A point named on the chart (a Pareto front's members).
#[derive(Clone, Debug, Default)]
pub struct Named {
    pub x: f64,
    pub y: f64,
    pub text: String,
}

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

fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("plotting: {e:?}")
}

const TITLE_PX: f64 = 20.0;
const AXIS_PX: f64 = 15.0;
const TICK_PX: f64 = 13.0;
const LEGEND_PX: f64 = 13.0;
const LEGEND_LINE: f64 = 18.0;
const LEGEND_TEXT_MAX: f64 = 330.0;

fn font(px: f64) -> FontDesc<'static> {
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

/// One legend entry: what its swatch shows and its (wrapped) text.
#[derive(Clone, Debug)]
enum Swatch {
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
struct Entry {
    swatch: Swatch,
    lines: Vec<String>,
}

fn entry(swatch: Swatch, text: &str) -> Entry {
    Entry {
        swatch,
        lines: wrap(text, LEGEND_PX, LEGEND_TEXT_MAX),
    }
}

fn legend_size(entries: &[Entry]) -> (f64, f64) {
    let tw = entries
        .iter()
        .flat_map(|e| e.lines.iter())
        .map(|l| text_width(l, LEGEND_PX))
        .fold(0.0, f64::max);
    let rows: usize = entries.iter().map(|e| e.lines.len()).sum();
    (tw + 44.0, rows as f64 * LEGEND_LINE + 14.0)
}

/// Title lines that fit `max` px (broken at " — " first, then at spaces).
fn title_lines(t: &str, max: f64) -> Vec<String> {
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

/// A numeric axis: range, ticks, and the map from values to pixels.
#[derive(Clone, Debug)]
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
    ticks: Vec<f64>,
    labels: Vec<String>,
}

impl Axis {
    fn new((lo, hi): (f64, f64), log: bool) -> Axis {
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
    fn t(&self, v: f64) -> f64 {
        if self.log {
            v.log10()
        } else {
            v
        }
    }
    /// 0 at `lo`, 1 at `hi`.
    fn frac(&self, v: f64) -> f64 {
        (self.t(v) - self.t(self.lo)) / (self.t(self.hi) - self.t(self.lo))
    }
    fn record(&self, title: &str, data: Option<[f64; 2]>) -> AxisRecord {
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

fn minmax(v: impl Iterator<Item = f64>) -> Option<[f64; 2]> {
    let mut r: Option<[f64; 2]> = None;
    for x in v {
        r = Some(match r {
            None => [x, x],
            Some([a, b]) => [a.min(x), b.max(x)],
        });
    }
    r
}

fn px(v: f64) -> i32 {
    v.round() as i32
}

fn text_style(px_size: f64, h: HPos, v: VPos, c: RGBColor) -> TextStyle<'static> {
    font(px_size).color(&c).pos(Pos::new(h, v))
}

/// The thin grey outline of `r` (plot areas, legend boxes).
fn draw_frame<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, r: &Rect) -> Result<()>
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
fn axis_title(label: &str, log: bool) -> String {
    if log {
        format!("{label} (log scale)")
    } else {
        label.to_string()
    }
}

const GRID: RGBColor = RGBColor(228, 228, 228);
const FRAME: RGBColor = RGBColor(120, 120, 120);
const MUTED: RGBColor = RGBColor(110, 110, 110);
const CONTEXT: RGBColor = RGBColor(200, 200, 200);

fn draw_marker<DB: DrawingBackend>(
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

fn draw_legend<DB: DrawingBackend>(
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

fn draw_title<DB: DrawingBackend>(
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

/// Writes the PNG, the SVG and the layout record of one chart.
fn write_all(
    dir: &Path,
    stem: &str,
    layout: &Layout,
    draw_png: &dyn Fn(&DrawingArea<BitMapBackend, Shift>) -> Result<()>,
    draw_svg: &dyn Fn(&DrawingArea<SVGBackend, Shift>) -> Result<()>,
) -> Result<()> {
    let size = (layout.width as u32, layout.height as u32);
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    if let Some(p) = png.parent() {
        std::fs::create_dir_all(p).with_context(|| format!("creating {}", p.display()))?;
    }
    {
        let root = BitMapBackend::new(&png, size).into_drawing_area();
        draw_png(&root)?;
        root.present().map_err(err)?;
    }
    {
        let root = SVGBackend::new(&svg, size).into_drawing_area();
        draw_svg(&root)?;
        root.present().map_err(err)?;
    }
    let json = dir.join(format!("{stem}.layout.json"));
    std::fs::write(&json, serde_json::to_string_pretty(layout)?)
        .with_context(|| format!("writing {}", json.display()))?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// XY charts

const PLOT_W: f64 = 640.0;
const PLOT_H: f64 = 440.0;
const ZERO_BAND: f64 = 30.0;
/// A front with more members is numbered on the chart and named in the caption.
const FRONT_NAMED_MAX: usize = 6;
/// Markers of different series closer than this (px) are moved apart so each shows.
const DODGE_PX: f64 = 9.0;
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

/// What tells a series apart in the layout record: its colour and marker.
fn style_key(c: RGBColor, family: usize) -> String {
    format!(
        "#{:02x}{:02x}{:02x} {}",
        c.0,
        c.1,
        c.2,
        SHAPE_NAMES[family % SHAPE_NAMES.len()]
    )
}

/// Moves a marker that would sit on (nearly) the same spot as an earlier one of another series
/// to the nearest free spot of a `DODGE_STEP` grid around it (sideways first), inside the plot
/// (`inside`, for marker centres), so none hides another and each stays by its value; returns how many moved.
fn dodge(pos: &mut [Vec<Option<(f64, f64)>>], inside: Rect) -> usize {
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
        for p in s.iter_mut() {
            let Some((x, y)) = *p else { continue };
            let clash = |cx: f64, cy: f64| {
                placed
                    .iter()
                    .any(|(k, ox, oy)| *k != i && (cx - ox).hypot(cy - oy) < DODGE_PX)
            };
            let (nx, ny) = grid
                .iter()
                .map(|(a, b)| (x + a * DODGE_STEP, y + b * DODGE_STEP))
                .filter(|(cx, cy)| {
                    (*cx, *cy) == (x, y)
                        || (inside.x..=inside.right()).contains(cx)
                            && (inside.y..=inside.bottom()).contains(cy)
                })
                .find(|(cx, cy)| !clash(*cx, *cy))
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
        let dodged = dodge(
            &mut pos,
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

// ---------------------------------------------------------------------------------------------
// Bar and dot charts (horizontal: categories down the left, never cut)

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

#[cfg(test)]
mod tests {
    use super::*;

    fn lab(c: u32) -> [f64; 3] {
        let lin = |u: u32| {
            let u = u as f64 / 255.0;
            if u <= 0.04045 {
                u / 12.92
            } else {
                ((u + 0.055) / 1.055).powf(2.4)
            }
        };
        let (r, g, b) = (lin(c >> 16 & 255), lin(c >> 8 & 255), lin(c & 255));
        let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
        let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
        let f = |t: f64| {
            if t > 0.008856 {
                t.cbrt()
            } else {
                7.787 * t + 16.0 / 116.0
            }
        };
        [
            116.0 * f(y) - 16.0,
            500.0 * (f(x) - f(y)),
            200.0 * (f(y) - f(z)),
        ]
    }

    #[test]
    fn palette_colours_are_far_apart_and_read_on_white() {
        // 23 legend entries used to share near-identical colours (depth_peel and wboit both
        // crimson). ΔE76 ≥ 25 is clearly distinguishable side by side.
        for (i, c) in PALETTE.iter().enumerate().take(24) {
            let a = lab(*c);
            assert!(a[0] < 75.0, "colour {i} too light on white");
            for (j, c2) in PALETTE.iter().enumerate().take(i) {
                let b = lab(*c2);
                let d =
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
                assert!(d >= 25.0, "colours {j} and {i}: ΔE {d:.1}");
            }
        }
    }

    /// A temp folder removed when the test ends, pass or fail (derefs to its path).
    struct Tmp(tempfile::TempDir);
    impl std::ops::Deref for Tmp {
        type Target = std::path::Path;
        fn deref(&self) -> &std::path::Path {
            self.0.path()
        }
    }
    impl AsRef<std::path::Path> for Tmp {
        fn as_ref(&self) -> &std::path::Path {
            self.0.path()
        }
    }
    fn tmp_dir(prefix: &str) -> Tmp {
        Tmp(tempfile::Builder::new()
            .prefix(&format!("{prefix}-"))
            .tempdir()
            .expect("a temp folder"))
    }

    fn tmp(name: &str) -> Tmp {
        tmp_dir(&format!("mfx-charts-{name}"))
    }

    fn read_layout(d: &Path, stem: &str) -> Layout {
        serde_json::from_str(
            &std::fs::read_to_string(d.join(format!("{stem}.layout.json"))).unwrap(),
        )
        .unwrap()
    }

    #[test]
    fn a_crowded_chart_keeps_its_legend_outside_and_its_range_on_the_data() {
        // 23 configurations with points in every corner: the old chart stretched y to 1e10.
        let d = tmp("crowded");
        let series: Vec<Series> = (0..23)
            .map(|i| Series {
                name: format!(
                    "configuration number {i} with a long name, layers={}",
                    1 << (i % 6)
                ),
                family: i % 5,
                color: None,
                points: (0..4)
                    .map(|k| {
                        Pt::new(
                            1.0 + 100.0 * k as f64 + i as f64,
                            1.0 + 1200.0 * ((i + k) % 4) as f64 / 3.0,
                        )
                        .flagged(k == 2)
                    })
                    .collect(),
            })
            .collect();
        let xy = XY {
            title: "Speedup".into(),
            x_label: "ms".into(),
            y_label: "×".into(),
            log_x: true,
            log_y: true,
            series,
            ..Default::default()
        };
        let f = xy.draw(&d, "c", "").unwrap();
        assert!(f.is_chart());
        let l = read_layout(&d, "c");
        assert_eq!(layout::check(&l), Ok(()));
        assert!(l.legend.is_some() && l.y.range[1] < 1e4, "{:?}", l.y);
        assert!(d.join("c.png").is_file() && d.join("c.svg").is_file());
    }

    #[test]
    fn zero_errors_get_their_own_band_and_one_point_is_a_note() {
        let d = tmp("zero");
        let xy = XY {
            title: "Error vs time".into(),
            log_x: true,
            log_y: true,
            zero_label: "exact (0)".into(),
            series: vec![Series::new(
                "a",
                vec![Pt::new(1.0, 0.0), Pt::new(2.0, 1e-3), Pt::new(3.0, 2e-2)],
            )],
            ..Default::default()
        };
        assert!(xy.draw(&d, "z", "").unwrap().is_chart());
        let l = read_layout(&d, "z");
        assert!(l.zero_band > 0.0);
        // The log axis spans the non-zero errors only: no 1e-7 floor.
        assert!(l.y.range[0] > 1e-4, "{:?}", l.y);
        assert_eq!(layout::check(&l), Ok(()));
        let one = XY {
            title: "t".into(),
            series: vec![Series::new("a", vec![Pt::new(1.0, 1.0)])],
            ..Default::default()
        };
        let f = one.draw(&d, "one", "").unwrap();
        assert!(f.note.as_deref().unwrap().contains("one point"));
        assert!(!d.join("one.png").exists());
    }

    #[test]
    fn bars_start_at_zero_and_decades_become_dots() {
        let d = tmp("bars");
        let cats: Vec<String> = (0..3)
            .map(|i| format!("obj(path=/a/very/long/folder/name/holes-{i}.obj,instances=4)"))
            .collect();
        let b = Bars {
            title: "x floor".into(),
            y_label: "×".into(),
            log_y: true,
            categories: cats.clone(),
            series: vec![(
                "s".into(),
                vec![Some(Pt::new(0.0, 2.0)), Some(Pt::new(0.0, 3.0)), None],
            )],
            reference: Some(1.0),
        };
        assert!(b
            .draw(&d, "b", "")
            .unwrap()
            .caption
            .contains("start at zero"));
        let l = read_layout(&d, "b");
        assert_eq!((l.kind.as_str(), l.x.range[0]), ("bars", 0.0));
        // Full category names are kept (the check would catch two equal ones).
        // A category without any value is left out.
        assert_eq!(l.y.ticks, cats[..2]);
        assert_eq!(layout::check(&l), Ok(()));
        let dots = Bars {
            series: vec![(
                "s".into(),
                vec![Some(Pt::new(0.0, 0.5)), Some(Pt::new(0.0, 900.0)), None],
            )],
            ..b
        };
        assert!(dots.draw(&d, "d", "").unwrap().caption.contains("log axis"));
        let l = read_layout(&d, "d");
        assert!(l.kind == "dots" && l.x.log);
        assert_eq!(layout::check(&l), Ok(()));
    }

    #[test]
    fn look_alike_series_fail_the_check() {
        // Two configurations given the same colour and marker: the reader cannot tell them apart.
        let d = tmp("alike");
        let s = |name: &str, y: f64| Series {
            name: name.into(),
            family: 1,
            color: Some(3),
            points: vec![Pt::new(1.0, y), Pt::new(2.0, y * 2.0)],
        };
        let xy = XY {
            title: "t".into(),
            series: vec![s("a", 1.0), s("b", 5.0)],
            ..Default::default()
        };
        xy.draw(&d, "alike", "").unwrap();
        let e = layout::check(&read_layout(&d, "alike")).unwrap_err();
        assert!(e.iter().any(|m| m.contains("looks like")), "{e:?}");
    }

    #[test]
    fn equal_points_are_spread_and_the_check_sees_them_hidden_otherwise() {
        // k=4 and k=8 with the same hazard rate at the same complexity: one used to hide the other.
        let d = tmp("equal");
        let s = |name: &str, c: usize| Series {
            name: name.into(),
            family: 2,
            color: Some(c),
            points: vec![Pt::new(8.0, 0.0), Pt::new(32.0, 0.1 * c as f64)],
        };
        let xy = XY {
            title: "hazard rate".into(),
            series: vec![s("k=4", 1), s("k=8", 2)],
            ..Default::default()
        };
        let f = xy.draw(&d, "eq", "").unwrap();
        assert!(f.caption.contains("moved apart"), "{}", f.caption);
        let mut l = read_layout(&d, "eq");
        assert_eq!(layout::check(&l), Ok(()));
        let (a, b) = (l.marks[0].rect, l.marks[2].rect);
        assert!((a.x - b.x).abs() >= DODGE_PX && a.y == b.y, "{a:?} {b:?}");
        // The same chart without the spreading fails.
        l.marks[2].rect = a;
        let e = layout::check(&l).unwrap_err();
        assert!(e.iter().any(|m| m.contains("same spot")), "{e:?}");
    }

    #[test]
    fn close_floors_and_front_names_keep_clear_and_the_check_sees_an_overlap() {
        // floor_depth 0.494 and floor_opaque 0.581: rotated names used to cross each other.
        let d = tmp("floors");
        let series: Vec<Series> = (0..6)
            .map(|i| Series {
                name: format!("method {i}"),
                family: i,
                color: Some(i),
                points: vec![Pt::new(0.6 + 0.05 * i as f64, 1e-3 / (1.0 + i as f64))],
            })
            .collect();
        let xy = XY {
            title: "Error vs time".into(),
            log_x: true,
            log_y: true,
            series,
            front: (0..6)
                .map(|i| Named {
                    x: 0.6 + 0.05 * i as f64,
                    y: 1e-3 / (1.0 + i as f64),
                    text: format!("method {i} with a long name"),
                })
                .collect(),
            front_name: "front".into(),
            vlines: vec![
                (0.494, "floor_depth 0.494".into()),
                (0.581, "floor_opaque 0.581".into()),
                (0.6, "floor_blend 0.6".into()),
            ],
            ..Default::default()
        };
        xy.draw(&d, "fl", "").unwrap();
        let mut l = read_layout(&d, "fl");
        assert_eq!(layout::check(&l), Ok(()));
        assert!(l.labels.len() >= 3, "{:?}", l.labels);
        // Floor names sit above the plot, never over a marker.
        assert!(l.labels[..3].iter().all(|t| t.rect.bottom() <= l.plot.y));
        // Put the second floor's name where the first one is: caught.
        l.labels[1].rect = l.labels[0].rect;
        let e = layout::check(&l).unwrap_err();
        assert!(e.iter().any(|m| m.contains("overlaps label")), "{e:?}");
        // A name over a marker: caught.
        let mut l = read_layout(&d, "fl");
        l.labels[0].rect = l.marks[0].rect;
        let e = layout::check(&l).unwrap_err();
        assert!(e.iter().any(|m| m.contains("covers a marker")), "{e:?}");
    }
}
