//! Charts over plotters, laid out by hand so the layout is known exactly: every chart is written
//! as `<stem>.png`, `<stem>.svg` and `<stem>.layout.json` (the rectangles and ranges that
//! `layout::check` and `scripts/check-report.sh` test). Legends sit outside the plot, axis ranges
//! come from the data alone, log axes carry decade or 1-2-5 ticks, bars start at zero on linear
//! axes and values that span decades become dot plots. A chart that cannot say anything is not
//! drawn: `Figure::note` says so in one line instead.

mod bars;
mod draw;
pub mod layout;
mod output;
mod style;
mod text;
pub mod ticks;
mod xy;

pub use bars::Bars;
pub use layout::{AxisRecord, Layout, Mark, Rect, TextBox};
pub use style::{color, MARKERS, PALETTE};
pub use text::{text_width, wrap};
pub use xy::XY;

/// One item of a report section: a chart (`<stem>.svg`/`.png`), a one-line note standing in for
/// a chart that would say nothing, or a block of HTML (a table).
#[derive(Clone, Debug, Default)]
pub struct Figure {
    pub title: String,
    pub stem: String,
    pub caption: String,
    /// Set when no chart was drawn: the line that says why.
    pub note: Option<String>,
    /// Set for a table or other HTML block (no chart), as written by its template.
    pub html: Option<maud::Markup>,
}

impl Figure {
    pub fn note(title: impl Into<String>, note: impl Into<String>) -> Figure {
        Figure {
            title: title.into(),
            note: Some(note.into()),
            ..Default::default()
        }
    }
    pub fn html(title: impl Into<String>, html: maud::Markup) -> Figure {
        Figure {
            title: title.into(),
            html: Some(html),
            ..Default::default()
        }
    }
    /// A drawn chart (not a note or a table).
    pub fn is_chart(&self) -> bool {
        self.note.is_none() && self.html.is_none()
    }
}

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

#[cfg(test)]
mod tests;
