//! `client plot`: a CSV recording (from `client record` or `client
//! decode`, either protocol) drawn in the house style ([`crate::plot`]):
//! one panel for each group of columns the recording has (angular rates,
//! accelerations, attitude, …), against device time (`device_time_s`,
//! from the frames' own counters or time fields, so a `--speed max`
//! recording spans the whole axis), else host time, else the frame number.
//! Columns named `pos_err_<name>` (an INS position error against the
//! truth) are drawn together in one more panel.

use std::path::Path;

use anyhow::{bail, Context as _};

use crate::plot::{Corner, Figure, Panel, Scale, Series};

/// Groups of columns drawn together: panel title, y label with unit, and
/// `(column, legend)` pairs.
type Group = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

/// The panels a KERNEL recording may have, in order.
const KERNEL_GROUPS: &[Group] = &[
    (
        "Angular rate",
        "angular rate (deg/s)",
        &[("gyro_x", "X"), ("gyro_y", "Y"), ("gyro_z", "Z")],
    ),
    (
        "Acceleration",
        "specific force (g)",
        &[("acc_x", "X"), ("acc_y", "Y"), ("acc_z", "Z")],
    ),
    (
        "Attitude",
        "angle (deg)",
        &[("heading", "heading"), ("pitch", "pitch"), ("roll", "roll")],
    ),
];

/// The panels of an ISB recording (`did` column), in the sets' own units.
const ISB_GROUPS: &[Group] = &[
    (
        "Angular rate",
        "angular rate (rad/s)",
        &[("pqr_x", "X"), ("pqr_y", "Y"), ("pqr_z", "Z")],
    ),
    (
        "Acceleration",
        "specific force (m/s²)",
        &[("acc_x", "X"), ("acc_y", "Y"), ("acc_z", "Z")],
    ),
    (
        "Delta angle",
        "Δθ per packet (rad)",
        &[("theta_x", "X"), ("theta_y", "Y"), ("theta_z", "Z")],
    ),
    (
        "Delta velocity",
        "Δv per packet (m/s)",
        &[("vel_x", "X"), ("vel_y", "Y"), ("vel_z", "Z")],
    ),
];

/// The x columns, best first: column, axis label.
const X_AXES: &[(&str, &str)] = &[
    ("device_time_s", "device time (s)"),
    ("host_time_s", "host time (s)"),
    ("frame", "frame"),
];

/// Plots `csv` to `out` (`.png` or `.svg`); returns the rows plotted.
pub fn plot(csv: &Path, out: &Path) -> anyhow::Result<usize> {
    crate::plot::check_output(out)?;
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
    let Some((x_col, x_label)) = X_AXES
        .iter()
        .find_map(|(c, label)| col(c).map(|i| (i, *label)))
    else {
        bail!(
            "plot {}: no device_time_s, host_time_s or frame column (a `client record` CSV?)",
            csv.display()
        );
    };
    let isb = col("did").is_some();
    let format = header
        .iter()
        .position(|h| *h == if isb { "did" } else { "format" })
        .and_then(|i| text.lines().nth(1)?.split(',').nth(i))
        .unwrap_or("recording");
    let groups = if isb { ISB_GROUPS } else { KERNEL_GROUPS };
    let mut panels: Vec<Panel> = groups
        .iter()
        .filter_map(|(title, y_label, cols)| {
            let series: Vec<Series> = cols
                .iter()
                .filter_map(|(c, legend)| {
                    let i = col(c)?;
                    Some(Series {
                        name: (*legend).to_owned(),
                        points: rows
                            .iter()
                            .filter_map(|r| Some((*r.get(x_col)?, *r.get(i)?)))
                            .collect(),
                        reference: false,
                    })
                })
                .collect();
            (!series.is_empty()).then(|| Panel {
                title: (*title).to_owned(),
                y_label: (*y_label).to_owned(),
                y_scale: Scale::Linear,
                series,
                legend: Corner::Right,
            })
        })
        .collect();
    // Columns `pos_err_<name>` (an INS position error against the truth,
    // e.g. `examples/nav_outage.rs`): one panel, one line each.
    let errs: Vec<Series> = header
        .iter()
        .enumerate()
        .filter_map(|(i, h)| {
            let name = h.strip_prefix("pos_err_")?;
            Some(Series {
                name: name.to_owned(),
                points: rows
                    .iter()
                    .filter_map(|r| Some((*r.get(x_col)?, *r.get(i)?)))
                    .collect(),
                reference: false,
            })
        })
        .collect();
    if !errs.is_empty() {
        panels.push(Panel {
            title: "INS position error".to_owned(),
            y_label: "horizontal error (m)".to_owned(),
            y_scale: Scale::Linear,
            series: errs,
            legend: Corner::UpperRight,
        });
    }
    if panels.is_empty() || rows.is_empty() {
        bail!(
            "plot {}: nothing to plot (no rows, or no rate, acceleration or attitude columns)",
            csv.display()
        );
    }
    let name = csv
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let fig = Figure {
        title: format!("{name}: {format}, {} rows", rows.len()),
        x_label: x_label.to_owned(),
        x_scale: Scale::Linear,
        panels,
    };
    crate::plot::render(&fig, out)?;
    Ok(rows.len())
}
