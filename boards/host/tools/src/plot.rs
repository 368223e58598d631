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

/// Where a panel's legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Corner {
    /// Upper right, inside the plot.
    #[default]
    UpperRight,
    /// Lower left, inside the plot (curves falling from the upper left,
    /// an Allan plot).
    LowerLeft,
    /// Beside the plot, right of it (time series: a legend inside would
    /// cover the last data).
    Right,
}

/// Width kept right of a plot for a [`Corner::Right`] legend, pixels.
const LEGEND_WIDTH: u32 = 100;

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
        let spans = (x.end - x.start, y.end - y.start);
        match (fig.x_scale, p.y_scale) {
            (Scale::Linear, Scale::Linear) => panel(area, fig, p, x.clone(), y, spans)?,
            (Scale::Linear, Scale::Log) => panel(area, fig, p, x.clone(), y.log_scale(), spans)?,
            (Scale::Log, Scale::Linear) => panel(area, fig, p, x.clone().log_scale(), y, spans)?,
            (Scale::Log, Scale::Log) => {
                panel(area, fig, p, x.clone().log_scale(), y.log_scale(), spans)?
            }
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
    spans: (f64, f64),
) -> anyhow::Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let beside = p.legend == Corner::Right;
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FontFamily::SansSerif, 20))
        .margin(10)
        .margin_right(10 + if beside { LEGEND_WIDTH } else { 0 })
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
    let x_linear = |v: &f64| linear_label(*v, spans.0);
    let y_linear = |v: &f64| linear_label(*v, spans.1);
    match fig.x_scale {
        Scale::Log => mesh.x_label_formatter(&decade),
        Scale::Linear => mesh.x_label_formatter(&x_linear),
    };
    match p.y_scale {
        Scale::Log => mesh.y_label_formatter(&decade),
        Scale::Linear => mesh.y_label_formatter(&y_linear),
    };
    mesh.draw()?;
    let keep = |&(x, y): &(f64, f64)| {
        x.is_finite()
            && y.is_finite()
            && (fig.x_scale == Scale::Linear || x > 0.0)
            && (p.y_scale == Scale::Linear || y > 0.0)
    };
    let (mut measured, mut reference) = (COLORS.iter().cycle(), REFERENCE_COLORS.iter().cycle());
    let mut entries = Vec::new();
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
        entries.push((s.name.as_str(), style));
    }
    let inside = match p.legend {
        Corner::UpperRight => SeriesLabelPosition::UpperRight,
        Corner::LowerLeft => SeriesLabelPosition::LowerLeft,
        Corner::Right => {
            // Beside the plotting area, from its top: a sample of each
            // line and its name.
            let (xs, ys) = chart.plotting_area().get_pixel_range();
            let (bx, by) = area.get_base_pixel();
            let x0 = xs.end - bx + 14;
            let font = (FontFamily::SansSerif, 14).into_font();
            for (k, (name, style)) in entries.into_iter().enumerate() {
                let y = ys.start - by + 10 + 22 * k as i32;
                area.draw(&PathElement::new([(x0, y), (x0 + 20, y)], style))?;
                area.draw(&Text::new(name.to_owned(), (x0 + 26, y - 8), font.clone()))?;
            }
            return Ok(());
        }
    };
    chart
        .configure_series_labels()
        .position(inside)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FontFamily::SansSerif, 14))
        .draw()?;
    Ok(())
}

/// The tick label of `v` on a linear axis spanning `span`: as many
/// decimals as ticks about a tenth of the span apart need (`0.004`,
/// `575.5`), scientific below 10⁻⁴ (`-1.5e-5`: a PIMU's Δθ), and `0`
/// rather than `-0.0`.
fn linear_label(v: f64, span: f64) -> String {
    let step = span / 10.0;
    if !(step.is_finite() && step > 0.0) {
        return format!("{v}");
    }
    // A tick at zero computed as ±1e-20 reads 0.
    if v.abs() < step * 1e-6 {
        return "0".to_owned();
    }
    let text = if step < 1e-4 {
        format!("{v:.1e}")
    } else {
        let decimals = (-step.log10().floor()).max(0.0) as usize;
        format!("{v:.decimals$}")
    };
    if text.parse::<f64>() == Ok(0.0) {
        "0".to_owned()
    } else {
        text
    }
}

/// The finite range of `v` (positive values only on a log scale), widened
/// by 5 % of its span on a linear scale (of its size when all values are
/// one, ±0.001 for zeros) and 4 % of its decades on a log scale, so the
/// lines stay inside the panel's frame whatever their magnitude (a PIMU's
/// Δθ of 10⁻⁵ rad is not drawn on ±0.001), and never empty.
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
            let pad = if hi > lo {
                (hi - lo) * 0.05
            } else if lo != 0.0 {
                lo.abs() * 0.05
            } else {
                1e-3
            };
            lo - pad..hi + pad
        }
        Scale::Log if hi <= lo => lo / 2.0..hi * 2.0,
        Scale::Log => {
            let f = (hi / lo).powf(0.04);
            lo / f..hi * f
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges() {
        assert_eq!(range([1.0, 3.0].into_iter(), Scale::Linear), 0.9..3.1);
        assert_eq!(range([f64::NAN].into_iter(), Scale::Linear), 0.0..1.0);
        // Small values keep their own scale.
        let r = range([-2e-5, 2e-5].into_iter(), Scale::Linear);
        assert!((r.start + 2.2e-5).abs() < 1e-12 && (r.end - 2.2e-5).abs() < 1e-12);
        assert_eq!(range([0.0, 0.0].into_iter(), Scale::Linear), -1e-3..1e-3);
        let r = range([4.0].into_iter(), Scale::Linear);
        assert!((r.start - 3.8).abs() < 1e-12 && (r.end - 4.2).abs() < 1e-12);
        let r = range([-1.0, 0.1, 10.0].into_iter(), Scale::Log);
        let f = 100f64.powf(0.04);
        assert!((r.start - 0.1 / f).abs() < 1e-12 && (r.end - 10.0 * f).abs() < 1e-9);
        assert_eq!(range([2.0].into_iter(), Scale::Log), 1.0..4.0);
    }

    #[test]
    fn tick_labels() {
        assert_eq!(linear_label(575.4, 1.0), "575.4");
        assert_eq!(linear_label(-0.000_000_1, 0.4), "0");
        assert_eq!(linear_label(0.15, 0.4), "0.15");
        assert_eq!(linear_label(-1.5e-5, 4e-5), "-1.5e-5");
        assert_eq!(linear_label(1.0, 1.1), "1.0");
        assert_eq!(linear_label(200.0, 2000.0), "200");
    }
}
