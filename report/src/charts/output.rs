//! Writing a chart: `<stem>.png`, `<stem>.svg`, `<stem>.pdf` and `<stem>.layout.json`. The PDF
//! is the SVG converted as vectors (svg2pdf, no rasterising) with the chart's one font embedded
//! (the DejaVu Sans in report/assets that the SVG's widths were measured with, not a system
//! font), so a paper includes the same chart on every machine.

use std::path::Path;
use std::sync::OnceLock;

use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::draw::err;
use super::layout::Layout;
use super::text::FONT_BYTES;

/// Writes the PNG, the SVG, its PDF and the layout record of one chart.
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
    let pdf = dir.join(format!("{stem}.pdf"));
    let text =
        std::fs::read_to_string(&svg).with_context(|| format!("reading {}", svg.display()))?;
    std::fs::write(
        &pdf,
        svg_to_pdf(&text).with_context(|| format!("{}", svg.display()))?,
    )
    .with_context(|| format!("writing {}", pdf.display()))?;
    let json = dir.join(format!("{stem}.layout.json"));
    std::fs::write(&json, serde_json::to_string_pretty(layout)?)
        .with_context(|| format!("writing {}", json.display()))?;
    Ok(())
}

/// The SVG parser's options: only the embedded font, as the family every chart names.
fn svg_options() -> &'static svg2pdf::usvg::Options<'static> {
    static OPTIONS: OnceLock<svg2pdf::usvg::Options<'static>> = OnceLock::new();
    OPTIONS.get_or_init(|| {
        let mut o = svg2pdf::usvg::Options::default();
        let db = o.fontdb_mut();
        db.load_font_data(FONT_BYTES.to_vec());
        db.set_sans_serif_family("DejaVu Sans");
        o
    })
}

/// A PDF of one SVG: vectors, the text as text in the embedded (subset) font.
pub(super) fn svg_to_pdf(svg: &str) -> Result<Vec<u8>> {
    let tree = svg2pdf::usvg::Tree::from_str(svg, svg_options())
        .map_err(|e| anyhow::anyhow!("parsing the SVG: {e}"))?;
    svg2pdf::to_pdf(
        &tree,
        svg2pdf::ConversionOptions::default(),
        svg2pdf::PageOptions::default(),
    )
    .map_err(|e| anyhow::anyhow!("converting the SVG to PDF: {e}"))
}
