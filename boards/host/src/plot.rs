//! The one plot style of every picture the host tools draw (`client plot`,
//! `imu-emu allan`'s Allan deviation): a titled figure of
//! panels stacked vertically sharing one x axis, each panel with a title,
//! labelled axes with units, ticks, a light grid and a legend.
//!
//! The output kind follows the file's extension: `.png` (the plotters
//! bitmap backend) or `.svg` (plain SVG `<text>`, drawn by the viewer).
//! Text is laid out with DejaVu Sans embedded in the binary (the `dejavu`
//! crate; Bitstream Vera / DejaVu licence, which allows embedding), so no
//! system font is read, and a plot looks the same on every machine.

use std::ops::Range;
use std::path::Path;
use std::sync::Once;

use anyhow::{bail, Context as _};
use plotters::coord::combinators::IntoLogRange;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::error::UsageError;

/// Image size of a PNG or SVG, pixels.
pub const SIZE: (u32, u32) = (1200, 900);

/// Series colours, in order (X, Y, Z; then three more).
pub const COLORS: [RGBColor; 6] = [
    RGBColor(0xD6, 0x27, 0x28),
    RGBColor(0x2C, 0xA0, 0x2C),
    RGBColor(0x1F, 0x77, 0xB4),
    RGBColor(0xFF, 0x7F, 0x0E),
    RGBColor(0x94, 0x67, 0xBD),
    RGBColor(0x8C, 0x56, 0x4B),
];

/// An axis scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scale {
    /// Linear.
    #[default]
    Linear,
    /// Base-10 logarithmic (non-positive values are left out).
    Log,
}

/// One named line.
#[derive(Debug, Clone, Default)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// `(x, y)` points; non-finite ones are left out.
    pub points: Vec<(f64, f64)>,
    /// A reference line (a model, a specification): thin and dashed, in
    /// [`REFERENCE_COLORS`] order, beside the measured lines in [`COLORS`].
    pub reference: bool,
}

/// Colours of the reference lines, in order.
pub const REFERENCE_COLORS: [RGBColor; 3] = [
    RGBColor(0x00, 0x00, 0x00),
    RGBColor(0x78, 0x78, 0x78),
    RGBColor(0xA0, 0x50, 0x00),
];

/// One panel: a title, a y axis and its lines.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Panel title.
    pub title: String,
    /// Y axis label, with its unit (`angular rate (deg/s)`).
    pub y_label: String,
    /// Y scale.
    pub y_scale: Scale,
    /// The lines.
    pub series: Vec<Series>,
    /// Where the legend goes: the corner the lines leave empty.
    pub legend: Corner,
}

/// A corner of a panel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Corner {
    /// Upper right (time series).
    #[default]
    UpperRight,
    /// Lower left (curves falling from the upper left, an Allan plot).
    LowerLeft,
}

/// A figure: panels stacked vertically sharing one x axis.
#[derive(Debug, Clone, Default)]
pub struct Figure {
    /// Figure title.
    pub title: String,
    /// X axis label, with its unit (`device time (s)`).
    pub x_label: String,
    /// X scale.
    pub x_scale: Scale,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
}

/// The output kind of `out`, from its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// PNG bitmap.
    Png,
    /// SVG.
    Svg,
}

/// Checks that `out` can be written as a plot before any work: a `.png`
/// or `.svg` name in a folder that exists.
pub fn check_output(out: &Path) -> anyhow::Result<Kind> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let kind = match ext.as_deref() {
        Some("png") => Kind::Png,
        Some("svg") => Kind::Svg,
        _ => {
            return Err(
                UsageError(format!("plot: {}: name a .png or .svg file", out.display())).into(),
            )
        }
    };
    let parent = out.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = parent {
        if !dir.is_dir() {
            bail!(
                "plot: {}: the folder {} does not exist",
                out.display(),
                dir.display()
            );
        }
    }
    Ok(kind)
}

/// Registers the embedded font (once).
fn fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TrueType font (the crate's own); a failure
        // would only leave text undrawn, never crash.
        let _ = register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
        let _ = register_font("sans-serif", FontStyle::Bold, dejavu::sans::bold());
    });
}

/// Draws `fig` to `out` (PNG or SVG by extension, see [`check_output`]).
pub fn render(fig: &Figure, out: &Path) -> anyhow::Result<()> {
    render_as(fig, out, check_output(out)?)
}

/// Draws `fig` to `out` as `kind`, whatever the file's name.
pub fn render_as(fig: &Figure, out: &Path, kind: Kind) -> anyhow::Result<()> {
    fonts();
    let what = || format!("plot: writing {}", out.display());
    match kind {
        Kind::Png => {
            let root = BitMapBackend::new(out, SIZE).into_drawing_area();
            draw(&root, fig)?;
            root.present().with_context(what)?;
        }
        Kind::Svg => {
            let root = SVGBackend::new(out, SIZE).into_drawing_area();
            draw(&root, fig)?;
            root.present().with_context(what)?;
        }
    }
    // The backends report some write failures only on drop: check.
    if !out.is_file() {
        bail!("{}: nothing written", what());
    }
    Ok(())
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let body = root.titled(
        &fig.title,
        (FontFamily::SansSerif, 26)
            .into_font()
            .style(FontStyle::Bold),
    )?;
    if fig.panels.is_empty() {
        return Ok(());
    }
    let areas = body.split_evenly((fig.panels.len(), 1));
    let all_x = fig
        .panels
        .iter()
        .flat_map(|p| &p.series)
        .flat_map(|s| s.points.iter().map(|p| p.0));
    let x = range(all_x, fig.x_scale);
    for (area, p) in areas.iter().zip(&fig.panels) {
        let y = range(
            p.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
            p.y_scale,
        );
        match (fig.x_scale, p.y_scale) {
            (Scale::Linear, Scale::Linear) => panel(area, fig, p, x.clone(), y)?,
            (Scale::Linear, Scale::Log) => panel(area, fig, p, x.clone(), y.log_scale())?,
            (Scale::Log, Scale::Linear) => panel(area, fig, p, x.clone().log_scale(), y)?,
            (Scale::Log, Scale::Log) => panel(area, fig, p, x.clone().log_scale(), y.log_scale())?,
        }
    }
    Ok(())
}

fn panel<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    fig: &Figure,
    p: &Panel,
    x: X,
    y: Y,
) -> anyhow::Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FontFamily::SansSerif, 20))
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x, y)?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(&fig.x_label)
        .y_desc(&p.y_label)
        .label_style((FontFamily::SansSerif, 14))
        .axis_desc_style((FontFamily::SansSerif, 16))
        .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
        .bold_line_style(RGBColor(0xCC, 0xCC, 0xCC));
    // On a log axis 1, 2 and 5 of each decade, as 1e-5 (not
    // 9.99999999e-6); the ticks between them stay unlabelled, or a span
    // of a decade or two crowds its labels.
    let decade = |v: &f64| {
        let text = format!("{v:.0e}");
        let keep = ["1e", "2e", "5e"].iter().any(|m| text.starts_with(m));
        if keep {
            text
        } else {
            String::new()
        }
    };
    if fig.x_scale == Scale::Log {
        mesh.x_label_formatter(&decade);
    }
    if p.y_scale == Scale::Log {
        mesh.y_label_formatter(&decade);
    }
    mesh.draw()?;
    let keep = |&(x, y): &(f64, f64)| {
        x.is_finite()
            && y.is_finite()
            && (fig.x_scale == Scale::Linear || x > 0.0)
            && (p.y_scale == Scale::Linear || y > 0.0)
    };
    let (mut measured, mut reference) = (COLORS.iter().cycle(), REFERENCE_COLORS.iter().cycle());
    for s in &p.series {
        let points = s.points.iter().copied().filter(keep);
        let (color, width) = match s.reference {
            false => (measured.next().copied().unwrap_or(BLACK), 2),
            true => (reference.next().copied().unwrap_or(BLACK), 1),
        };
        let style = color.stroke_width(width);
        let drawn = if s.reference {
            chart.draw_series(DashedLineSeries::new(points, 8, 5, style))?
        } else {
            chart.draw_series(LineSeries::new(points, style))?
        };
        drawn
            .label(&s.name)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
    }
    chart
        .configure_series_labels()
        .position(match p.legend {
            Corner::UpperRight => SeriesLabelPosition::UpperRight,
            Corner::LowerLeft => SeriesLabelPosition::LowerLeft,
        })
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FontFamily::SansSerif, 14))
        .draw()?;
    Ok(())
}

/// The finite range of `v` (positive values only on a log scale), widened
/// a little on a linear scale, and never empty.
fn range(v: impl Iterator<Item = f64>, scale: Scale) -> Range<f64> {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && (scale == Scale::Linear || *x > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    match scale {
        _ if !lo.is_finite() => match scale {
            Scale::Linear => 0.0..1.0,
            Scale::Log => 1.0..10.0,
        },
        Scale::Linear => {
            let pad = ((hi - lo) * 0.05).max(1e-3);
            lo - pad..hi + pad
        }
        Scale::Log if hi <= lo => lo / 2.0..hi * 2.0,
        Scale::Log => lo..hi,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges() {
        assert_eq!(range([1.0, 3.0].into_iter(), Scale::Linear), 0.9..3.1);
        assert_eq!(range([f64::NAN].into_iter(), Scale::Linear), 0.0..1.0);
        assert_eq!(range([-1.0, 0.1, 10.0].into_iter(), Scale::Log), 0.1..10.0);
        assert_eq!(range([2.0].into_iter(), Scale::Log), 1.0..4.0);
    }
}
