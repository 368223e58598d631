// The imu-emu web view: polls /api/state at about 12 Hz, plots the decoded
// output against device time, sends control-socket lines. No library, no
// network beyond this server.
//
// One clock: every point (whatever its format carries), the truth and the
// status come on the device's time since power-on (the server puts them
// there: web.rs "One device clock"), and every time plot shows the same
// last WINDOW_S seconds of it; an IMX's axes carry the GPS time of week
// as a second label.
"use strict";

const POLL_MS = 80; // after each answer: about 12 polls a second
const WINDOW_S = 10;
const COLORS = ["#d62728", "#2ca02c", "#1f77b4"];

const state = {
  protocol: "kernel",
  dev: 0,
  since: 0,
  truthSince: 0,
  points: [],
  truth: [],
  polls: 0,
  drawn: 0,
  lastT: null,
  lastReply: "",
  status: {},
  nav: null, // IMX: counts of the navigation points held, last INS status and GPS fix
  deviceTime: 0, // device time now (s since power-on), the right edge of every time plot
  towAtZero: null, // IMX: GPS time of week at device time 0, s
  track: null, // the position panel: points of each track, the span shown (m)
};
window.imuEmu = state;

const $ = (id) => document.getElementById(id);

async function api(path, options) {
  const r = await fetch(path, Object.assign({ cache: "no-store" }, options || {}));
  const text = await r.text();
  return { ok: r.ok, status: r.status, text };
}

async function send(line) {
  const r = await api("/api/command?dev=" + state.dev, {
    method: "POST",
    headers: { "X-Imu-Emu": "1", "Content-Type": "text/plain" },
    body: line,
  });
  state.lastReply = line + " → " + r.text;
  $("reply").textContent = state.lastReply;
  $("reply").className = r.ok ? "" : "bad";
  return r;
}

function units() {
  return state.protocol === "isb"
    ? { rate: ["pqr", "rad/s"], acc: ["acc", "m/s²"] }
    : { rate: ["gyro", "deg/s"], acc: ["acc", "g"] };
}

function row(table, k, v, bad) {
  const tr = document.createElement("tr");
  const a = document.createElement("td");
  const b = document.createElement("td");
  a.textContent = k;
  b.textContent = v;
  if (bad) b.className = "bad";
  tr.append(a, b);
  table.append(tr);
}

function showStatus(s, on, deviceTime) {
  const t = $("status");
  t.replaceChildren();
  if (!on) {
    row(t, "mode", "off (powers on when a client connects)");
    return;
  }
  const keys = [
    ["mode", "mode"], ["format", "output format"], ["output-rate", "output rate, Hz"],
    ["line-rate", "line rate, bit/s"], ["frames-sent", "frames sent"], ["bytes-sent", "bytes sent"],
    ["tx-dropped", "frames dropped (TX full)"], ["commands", "commands received"],
    ["backlog-dropped", "bytes dropped (client too slow)"],
    ["held-back-ms", "device time held back, ms"],
  ];
  row(t, "device time, s", deviceTime.toFixed(3));
  if (state.towAtZero !== null) row(t, "GPS time of week, s", tow(deviceTime).toFixed(3));
  for (const [k, label] of keys) if (k in s) row(t, label, s[k], (k === "tx-dropped" || k === "backlog-dropped") && s[k] !== "0");
  const rj = $("rejected");
  rj.replaceChildren();
  row(rj, "total", s.rejected || "0", s.rejected && s.rejected !== "0");
  for (const k of Object.keys(s)) if (k.startsWith("rejected-")) row(rj, k.slice(9), s[k], true);
  const lk = $("link");
  lk.replaceChildren();
  row(lk, "faults", s.link || "clean", s.link && s.link !== "clean");
  for (const k of Object.keys(s)) if (k.startsWith("link-")) row(lk, k.slice(5), s[k], s[k] !== "0");
}

// One plot: series [{name, pts:[[t, y]]}] on a canvas, with title, axes,
// ticks, unit labels and a legend; x = device time.
function niceStep(span, n) {
  const raw = span / n;
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  for (const m of [1, 2, 5, 10]) if (m * p >= raw) return m * p;
  return 10 * p;
}

// A tick label: as many decimals as the step needs.
function tick(y, step) {
  if (Math.abs(y) < step / 1e6) return "0";
  const decimals = Math.max(0, -Math.floor(Math.log10(step)));
  return y.toFixed(decimals);
}

const WEEK_S = 604800;
const tow = (t) => (((t + state.towAtZero) % WEEK_S) + WEEK_S) % WEEK_S;

// The time axis shared by every time plot: device time ticks, and for an
// IMX a second row with the GPS time of week of the same instants.
function timeAxis(ctx, X, t0, t1, T, H, B, L, W, R) {
  ctx.textAlign = "center";
  for (let t = Math.ceil(t0); t <= t1; t += 1) {
    ctx.strokeStyle = "#eee"; ctx.beginPath(); ctx.moveTo(X(t), T); ctx.lineTo(X(t), H - B); ctx.stroke();
    if (t >= 0) ctx.fillText(String(t), X(t), H - B + 13);
    if (state.towAtZero !== null && t >= 0 && (t - Math.ceil(t0)) % 2 === 0) {
      ctx.fillStyle = "#666"; ctx.fillText(tow(t).toFixed(0), X(t), H - B + 26); ctx.fillStyle = "#222";
    }
  }
  const label = state.towAtZero !== null
    ? "device time (s since power-on); grey: GPS time of week (s)"
    : "device time (s since power-on)";
  ctx.fillText(label, L + (W - L - R) / 2, H - 4);
}

// Lines of one series; a step beyond half of `wrap` (heading 359° → 1°)
// starts a new line instead of drawing a bar across the plot, and so does
// a gap in time (a stream stopped, a realignment: more than three of its
// steps and 0.25 s), instead of a straight line across it.
function lines(ctx, pts, t0, X, Y, wrap) {
  ctx.beginPath();
  let first = true, last = null, lastT = null, step = Infinity;
  for (const [t, y] of pts) {
    if (t < t0 || !Number.isFinite(y)) continue;
    const gap = lastT !== null && t - lastT > Math.max(0.25, 3 * step);
    if (first || gap || (wrap && Math.abs(y - last) > wrap / 2)) { ctx.moveTo(X(t), Y(y)); first = false; } else ctx.lineTo(X(t), Y(y));
    if (lastT !== null && !gap) step = t - lastT;
    last = y; lastT = t;
  }
  ctx.stroke();
}

function legend(ctx, series, W, R, T) {
  series.forEach((s, i) => {
    ctx.fillStyle = COLORS[i % COLORS.length];
    ctx.fillRect(W - R + 10, T + 6 + i * 16, 14, 3);
    ctx.fillStyle = "#222"; ctx.textAlign = "left";
    ctx.fillText(s.name, W - R + 28, T + 11 + i * 16);
  });
}

// A cleared canvas with its title: [context, width, height].
function panel(canvas, title) {
  const ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height;
  ctx.clearRect(0, 0, W, H);
  ctx.font = "13px 'DejaVu Sans', sans-serif";
  ctx.fillStyle = "#222";
  ctx.textAlign = "center";
  ctx.fillText(title, W / 2, 16);
  return [ctx, W, H];
}

// `empty`: what the plot says when none of its series has a point;
// `wrap`: the period of an angle drawn without wrap bars.
function plot(canvas, title, yLabel, series, t1, empty, wrap) {
  const [ctx, W, H] = panel(canvas, title);
  const L = 64, R = 90, T = 24, B = state.towAtZero !== null ? 44 : 34;
  const t0 = t1 - WINDOW_S;
  let lo = Infinity, hi = -Infinity;
  for (const s of series) for (const [t, y] of s.pts) if (t >= t0 && Number.isFinite(y)) { lo = Math.min(lo, y); hi = Math.max(hi, y); }
  if (!Number.isFinite(lo)) { lo = -1; hi = 1; }
  if (hi - lo < 1e-6) { lo -= 0.5; hi += 0.5; }
  const pad = (hi - lo) * 0.08; lo -= pad; hi += pad;
  const X = (t) => L + ((t - t0) / WINDOW_S) * (W - L - R);
  const Y = (y) => T + (1 - (y - lo) / (hi - lo)) * (H - T - B);
  ctx.strokeStyle = "#ccc"; ctx.lineWidth = 1;
  ctx.strokeRect(L, T, W - L - R, H - T - B);
  ctx.font = "11px 'DejaVu Sans', sans-serif";
  const ys = niceStep(hi - lo, 4);
  ctx.textAlign = "right";
  for (let y = Math.ceil(lo / ys) * ys; y <= hi; y += ys) {
    ctx.strokeStyle = "#eee"; ctx.beginPath(); ctx.moveTo(L, Y(y)); ctx.lineTo(W - R, Y(y)); ctx.stroke();
    ctx.fillText(tick(y, ys), L - 4, Y(y) + 4);
  }
  timeAxis(ctx, X, t0, t1, T, H, B, L, W, R);
  if (empty && series.every((s) => !s.pts.length)) {
    ctx.fillStyle = "#888";
    ctx.fillText(empty, L + (W - L - R) / 2, T + (H - T - B) / 2);
    ctx.fillStyle = "#222";
  }
  ctx.save(); ctx.translate(12, T + (H - T - B) / 2); ctx.rotate(-Math.PI / 2); ctx.fillText(yLabel, 0, 0); ctx.restore();
  ctx.save(); ctx.beginPath(); ctx.rect(L, T, W - L - R, H - T - B); ctx.clip();
  series.forEach((s, i) => {
    ctx.strokeStyle = COLORS[i % COLORS.length]; ctx.lineWidth = 1.5;
    lines(ctx, s.pts, t0, X, Y, wrap);
  });
  ctx.restore();
  legend(ctx, series, W, R, T);
}

// One band per series, each with its own y scale: three axes of one
// sensor stay readable whatever their offsets (X near 0, Z near 1 g) and
// however small the noise.
function plotStack(canvas, title, unit, series, t1, empty) {
  const [ctx, W, H] = panel(canvas, title);
  const L = 74, R = 90, T = 24, B = state.towAtZero !== null ? 44 : 34, GAP = 8;
  const t0 = t1 - WINDOW_S;
  const X = (t) => L + ((t - t0) / WINDOW_S) * (W - L - R);
  const band = (H - T - B - GAP * (series.length - 1)) / series.length;
  ctx.font = "11px 'DejaVu Sans', sans-serif";
  series.forEach((s, i) => {
    const top = T + i * (band + GAP);
    let lo = Infinity, hi = -Infinity;
    for (const [t, y] of s.pts) if (t >= t0 && Number.isFinite(y)) { lo = Math.min(lo, y); hi = Math.max(hi, y); }
    if (!Number.isFinite(lo)) { lo = -1; hi = 1; }
    if (hi - lo < 1e-6) { lo -= 1e-3; hi += 1e-3; }
    const pad = (hi - lo) * 0.1; lo -= pad; hi += pad;
    const Y = (y) => top + (1 - (y - lo) / (hi - lo)) * band;
    ctx.strokeStyle = "#ccc"; ctx.lineWidth = 1;
    ctx.strokeRect(L, top, W - L - R, band);
    const ys = niceStep(hi - lo, 3);
    ctx.textAlign = "right"; ctx.fillStyle = "#222";
    for (let y = Math.ceil(lo / ys) * ys; y <= hi; y += ys) {
      ctx.strokeStyle = "#eee"; ctx.beginPath(); ctx.moveTo(L, Y(y)); ctx.lineTo(W - R, Y(y)); ctx.stroke();
      ctx.fillText(tick(y, ys), L - 4, Y(y) + 4);
    }
    for (let t = Math.ceil(t0); t <= t1; t += 1) {
      ctx.strokeStyle = "#eee"; ctx.beginPath(); ctx.moveTo(X(t), top); ctx.lineTo(X(t), top + band); ctx.stroke();
    }
    ctx.save(); ctx.beginPath(); ctx.rect(L, top, W - L - R, band); ctx.clip();
    ctx.strokeStyle = COLORS[i % COLORS.length]; ctx.lineWidth = 1.5;
    lines(ctx, s.pts, t0, X, Y);
    ctx.restore();
    ctx.fillStyle = COLORS[i % COLORS.length];
    ctx.fillRect(W - R + 10, top + band / 2 - 2, 14, 3);
    ctx.fillStyle = "#222"; ctx.textAlign = "left";
    ctx.fillText(s.name + " (" + unit + ")", W - R + 28, top + band / 2 + 3);
  });
  timeAxis(ctx, X, t0, t1, T, H, B, L, W, R);
  if (empty && series.every((s) => !s.pts.length)) {
    ctx.fillStyle = "#888"; ctx.textAlign = "center";
    ctx.fillText(empty, L + (W - L - R) / 2, T + (H - T - B) / 2);
    ctx.fillStyle = "#222";
  }
}

// East-north tracks (m) from a common origin on equal axes: each track
// [{name, pts:[[east, north]]}], the newest point marked. No map: the
// page's own data only.
function plotTrack(canvas, title, tracks, empty) {
  const [ctx, W, H] = panel(canvas, title);
  const L = 64, R = 120, T = 24, B = 34;
  let e0 = Infinity, e1 = -Infinity, n0 = Infinity, n1 = -Infinity;
  for (const s of tracks) for (const [e, n] of s.pts) {
    if (!Number.isFinite(e) || !Number.isFinite(n)) continue;
    e0 = Math.min(e0, e); e1 = Math.max(e1, e); n0 = Math.min(n0, n); n1 = Math.max(n1, n);
  }
  if (!Number.isFinite(e0)) { e0 = n0 = -1; e1 = n1 = 1; }
  // Equal scales, at least 10 m across, centred on the tracks.
  const pw = W - L - R, ph = H - T - B;
  const span = Math.max(10, (e1 - e0) * 1.1, (n1 - n0) * 1.1 * pw / ph);
  const ec = (e0 + e1) / 2, nc = (n0 + n1) / 2;
  const k = pw / span;
  const X = (e) => L + pw / 2 + (e - ec) * k;
  const Y = (n) => T + ph / 2 - (n - nc) * k;
  ctx.strokeStyle = "#ccc"; ctx.lineWidth = 1;
  ctx.strokeRect(L, T, pw, ph);
  ctx.font = "11px 'DejaVu Sans', sans-serif";
  const st = niceStep(span, 6);
  ctx.textAlign = "center";
  for (let e = Math.ceil((ec - pw / 2 / k) / st) * st; X(e) <= L + pw; e += st) {
    ctx.strokeStyle = "#eee"; ctx.beginPath(); ctx.moveTo(X(e), T); ctx.lineTo(X(e), T + ph); ctx.stroke();
    ctx.fillText(tick(e, st), X(e), T + ph + 13);
  }
  ctx.textAlign = "right";
  for (let n = Math.ceil((nc - ph / 2 / k) / st) * st; Y(n) >= T; n += st) {
    ctx.strokeStyle = "#eee"; ctx.beginPath(); ctx.moveTo(L, Y(n)); ctx.lineTo(L + pw, Y(n)); ctx.stroke();
    ctx.fillText(tick(n, st), L - 4, Y(n) + 4);
  }
  ctx.textAlign = "center";
  ctx.fillText("east (m)", L + pw / 2, H - 4);
  ctx.save(); ctx.translate(12, T + ph / 2); ctx.rotate(-Math.PI / 2); ctx.fillText("north (m)", 0, 0); ctx.restore();
  if (empty && tracks.every((s) => !s.pts.length)) {
    ctx.fillStyle = "#888"; ctx.fillText(empty, L + pw / 2, T + ph / 2); ctx.fillStyle = "#222";
  }
  ctx.save(); ctx.beginPath(); ctx.rect(L, T, pw, ph); ctx.clip();
  // The GPS fixes as small dots, the truth a wide grey line over them,
  // the INS a dashed one on top: where they agree, all three stay visible.
  [2, 0, 1].filter((i) => i < tracks.length).forEach((i) => {
    const s = tracks[i];
    ctx.strokeStyle = ctx.fillStyle = TRACK_COLORS[i % TRACK_COLORS.length];
    ctx.lineWidth = i === 0 ? 4 : 1.5;
    ctx.setLineDash(i === 1 ? [6, 4] : []);
    if (i === 2) {
      for (const [e, n] of s.pts) { ctx.beginPath(); ctx.arc(X(e), Y(n), 1.5, 0, 2 * Math.PI); ctx.fill(); }
    } else {
      ctx.beginPath();
      s.pts.forEach(([e, n], j) => (j ? ctx.lineTo(X(e), Y(n)) : ctx.moveTo(X(e), Y(n))));
      ctx.stroke();
    }
    ctx.setLineDash([]);
    const p = s.pts[s.pts.length - 1];
    if (p) { ctx.beginPath(); ctx.arc(X(p[0]), Y(p[1]), 3.5, 0, 2 * Math.PI); ctx.fill(); }
  });
  ctx.restore();
  tracks.forEach((s, i) => {
    ctx.fillStyle = TRACK_COLORS[i % TRACK_COLORS.length];
    ctx.fillRect(W - R + 10, T + 6 + i * 16, 14, 3);
    ctx.fillStyle = "#222"; ctx.textAlign = "left";
    ctx.fillText(s.name, W - R + 28, T + 11 + i * 16);
  });
  state.track = { span, counts: tracks.map((s) => s.pts.length) };
}
const TRACK_COLORS = ["#aaa", "#1f77b4", "#ff7f0e"];

function series(points, names, labels) {
  return names.map((n, i) => ({ name: labels[i], pts: points.filter((p) => n in p).map((p) => [p.t, p[n]]) }));
}

function draw() {
  const u = units();
  const xyz = (p) => [p + "_x", p + "_y", p + "_z"];
  // One clock: every time plot ends at the device time now (the first
  // WINDOW_S seconds: from power-on).
  const t1 = Math.max(state.deviceTime, state.lastT || 0, WINDOW_S);
  const rates = series(state.points, xyz(u.rate[0]), ["X", "Y", "Z"]);
  const accs = series(state.points, xyz(u.acc[0]), ["X", "Y", "Z"]);
  // KERNEL: heading, pitch, roll (deg); IMX INS_1: theta = roll, pitch, yaw (rad).
  const att = state.protocol === "isb"
    ? series(insEuler(state.points), ["heading", "pitch", "roll"], ["yaw", "pitch", "roll"])
    : series(state.points, ["heading", "pitch", "roll"], ["heading", "pitch", "roll"]);
  const truth = series(state.truth, ["heading", "pitch", "roll"], ["heading", "pitch", "roll"]);
  const imu = state.protocol === "isb" ? "not streamed: a client asks for IMU or IMU_RAW" : undefined;
  plot($("plot-rate"), "Angular rate (sent)", "angular rate (" + u.rate[1] + ")", rates, t1, imu);
  plotStack($("plot-acc"), "Acceleration (sent), each axis on its own scale", u.acc[1], accs, t1, imu);
  // Heading (yaw) wraps at 360°: drawn without the bar across the plot.
  plot($("plot-att"), state.protocol === "isb" ? "Attitude (sent, INS_1/2/3)" : "Attitude (sent)", "angle (deg)", att, t1,
    state.protocol === "isb" ? "not streamed: a client asks for INS_1, INS_2 or INS_3"
      : "not in this format: Orientation, Quaternion, Calibrated HR or a UDD with Euler angles", 360);
  plot($("plot-truth"), "Attitude (truth)", "angle (deg)", truth, t1, undefined, 360);
  drawTrack(t1);
  if (state.protocol === "isb") drawNav(t1);
  state.drawn += 1;
}

// The position panel: the truth's east-north track over the last TRACK_S
// seconds of device time — since the truth last jumped (a motion script's
// `start` elsewhere: faster than 400 m/s), if it did — and an IMX's INS (once it has a
// position) and GPS1 (with a fix) over the same time, all from the newest
// truth point as origin (a local flat Earth: enough for a bench plot).
const TRACK_S = 120;
function drawTrack(t1) {
  let from = t1 - TRACK_S;
  const truth = state.truth.filter((p) => p.t >= from && "lat" in p);
  for (let i = 1; i < truth.length; i++) {
    const dn = (truth[i].lat - truth[i - 1].lat) * 111132.954, de = (truth[i].lon - truth[i - 1].lon) * 111319.49;
    // Farther than 400 m/s (and 50 m) would carry it: a jump.
    if (Math.hypot(dn, de) > 50 + 400 * (truth[i].t - truth[i - 1].t)) from = truth[i].t;
  }
  const o = truth[truth.length - 1];
  const tracks = [];
  if (o) {
    const mLat = 111132.954, mLon = 111319.49 * Math.cos(o.lat / DEG);
    const en = (lat, lon) => [(lon - o.lon) * mLon, (lat - o.lat) * mLat];
    tracks.push({ name: "truth", pts: truth.filter((p) => p.t >= from).map((p) => en(p.lat, p.lon)) });
    if (state.protocol === "isb") {
      const placed = (p) => p.t >= from && (p.lla_x !== 0 || p.lla_y !== 0);
      tracks.push({ name: "INS", pts: of(INS).filter(placed).map((p) => en(p.lla_x, p.lla_y)) });
      const gps = of(new Set(["GPS1_POS"])).filter((p) => placed(p) && ((p.status >>> 8) & 0x1f) !== 0);
      tracks.push({ name: "GPS1 (fix)", pts: gps.map((p) => en(p.lla_x, p.lla_y)) });
    }
  }
  plotTrack($("plot-track"), "Position: east-north track (m from the unit now), last " + TRACK_S + " s of device time",
    tracks, "no position yet");
}

// IMX navigation sets (ISB, docs/isb.md; field names of data_sets.h).
const DEG = 180 / Math.PI;
const INS = new Set(["INS_1", "INS_2", "INS_3"]);
const of = (sets) => state.points.filter((p) => sets.has(p.set));

// Yaw, pitch, roll (deg) of INS_1's theta (roll, pitch, yaw, rad) or of
// INS_2/3's qn2b (w, x, y, z: NED to body; ZYX Euler angles).
function insEuler(points) {
  return points.filter((p) => INS.has(p.set)).map((p) => {
    if ("theta_x" in p) return { t: p.t, heading: p.theta_z * DEG, pitch: p.theta_y * DEG, roll: p.theta_x * DEG };
    const [w, x, y, z] = [p.qn2b_w, p.qn2b_x, p.qn2b_y, p.qn2b_z];
    return {
      t: p.t,
      heading: Math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)) * DEG,
      pitch: Math.asin(Math.max(-1, Math.min(1, 2 * (w * y - z * x)))) * DEG,
      roll: Math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)) * DEG,
    };
  });
}

// North, east, up (m) of lla_* from the first point of the plot's window
// (the last WINDOW_S seconds; a local flat Earth, enough for a bench plot).
function neu(all) {
  if (!all.length) return [];
  const t0 = all[all.length - 1].t - WINDOW_S;
  const points = all.filter((p) => p.t >= t0);
  const [lat0, lon0, h0] = [points[0].lla_x, points[0].lla_y, points[0].lla_z];
  const mLat = 111132.954, mLon = 111319.49 * Math.cos(lat0 / DEG);
  return points.map((p) => ({ t: p.t, n: (p.lla_x - lat0) * mLat, e: (p.lla_y - lon0) * mLon, u: p.lla_z - h0 }));
}

const hex = (x) => "0x" + (x >>> 0).toString(16).padStart(8, "0");
const FIX = ["none", "dead reckoning", "2D", "3D", "GPS + DR", "time only"];

function drawNav(t1) {
  const ins = of(INS);
  const gps = of(new Set(["GPS1_POS"]));
  const fixed = gps.filter((p) => ((p.status >>> 8) & 0x1f) !== 0);
  const mag = of(new Set(["MAGNETOMETER", "IMU_MAG", "PIMU_MAG"]));
  const baro = of(new Set(["BAROMETER"]));
  const ask = (sets) => "not streamed: a client asks for " + sets;
  const pos = series(neu(ins), ["n", "e", "u"], ["north", "east", "up"]);
  plot($("plot-ins-pos"), "INS position (from the left edge)", "offset (m)", pos, t1, ask("INS_1, INS_2 or INS_3"));
  const vel = series(ins, ["uvw_x", "uvw_y", "uvw_z"], ["u (fwd)", "v (right)", "w (down)"]);
  plot($("plot-ins-vel"), "INS velocity (body axes)", "velocity (m/s)", vel, t1, ask("INS_1, INS_2 or INS_3"));
  const gpos = series(neu(fixed), ["n", "e", "u"], ["north", "east", "up"]);
  plot($("plot-gps-pos"), "GPS1 position (from the left edge)", "offset (m)", gpos, t1,
    gps.length ? "no fix" : ask("GPS1_POS"));
  const sats = series(gps.map((p) => ({ t: p.t, sats: p.satsUsed, fix: (p.status >>> 8) & 0x1f })), ["sats", "fix"], ["satellites", "fix type"]);
  plot($("plot-gps-fix"), "GPS1 fix", "count / fix type", sats, t1, ask("GPS1_POS"));
  const m = series(mag, ["mag_x", "mag_y", "mag_z"], ["X", "Y", "Z"]);
  plot($("plot-mag"), "Magnetometer", "field (normalized)", m, t1, ask("MAGNETOMETER"));
  const bp = series(baro, ["bar"], ["pressure"]);
  plot($("plot-baro-p"), "Barometer pressure", "pressure (kPa)", bp, t1, ask("BAROMETER"));
  const ba = series(baro, ["mslBar"], ["altitude"]);
  plot($("plot-baro-alt"), "Barometer altitude (MSL)", "altitude (m)", ba, t1, ask("BAROMETER"));
  const t = $("nav-status");
  t.replaceChildren();
  const li = ins[ins.length - 1], lg = gps[gps.length - 1];
  row(t, "INS status (insStatus)", li ? hex(li.insStatus) : "—");
  const fix = lg ? (lg.status >>> 8) & 0x1f : null;
  row(t, "GPS1 fix, satellites", lg ? (FIX[fix] || String(fix)) + ", " + lg.satsUsed : "—", lg && fix === 0);
  state.nav = { ins: ins.length, gps: gps.length, gpsFix: fix, insStatus: li ? li.insStatus : null, mag: mag.length, baro: baro.length,
    insT: li ? li.t : null };
}

// The newest points only (by count).
const KEEP = 24000;
function keep(list) {
  return list.length > KEEP ? list.slice(list.length - KEEP) : list;
}

async function poll() {
  try {
    const r = await api("/api/state?dev=" + state.dev + "&since=" + state.since + "&truth_since=" + state.truthSince);
    if (r.ok) {
      const s = JSON.parse(r.text);
      state.polls += 1;
      state.status = s.status;
      for (const p of s.points) { state.points.push(p); state.since = p.seq; }
      for (const p of s.truth) { state.truth.push(p); state.truthSince = p.seq; }
      state.points = keep(state.points);
      state.truth = keep(state.truth);
      if (state.points.length) state.lastT = state.points[state.points.length - 1].t;
      state.deviceTime = s.device_time_s;
      state.towAtZero = s.gps_tow_at_zero_s;
      showStatus(s.status, s.on, s.device_time_s);
      $("conn").textContent = s.frames_decoded + " frames decoded" + (s.view_lost_bytes ? ", " + s.view_lost_bytes + " bytes not shown" : "");
      draw();
    } else {
      $("conn").textContent = "server: " + r.status;
    }
  } catch (e) {
    $("conn").textContent = "no connection to imu-emu";
  }
  setTimeout(poll, POLL_MS);
}

async function start() {
  const r = await api("/api/devices");
  const d = JSON.parse(r.text);
  state.protocol = d.protocol;
  $("nav").hidden = $("nav-controls").hidden = d.protocol !== "isb";
  $("help").textContent = "control commands: " + d.help;
  const sel = $("device");
  for (const x of d.devices) {
    const o = document.createElement("option");
    o.value = x.dev;
    o.textContent = "dev " + x.dev + " (" + x.place + ")";
    sel.append(o);
  }
  const ident = () => {
    const x = d.devices[state.dev];
    $("identity").textContent = x.name + " · " + (d.protocol === "isb" ? "ISB" : "KERNEL") + " · " + x.place;
  };
  ident();
  sel.onchange = () => {
    state.dev = Number(sel.value);
    state.since = 0; state.truthSince = 0; state.points = []; state.truth = [];
    ident();
  };
  for (const b of document.querySelectorAll("button[data-cmd]")) b.onclick = () => send(b.dataset.cmd);
  $("file-form").onsubmit = (e) => { e.preventDefault(); const v = $("motion-file").value.trim(); if (v) send("motion file " + v); };
  $("cmd-form").onsubmit = (e) => { e.preventDefault(); const v = $("cmd").value.trim(); if (v) send(v); };
  poll();
}

start();
