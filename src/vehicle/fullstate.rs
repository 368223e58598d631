//! Full-state rows: the vehicle given sample by sample (a file for
//! `--motion`, or the live feed's rows after a full-state header:
//! `crate::feed`, docs/feed.md), parsed sans-IO, and the state between
//! two rows (docs/motion.md, "Full-state CSV").
//!
//! A header line names the columns and so the layout:
//!
//! ```text
//! time,lat,lon,height,vn,ve,vd,roll,pitch,yaw[,wx,wy,wz,fx,fy,fz][,temp]
//! ```
//!
//! time s; lat, lon degrees; height m above the WGS84 ellipsoid; velocity
//! NED m/s; roll, pitch, yaw degrees (body FRD → NED, z-y-x); optionally
//! the angular rate ω_ib^b °/s and the specific force f^b m/s² in body
//! axes, and the sensor temperature °C. Values are separated by commas
//! (spaces around them allowed).
//!
//! Between two rows ([`between`]) the position follows the cubic Hermite
//! curve through both rows' positions with both rows' velocities as its
//! slopes, the velocity is that curve's derivative, and the attitude
//! turns at the constant body rate that takes one row's attitude to the
//! next — so the state is self-consistent and the derived rates and forces
//! integrate back to it. Rows that give rates and forces have them
//! interpolated linearly instead of derived.

use super::{
    quat_conj, quat_from_euler, quat_from_rotvec, quat_mul, rotvec_from_quat, scale, wgs84,
    wrap_pi, Motion6, VehicleState, V3,
};
use libm::{cos, sin};

/// The optional columns a header names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FullStateLayout {
    /// `wx,wy,wz,fx,fy,fz` follow the attitude.
    pub rates_forces: bool,
    /// `temp` is the last column.
    pub temperature: bool,
}

/// The mandatory columns, in order.
const COLUMNS: [&str; 10] = [
    "time", "lat", "lon", "height", "vn", "ve", "vd", "roll", "pitch", "yaw",
];
/// The rate and force columns, in order.
const RATE_FORCE: [&str; 6] = ["wx", "wy", "wz", "fx", "fy", "fz"];

impl FullStateLayout {
    /// The layout of a header line, or `None` if `line` is not a
    /// full-state header (column names are case-insensitive).
    pub fn from_header(line: &str) -> Option<Self> {
        let mut cols = line.split(',').map(str::trim);
        for want in COLUMNS {
            if !cols.next()?.eq_ignore_ascii_case(want) {
                return None;
            }
        }
        let mut layout = FullStateLayout::default();
        let mut next = cols.next();
        if next.is_some_and(|c| c.eq_ignore_ascii_case("wx")) {
            for want in &RATE_FORCE[1..] {
                if !cols.next()?.eq_ignore_ascii_case(want) {
                    return None;
                }
            }
            layout.rates_forces = true;
            next = cols.next();
        }
        if let Some(c) = next {
            if !c.eq_ignore_ascii_case("temp") {
                return None;
            }
            layout.temperature = true;
        }
        cols.next().is_none().then_some(layout)
    }

    /// Values a row of this layout has.
    pub fn columns(&self) -> usize {
        10 + if self.rates_forces { 6 } else { 0 } + usize::from(self.temperature)
    }

    /// The header name of column `i` (`lat`, `wx`, `temp`).
    pub fn column_name(&self, i: usize) -> &'static str {
        match i {
            0..=9 => COLUMNS[i],
            10..=15 if self.rates_forces => RATE_FORCE[i - 10],
            _ => "temp",
        }
    }

    /// The closed range of column `i`'s values (module doc).
    fn limits(&self, i: usize) -> (f64, f64) {
        match (i, self.rates_forces) {
            (0, _) => (0.0, f64::INFINITY),
            (1, _) => (-89.9, 89.9),
            (2, _) => (-360.0, 360.0),
            (3, _) => (-12_000.0, 1_000_000.0),
            (4..=6, _) => (-10_000.0, 10_000.0),
            (7..=9, _) => (-720.0, 720.0),
            (10..=15, true) => (-1e4, 1e4),
            _ => (-100.0, 200.0),
        }
    }
}

/// Why a row was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowError {
    /// Not as many values as the layout has columns.
    WrongCount,
    /// A value is not a finite number.
    NotANumber,
    /// A value is outside its range (latitude beyond ±89.9°, height beyond
    /// −12 km…1000 km, a speed beyond 10 km/s, a rate beyond 1e4 °/s, a
    /// force beyond 1e4 m/s², a temperature beyond −100…200 °C, a
    /// negative time).
    OutOfRange,
}

impl core::fmt::Display for RowError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            RowError::WrongCount => "wrong number of values",
            RowError::NotANumber => "not a finite number",
            RowError::OutOfRange => "value out of range",
        })
    }
}

/// One full-state sample (module doc for units and frames).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FullStateRow {
    /// Time, s.
    pub time_s: f64,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Height above the ellipsoid, m.
    pub height_m: f64,
    /// Velocity NED, m/s.
    pub vel_ned: V3,
    /// Roll, pitch, yaw, degrees.
    pub euler_deg: V3,
    /// ω_ib^b, body axes, °/s, if given.
    pub rate_dps: Option<V3>,
    /// f^b, body axes, m/s², if given.
    pub force_mps2: Option<V3>,
    /// Sensor temperature, °C, if given.
    pub temperature_c: Option<f32>,
}

impl FullStateRow {
    /// Parses one data line of `layout`.
    pub fn parse(line: &str, layout: &FullStateLayout) -> Result<Self, RowError> {
        Self::parse_column(line, layout).map_err(|(e, _)| e)
    }

    /// [`FullStateRow::parse`], the error with the column it is in
    /// (`None` for a wrong count; [`FullStateLayout::column_name`] names
    /// it): every value is read before any is range-checked, so a row
    /// with both faults is [`RowError::NotANumber`].
    pub fn parse_column(
        line: &str,
        layout: &FullStateLayout,
    ) -> Result<Self, (RowError, Option<usize>)> {
        let mut v = [0.0f64; 17];
        let mut n = 0;
        for cell in line.split(',') {
            if n == layout.columns() {
                return Err((RowError::WrongCount, None));
            }
            // The feed's number parser: no `str::parse` tables in firmware.
            v[n] = crate::math::decimal::parse(cell.trim())
                .filter(|x| x.is_finite())
                .ok_or((RowError::NotANumber, Some(n)))?;
            n += 1;
        }
        if n != layout.columns() {
            return Err((RowError::WrongCount, None));
        }
        for (i, &x) in v[..n].iter().enumerate() {
            let (lo, hi) = layout.limits(i);
            if !(lo..=hi).contains(&x) {
                return Err((RowError::OutOfRange, Some(i)));
            }
        }
        let (rate_dps, force_mps2) = if layout.rates_forces {
            (Some([v[10], v[11], v[12]]), Some([v[13], v[14], v[15]]))
        } else {
            (None, None)
        };
        let temperature_c = layout.temperature.then(|| v[n - 1] as f32);
        Ok(FullStateRow {
            time_s: v[0],
            lat_deg: v[1],
            lon_deg: v[2],
            height_m: v[3],
            vel_ned: [v[4], v[5], v[6]],
            euler_deg: [v[7], v[8], v[9]],
            rate_dps,
            force_mps2,
            temperature_c,
        })
    }

    /// Latitude, longitude (rad) and height.
    fn position(&self) -> V3 {
        [
            self.lat_deg.to_radians(),
            wrap_pi(self.lon_deg.to_radians()),
            self.height_m,
        ]
    }

    /// d(lat, lon, h)/dt of the row.
    fn position_rate(&self) -> V3 {
        let p = self.position();
        let (m, n) = wgs84::radii(p[0]);
        let v = self.vel_ned;
        [v[0] / (m + p[2]), v[1] / ((n + p[2]) * cos(p[0])), -v[2]]
    }

    fn q_nb(&self) -> super::Q4 {
        let e = self.euler_deg.map(f64::to_radians);
        quat_from_euler(e[0], e[1], e[2])
    }

    /// The row as a state held still: its position, velocity and attitude
    /// at `time_s`, measuring as if neither the velocity nor the attitude
    /// changed (its own rates and forces if it has them). What a source
    /// gives before its first row and after its last.
    pub fn held(&self, time_s: f64) -> VehicleState {
        let p = self.position();
        let mut s = VehicleState {
            time_s,
            lat_rad: p[0],
            lon_rad: p[1],
            height_m: p[2],
            vel_ned: self.vel_ned,
            q_nb: self.q_nb(),
            rate_ib_b: [0.0; 3],
            force_b: [0.0; 3],
            temperature_c: self.temperature_c,
        };
        s.measure(&Motion6 {
            acc_ned: [0.0; 3],
            rate_nb_b: [0.0; 3],
        });
        if let (Some(w), Some(f)) = (self.rate_dps, self.force_mps2) {
            s.rate_ib_b = w.map(f64::to_radians);
            s.force_b = f;
        }
        s
    }
}

/// The state at `t` between rows `a` and `b` (`a.time_s < b.time_s`; `t`
/// is clamped into their span): module doc.
pub fn between(a: &FullStateRow, b: &FullStateRow, t: f64) -> VehicleState {
    let dt = b.time_s - a.time_s;
    if dt <= 0.0 || !dt.is_finite() {
        return a.held(t);
    }
    let s = ((t - a.time_s) / dt).clamp(0.0, 1.0);
    let (pa, mut pb) = (a.position(), b.position());
    // The shorter way round in longitude.
    pb[1] = pa[1] + wrap_pi(pb[1] - pa[1]);
    let (da, db) = (a.position_rate(), b.position_rate());
    // Cubic Hermite basis and its derivatives in s.
    let (s2, s3) = (s * s, s * s * s);
    let h = [
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    ];
    let h1 = [
        6.0 * s2 - 6.0 * s,
        3.0 * s2 - 4.0 * s + 1.0,
        -6.0 * s2 + 6.0 * s,
        3.0 * s2 - 2.0 * s,
    ];
    let h2 = [
        12.0 * s - 6.0,
        6.0 * s - 4.0,
        -12.0 * s + 6.0,
        6.0 * s - 2.0,
    ];
    let mut p = [0.0; 3];
    let mut pd = [0.0; 3];
    let mut pdd = [0.0; 3];
    for i in 0..3 {
        p[i] = h[0] * pa[i] + h[1] * dt * da[i] + h[2] * pb[i] + h[3] * dt * db[i];
        pd[i] = (h1[0] * pa[i] + h1[1] * dt * da[i] + h1[2] * pb[i] + h1[3] * dt * db[i]) / dt;
        pdd[i] =
            (h2[0] * pa[i] + h2[1] * dt * da[i] + h2[2] * pb[i] + h2[3] * dt * db[i]) / (dt * dt);
    }
    // NED velocity of the curve and its derivative (the radii move with
    // the latitude).
    let (lat, hgt) = (p[0], p[2]);
    let (m, n) = wgs84::radii(lat);
    let (dm, dn) = wgs84::radii_slope(lat);
    let (sl, cl) = (sin(lat), cos(lat));
    let vel = [(m + hgt) * pd[0], (n + hgt) * cl * pd[1], -pd[2]];
    let acc = [
        (m + hgt) * pdd[0] + (dm * pd[0] + pd[2]) * pd[0],
        (n + hgt) * cl * pdd[1] + ((dn * pd[0] + pd[2]) * cl - (n + hgt) * sl * pd[0]) * pd[1],
        -pdd[2],
    ];
    // Attitude: constant body rate from a's attitude to b's.
    let (qa, qb) = (a.q_nb(), b.q_nb());
    let rot = rotvec_from_quat(&quat_mul(&quat_conj(&qa), &qb));
    let q = super::quat_normalize(&quat_mul(&qa, &quat_from_rotvec(&scale(&rot, s))));
    let lerp = |x: f64, y: f64| x + (y - x) * s;
    let mut st = VehicleState {
        time_s: t,
        lat_rad: lat,
        lon_rad: wrap_pi(p[1]),
        height_m: hgt,
        vel_ned: vel,
        q_nb: q,
        rate_ib_b: [0.0; 3],
        force_b: [0.0; 3],
        temperature_c: match (a.temperature_c, b.temperature_c) {
            (Some(x), Some(y)) => Some(lerp(f64::from(x), f64::from(y)) as f32),
            (x, y) => x.or(y),
        },
    };
    st.measure(&Motion6 {
        acc_ned: acc,
        rate_nb_b: scale(&rot, 1.0 / dt),
    });
    if let (Some(wa), Some(wb), Some(fa), Some(fb)) =
        (a.rate_dps, b.rate_dps, a.force_mps2, b.force_mps2)
    {
        for i in 0..3 {
            st.rate_ib_b[i] = lerp(wa[i], wb[i]).to_radians();
            st.force_b[i] = lerp(fa[i], fb[i]);
        }
    }
    st
}

/// The state at `t` of the vehicle `rows` describe (sorted by time,
/// increasing): [`between`] the rows around `t`, or the first or last row
/// [`FullStateRow::held`] outside their span; `None` without rows. The
/// measurement is the one at `t`.
pub fn state_at(rows: &[FullStateRow], t: f64) -> Option<VehicleState> {
    let (first, last) = (rows.first()?, rows.last()?);
    if t <= first.time_s {
        return Some(first.held(t));
    }
    if t >= last.time_s {
        return Some(last.held(t));
    }
    let i = rows.partition_point(|r| r.time_s <= t).max(1) - 1;
    Some(between(&rows[i], &rows[(i + 1).min(rows.len() - 1)], t))
}

/// The vehicle of `rows` at `t`, measuring the mean ω_ib^b and f^b over
/// `t0..t` (an integrating IMU's sample, docs/motion.md "Samples"):
/// Simpson's rule between the rows' times, where the derived rates
/// change; at most [`MAX_PIECES`] pieces (rows denser than that within
/// one sample are averaged over the first ones only). `t ≤ t0`: the
/// measurement at `t`.
pub fn sample(rows: &[FullStateRow], t0: f64, t: f64) -> Option<VehicleState> {
    let mut s = state_at(rows, t)?;
    if t <= t0 {
        return Some(s);
    }
    let (mut sw, mut sf) = ([0.0; 3], [0.0; 3]);
    let mut a = t0;
    let mut pieces = 0;
    while a < t && pieces < MAX_PIECES {
        pieces += 1;
        let k = rows.partition_point(|r| r.time_s <= a);
        let b = rows.get(k).map_or(t, |r| r.time_s.min(t));
        let eval = |x: f64| match k {
            0 => rows[0].held(x),
            k if k == rows.len() => rows[k - 1].held(x),
            k => between(&rows[k - 1], &rows[k], x),
        };
        let (p, m, q) = (eval(a), eval(0.5 * (a + b)), eval(b));
        for i in 0..3 {
            sw[i] += (p.rate_ib_b[i] + 4.0 * m.rate_ib_b[i] + q.rate_ib_b[i]) * (b - a) / 6.0;
            sf[i] += (p.force_b[i] + 4.0 * m.force_b[i] + q.force_b[i]) * (b - a) / 6.0;
        }
        a = b;
    }
    let span = a - t0;
    s.rate_ib_b = sw.map(|x| x / span);
    s.force_b = sf.map(|x| x / span);
    Some(s)
}

/// Pieces [`sample`] integrates at most per sample.
pub const MAX_PIECES: usize = 64;

#[cfg(test)]
mod tests {
    use super::*;
    use std::format;

    #[test]
    fn headers_choose_the_layout() {
        let h = FullStateLayout::from_header;
        let base = "time,lat,lon,height,vn,ve,vd,roll,pitch,yaw";
        assert_eq!(h(base), Some(FullStateLayout::default()));
        let all = h(&format!("{base},wx,wy,wz,fx,fy,fz,temp")).unwrap();
        assert!(all.rates_forces && all.temperature);
        assert_eq!(all.columns(), 17);
        assert!(h(&format!("{base}, TEMP")).unwrap().temperature);
        assert_eq!(h("time_s,wx,wy,wz,fx,fy,fz"), None);
        assert_eq!(h(&format!("{base},wx")), None);
        assert_eq!(h(&format!("{base},temp,x")), None);
    }

    #[test]
    fn rows_parse_or_say_why_not() {
        let l = FullStateLayout {
            rates_forces: false,
            temperature: true,
        };
        let r = FullStateRow::parse("1.5, 45, 7, 300, 10, 0, -1, 0, 5, 90, 30", &l).unwrap();
        assert_eq!(r.vel_ned, [10.0, 0.0, -1.0]);
        assert_eq!(r.temperature_c, Some(30.0));
        let p = |s: &str| FullStateRow::parse(s, &l).unwrap_err();
        assert_eq!(
            p("1, 45, 7, 300, 10, 0, -1, 0, 5, 90"),
            RowError::WrongCount
        );
        assert_eq!(
            p("1, 45, 7, 300, 10, 0, -1, 0, 5, 90, 30, 1"),
            RowError::WrongCount
        );
        assert_eq!(
            p("1, 45, 7, x, 10, 0, -1, 0, 5, 90, 30"),
            RowError::NotANumber
        );
        assert_eq!(
            p("1, 95, 7, 0, 10, 0, -1, 0, 5, 90, 30"),
            RowError::OutOfRange
        );
        assert_eq!(
            p("1, 45, 7, 0, 10, 0, -1, 0, 5, 90, inf"),
            RowError::NotANumber
        );
    }

    /// Between two rows the state passes through both, its velocity is its
    /// position's derivative, and the attitude turns at one rate.
    #[test]
    fn between_rows_is_consistent() {
        let l = FullStateLayout::default();
        let a = FullStateRow::parse("10, 45, 179.999, 300, 50, 20, -2, 5, 3, 170", &l).unwrap();
        let b = FullStateRow::parse("11, 45.0004, -179.9995, 302, 48, 25, -1, 10, 2, -175", &l)
            .unwrap();
        let sa = between(&a, &b, 10.0);
        assert!((sa.lat_rad - 45f64.to_radians()).abs() < 1e-15);
        assert!(sa
            .vel_ned
            .iter()
            .zip(&a.vel_ned)
            .all(|(x, y)| (x - y).abs() < 1e-9));
        let sb = between(&a, &b, 11.0);
        assert!(sb
            .vel_ned
            .iter()
            .zip(&b.vel_ned)
            .all(|(x, y)| (x - y).abs() < 1e-9));
        assert!((sb.euler_rad()[2].to_degrees() + 175.0).abs() < 1e-9);
        // Velocity = d(position)/dt, numerically, in the middle.
        let (x0, x1) = (between(&a, &b, 10.4999), between(&a, &b, 10.5001));
        let (m, n) = wgs84::radii(x0.lat_rad);
        let vn = (x1.lat_rad - x0.lat_rad) / 2e-4 * (m + x0.height_m);
        let ve = wrap_pi(x1.lon_rad - x0.lon_rad) / 2e-4 * (n + x0.height_m) * cos(x0.lat_rad);
        let mid = between(&a, &b, 10.5);
        assert!((vn - mid.vel_ned[0]).abs() < 1e-3, "{vn} {:?}", mid.vel_ned);
        assert!((ve - mid.vel_ned[1]).abs() < 1e-3, "{ve} {:?}", mid.vel_ned);
    }
}
