// The imu-emu web view: polls /api/state at about 12 Hz, plots the decoded
// output against device time, sends control-socket lines. No library, no
// network beyond this server.
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
    ["held-back-ms", "device time held back, ms"],
  ];
  row(t, "device time, s", deviceTime.toFixed(3));
  for (const [k, label] of keys) if (k in s) row(t, label, s[k], k === "tx-dropped" && s[k] !== "0");
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

// `empty`: what the plot says when none of its series has a point.
function plot(canvas, title, yLabel, series, t1, empty) {
  const ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height;
  const L = 64, R = 90, T = 24, B = 34;
  ctx.clearRect(0, 0, W, H);
  ctx.font = "13px 'DejaVu Sans', sans-serif";
  ctx.fillStyle = "#222";
  ctx.textAlign = "center";
  ctx.fillText(title, W / 2, 16);
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
  ctx.textAlign = "center";
  for (let t = Math.ceil(t0); t <= t1; t += 1) {
    ctx.strokeStyle = "#eee"; ctx.beginPath(); ctx.moveTo(X(t), T); ctx.lineTo(X(t), H - B); ctx.stroke();
    if (t >= 0) ctx.fillText(String(t), X(t), H - B + 14);
  }
  ctx.fillText("device time (s)", L + (W - L - R) / 2, H - 4);
  if (empty && series.every((s) => !s.pts.length)) {
    ctx.fillStyle = "#888";
    ctx.fillText(empty, L + (W - L - R) / 2, T + (H - T - B) / 2);
    ctx.fillStyle = "#222";
  }
  ctx.save(); ctx.translate(12, T + (H - T - B) / 2); ctx.rotate(-Math.PI / 2); ctx.fillText(yLabel, 0, 0); ctx.restore();
  series.forEach((s, i) => {
    ctx.strokeStyle = COLORS[i % COLORS.length]; ctx.lineWidth = 1.5;
    ctx.beginPath();
    let first = true;
    for (const [t, y] of s.pts) {
      if (t < t0 || !Number.isFinite(y)) continue;
      if (first) { ctx.moveTo(X(t), Y(y)); first = false; } else ctx.lineTo(X(t), Y(y));
    }
    ctx.stroke();
    ctx.fillStyle = COLORS[i % COLORS.length];
    ctx.fillRect(W - R + 10, T + 6 + i * 16, 14, 3);
    ctx.fillStyle = "#222"; ctx.textAlign = "left";
    ctx.fillText(s.name, W - R + 28, T + 11 + i * 16);
  });
}

function series(points, names, labels) {
  return names.map((n, i) => ({ name: labels[i], pts: points.filter((p) => n in p).map((p) => [p.t, p[n]]) }));
}

// The newest device time among a plot's own points: sets of one unit may
// count time differently (an IMX's IMU since boot, its INS in GPS time).
function lastOf(ser) {
  let t = -Infinity;
  for (const s of ser) if (s.pts.length) t = Math.max(t, s.pts[s.pts.length - 1][0]);
  return Number.isFinite(t) ? t : 0;
}

function draw() {
  const u = units();
  const xyz = (p) => [p + "_x", p + "_y", p + "_z"];
  const rates = series(state.points, xyz(u.rate[0]), ["X", "Y", "Z"]);
  const accs = series(state.points, xyz(u.acc[0]), ["X", "Y", "Z"]);
  // KERNEL: heading, pitch, roll (deg); IMX INS_1: theta = roll, pitch, yaw (rad).
  const att = state.protocol === "isb"
    ? series(insEuler(state.points), ["heading", "pitch", "roll"], ["yaw", "pitch", "roll"])
    : series(state.points, ["heading", "pitch", "roll"], ["heading", "pitch", "roll"]);
  const truth = series(state.truth, ["heading", "pitch", "roll"], ["heading", "pitch", "roll"]);
  const imu = state.protocol === "isb" ? "not streamed: a client asks for IMU or IMU_RAW" : undefined;
  plot($("plot-rate"), "Angular rate (sent)", "angular rate (" + u.rate[1] + ")", rates, lastOf(rates), imu);
  plot($("plot-acc"), "Acceleration (sent)", "specific force (" + u.acc[1] + ")", accs, lastOf(accs), imu);
  plot($("plot-att"), state.protocol === "isb" ? "Attitude (sent, INS_1/2/3)" : "Attitude (sent)", "angle (deg)", att, lastOf(att),
    state.protocol === "isb" ? "not streamed: a client asks for INS_1, INS_2 or INS_3" : undefined);
  plot($("plot-truth"), "Attitude (truth)", "angle (deg)", truth, lastOf(truth));
  if (state.protocol === "isb") drawNav();
  state.drawn += 1;
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

function drawNav() {
  const ins = of(INS);
  const gps = of(new Set(["GPS1_POS"]));
  const fixed = gps.filter((p) => ((p.status >>> 8) & 0x1f) !== 0);
  const mag = of(new Set(["MAGNETOMETER", "IMU_MAG", "PIMU_MAG"]));
  const baro = of(new Set(["BAROMETER"]));
  const ask = (sets) => "not streamed: a client asks for " + sets;
  const pos = series(neu(ins), ["n", "e", "u"], ["north", "east", "up"]);
  plot($("plot-ins-pos"), "INS position (from the left edge)", "offset (m)", pos, lastOf(pos), ask("INS_1, INS_2 or INS_3"));
  const vel = series(ins, ["uvw_x", "uvw_y", "uvw_z"], ["u (fwd)", "v (right)", "w (down)"]);
  plot($("plot-ins-vel"), "INS velocity (body axes)", "velocity (m/s)", vel, lastOf(vel), ask("INS_1, INS_2 or INS_3"));
  const gpos = series(neu(fixed), ["n", "e", "u"], ["north", "east", "up"]);
  plot($("plot-gps-pos"), "GPS1 position (from the left edge)", "offset (m)", gpos, lastOf(gpos),
    gps.length ? "no fix" : ask("GPS1_POS"));
  const sats = series(gps.map((p) => ({ t: p.t, sats: p.satsUsed, fix: (p.status >>> 8) & 0x1f })), ["sats", "fix"], ["satellites", "fix type"]);
  plot($("plot-gps-fix"), "GPS1 fix", "count / fix type", sats, lastOf(sats), ask("GPS1_POS"));
  const m = series(mag, ["mag_x", "mag_y", "mag_z"], ["X", "Y", "Z"]);
  plot($("plot-mag"), "Magnetometer", "field (normalized)", m, lastOf(m), ask("MAGNETOMETER"));
  const bp = series(baro, ["bar"], ["pressure"]);
  plot($("plot-baro-p"), "Barometer pressure", "pressure (kPa)", bp, lastOf(bp), ask("BAROMETER"));
  const ba = series(baro, ["mslBar"], ["altitude"]);
  plot($("plot-baro-alt"), "Barometer altitude (MSL)", "altitude (m)", ba, lastOf(ba), ask("BAROMETER"));
  const t = $("nav-status");
  t.replaceChildren();
  const li = ins[ins.length - 1], lg = gps[gps.length - 1];
  row(t, "INS status (insStatus)", li ? hex(li.insStatus) : "—");
  const fix = lg ? (lg.status >>> 8) & 0x1f : null;
  row(t, "GPS1 fix, satellites", lg ? (FIX[fix] || String(fix)) + ", " + lg.satsUsed : "—", lg && fix === 0);
  state.nav = { ins: ins.length, gps: gps.length, gpsFix: fix, insStatus: li ? li.insStatus : null, mag: mag.length, baro: baro.length,
    insT: li ? li.t : null };
}

// The newest points only (by count: sets of one unit may count time
// differently; each plot then takes its own last WINDOW_S seconds).
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
