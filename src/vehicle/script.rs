//! Scripted manoeuvres: a start (position, heading, speed) and a list of
//! segments, parsed sans-IO from a small text format and flown by
//! [`Manoeuvres`] (docs/motion.md, "Manoeuvre scripts").
//!
//! ```text
//! # a comment; statements end at a newline or a ';'
//! start 45.0 7.5 300 90 50   # lat °, lon °, height m, heading °, speed m/s
//! hold 10                    # s: keep speed, heading, path angle
//! accel 2 15                 # m/s² along the body x axis, for 15 s
//! turn 3 30                  # a flat turn at 3 °/s (no bank), 30 s
//! coord-turn 3 60            # a coordinated (banked) turn at 3 °/s, 60 s
//! climb 5 20                 # path angle to +5°, then hold it; 20 s
//! descend 5 20               # path angle to −5°
//! ```
//!
//! The vehicle flies with its body x axis along its velocity (no angle of
//! attack or sideslip): pitch = the path angle γ, roll = the bank φ,
//! yaw = the heading ψ. Within a segment each of speed V, γ, φ and ψ
//! changes at a constant rate until its target is reached:
//! - `accel a`: V̇ = a (V stays within 0…[`MAX_SPEED`]);
//! - `climb θ` / `descend θ`: γ moves to ±θ at [`PITCH_RATE_DPS`], then
//!   holds; other segments keep γ;
//! - `coord-turn r`: φ rolls at [`ROLL_RATE_DPS`] to `atan(V r / g₀)`
//!   (g₀ = 9.80665 m/s²; at most ±[`MAX_BANK_DEG`]); other segments roll
//!   back to level. Whenever banked (rolling in, turning, rolling out) the
//!   heading turns at the coordinated rate `g₀ tan φ / V` (below
//!   [`MIN_COORD_SPEED`] a coordinated turn is a flat one);
//! - `turn r`: ψ̇ = r, wings level (a ground vehicle's turn).
//!
//! After the last segment the vehicle holds. The state is exact in
//! continuous time between the instants a rate changes; the position is
//! integrated with RK4 in steps of at most 10 ms.

use heapless::Vec;
use libm::{atan, cos, sin, tan};

use super::{body_rate_of_euler, quat_from_euler, wgs84, wrap_pi, Motion6, VehicleState, V3};

/// Segments a script holds at most.
pub(crate) const MAX_SEGMENTS: usize = 64;
/// Rate of the path angle's change in `climb`/`descend`, °/s.
pub(crate) const PITCH_RATE_DPS: f64 = 3.0;
/// Roll rate into and out of a coordinated turn, °/s.
pub(crate) const ROLL_RATE_DPS: f64 = 10.0;
/// Largest bank of a coordinated turn, degrees.
pub(crate) const MAX_BANK_DEG: f64 = 80.0;
/// Below this speed, m/s, a coordinated turn turns flat (the bank formula
/// divides by the speed).
pub(crate) const MIN_COORD_SPEED: f64 = 1.0;
/// Largest speed, m/s.
pub(crate) const MAX_SPEED: f64 = 3000.0;
/// Standard gravity, m/s², for the coordinated turn's bank (its
/// definition, not the vehicle's gravity).
const G0: f64 = 9.806_65;
/// Longest integration step, s.
const MAX_STEP: f64 = 0.01;

/// Where and how the vehicle starts: level, path angle 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Start {
    /// Latitude, degrees (−89.9…89.9).
    pub lat_deg: f64,
    /// Longitude, degrees (−360…360).
    pub lon_deg: f64,
    /// Height above the WGS84 ellipsoid, m (−12 000…100 000).
    pub height_m: f64,
    /// Heading, degrees clockwise from north (−360…360).
    pub heading_deg: f64,
    /// Speed along the body x axis, m/s (0…[`MAX_SPEED`]).
    pub speed_mps: f64,
}

/// What a segment does (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Manoeuvre {
    /// Keep speed, heading and path angle; roll level.
    Hold,
    /// Accelerate along the body x axis, m/s² (negative: brake).
    Accelerate(f64),
    /// Flat turn at a rate, °/s (positive: clockwise seen from above).
    Turn(f64),
    /// Move the path angle to this angle, degrees (positive: climb), and
    /// hold it.
    Climb(f64),
    /// Coordinated (banked) turn at a rate, °/s.
    CoordinatedTurn(f64),
}

/// One segment: a manoeuvre for a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// What the vehicle does.
    pub manoeuvre: Manoeuvre,
    /// For how long, s (> 0).
    pub duration_s: f64,
}

/// A parsed manoeuvre script: fixed capacity, no heap.
#[derive(Debug, Clone, PartialEq)]
pub struct Script {
    /// The start.
    pub start: Start,
    /// The segments, in order.
    pub segments: Vec<Segment, MAX_SEGMENTS>,
}

/// Why a script was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScriptErrorKind {
    /// A statement starts with a word that is no statement.
    UnknownStatement,
    /// A statement has too few or too many values.
    WrongCount,
    /// A value is not a finite number.
    NotANumber,
    /// A value is outside its range (module doc, [`Start`]).
    OutOfRange,
    /// No `start`, or a second one, or a segment before it.
    Start,
    /// More than [`MAX_SEGMENTS`] segments.
    TooManySegments,
}

/// A script error: where (1-based line of the text and statement number)
/// and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScriptError {
    /// Line of the text, from 1.
    pub line: u32,
    /// Statement, from 1 (comments and blank pieces not counted).
    pub statement: u32,
    /// What is wrong.
    pub kind: ScriptErrorKind,
}

impl core::fmt::Display for ScriptError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let why = match self.kind {
            ScriptErrorKind::UnknownStatement => {
                "unknown statement (start, hold, accel, turn, coord-turn, climb, descend)"
            }
            ScriptErrorKind::WrongCount => "wrong number of values",
            ScriptErrorKind::NotANumber => "not a finite number",
            ScriptErrorKind::OutOfRange => "value out of range",
            ScriptErrorKind::Start => "exactly one start, before the segments",
            ScriptErrorKind::TooManySegments => "more than 64 segments",
        };
        write!(f, "line {} statement {}: {why}", self.line, self.statement)
    }
}

/// `w` as a finite number within `lo..=hi`.
fn value(w: &str, lo: f64, hi: f64) -> Result<f64, ScriptErrorKind> {
    let x = w
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or(ScriptErrorKind::NotANumber)?;
    if (lo..=hi).contains(&x) {
        Ok(x)
    } else {
        Err(ScriptErrorKind::OutOfRange)
    }
}

/// Whether `text` looks like a manoeuvre script: its first statement is
/// `start`.
pub fn is_script(text: &str) -> bool {
    statements(text)
        .next()
        .is_some_and(|(_, s)| s.split_whitespace().next() == Some("start"))
}

/// The statements of `text` with their line numbers: comments cut, split at
/// newlines and `;`, blank pieces skipped.
fn statements(text: &str) -> impl Iterator<Item = (u32, &str)> {
    text.split('\n').enumerate().flat_map(|(i, line)| {
        let line = line.split('#').next().unwrap_or("");
        line.split(';')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(move |s| (i as u32 + 1, s))
    })
}

impl Script {
    /// Parses a script (module doc); `;` and newlines both end a statement,
    /// so one line carries a whole script (the control socket's `motion
    /// script …`).
    pub fn parse(text: &str) -> Result<Script, ScriptError> {
        let mut start = None;
        let mut segments = Vec::new();
        let mut n = 0u32;
        let mut last_line = 1;
        for (line, st) in statements(text) {
            n += 1;
            last_line = line;
            let err = |kind| ScriptError {
                line,
                statement: n,
                kind,
            };
            let mut words = st.split_whitespace();
            let Some(word) = words.next() else { continue };
            let mut vals = [""; 6];
            let mut count = 0;
            for w in words {
                if count == vals.len() {
                    return Err(err(ScriptErrorKind::WrongCount));
                }
                vals[count] = w;
                count += 1;
            }
            let want = if word == "start" {
                5
            } else if word == "hold" {
                1
            } else {
                2
            };
            if !matches!(
                word,
                "start" | "hold" | "accel" | "turn" | "coord-turn" | "climb" | "descend"
            ) {
                return Err(err(ScriptErrorKind::UnknownStatement));
            }
            if count != want {
                return Err(err(ScriptErrorKind::WrongCount));
            }
            if word == "start" {
                if start.is_some() {
                    return Err(err(ScriptErrorKind::Start));
                }
                let v = |i: usize, lo, hi| value(vals[i], lo, hi).map_err(err);
                start = Some(Start {
                    lat_deg: v(0, -89.9, 89.9)?,
                    lon_deg: v(1, -360.0, 360.0)?,
                    height_m: v(2, -12_000.0, 100_000.0)?,
                    heading_deg: v(3, -360.0, 360.0)?,
                    speed_mps: v(4, 0.0, MAX_SPEED)?,
                });
                continue;
            }
            if start.is_none() {
                return Err(err(ScriptErrorKind::Start));
            }
            let duration_s = value(vals[want - 1], 0.0, 1e6).map_err(err)?;
            if duration_s <= 0.0 {
                return Err(err(ScriptErrorKind::OutOfRange));
            }
            let x = |lo, hi| value(vals[0], lo, hi).map_err(err);
            let manoeuvre = match word {
                "hold" => Manoeuvre::Hold,
                "accel" => Manoeuvre::Accelerate(x(-200.0, 200.0)?),
                "turn" => Manoeuvre::Turn(x(-500.0, 500.0)?),
                "coord-turn" => Manoeuvre::CoordinatedTurn(x(-100.0, 100.0)?),
                "climb" => Manoeuvre::Climb(x(-85.0, 85.0)?),
                _ => Manoeuvre::Climb(-x(-85.0, 85.0)?),
            };
            segments
                .push(Segment {
                    manoeuvre,
                    duration_s,
                })
                .map_err(|_| err(ScriptErrorKind::TooManySegments))?;
        }
        let start = start.ok_or(ScriptError {
            line: last_line,
            statement: n,
            kind: ScriptErrorKind::Start,
        })?;
        Ok(Script { start, segments })
    }

    /// The total time of the segments, s.
    pub fn duration_s(&self) -> f64 {
        self.segments.iter().map(|s| s.duration_s).sum()
    }
}

/// The rates of the vehicle's flight variables over the next step and how
/// long they hold at most.
#[derive(Debug, Clone, Copy)]
struct Rates {
    speed: f64,
    path: f64,
    bank: f64,
    yaw: f64,
    /// Time until a rate changes (a target reached, the segment's end), s.
    until: f64,
    /// The targets (path, bank) a rate moves to.
    path_target: f64,
    bank_target: f64,
}

/// The flight variables and the time (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Flight {
    t: f64,
    lat: f64,
    lon: f64,
    h: f64,
    speed: f64,
    yaw: f64,
    path: f64,
    bank: f64,
}

impl Flight {
    /// The state at rates `r`, with what a perfect IMU measures now.
    fn state(&self, r: &Rates) -> VehicleState {
        let v = velocity(self.speed, self.yaw, self.path);
        // d/dt of V·u(ψ, γ).
        let (sy, cy) = (sin(self.yaw), cos(self.yaw));
        let (sp, cp) = (sin(self.path), cos(self.path));
        let du_yaw = [-cp * sy, cp * cy, 0.0];
        let du_path = [-sp * cy, -sp * sy, -cp];
        let u = [cp * cy, cp * sy, -sp];
        let mut acc = [0.0; 3];
        for i in 0..3 {
            acc[i] = r.speed * u[i] + self.speed * (r.yaw * du_yaw[i] + r.path * du_path[i]);
        }
        let e = [self.bank, self.path, self.yaw];
        let mut s = VehicleState {
            time_s: self.t,
            lat_rad: self.lat,
            lon_rad: self.lon,
            height_m: self.h,
            vel_ned: v,
            q_nb: quat_from_euler(self.bank, self.path, self.yaw),
            rate_ib_b: [0.0; 3],
            force_b: [0.0; 3],
            temperature_c: None,
        };
        s.measure(&Motion6 {
            acc_ned: acc,
            rate_nb_b: body_rate_of_euler(&e, &[r.bank, r.path, r.yaw]),
        });
        s
    }

    /// One step of `h` seconds at rates `r` (landing exactly on a target
    /// the step was cut for).
    fn step(&mut self, r: &Rates, h: f64) {
        let (v0, y0, p0) = (self.speed, self.yaw, self.path);
        let vel = |k: f64| velocity(v0 + r.speed * k, y0 + r.yaw * k, p0 + r.path * k);
        // RK4 for the position; the velocity is exact at any k.
        let p = [self.lat, self.lon, self.h];
        let at = |p: &V3, d: &V3, k: f64| [p[0] + d[0] * k, p[1] + d[1] * k, p[2] + d[2] * k];
        let k1 = position_rate(&p, &vel(0.0));
        let k2 = position_rate(&at(&p, &k1, 0.5 * h), &vel(0.5 * h));
        let k3 = position_rate(&at(&p, &k2, 0.5 * h), &vel(0.5 * h));
        let k4 = position_rate(&at(&p, &k3, h), &vel(h));
        let d: V3 = core::array::from_fn(|i| (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) * h / 6.0);
        self.lat += d[0];
        self.lon = wrap_pi(self.lon + d[1]);
        self.h += d[2];
        self.speed = (v0 + r.speed * h).clamp(0.0, MAX_SPEED);
        self.yaw = wrap_pi(y0 + r.yaw * h);
        self.path += r.path * h;
        self.bank += r.bank * h;
        if h >= r.until {
            let snap = |x: &mut f64, target: f64| {
                if (*x - target).abs() < 1e-9 {
                    *x = target;
                }
            };
            snap(&mut self.path, r.path_target);
            snap(&mut self.bank, r.bank_target);
            if self.speed < 1e-9 {
                self.speed = 0.0;
            }
        }
        self.t += h;
    }
}

/// A script being flown: the vehicle's state at the time of the last
/// [`Manoeuvres::at`].
///
/// The measurement [`Manoeuvres::at`] reports is the mean of ω_ib^b and
/// f^b over the time since the previous call — what an integrating IMU
/// gives for a sample (Δθ/Δt, Δv/Δt) — integrated exactly across the
/// instants a rate changes (Simpson's rule between them), so that the
/// samples sum to the true angle and velocity increments
/// (docs/motion.md, "Samples").
#[derive(Debug, Clone, PartialEq)]
pub struct Manoeuvres {
    script: Script,
    /// Index of the segment in force (`segments.len()`: past the last).
    seg: usize,
    /// Time left in it, s.
    seg_left: f64,
    f: Flight,
}

/// The NED velocity of speed `v` along heading `yaw` at path angle `path`.
fn velocity(v: f64, yaw: f64, path: f64) -> V3 {
    let (sy, cy) = (sin(yaw), cos(yaw));
    let (sp, cp) = (sin(path), cos(path));
    [v * cp * cy, v * cp * sy, -v * sp]
}

/// d(lat, lon, h)/dt at position `p` moving at NED velocity `v`.
fn position_rate(p: &V3, v: &V3) -> V3 {
    let (m, n) = wgs84::radii(p[0]);
    [v[0] / (m + p[2]), v[1] / ((n + p[2]) * cos(p[0])), -v[2]]
}

impl Manoeuvres {
    /// The vehicle at the script's start, time 0.
    pub fn new(script: Script) -> Self {
        let s = script.start;
        let seg_left = script
            .segments
            .first()
            .map_or(f64::INFINITY, |s| s.duration_s);
        Manoeuvres {
            seg: 0,
            seg_left,
            f: Flight {
                t: 0.0,
                lat: s.lat_deg.to_radians(),
                lon: wrap_pi(s.lon_deg.to_radians()),
                h: s.height_m,
                speed: s.speed_mps,
                yaw: wrap_pi(s.heading_deg.to_radians()),
                path: 0.0,
                bank: 0.0,
            },
            script,
        }
    }

    /// The script flown.
    pub fn script(&self) -> &Script {
        &self.script
    }

    /// Whether every segment has been flown (the vehicle holds).
    pub fn finished(&self) -> bool {
        self.seg >= self.script.segments.len()
    }

    fn manoeuvre(&self) -> Manoeuvre {
        self.script
            .segments
            .get(self.seg)
            .map_or(Manoeuvre::Hold, |s| s.manoeuvre)
    }

    /// The rates in force now (module doc).
    fn rates(&self) -> Rates {
        let m = self.manoeuvre();
        let f = &self.f;
        let mut until = self.seg_left;
        let toward = |x: f64, target: f64, rate: f64, until: &mut f64| {
            let d = target - x;
            if d == 0.0 {
                return 0.0;
            }
            *until = until.min(d.abs() / rate);
            rate.copysign(d)
        };
        let speed = match m {
            Manoeuvre::Accelerate(a) if a < 0.0 && f.speed > 0.0 => {
                until = until.min(f.speed / -a);
                a
            }
            Manoeuvre::Accelerate(a) if a > 0.0 && f.speed < MAX_SPEED => {
                until = until.min((MAX_SPEED - f.speed) / a);
                a
            }
            _ => 0.0,
        };
        let path_target = match m {
            Manoeuvre::Climb(deg) => deg.to_radians(),
            _ => f.path,
        };
        let path = toward(f.path, path_target, PITCH_RATE_DPS.to_radians(), &mut until);
        let coord = f.speed >= MIN_COORD_SPEED;
        let bank_target = match m {
            Manoeuvre::CoordinatedTurn(r) if coord => atan(f.speed * r.to_radians() / G0)
                .clamp(-MAX_BANK_DEG.to_radians(), MAX_BANK_DEG.to_radians()),
            _ => 0.0,
        };
        let bank = toward(f.bank, bank_target, ROLL_RATE_DPS.to_radians(), &mut until);
        let yaw = match m {
            Manoeuvre::Turn(r) => r.to_radians(),
            Manoeuvre::CoordinatedTurn(r) if !coord => r.to_radians(),
            _ => 0.0,
        } + if coord && f.bank != 0.0 {
            G0 * tan(f.bank) / f.speed
        } else {
            0.0
        };
        Rates {
            speed,
            path,
            bank,
            yaw,
            until,
            path_target,
            bank_target,
        }
    }

    /// The vehicle now, measuring what a perfect IMU measures at this
    /// instant.
    pub fn state(&self) -> VehicleState {
        self.f.state(&self.rates())
    }

    /// Flies on to time `t` (s) and gives the state there, measuring the
    /// mean rate and specific force since the previous call (struct doc);
    /// at or before the time reached, the state there, measuring now.
    pub fn at(&mut self, t: f64) -> VehicleState {
        let t0 = self.f.t;
        if t <= t0 {
            return self.state();
        }
        let (mut sw, mut sf) = ([0.0; 3], [0.0; 3]);
        // A bounded number of steps per call whatever `t` is (a host clock
        // jump): beyond it the vehicle catches up at the next calls.
        for _ in 0..1_000_000 {
            if self.f.t >= t {
                break;
            }
            let r = self.rates();
            let h = (t - self.f.t).min(MAX_STEP).min(r.until).max(0.0);
            let a = self.f.state(&r);
            let mut mid = self.f;
            mid.step(&r, 0.5 * h);
            let m = mid.state(&r);
            self.f.step(&r, h);
            let b = self.f.state(&r);
            for i in 0..3 {
                sw[i] += (a.rate_ib_b[i] + 4.0 * m.rate_ib_b[i] + b.rate_ib_b[i]) * h / 6.0;
                sf[i] += (a.force_b[i] + 4.0 * m.force_b[i] + b.force_b[i]) * h / 6.0;
            }
            self.seg_left -= h;
            if self.seg_left <= 1e-12 && self.seg < self.script.segments.len() {
                self.seg += 1;
                self.seg_left = self
                    .script
                    .segments
                    .get(self.seg)
                    .map_or(f64::INFINITY, |s| s.duration_s);
            }
        }
        let mut s = self.state();
        let span = self.f.t - t0;
        s.rate_ib_b = sw.map(|x| x / span);
        s.force_b = sf.map(|x| x / span);
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::borrow::ToOwned;

    #[test]
    fn parses_the_documented_example() {
        let s = Script::parse(
            "# example\nstart 45.0 7.5 300 90 50\nhold 10; accel 2 15\nturn 3 30\n\
             coord-turn 3 60 # banked\nclimb 5 20\ndescend 5 20\n",
        )
        .unwrap();
        assert_eq!(s.start.heading_deg, 90.0);
        assert_eq!(s.segments.len(), 6);
        assert_eq!(s.segments[5].manoeuvre, Manoeuvre::Climb(-5.0));
        assert_eq!(s.duration_s(), 155.0);
        assert!(is_script("# x\n start 1 2 3 4 5"));
        assert!(!is_script("time,lat,lon"));
    }

    #[test]
    fn refuses_bad_scripts_with_a_place_and_a_reason() {
        let e = |t: &str| Script::parse(t).unwrap_err();
        use ScriptErrorKind::*;
        assert_eq!(e("hold 1").kind, Start);
        assert_eq!(e("start 0 0 0 0 0\nstart 0 0 0 0 0").kind, Start);
        assert_eq!(e("start 0 0 0 0 0\njump 3").kind, UnknownStatement);
        let x = e("start 0 0 0 0 0\nhold 1\nturn 3");
        assert_eq!((x.line, x.statement, x.kind), (3, 3, WrongCount));
        assert_eq!(e("start 0 0 0 0 0; hold NaN").kind, NotANumber);
        assert_eq!(e("start 95 0 0 0 0").kind, OutOfRange);
        assert_eq!(e("start 0 0 0 0 0; hold 0").kind, OutOfRange);
        assert_eq!(e("start 0 0 0 0 0 1 2 3 4").kind, WrongCount);
        assert_eq!(e("").kind, Start);
        let many = "start 0 0 0 0 0\n".to_owned() + &"hold 1\n".repeat(65);
        assert_eq!(e(&many).kind, TooManySegments);
    }

    /// A coordinated turn reaches its bank and turns at its rate; speed
    /// and path angle reach their targets exactly.
    #[test]
    fn flies_to_the_targets() {
        let s = Script::parse("start 10 20 1000 0 100; coord-turn 3 30; accel -50 5; climb 10 10")
            .unwrap();
        let mut m = Manoeuvres::new(s);
        let st = m.at(20.0);
        let bank = atan(100.0 * 3f64.to_radians() / G0);
        assert!((st.euler_rad()[0] - bank).abs() < 1e-9);
        assert!((m.rates().yaw - 3f64.to_radians()).abs() < 1e-12);
        m.at(40.0);
        assert_eq!(m.f.speed, 0.0);
        assert_eq!(m.f.bank, 0.0);
        let st = m.at(50.0);
        assert!((st.euler_rad()[1] - 10f64.to_radians()).abs() < 1e-12);
        assert!(m.finished());
    }
}
