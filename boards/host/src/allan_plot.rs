//! The plot of `imu-emu allan`: the Allan deviation of each axis on
//! log-log axes, one panel for the gyros (°/s) and one for the
//! accelerometers (g), with the profile's lines (white noise N/√τ, the
//! bias-instability floor 0.6643·B, the random walk K·√(τ/3) where the
//! profile has one) dashed, a title, labelled axes with units, ticks and a
//! legend. PNG (plotters' bitmap backend; text drawn with the DejaVu Sans
//! font embedded in the binary, `assets/`, so no system font is needed)
//! and SVG (text as SVG `<text>`).

use std::path::Path;

use anyhow::Context as _;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::allan::{Curve, Fit, FLICKER_FLOOR};
use imu_emu::sensor::profile::{SensorProfile, SensorSpec};

/// A profile term's line: legend label, σ(τ), colour.
type ProfileLine = (&'static str, Box<dyn Fn(f64) -> f64>, RGBColor);

/// DejaVu Sans (licence: assets/DejaVuSans-LICENSE.txt).
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
/// Image size, pixels.
pub const SIZE: (u32, u32) = (1400, 700);

/// What is drawn.
pub struct Plot<'a> {
    /// Above the panels.
    pub title: &'a str,
    /// Six curves: gyro X Y Z, acc X Y Z.
    pub curves: &'a [Curve],
    /// Their fits.
    pub fits: &'a [Fit],
    /// The profile's lines, if known.
    pub profile: Option<&'a SensorProfile>,
}

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            // The bytes are a valid TrueType font (a unit test draws).
            let _ = plotters::style::register_font("sans-serif", style, FONT);
        }
    });
}

impl Plot<'_> {
    /// Draws to a PNG file.
    pub fn png(&self, path: &Path) -> anyhow::Result<()> {
        register_font();
        let root = BitMapBackend::new(path, SIZE).into_drawing_area();
        self.draw(&root)
            .with_context(|| format!("allan --png {}", path.display()))?;
        root.present()
            .with_context(|| format!("allan --png {}", path.display()))?;
        Ok(())
    }

    /// Draws to an SVG file.
    pub fn svg(&self, path: &Path) -> anyhow::Result<()> {
        let root = SVGBackend::new(path, SIZE).into_drawing_area();
        self.draw(&root)
            .with_context(|| format!("allan --svg {}", path.display()))?;
        root.present()
            .with_context(|| format!("allan --svg {}", path.display()))?;
        Ok(())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let root = root
            .titled(
                &format!("Allan deviation: {}", self.title),
                ("sans-serif", 22).into_font(),
            )
            .map_err(err)?;
        let panels = root.split_evenly((1, 2));
        let colors = [RED, GREEN, BLUE];
        for (s, panel) in panels.iter().enumerate() {
            let (name, unit, spec) = if s == 0 {
                ("gyro", "°/s", self.profile.map(|p| &p.gyro))
            } else {
                ("acc", "g", self.profile.map(|p| &p.acc))
            };
            let curves = &self.curves[3 * s..3 * s + 3];
            let pts = curves.iter().flat_map(|c| c.points.iter());
            let (mut t0, mut t1, mut y0, mut y1) = (f64::MAX, 0.0f64, f64::MAX, 0.0f64);
            for p in pts.clone() {
                if p.1 > 0.0 {
                    t0 = t0.min(p.0);
                    t1 = t1.max(p.0);
                    y0 = y0.min(p.1);
                    y1 = y1.max(p.1);
                }
            }
            if t1 <= t0 || y1 <= y0 {
                continue;
            }
            let (y0, y1) = (y0 / 3.0, y1 * 3.0);
            let mut chart = ChartBuilder::on(panel)
                .caption(format!("{name} ({unit})"), ("sans-serif", 18).into_font())
                .margin(14)
                .x_label_area_size(48)
                .y_label_area_size(80)
                .build_cartesian_2d((t0..t1).log_scale(), (y0..y1).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("averaging time τ (s)")
                .y_desc(format!("Allan deviation σ(τ) ({unit})"))
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style(("sans-serif", 13).into_font())
                .axis_desc_style(("sans-serif", 15).into_font())
                .draw()
                .map_err(err)?;
            for (a, c) in curves.iter().enumerate() {
                let color = colors[a];
                chart
                    .draw_series(LineSeries::new(
                        c.points.iter().filter(|p| p.1 > 0.0).map(|p| (p.0, p.1)),
                        color.stroke_width(2),
                    ))
                    .map_err(err)?
                    .label(format!("{name} {}", ["X", "Y", "Z"][a]))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
            }
            if let Some(spec) = spec {
                self.profile_lines(&mut chart, spec, t0, t1)?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 13).into_font())
                .draw()
                .map_err(err)?;
        }
        Ok(())
    }

    /// The profile's terms as dashed black lines over τ ∈ [t0, t1].
    fn profile_lines<DB: DrawingBackend>(
        &self,
        chart: &mut ChartContext<
            '_,
            DB,
            Cartesian2d<
                plotters::coord::combinators::LogCoord<f64>,
                plotters::coord::combinators::LogCoord<f64>,
            >,
        >,
        spec: &SensorSpec,
        t0: f64,
        t1: f64,
    ) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        let grid: Vec<f64> = (0..=60)
            .map(|i| t0 * (t1 / t0).powf(f64::from(i) / 60.0))
            .collect();
        let n = f64::from(spec.noise_density);
        let b = f64::from(spec.bias_instability) * FLICKER_FLOOR;
        let k = f64::from(spec.rate_random_walk);
        let lines: [ProfileLine; 3] = [
            (
                "profile: white N/√τ",
                Box::new(move |t| n / t.sqrt()),
                BLACK,
            ),
            (
                "profile: 0.6643·B (bias instability)",
                Box::new(move |_| b),
                RGBColor(120, 120, 120),
            ),
            (
                "profile: RRW K·√(τ/3)",
                Box::new(move |t| k * (t / 3.0).sqrt()),
                RGBColor(160, 80, 0),
            ),
        ];
        for (label, f, color) in lines {
            if f(t0) <= 0.0 {
                continue;
            }
            chart
                .draw_series(DashedLineSeries::new(
                    grid.iter().map(|&t| (t, f(t))),
                    8,
                    5,
                    color.stroke_width(1),
                ))
                .map_err(err)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(1))
                });
        }
        Ok(())
    }
}

fn err<E: std::error::Error + Send + Sync + 'static>(e: DrawingAreaErrorKind<E>) -> anyhow::Error {
    anyhow::anyhow!("{e}")
}
