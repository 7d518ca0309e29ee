//! Writing a chart: `<stem>.png`, `<stem>.svg` and `<stem>.layout.json`.

use std::path::Path;

use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::draw::err;
use super::layout::Layout;

/// Writes the PNG, the SVG and the layout record of one chart.
pub(super) fn write_all(
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
