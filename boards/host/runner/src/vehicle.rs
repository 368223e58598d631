//! The vehicle sources of `--motion FILE` and the control socket's
//! `motion script …` / `motion file …`: a manoeuvre script or a
//! full-state CSV (chosen by the file's first statement or header),
//! flown or played once a tick into the core's vehicle truth
//! (`imu_emu::vehicle`, docs/motion.md).

use std::path::Path;

use anyhow::{bail, Context as _};
use imu_emu::vehicle::{
    fullstate, FullStateLayout, FullStateRow, Manoeuvres, Script, VehicleState,
};

/// Largest motion file read (`--motion`, `motion file`, `--trajectory`),
/// bytes: an hour of full-state rows at 100 Hz is about 30 MB.
pub const MAX_MOTION_FILE: u64 = 64 * 1024 * 1024;

/// Reads a motion file (`what`: `motion`, `trajectory`) as `--flash`
/// opens its file: without blocking on a FIFO or becoming a controlling
/// terminal, refusing what is not a regular file (a FIFO, `/dev/zero`, a
/// directory) and a file beyond [`MAX_MOTION_FILE`], so a `motion file`
/// command never stalls the device loop or grows the process.
pub fn read_motion_file(path: &Path, what: &str) -> anyhow::Result<String> {
    use std::io::Read as _;
    use std::os::unix::fs::OpenOptionsExt as _;
    let shown = path.display();
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(nix::fcntl::OFlag::O_NONBLOCK.bits() | nix::fcntl::OFlag::O_NOCTTY.bits())
        .open(path)
        .with_context(|| format!("reading {what} {shown}"))?;
    let meta = file
        .metadata()
        .with_context(|| format!("reading {what} {shown}"))?;
    if !meta.file_type().is_file() {
        bail!(
            "{what} {shown}: not a regular file ({})",
            crate::flash::describe(meta.file_type())
        );
    }
    if meta.len() > MAX_MOTION_FILE {
        bail!(
            "{what} {shown}: {} bytes, more than the {MAX_MOTION_FILE} a motion file may have",
            meta.len()
        );
    }
    let mut raw = Vec::new();
    file.take(MAX_MOTION_FILE + 1)
        .read_to_end(&mut raw)
        .with_context(|| format!("reading {what} {shown}"))?;
    if raw.len() as u64 > MAX_MOTION_FILE {
        bail!("{what} {shown}: grew beyond {MAX_MOTION_FILE} bytes while read");
    }
    String::from_utf8(raw).with_context(|| format!("{what} {shown}: not UTF-8 text"))
}

/// A loaded vehicle source, with the device time it started at.
#[derive(Debug, Clone)]
pub struct VehicleSource {
    kind: Kind,
    /// Device time of the source's time 0, s.
    epoch_s: f64,
    /// Source time of the last sample, s.
    last_s: f64,
}

#[derive(Debug, Clone)]
enum Kind {
    Script(Box<Manoeuvres>),
    FullState(Vec<FullStateRow>),
}

impl VehicleSource {
    /// Reads and parses `path` (a script or a full-state CSV).
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = read_motion_file(path, "motion")?;
        Self::parse(&text).with_context(|| format!("in {}", path.display()))
    }

    /// Parses a manoeuvre script (first statement `start`) or a full-state
    /// CSV (first line that is not blank or a `#` comment: the header).
    pub fn parse(text: &str) -> anyhow::Result<Self> {
        if imu_emu::vehicle::script::is_script(text) {
            let s = Script::parse(text).map_err(|e| anyhow::anyhow!("manoeuvre script: {e}"))?;
            return Ok(Self::script(s));
        }
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let Some((_, header)) = lines.next() else {
            bail!(
                "empty: expected a manoeuvre script (first statement `start`) or a full-state CSV"
            )
        };
        let Some(layout) = FullStateLayout::from_header(header) else {
            bail!(
                "neither a manoeuvre script (first statement `start …`) nor a full-state CSV \
                 (header `time,lat,lon,height,vn,ve,vd,roll,pitch,yaw[,wx,wy,wz,fx,fy,fz][,temp]`): \
                 {header:?}"
            )
        };
        let mut rows: Vec<FullStateRow> = Vec::new();
        for (n, line) in lines {
            let r = FullStateRow::parse_column(line, &layout).map_err(|(e, col)| match col {
                Some(c) => anyhow::anyhow!(
                    "line {n}, column {} (value {}): {e}: {line:?}",
                    layout.column_name(c),
                    c + 1
                ),
                None => anyhow::anyhow!("line {n}: {e} ({} expected): {line:?}", layout.columns()),
            })?;
            if rows.last().is_some_and(|p| r.time_s <= p.time_s) {
                bail!("line {n}: time {} does not increase", r.time_s);
            }
            rows.push(r);
        }
        if rows.is_empty() {
            bail!("full-state CSV without rows");
        }
        Ok(VehicleSource {
            kind: Kind::FullState(rows),
            epoch_s: 0.0,
            last_s: 0.0,
        })
    }

    /// A parsed script, flown from time 0.
    pub fn script(s: Script) -> Self {
        VehicleSource {
            kind: Kind::Script(Box::new(Manoeuvres::new(s))),
            epoch_s: 0.0,
            last_s: 0.0,
        }
    }

    /// The source started at device time `epoch_s` instead of 0 (a control
    /// command's).
    pub fn starting_at(mut self, epoch_s: f64) -> Self {
        self.epoch_s = epoch_s;
        self
    }

    /// `script` or `full-state`.
    pub fn kind(&self) -> &'static str {
        match self.kind {
            Kind::Script(_) => "script",
            Kind::FullState(_) => "full-state",
        }
    }

    /// One line for stderr: what the source is.
    pub fn describe(&self) -> String {
        match &self.kind {
            Kind::Script(m) => format!(
                "manoeuvre script ({} segments, {} s)",
                m.script().segments.len(),
                m.script().duration_s()
            ),
            Kind::FullState(rows) => format!(
                "full-state CSV ({} rows, {} s to {} s)",
                rows.len(),
                rows[0].time_s,
                rows[rows.len() - 1].time_s
            ),
        }
    }

    /// The vehicle at device time `now_s` (times never go back), measuring
    /// the mean since the previous call (docs/motion.md, "Samples"); its
    /// `time_s` is the device time.
    pub fn at(&mut self, now_s: f64) -> VehicleState {
        let t = (now_s - self.epoch_s).max(0.0);
        let mut s = match &mut self.kind {
            Kind::Script(m) => m.at(t),
            Kind::FullState(rows) => fullstate::sample(rows, self.last_s, t)
                .unwrap_or_else(|| VehicleState::at_rest(0.0, 0.0, 0.0, 0.0)),
        };
        self.last_s = t;
        s.time_s = now_s;
        s
    }
}

/// The `truth` reply (and the `truth-…` words of `status`): `source=…`
/// then the state in `key=value` words — time s (device), lat, lon deg,
/// height m, vn ve vd m/s, roll pitch yaw deg, wx wy wz deg/s and fx fy fz
/// m/s² (ω_ib^b, f^b, body axes FRD), temp °C (the sensor's: the source's
/// or the chain's model). `prefix` goes before each key.
pub fn truth_words(s: &VehicleState, source: &str, temperature_c: f32, prefix: &str) -> String {
    let e = s.euler_rad().map(f64::to_degrees);
    let w = s.rate_ib_b.map(f64::to_degrees);
    let f = s.force_b;
    let v = s.vel_ned;
    format!(
        "{prefix}source={source} {prefix}time={:.6} {prefix}lat={:.9} {prefix}lon={:.9} \
         {prefix}height={:.4} {prefix}vn={:.5} {prefix}ve={:.5} {prefix}vd={:.5} \
         {prefix}roll={:.6} {prefix}pitch={:.6} {prefix}yaw={:.6} {prefix}wx={:.7} \
         {prefix}wy={:.7} {prefix}wz={:.7} {prefix}fx={:.6} {prefix}fy={:.6} {prefix}fz={:.6} \
         {prefix}temp={:.2}",
        s.time_s,
        s.lat_rad.to_degrees(),
        s.lon_rad.to_degrees(),
        s.height_m,
        v[0],
        v[1],
        v[2],
        e[0],
        e[1],
        e[2],
        w[0],
        w[1],
        w[2],
        f[0],
        f[1],
        f[2],
        s.temperature_c.unwrap_or(temperature_c),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chooses_by_the_first_statement_or_header() {
        let s = VehicleSource::parse("# x\nstart 45 7 300 90 50\nturn 3 10\n").unwrap();
        assert_eq!(s.kind(), "script");
        let f = VehicleSource::parse(
            "time,lat,lon,height,vn,ve,vd,roll,pitch,yaw\n0,45,7,300,0,50,0,0,0,90\n\
             1,45,7.0006,300,0,50,0,0,0,90\n",
        )
        .unwrap();
        assert_eq!(f.kind(), "full-state");
        assert!(f.describe().contains("2 rows"), "{}", f.describe());
        let e = |t: &str| VehicleSource::parse(t).unwrap_err().to_string();
        assert!(e("time_s,wx,wy,wz,fx,fy,fz\n").contains("neither"));
        assert!(
            e("start 45 7 300 90\n").contains("line 1 statement 1"),
            "{}",
            e("start 1")
        );
        assert!(e("time,lat,lon,height,vn,ve,vd,roll,pitch,yaw\n").contains("without rows"));
        let back = "time,lat,lon,height,vn,ve,vd,roll,pitch,yaw\n1,0,0,0,0,0,0,0,0,0\n\
                    1,0,0,0,0,0,0,0,0,0\n";
        assert!(
            e(back).contains("line 3: time 1 does not increase"),
            "{}",
            e(back)
        );
        assert!(e("").contains("empty"));
    }

    #[test]
    fn a_script_started_later_starts_then() {
        let mut s = VehicleSource::parse("start 45 7 300 90 50\n")
            .unwrap()
            .starting_at(10.0);
        let a = s.at(10.0);
        let b = s.at(11.0);
        assert_eq!(a.time_s, 10.0);
        assert!((b.lon_rad - a.lon_rad).to_degrees() > 5e-4, "{a:?} {b:?}");
    }
}
