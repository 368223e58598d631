//! `client plot`: a CSV recording drawn to PNG with the plotters bitmap
//! backend: one panel each for the angular rates (`gyro_*`), the
//! accelerations (`acc_*`) and the attitude (`heading`, `pitch`, `roll`),
//! those the recording has, against `host_time_s` (or the frame number).
//! X red, Y green, Z blue (heading, pitch, roll likewise).
//!
//! No text is drawn (no axis labels or captions), so no font — system or
//! bundled — is needed: the plot is for looking at shapes; the numbers are
//! in the CSV.

use std::path::Path;

use anyhow::{bail, Context as _};
use plotters::prelude::*;

/// Image size, pixels.
pub const SIZE: (u32, u32) = (1200, 900);

/// Plots `csv` to `png`; returns the rows plotted.
pub fn plot(csv: &Path, png: &Path) -> anyhow::Result<usize> {
    let text = std::fs::read_to_string(csv).with_context(|| format!("plot {}", csv.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .with_context(|| format!("plot {}: empty file", csv.display()))?
        .split(',')
        .collect();
    let rows: Vec<Vec<f64>> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|v| v.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let x_col = col("host_time_s").or_else(|| col("frame"));
    let Some(x_col) = x_col else {
        bail!(
            "plot {}: no host_time_s or frame column (a `client record` CSV?)",
            csv.display()
        );
    };
    let groups: Vec<[Option<usize>; 3]> = [
        ["gyro_x", "gyro_y", "gyro_z"],
        ["acc_x", "acc_y", "acc_z"],
        ["heading", "pitch", "roll"],
    ]
    .iter()
    .map(|g| [col(g[0]), col(g[1]), col(g[2])])
    .filter(|g| g.iter().any(Option::is_some))
    .collect();
    if groups.is_empty() || rows.is_empty() {
        bail!(
            "plot {}: nothing to plot (no rows, or no gyro_*, acc_* or attitude columns)",
            csv.display()
        );
    }
    let xs: Vec<f64> = rows
        .iter()
        .map(|r| r.get(x_col).copied().unwrap_or(f64::NAN))
        .collect();
    let (x0, x1) = range(xs.iter().copied());
    let root = BitMapBackend::new(png, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((groups.len(), 1));
    let colors = [RED, GREEN, BLUE];
    for (panel, group) in panels.iter().zip(&groups) {
        let ys = group
            .iter()
            .flatten()
            .flat_map(|&c| rows.iter().filter_map(move |r| r.get(c).copied()));
        let (y0, y1) = range(ys);
        let mut chart = ChartBuilder::on(panel)
            .margin(12)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_labels(0)
            .y_labels(0)
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        for (c, color) in group.iter().zip(colors) {
            let Some(c) = *c else { continue };
            let points = rows
                .iter()
                .zip(&xs)
                .filter_map(|(r, &x)| r.get(c).map(|&y| (x, y)))
                .filter(|(x, y)| x.is_finite() && y.is_finite());
            chart.draw_series(LineSeries::new(points, color.stroke_width(2)))?;
        }
    }
    root.present()
        .with_context(|| format!("plot: writing {}", png.display()))?;
    Ok(rows.len())
}

/// The finite range of `v`, widened a little (and never empty).
fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-3);
    (lo - pad, hi + pad)
}
