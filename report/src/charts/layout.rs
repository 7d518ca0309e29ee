//! The layout record every chart writes beside its PNG/SVG (`<stem>.layout.json`), and the checks
//! a reader's eye would make: the legend never covers the plot, each axis shows its data with at
//! most a decade to spare (or marks what lies off its scale), tick labels are distinct, no text
//! drawn on the chart covers another text or a marker, no two markers of different series sit on
//! the same spot, and no two series share a colour and a marker. `scripts/check-report.sh` runs
//! the same rules in the browser over every chart of a page; `check` is their definition.

use serde::{Deserialize, Serialize};

/// A pixel rectangle, origin top-left.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Rect {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

impl Rect {
    pub fn new(x: f64, y: f64, w: f64, h: f64) -> Rect {
        Rect { x, y, w, h }
    }
    pub fn right(&self) -> f64 {
        self.x + self.w
    }
    pub fn bottom(&self) -> f64 {
        self.y + self.h
    }
    /// True when the interiors overlap (touching edges do not count).
    pub fn intersects(&self, o: &Rect) -> bool {
        self.x < o.right() && o.x < self.right() && self.y < o.bottom() && o.y < self.bottom()
    }
    pub fn contains(&self, o: &Rect) -> bool {
        o.x >= self.x - 0.5
            && o.y >= self.y - 0.5
            && o.right() <= self.right() + 0.5
            && o.bottom() <= self.bottom() + 0.5
    }
}

/// One axis: what the data spans and what the axis shows, in data units.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AxisRecord {
    pub title: String,
    pub log: bool,
    /// Categories (a bar or dot chart's names): no numeric range.
    pub categorical: bool,
    /// [min, max] of everything drawn on this axis (points, whiskers, bar bases, reference
    /// lines); absent when nothing numeric is drawn.
    pub data: Option<[f64; 2]>,
    /// [min, max] shown by the axis.
    pub range: [f64; 2],
    pub ticks: Vec<String>,
    /// Values drawn clamped to the axis's edge with an off-scale mark (an arrow and the value):
    /// data may lie outside `range` only when this is > 0.
    #[serde(default)]
    pub off_scale: usize,
}

/// A text drawn on the chart (a front member's name, a floor's name), with its box.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TextBox {
    pub text: String,
    pub rect: Rect,
}

/// A data marker as drawn: its series (index into `styles`) and its box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mark {
    pub series: usize,
    pub rect: Rect,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Layout {
    pub stem: String,
    /// "xy", "dots" (log value axis) or "bars" (linear, from zero).
    pub kind: String,
    pub width: f64,
    pub height: f64,
    /// The plot area: the frame inside which data is drawn (an "exact (0)" band included).
    pub plot: Rect,
    /// The legend box, when there is one.
    pub legend: Option<Rect>,
    pub x: AxisRecord,
    pub y: AxisRecord,
    /// Series (legend entries of data) drawn.
    pub series: usize,
    /// Height in pixels of the band below a log y axis where y = 0 points are drawn (0: none).
    pub zero_band: f64,
    /// Per series, what tells it apart: "colour marker" (e.g. "#1f77b4 circle"); "" for a series
    /// without a legend entry (grey context lines).
    #[serde(default)]
    pub styles: Vec<String>,
    /// The texts drawn in or around the plot (not the axes' tick labels or the legend).
    #[serde(default)]
    pub labels: Vec<TextBox>,
    /// Every data marker drawn.
    #[serde(default)]
    pub marks: Vec<Mark>,
}

/// Markers of different series whose centres are closer than this (px) hide each other.
pub const HIDDEN_PX: f64 = 3.0;

/// How far an axis may reach beyond its data. Log axes: at most one decade of padding on each
/// side. Linear axes: the axis span at most ten times the data span (a constant gets a window of
/// at most ten times a tenth of its size, i.e. its own magnitude), and a zero baseline counts as
/// data for bars. Either way the axis must contain the data.
pub fn check(l: &Layout) -> Result<(), Vec<String>> {
    let mut bad = Vec::new();
    if let Some(g) = &l.legend {
        if g.intersects(&l.plot) {
            bad.push(format!(
                "{}: legend {g:?} overlaps the plot area {:?}",
                l.stem, l.plot
            ));
        }
    }
    for (name, a) in [("x", &l.x), ("y", &l.y)] {
        for (i, t) in a.ticks.iter().enumerate() {
            if a.ticks[..i].contains(t) {
                bad.push(format!("{}: {name} tick label {t:?} repeats", l.stem));
            }
        }
        if a.categorical {
            continue;
        }
        let [r0, r1] = a.range;
        if r0.partial_cmp(&r1) != Some(std::cmp::Ordering::Less) {
            bad.push(format!("{}: {name} axis range {r0}..{r1} is empty", l.stem));
            continue;
        }
        let Some([d0, d1]) = a.data else { continue };
        let tol = (r1 - r0).abs() * 1e-9;
        if (d0 < r0 - tol || d1 > r1 + tol) && a.off_scale == 0 {
            bad.push(format!(
                "{}: {name} data {d0}..{d1} lies outside the axis {r0}..{r1} with no off-scale mark",
                l.stem
            ));
        }
        if a.off_scale > 0 {
            // Clamped values: the padding rules below are about the axis's own data.
            continue;
        }
        if a.log {
            if d0 <= 0.0 || r0 <= 0.0 {
                bad.push(format!(
                    "{}: {name} log axis reaches {r0} / data {d0}",
                    l.stem
                ));
            } else if d0 / r0 > 10.0 * (1.0 + 1e-9) || r1 / d1 > 10.0 * (1.0 + 1e-9) {
                bad.push(format!(
                    "{}: {name} log axis {r0:e}..{r1:e} reaches more than a decade beyond its data {d0:e}..{d1:e}",
                    l.stem
                ));
            }
        } else {
            let span = (d1 - d0).max(0.1 * d0.abs().max(d1.abs()));
            if span > 0.0 && (r1 - r0) > 10.0 * span * (1.0 + 1e-9) {
                bad.push(format!(
                    "{}: {name} axis {r0}..{r1} is more than ten times its data's span {d0}..{d1}",
                    l.stem
                ));
            }
        }
    }
    for (i, t) in l.labels.iter().enumerate() {
        for o in &l.labels[..i] {
            if t.rect.intersects(&o.rect) {
                bad.push(format!(
                    "{}: label {:?} overlaps label {:?}",
                    l.stem, t.text, o.text
                ));
            }
        }
        if let Some(m) = l.marks.iter().find(|m| m.rect.intersects(&t.rect)) {
            bad.push(format!(
                "{}: label {:?} covers a marker of series {}",
                l.stem, t.text, m.series
            ));
        }
    }
    let centre = |r: &Rect| (r.x + r.w / 2.0, r.y + r.h / 2.0);
    'hidden: for (i, m) in l.marks.iter().enumerate() {
        let (x, y) = centre(&m.rect);
        for o in &l.marks[..i] {
            let (ox, oy) = centre(&o.rect);
            if o.series != m.series && (x - ox).hypot(y - oy) < HIDDEN_PX {
                bad.push(format!(
                    "{}: markers of series {} and {} sit on the same spot ({x:.0}, {y:.0})",
                    l.stem, o.series, m.series
                ));
                break 'hidden;
            }
        }
    }
    for (i, s) in l.styles.iter().enumerate() {
        if !s.is_empty() && l.styles[..i].contains(s) {
            bad.push(format!(
                "{}: series {i} looks like an earlier one ({s})",
                l.stem
            ));
        }
    }
    if bad.is_empty() {
        Ok(())
    } else {
        Err(bad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn good() -> Layout {
        Layout {
            stem: "t".into(),
            kind: "xy".into(),
            width: 1000.0,
            height: 600.0,
            plot: Rect::new(90.0, 40.0, 640.0, 460.0),
            legend: Some(Rect::new(760.0, 40.0, 220.0, 300.0)),
            x: AxisRecord {
                log: true,
                data: Some([2.0, 358.0]),
                range: [1.5, 450.0],
                ticks: vec!["2".into(), "10".into(), "100".into()],
                ..Default::default()
            },
            y: AxisRecord {
                data: Some([0.0, 1200.0]),
                range: [-60.0, 1260.0],
                ticks: vec!["0".into(), "500".into(), "1000".into()],
                ..Default::default()
            },
            series: 3,
            zero_band: 0.0,
            styles: vec![
                "#1f77b4 circle".into(),
                "#ff7f0e circle".into(),
                "#1f77b4 square".into(),
            ],
            labels: vec![TextBox {
                text: "a".into(),
                rect: Rect::new(100.0, 50.0, 40.0, 15.0),
            }],
            marks: vec![
                Mark {
                    series: 0,
                    rect: Rect::new(150.0, 50.0, 12.0, 12.0),
                },
                Mark {
                    series: 1,
                    rect: Rect::new(150.0, 62.0, 12.0, 12.0),
                },
            ],
        }
    }

    #[test]
    fn a_sound_layout_passes() {
        assert_eq!(check(&good()), Ok(()));
    }

    #[test]
    fn a_legend_over_the_plot_fails() {
        let mut l = good();
        l.legend = Some(Rect::new(600.0, 50.0, 220.0, 300.0));
        let e = check(&l).unwrap_err();
        assert!(e[0].contains("overlaps the plot area"), "{e:?}");
        // Touching the frame is not overlapping.
        l.legend = Some(Rect::new(730.0, 40.0, 220.0, 300.0));
        assert_eq!(check(&l), Ok(()));
    }

    #[test]
    fn a_range_stretched_for_the_legend_fails() {
        // The old charts: speedups under 1,200 on an axis to 1e10, times under 358 ms to 1e8.
        let mut l = good();
        l.x.range = [1.5, 1e8];
        l.y.range = [-60.0, 1e10];
        let e = check(&l).unwrap_err();
        assert_eq!(e.len(), 2, "{e:?}");
        assert!(e[0].contains("more than a decade") && e[1].contains("ten times"));
    }

    #[test]
    fn data_outside_the_axis_and_repeated_ticks_fail() {
        let mut l = good();
        l.y.data = Some([0.0, 2000.0]);
        l.x.ticks = vec!["6.5e-6".into(); 7];
        let e = check(&l).unwrap_err();
        assert!(e.iter().any(|m| m.contains("outside the axis")), "{e:?}");
        assert!(e.iter().any(|m| m.contains("repeats")), "{e:?}");
    }

    #[test]
    fn labels_over_labels_or_markers_fail() {
        let mut l = good();
        l.labels.push(TextBox {
            text: "b".into(),
            rect: Rect::new(130.0, 55.0, 40.0, 15.0),
        });
        let e = check(&l).unwrap_err();
        assert!(e.iter().any(|m| m.contains("overlaps label")), "{e:?}");
        assert!(e.iter().any(|m| m.contains("covers a marker")), "{e:?}");
    }

    #[test]
    fn coincident_markers_and_look_alike_series_fail() {
        let mut l = good();
        l.marks[1].rect = Rect::new(151.0, 51.0, 12.0, 12.0);
        l.styles[2] = "#1f77b4 circle".into();
        let e = check(&l).unwrap_err();
        assert!(e.iter().any(|m| m.contains("same spot")), "{e:?}");
        assert!(e.iter().any(|m| m.contains("looks like")), "{e:?}");
        // One series' own points may touch (a line of them).
        let mut l = good();
        l.marks[1] = Mark {
            series: 0,
            rect: Rect::new(151.0, 51.0, 12.0, 12.0),
        };
        assert_eq!(check(&l), Ok(()));
    }

    #[test]
    fn data_off_the_scale_needs_its_mark() {
        let mut l = good();
        l.x.data = Some([2.0, 7.49]);
        l.x.range = [0.25, 4.0];
        let e = check(&l).unwrap_err();
        assert!(e[0].contains("no off-scale mark"), "{e:?}");
        l.x.off_scale = 1;
        assert_eq!(check(&l), Ok(()));
    }
}
