/* rotordiag web page: a client of the service's HTTP API, plots drawn on <canvas>.
 *
 * Verdict: POST /diagnose. Orbit/spectrum arrays: POST /ui/plot-data (same body). Start-up / coast-down
 * plots: POST /ui/transient-plots (same body; PNGs). Report: GET /assets/{id}/report.
 * Trend: GET /assets/{id}/history. Models: GET /models. Health: GET /health.
 * No build step, no third-party code, nothing fetched from anywhere but this server.
 */
"use strict";
(function () {
  const $ = (id) => document.getElementById(id);
  const state = { verdict: null, plots: null, history: null, models: null, examples: [], pending: 0 };

  // ---- formatting ---------------------------------------------------------------------------
  function num(v, digits = 3) {
    if (v === null || v === undefined || !Number.isFinite(Number(v))) return "—";
    const x = Number(v);
    if (x === 0) return "0";
    const a = Math.abs(x);
    if (a >= 1e5 || a < 1e-3) return x.toExponential(digits - 1);
    return String(Number(x.toPrecision(digits)));
  }
  function fixed(v, d) {
    return v === null || v === undefined || !Number.isFinite(Number(v)) ? "—" : Number(v).toFixed(d);
  }
  function el(tag, attrs, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "class") e.className = v; else if (k === "text") e.textContent = v; else e.setAttribute(k, v);
    }
    for (const c of children) e.append(c);
    return e;
  }
  function show(node, on) { node.hidden = !on; }
  function setError(node, text) { node.textContent = text || ""; show(node, Boolean(text)); }

  // the form's words for the service's parameter names (messages are written for API clients too)
  const FIELD_WORDS = {
    sample_rate_hz: "the sample rate (Hz)", speed_rpm: "the running speed (r/min)", clearance_um: "the bearing clearance (µm)",
    speed_range_rpm: "the nominal speed range (r/min)",
    keyphasor_times_s: "keyphasor pulse times", units: "the units of the waveforms", bearings: "the bearing of each channel",
    angles_deg: "the probe angle of each channel", asset_id: "the asset id", sample_index: "the sample index",
    dc_removed: "“DC part is no shaft position”", acquisitions: "the bearings sampled together",
    keyphasor_channel: "the keyphasor channel(s)",
    sensitivity_v_per_mm: "the probe sensitivity (V/mm)", gap_voltage_v: "the gap voltage (V)",
    sensitivity: "the probe sensitivity", channel_map: "the probe columns by name",
  };
  // whole messages an engineer meets first, said as what to do in this form
  const PLAIN = [
    [/^sample rate unknown\b.*/i, "Fill in the sample rate (Hz): this file does not say it (no time column or sample-rate attribute)."],
    [/^cannot estimate the running speed\b[^;]*;?.*/i,
      (m) => `${m.split(";")[0].replace(/^cannot/, "Cannot")}. Fill in the running speed (r/min).`],
  ];
  function plainWords(text) {
    let t = String(text);
    for (const [re, to] of PLAIN) if (re.test(t)) return typeof to === "function" ? to(t) : to;
    t = t.replace(/\s*\((?:CLI|API)[^)]*\)/g, "");                 // "(CLI --sample-rate-hz, API sample_rate_hz=)"
    t = t.replace(/\bgive ([a-z_]+) or ([a-z_]+)\b/g, (m, a, b) => (a in FIELD_WORDS && b in FIELD_WORDS)
      ? `fill in ${FIELD_WORDS[a]} or ${FIELD_WORDS[b]}` : m);
    return t.replace(/\b([a-z]+(?:_[a-z]+)+)=?/g, (m, name) => FIELD_WORDS[name] || m);
  }

  function errorText(status, body, what422) {
    let d = body && body.detail !== undefined ? body.detail : body;
    if (Array.isArray(d)) {
      d = d.map((e) => {
        const loc = (e.loc || []).filter((p) => p !== "body" && p !== "query");
        const where = loc.map((p) => FIELD_WORDS[p] || p).join(" → ");
        return (where ? where + ": " : "") + (e.msg || JSON.stringify(e));
      }).join("\n");
    } else if (typeof d !== "string") {
      d = JSON.stringify(d);
    } else {
      d = plainWords(d);
    }
    const what = {
      400: "The request is malformed", 404: "Not found", 413: "The upload is too large for this server",
      415: "Unsupported file or content type", 422: what422 || "The recording cannot be used", 503: "The service cannot diagnose right now",
    }[status] || `The service answered HTTP ${status}`;
    return `${what}: ${d}`;
  }

  async function api(path, options, what422) {
    let resp;
    try {
      resp = await fetch(path, options);
    } catch (exc) {
      throw new Error(`Cannot reach the service (${exc.message}); is it running?`);
    }
    const text = await resp.text();
    let body = null;
    try { body = text ? JSON.parse(text) : null; } catch (_) { body = text.slice(0, 500); }
    if (!resp.ok) { const e = new Error(errorText(resp.status, body, what422)); e.status = resp.status; throw e; }
    return body;
  }

  // ---- plotting on <canvas> ---------------------------------------------------------------------
  const COLORS = { raw: "#8d96a0", "1x": "#1f5fa8", "2x": "#d9480f", "1x2x": "#2b8a3e",
    probe0: "#1f5fa8", probe1: "#c2255c", full: "#5f3dc4",
    bearing: ["#1f5fa8", "#d9480f", "#2b8a3e", "#862e9c"] };
  const SEVERITY_COLORS = { aligned: "#2e7d32", slight: "#b5a300", moderate: "#ef6c00", severe: "#c62828" };
  const FALLBACK_BAND_COLORS = ["#2e7d32", "#b5a300", "#ef6c00", "#c62828", "#6a1b9a"];

  function niceStep(span, target) {
    const raw = span / Math.max(1, target);
    const p = Math.pow(10, Math.floor(Math.log10(raw)));
    const m = raw / p;
    return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10) * p;
  }
  function linTicks(lo, hi, target) {
    const step = niceStep(hi - lo, target);
    const out = [];
    for (let v = Math.ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    const dec = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
    return out.map((v) => ({ v, s: Math.abs(v) >= 1e5 ? v.toExponential(1) : v.toFixed(Math.min(dec, 6)) }));
  }
  function logTicks(lo, hi) {
    const out = [];
    for (let k = Math.floor(Math.log10(lo)); k <= Math.ceil(Math.log10(hi)); k++) {
      const v = Math.pow(10, k);
      if (v >= lo * 0.999 && v <= hi * 1.001) out.push({ v, s: k >= -3 && k <= 4 ? String(Number(v.toPrecision(1))) : `1e${k}` });
    }
    return out;
  }
  const TIME_STEPS = [1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 10800, 21600, 43200,
    86400, 172800, 604800, 1209600, 2592000, 7776000, 31536000].map((s) => s * 1000);
  function pad(n) { return String(n).padStart(2, "0"); }
  function timeTicks(lo, hi, target) {
    const raw = (hi - lo) / Math.max(1, target);
    const step = TIME_STEPS.find((s) => s >= raw) || TIME_STEPS[TIME_STEPS.length - 1];
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi; v += step) {
      const d = new Date(v);
      let s;
      if (step < 60000) s = `${pad(d.getUTCHours())}:${pad(d.getUTCMinutes())}:${pad(d.getUTCSeconds())}`;
      else if (step < 86400000) s = `${pad(d.getUTCHours())}:${pad(d.getUTCMinutes())}`;
      else s = `${d.getUTCFullYear()}-${pad(d.getUTCMonth() + 1)}-${pad(d.getUTCDate())}`;
      out.push({ v, s });
    }
    return out;
  }
  function alpha(hex, a) {
    const n = parseInt(hex.slice(1), 16);
    return `rgba(${(n >> 16) & 255},${(n >> 8) & 255},${n & 255},${a})`;
  }

  /* drawPlot(canvas, spec): spec = {x: {label, min, max, time?}, y: {label, min, max, log?}, equal?,
   * hbands: [{from, to, color, label}], vbands: [...], vlines: [{x, label, color}],
   * series: [{x, y, color, width, mode: "line"|"stems"|"markers", label, lo, hi, hollow, arrow, size}]} */
  function drawPlot(canvas, spec) {
    canvas._spec = spec;
    const dpr = window.devicePixelRatio || 1;
    const W = Math.max(120, canvas.clientWidth), H = Math.max(100, canvas.clientHeight);
    canvas.width = Math.round(W * dpr);
    canvas.height = Math.round(H * dpr);
    const ctx = canvas.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.fillStyle = "#fff";
    ctx.fillRect(0, 0, W, H);
    ctx.font = "12px system-ui, sans-serif";

    // legend rows in the top margin
    const legend = (spec.series || []).filter((s) => s.label).map((s) => ({ label: s.label, color: s.color, mode: s.mode, hollow: s.hollow }))
      .concat((spec.legendExtra || []));
    const L = 64, R = 14, B = 44;
    let rows = 0, lx = L;
    const legendPos = [];
    for (const it of legend) {
      const w = 22 + ctx.measureText(it.label).width + 14;
      if (lx + w > W - R && lx > L) { rows++; lx = L; }
      legendPos.push({ it, x: lx, row: rows });
      lx += w;
    }
    const T = 10 + (legend.length ? (rows + 1) * 16 : 0);
    const pw = W - L - R, ph = H - T - B;
    if (pw < 20 || ph < 20) return;

    let [x0, x1] = [spec.x.min, spec.x.max];
    let [y0, y1] = [spec.y.min, spec.y.max];
    if (!(x1 > x0)) { x0 -= 1; x1 += 1; }
    if (!(y1 > y0)) { y0 = spec.y.log ? y0 / 10 : y0 - 1; y1 = spec.y.log ? y1 * 10 : y1 + 1; }
    if (spec.equal) {           // same µm per pixel on both axes, centred
      const s = Math.min(pw / (x1 - x0), ph / (y1 - y0));
      const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
      x0 = cx - pw / s / 2; x1 = cx + pw / s / 2; y0 = cy - ph / s / 2; y1 = cy + ph / s / 2;
    }
    const ylog = Boolean(spec.y.log);
    const ly0 = ylog ? Math.log10(y0) : y0, ly1 = ylog ? Math.log10(y1) : y1;
    const X = (v) => L + ((v - x0) / (x1 - x0)) * pw;
    const Y = (v) => {
      const u = ylog ? Math.log10(Math.max(v, y0 * 1e-3)) : v;
      return T + ph - ((u - ly0) / (ly1 - ly0)) * ph;
    };

    // bands
    ctx.save();
    ctx.beginPath(); ctx.rect(L, T, pw, ph); ctx.clip();
    for (const b of spec.hbands || []) {
      const ya = Y(Math.min(Math.max(b.from, y0), y1)), yb = Y(Math.min(Math.max(b.to, y0), y1));
      ctx.fillStyle = alpha(b.color, 0.13); ctx.fillRect(L, Math.min(ya, yb), pw, Math.abs(yb - ya));
      if (b.label && Math.abs(yb - ya) > 13) {
        ctx.fillStyle = alpha(b.color, 0.9); ctx.textAlign = "right"; ctx.textBaseline = "top";
        ctx.fillText(b.label, L + pw - 4, Math.min(ya, yb) + 2);
      }
    }
    for (const b of spec.vbands || []) {
      const xa = X(b.from), xb = X(b.to);
      ctx.fillStyle = alpha(b.color, 0.16); ctx.fillRect(Math.min(xa, xb), T, Math.max(1, Math.abs(xb - xa)), ph);
    }
    ctx.restore();

    // grid and ticks
    const xt = spec.x.time ? timeTicks(x0, x1, Math.max(3, pw / 90)) : linTicks(x0, x1, Math.max(4, pw / 70));
    const yt = ylog ? logTicks(y0, y1) : linTicks(y0, y1, Math.max(4, ph / 38));
    ctx.strokeStyle = "#e6e8eb"; ctx.lineWidth = 1;
    ctx.beginPath();
    for (const t of xt) { const x = Math.round(X(t.v)) + 0.5; ctx.moveTo(x, T); ctx.lineTo(x, T + ph); }
    for (const t of yt) { const y = Math.round(Y(t.v)) + 0.5; ctx.moveTo(L, y); ctx.lineTo(L + pw, y); }
    ctx.stroke();
    ctx.fillStyle = "#333"; ctx.textAlign = "center"; ctx.textBaseline = "top";
    for (const t of xt) {        // a label that would spill past the frame (into the y labels) is left out
      const half = ctx.measureText(t.s).width / 2;
      if (X(t.v) - half >= L - 8 && X(t.v) + half <= L + pw + R) ctx.fillText(t.s, X(t.v), T + ph + 4);
    }
    ctx.textAlign = "right"; ctx.textBaseline = "middle";
    for (const t of yt) ctx.fillText(t.s, L - 5, Y(t.v));
    ctx.strokeStyle = "#555"; ctx.strokeRect(L + 0.5, T + 0.5, pw - 1, ph - 1);
    if (spec.zeroLines) {
      ctx.strokeStyle = "#b9bec5"; ctx.beginPath();
      if (x0 < 0 && x1 > 0) { ctx.moveTo(X(0), T); ctx.lineTo(X(0), T + ph); }
      if (y0 < 0 && y1 > 0) { ctx.moveTo(L, Y(0)); ctx.lineTo(L + pw, Y(0)); }
      ctx.stroke();
    }
    // axis labels (units in every label)
    ctx.fillStyle = "#111"; ctx.font = "600 12px system-ui, sans-serif";
    ctx.textAlign = "center"; ctx.textBaseline = "bottom";
    ctx.fillText(spec.x.label, L + pw / 2, H - 3);
    ctx.save(); ctx.translate(13, T + ph / 2); ctx.rotate(-Math.PI / 2); ctx.textBaseline = "middle";
    ctx.fillText(spec.y.label, 0, 0); ctx.restore();
    ctx.font = "12px system-ui, sans-serif";

    // vertical marker lines (1X, 2X, ...)
    ctx.save(); ctx.beginPath(); ctx.rect(L, T, pw, ph); ctx.clip();
    for (const v of spec.vlines || []) {
      if (v.x < x0 || v.x > x1) continue;
      ctx.strokeStyle = v.color || "#666"; ctx.setLineDash([4, 3]); ctx.lineWidth = 1;
      ctx.beginPath(); ctx.moveTo(Math.round(X(v.x)) + 0.5, T); ctx.lineTo(Math.round(X(v.x)) + 0.5, T + ph); ctx.stroke();
      ctx.setLineDash([]);
      if (v.label) { ctx.fillStyle = v.color || "#444"; ctx.textAlign = "left"; ctx.textBaseline = "top"; ctx.fillText(v.label, X(v.x) + 3, T + 3); }
    }
    for (const b of spec.vbands || []) {
      if (b.label) { ctx.fillStyle = alpha(b.color, 1); ctx.textAlign = "center"; ctx.textBaseline = "top";
        ctx.fillText(b.label, (X(b.from) + X(b.to)) / 2, T + 17); }
    }

    // series
    for (const s of spec.series || []) {
      const n = Math.min(s.x.length, s.y.length);
      ctx.strokeStyle = s.color; ctx.fillStyle = s.color; ctx.lineWidth = s.width || 1.5;
      if (s.lo && s.hi) {      // interval whiskers
        ctx.lineWidth = 1.2;
        for (let i = 0; i < n; i++) {
          if (s.lo[i] === null || s.hi[i] === null) continue;
          const x = X(s.x[i]);
          ctx.strokeStyle = s.colors ? s.colors[i] : s.color;
          ctx.beginPath(); ctx.moveTo(x, Y(s.lo[i])); ctx.lineTo(x, Y(s.hi[i]));
          ctx.moveTo(x - 4, Y(s.lo[i])); ctx.lineTo(x + 4, Y(s.lo[i]));
          ctx.moveTo(x - 4, Y(s.hi[i])); ctx.lineTo(x + 4, Y(s.hi[i])); ctx.stroke();
        }
        ctx.strokeStyle = s.color; ctx.lineWidth = s.width || 1.5;
      }
      if (s.mode === "stems") {
        const base = ylog ? T + ph : Y(Math.max(0, y0));
        ctx.beginPath();
        for (let i = 0; i < n; i++) {
          if (s.y[i] === null) continue;
          const x = X(s.x[i]) + (s.dx || 0); ctx.moveTo(x, base); ctx.lineTo(x, Y(s.y[i]));
        }
        ctx.stroke();
      } else if (s.mode !== "markers") {
        ctx.beginPath();
        let pen = false;
        for (let i = 0; i < n; i++) {
          if (s.y[i] === null || s.x[i] === null) { pen = false; continue; }
          const x = X(s.x[i]), y = Y(s.y[i]);
          if (pen) ctx.lineTo(x, y); else ctx.moveTo(x, y);
          pen = true;
        }
        ctx.stroke();
        if (s.arrow && n > 8) {  // direction of whirl: arrowhead along increasing shaft angle
          const i = Math.floor(n / 4);
          const ax = X(s.x[i]), ay = Y(s.y[i]), bx = X(s.x[i + 1]), by = Y(s.y[i + 1]);
          const a = Math.atan2(by - ay, bx - ax);
          ctx.beginPath(); ctx.moveTo(bx, by);
          ctx.lineTo(bx - 9 * Math.cos(a - 0.45), by - 9 * Math.sin(a - 0.45));
          ctx.lineTo(bx - 9 * Math.cos(a + 0.45), by - 9 * Math.sin(a + 0.45));
          ctx.closePath(); ctx.fill();
        }
      }
      if (s.mode === "markers" || s.markers) {
        const r = s.size || 3.5;
        for (let i = 0; i < n; i++) {
          if (s.y[i] === null || s.x[i] === null) continue;
          const c = s.colors ? s.colors[i] : (s.markerColor || s.color);
          ctx.beginPath(); ctx.arc(X(s.x[i]), Y(s.y[i]), r, 0, 2 * Math.PI);
          const hollow = s.hollowAt ? s.hollowAt[i] : s.hollow;
          if (hollow) { ctx.fillStyle = "#fff"; ctx.fill(); ctx.strokeStyle = c; ctx.lineWidth = 2; ctx.stroke(); }
          else { ctx.fillStyle = c; ctx.fill(); ctx.strokeStyle = s.outline || "#fff"; ctx.lineWidth = 1; ctx.stroke(); }
        }
      }
    }
    ctx.restore();

    // legend
    ctx.textAlign = "left"; ctx.textBaseline = "middle";
    for (const p of legendPos) {
      const y = 10 + p.row * 16 + 1;
      ctx.strokeStyle = p.it.color; ctx.fillStyle = p.it.color; ctx.lineWidth = 2;
      if (p.it.mode === "markers") {
        ctx.beginPath(); ctx.arc(p.x + 8, y, 3.5, 0, 2 * Math.PI);
        if (p.it.hollow) { ctx.fillStyle = "#fff"; ctx.fill(); ctx.stroke(); } else ctx.fill();
      } else { ctx.beginPath(); ctx.moveTo(p.x, y); ctx.lineTo(p.x + 16, y); ctx.stroke(); }
      ctx.fillStyle = "#222"; ctx.fillText(p.it.label, p.x + 21, y);
    }
  }

  function extent(arrays, pad0 = 0) {
    let lo = Infinity, hi = -Infinity;
    for (const a of arrays) for (const v of a) if (v !== null && Number.isFinite(v)) { if (v < lo) lo = v; if (v > hi) hi = v; }
    if (!Number.isFinite(lo)) return [0, 1];
    const p = (hi - lo) * pad0;
    return [lo - p, hi + p];
  }

  let resizeTimer = null;
  window.addEventListener("resize", () => {
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(() => {
      document.querySelectorAll("canvas").forEach((c) => { if (c._spec && c.offsetParent !== null) drawPlot(c, c._spec); });
    }, 120);
  });

  // ---- orbits and spectra -------------------------------------------------------------------------
  const BEARING_NAMES = { 1: "generator, far end", 2: "generator, coupling end", 3: "exciter, coupling end", 4: "exciter, far end" };

  // lengths shown in µm or mils (the form's "Lengths in" choice); the service's arrays are µm
  function lengthUnit() {
    return $("length-units").value === "mil" ? { k: 1 / 25.4, name: "mil" } : { k: 1, name: "µm" };
  }
  function scaled(a) { const k = lengthUnit().k; return k === 1 ? a : a.map((v) => (v === null ? null : v * k)); }

  function orbitSpec(b) {
    const o = b.orbit, f = o.filtered, series = [], L = lengthUnit();
    const on = (id) => $(id).checked;
    const arrays = [];
    if (on("show-raw")) {
      const rx = scaled(o.raw_x_um), ry = scaled(o.raw_y_um);
      series.push({ x: rx, y: ry, color: COLORS.raw, width: 1 });
      series.push({ x: scaled(o.raw_marks_um.map((p) => p[0])), y: scaled(o.raw_marks_um.map((p) => p[1])), color: "#222", mode: "markers", size: 3 });
      arrays.push(rx, ry);
    }
    for (const [key, id] of [["1x", "show-1x"], ["2x", "show-2x"], ["1x2x", "show-1x2x"]]) {
      if (!on(id)) continue;
      const fx = scaled(f[key].x_um), fy = scaled(f[key].y_um);
      series.push({ x: fx, y: fy, color: COLORS[key], width: 2, arrow: true });
      series.push({ x: [fx[0]], y: [fy[0]], color: COLORS[key], mode: "markers", size: 4.5, outline: "#000" });
      arrays.push(fx, fy);
    }
    let r = 0;
    for (const a of arrays) for (const v of a) if (v !== null) r = Math.max(r, Math.abs(v));
    r = r > 0 ? r * 1.08 : 1;
    return { x: { label: `x (horizontal), ${L.name}`, min: -r, max: r }, y: { label: `y (vertical, up), ${L.name}`, min: -r, max: r },
      equal: true, zeroLines: true, series };
  }

  function orderLines(f1, signs) {
    const lines = [];
    for (const sg of signs) for (const k of [1, 2, 3]) {
      lines.push({ x: sg * k * f1, label: `${sg < 0 ? "−" : ""}${k}X`, color: "#444" });
    }
    return lines;
  }

  function spectrumSpecs(b, plots, log) {
    const f1 = plots.speed_rpm / 60, wb = plots.whirl_band_orders;
    const whirl = { from: wb[0] * f1, to: wb[1] * f1, color: "#e8590c", label: "oil whirl" };
    const hs = b.half_spectrum, fs = b.full_spectrum, L = lengthUnit();
    const hamp = hs.amp_um_pp.map(scaled), famp = scaled(fs.amp_um_pp);
    const amps = hamp.concat([famp]);
    let ymax = 0;
    for (const a of amps) for (const v of a) if (v !== null) ymax = Math.max(ymax, v);
    ymax = ymax > 0 ? ymax : 1;
    const y = log ? { label: `amplitude, ${L.name} pk-pk`, min: ymax * 1e-4, max: ymax * 1.5, log: true }
      : { label: `amplitude, ${L.name} pk-pk`, min: 0, max: ymax * 1.12 };
    const fmax = hs.freq_hz.length ? hs.freq_hz[hs.freq_hz.length - 1] : 4 * f1;
    const half = {
      x: { label: "frequency, Hz", min: 0, max: fmax }, y: { ...y }, vbands: [whirl], vlines: orderLines(f1, [1]),
      series: hamp.map((a, i) => ({ x: hs.freq_hz, y: a, mode: "stems", width: 2, dx: i ? 1.5 : -1.5,
        color: i ? COLORS.probe1 : COLORS.probe0, label: `probe at ${num(b.probe_angles_deg[i])}°` })),
    };
    const full = {
      x: { label: "frequency, Hz (− reverse, + forward whirl)", min: -fmax, max: fmax }, y: { ...y },
      vbands: [whirl], vlines: orderLines(f1, [-1, 1]), zeroLines: true,
      series: [{ x: fs.freq_hz, y: famp, mode: "stems", width: 1.6, color: COLORS.full, label: "full spectrum of x + jy" }],
    };
    return [half, full];
  }

  function renderPlots() {
    const plots = state.plots, box = $("bearing-plots");
    box.replaceChildren();
    if (!plots) return;
    const log = $("spectrum-scale").value === "log";
    $("plots-info").textContent = `Running speed ${fixed(plots.speed_rpm, 1)} r/min (${fixed(plots.speed_rpm / 60, 2)} Hz, ` +
      `${plots.speed_source}); ${plots.n_revs} whole revolutions analysed; shaft angle θ = 0 at the ` +
      `${plots.phase_reference}. Spectra: Hann window over the analysed revolutions; 1X–3X marked, ` +
      `oil-whirl band ${plots.whirl_band_orders[0]}–${plots.whirl_band_orders[1]}X shaded.`;
    for (const b of plots.bearings) {
      const n = b.bearing;
      const orbit = el("canvas", { class: "orbit", id: `orbit-${n}`, role: "img",
        "aria-label": `Orbit of bearing ${n}: raw and filtered, µm` });
      const half = el("canvas", { class: "spectrum", id: `half-${n}`, role: "img",
        "aria-label": `Half spectrum of bearing ${n}'s probes, µm pk-pk against Hz` });
      const full = el("canvas", { class: "spectrum", id: `full-${n}`, role: "img",
        "aria-label": `Full spectrum of bearing ${n}, µm pk-pk against Hz` });
      const card = el("article", { class: "bearing", id: `bearing-${n}`, "aria-label": `Bearing ${n}` },
        el("h3", { text: `Bearing ${n} — ${BEARING_NAMES[n] || ""}` }),
        el("div", { class: "pics" },
          el("figure", { class: "orbit-fig" }, orbit, el("figcaption", { text:
            `Orbit (x right, y up; shaft turns x → y). Dots: once per revolution (θ = 0); arrows: direction of travel.` })),
          el("figure", {}, half, el("figcaption", { text: `Half spectrum of each probe (${b.probe_angles_deg.map((a) => num(a) + "°").join(", ")}).` })),
          el("figure", {}, full, el("figcaption", { text: "Full spectrum: forward whirl right of 0, reverse whirl left." }))));
      box.append(card);
    }
    // draw after layout so clientWidth is known
    for (const b of plots.bearings) {
      const n = b.bearing;
      drawPlot($(`orbit-${n}`), orbitSpec(b));
      const [h, f] = spectrumSpecs(b, plots, log);
      drawPlot($(`half-${n}`), h);
      drawPlot($(`full-${n}`), f);
    }
  }

  // ---- verdict ------------------------------------------------------------------------------------
  function bandRanges(bands) {
    const e = bands.edges || [], names = bands.names || [];
    return names.map((name, i) => {
      if (i === 0) return [name, `Δ < ${e[0]}`];
      if (i === names.length - 1) return [name, `Δ ≥ ${e[i - 1]}`];
      return [name, `${e[i - 1]} ≤ Δ < ${e[i]}`];
    });
  }

  function intervalText(what, iv, digits, unit) {
    const [lo, hi] = iv || [null, null];
    const ok = (x) => x !== null && x !== undefined && Number.isFinite(Number(x));
    if (ok(lo) && ok(hi)) return `${what} ${fixed(lo, digits)}–${fixed(hi, digits)}${unit}`;
    if (ok(lo)) return `${what} from ${fixed(lo, digits)}${unit}, no upper bound`;
    if (ok(hi)) return `${what} up to ${fixed(hi, digits)}${unit}`;
    return `${what} not available`;
  }

  const STATUS_TEXT = {
    confident: "Confident: the checks passed and the model knows recordings like this one.",
    uncertain: "Uncertain: a severity is given, but read the reasons below before acting on it.",
    inconclusive: "Inconclusive: no severity is given. Read the reasons (what to check) and the measured evidence.",
  };

  // the headline's urgency as the engineer reads it (models.headline)
  const URGENCY_TEXT = { none: "no action", before_acting: "before acting", routine: "routine",
    next_outage: "at the next outage", soon: "soon" };

  // an uncertain verdict whose measurement is in doubt shows no severity: its banner says so
  function noSeverityText(status, head) {
    if (!head || head.show_severity || status === "inconclusive") return "";
    return "Measurement in doubt: no severity is shown until the units and the probes are checked. " +
      "The reasons below say what to check.";
  }

  function renderVerdict(v) {
    const status = v.status || "confident";
    const head = v.headline || null;
    const hl = $("verdict-headline");
    hl.textContent = head ? `What to do (${URGENCY_TEXT[head.urgency] || head.urgency}): ${head.text}` : "";
    hl.className = "headline " + (head ? head.urgency : "");
    show(hl, Boolean(head));
    // a recording whose measurement is in doubt (units or physics checks) shows no severity at all
    const noSeverity = head ? !head.show_severity : false;
    const st = $("verdict-status");
    st.textContent = noSeverityText(status, head) || STATUS_TEXT[status] || status;
    st.className = "status " + status;
    const reasons = v.reasons || [];
    // the message says what was found in this recording; the action (the reasons catalogue's, the same for every
    // answer with the code) what to do
    $("verdict-reasons").replaceChildren(...reasons.map((r) => el("li", {
      class: r.status, text: plainWords(r.message) + (r.action ? ` — What to do: ${plainWords(r.action)}.` : "") })));
    show($("verdict-reasons-box"), reasons.length > 0);
    const ev = $("verdict-evidence").tBodies[0];
    ev.replaceChildren(...(v.evidence || []).map((e) => el("tr", {}, el("td", { text: e.scope }), el("td", { text: e.name }),
      el("td", { text: e.value }), el("td", { text: e.meaning }))));
    const inconclusive = status === "inconclusive" || noSeverity;
    // an inconclusive verdict, or one whose measurement is in doubt, shows no severity badge, no Δ and no class
    // probabilities: only the evidence
    show($("verdict-severity-row"), !inconclusive);
    show($("verdict-delta-row"), !inconclusive);
    show($("verdict-offset-row"), !inconclusive);
    show($("verdict-model-part"), !inconclusive);
    const sev = $("verdict-severity");
    sev.textContent = inconclusive ? "" : v.severity;
    sev.className = "badge " + (!inconclusive && SEVERITY_COLORS[v.severity] ? v.severity : "");
    const lvl = v.interval_level ? `${Math.round(v.interval_level * 100)} % interval` : "interval";
    $("verdict-delta").textContent = `${fixed(v.misalignment, 3)} (${intervalText(lvl, v.misalignment_interval, 3, "")})`;
    if (v.output_units === "mil" && v.offset_mil !== null && v.offset_mil !== undefined) {
      $("verdict-offset").textContent = `${fixed(v.offset_mil, 2)} mil (${intervalText(lvl, v.offset_interval_mil, 2, " mil")})`;
    } else if (v.offset_um !== null && v.offset_um !== undefined) {
      $("verdict-offset").textContent = `${fixed(v.offset_um, 1)} µm (${intervalText(lvl, v.offset_interval_um, 1, " µm")})`;
    } else {
      $("verdict-offset").textContent = "— (give the clearance to get δ in µm)";
    }
    // which way the exciter sits (models.direction): its text, or why there is none
    show($("verdict-direction-row"), !inconclusive && !!v.direction);
    if (v.direction) {
      $("verdict-direction").textContent = v.direction.estimated ? v.direction.text : `not estimated — ${v.direction.why_not}`;
    }
    $("verdict-motion").textContent = v.motion_type || "not determined";
    // an estimated speed in doubt (the speed_ambiguous reason; perhaps a reading the model chose) is marked as such
    const speedDoubt = (v.reasons || []).some((r) => r.code === "speed_ambiguous");
    $("verdict-speed").textContent = v.speed_rpm ? `${fixed(v.speed_rpm, 1)} r/min (${fixed(v.speed_rpm / 60, 2)} Hz)` +
      (v.speed_source ? `, ${v.speed_source}` : "") + (speedDoubt ? " — in doubt: see the reasons" : "") : "—";
    $("verdict-model").textContent = v.model_version;
    // which model answered, trained on what, and the plant model the recording was judged as (and whose)
    $("verdict-answered-by").textContent = v.answered_by ? v.answered_by.text : "";
    show($("verdict-answered-row"), Boolean(v.answered_by));
    const ood = $("ood-warning");
    if (v.ood) {
      const outside = (v.ood_findings || []).map((f) => f.feature);
      ood.textContent = `Out of distribution: this recording is unlike the model's training data ` +
        `(OOD score ${num(v.ood_score)}, flagged above 1` +
        (outside.length ? `; outside the training range: ${outside.slice(0, 5).join(", ")}` : "") +
        `). Treat the verdict with caution; the reasons above say what to check.`;
    }
    show(ood, Boolean(v.ood));
    renderBaselineSection(v.baseline);
    const tb = $("verdict-probs").tBodies[0];
    tb.replaceChildren();
    const ranges = Object.fromEntries(bandRanges(v.bands || {}));
    const names = (v.bands && v.bands.names) || Object.keys(v.probabilities);
    for (const name of names) {
      const p = v.probabilities[name] || 0;
      const bar = el("span", { class: "bar" });
      bar.style.width = `${Math.max(1, Math.round(p * 120))}px`;
      bar.style.background = SEVERITY_COLORS[name] || COLORS["1x"];
      tb.append(el("tr", { "data-class": name }, el("th", { scope: "row", text: name }), el("td", { text: ranges[name] || "" }),
        el("td", { class: "num" }, bar, `${(100 * p).toFixed(1)} %`)));
    }
    const fb = $("verdict-features").tBodies[0];
    fb.replaceChildren();
    for (const f of v.top_features || []) {
      fb.append(el("tr", {}, el("td", {}, el("code", { text: f.name })), el("td", { class: "num", text: num(f.value, 4) }),
        el("td", { class: "num", text: num(f.reference, 4) }),
        el("td", { class: "num", text: f.contribution === null ? "—" : (f.contribution >= 0 ? "+" : "") + num(f.contribution, 3) })));
    }
    const wl = $("verdict-warnings");
    wl.replaceChildren(...(v.warnings || []).map((w) => el("li", { text: plainWords(w) })));
    $("verdict-input-notes").replaceChildren(...(v.input_notes || []).map((n) => el("li", { text: n })));
    show($("verdict-input-notes-box"), (v.input_notes || []).length > 0);
    show($("verdict"), true);
  }

  // change quantities and timestamps as an engineer reads them (models.change.CHANGE_NAMES, core.timefmt)
  const CHANGE_NAMES = { "1x_change": "1X vector change", "2x_change": "2X vector change", dc_shift: "centreline shift",
    orbit_ellipticity_change: "orbit ellipticity change", orbit_2x_1x_change: "orbit 2X/1X change" };
  const changeName = (k) => CHANGE_NAMES[k] || k.replace(/_/g, " ");
  function when(s) {
    if (!s) return "—";
    const t = Date.parse(/Z$|[+-]\d\d:?\d\d$/.test(s) ? s : s + "Z");
    return Number.isFinite(t) ? new Date(t).toISOString().slice(0, 16).replace("T", " ") + " UTC" : s;
  }
  // a change quantity's value in the page's length units (µm-valued ones) or as a plain number
  function changeValue(x, v) {
    if (v === null || v === undefined) return "—";
    return String(x.unit || "").startsWith("µm") ? `${num(v * lengthUnit().k, 3)} ${lengthUnit().name}${x.unit.slice(2)}`
      : num(v, 3);
  }

  // the answer's baseline section: whether the asset's baseline was used, its date, what changed
  function renderBaselineSection(b) {
    const box = $("verdict-baseline");
    if (!b) { show(box, false); return; }
    box.className = "baseline " + (b.changed ? "changed" : (b.used ? "unchanged" : "none"));
    const parts = [b.used ? `Baseline of ${when(b.set_at)} used (${b.source}, ${fixed(b.speed_rpm, 0)} r/min).` :
      "No baseline used."];
    parts.push(plainWords(b.message));
    const basis = b.used ? b.thresholds_basis : null;
    if (basis) {
      const n = basis.n_recordings;
      parts.push(basis.basis === "own" ?
        `Alarm thresholds: this asset's own, from how much its ${n} baseline recordings differ.` :
        `Alarm thresholds: the fleet-wide ones (${n} baseline recording${n === 1 ? "" : "s"}; ${basis.needed} at one ` +
        "speed set this asset's own): a change of a few µm on a small machine stays under them.");
    }
    if (state.verdict && state.verdict.storage_note) parts.push(plainWords(state.verdict.storage_note) + ".");
    box.textContent = parts.join(" ");
    show(box, true);
  }

  // ---- diagnose ---------------------------------------------------------------------------------
  function formValue(id) { const v = $(id).value.trim(); return v === "" ? null : v; }
  // the API key typed in the form: a diagnosis is stored in the asset's history only with it
  function keyHeader() { const k = $("diagnose-key").value; return k ? { "X-API-Key": k } : {}; }

  function buildRequests() {
    const source = document.querySelector("input[name=source]:checked").value;
    const numeric = { sample_rate_hz: "sample-rate", speed_rpm: "speed", clearance_um: "clearance" };
    if (source === "json") {
      const text = $("json-text").value.trim();
      if (!text) throw new Error("Paste a recording as JSON, or switch the source to a file upload.");
      let body;
      try { body = JSON.parse(text); } catch (exc) { throw new Error(`The pasted text is not valid JSON: ${exc.message}`); }
      if (body === null || typeof body !== "object" || Array.isArray(body)) {
        throw new Error("The pasted JSON must be one object: {\"sample_rate_hz\": …, \"channels\": [{\"bearing\", \"angle_deg\", \"units\", \"data\"}, …]}");
      }
      for (const [key, id] of Object.entries(numeric)) {
        if (!(key in body) && formValue(id) !== null) body[key] = Number(formValue(id));
      }
      if (!("speed_range_rpm" in body) && formValue("speed-range") !== null) {
        body.speed_range_rpm = formValue("speed-range").split(/[,;\s]+/).filter((x) => x).map(Number);
      }
      if (!("dc_removed" in body) && $("dc-removed").checked) body.dc_removed = true;
      if (!("acquisitions" in body) && formValue("acquisitions") !== null) body.acquisitions = formValue("acquisitions");
      if (!("asset_id" in body) && formValue("asset")) body.asset_id = formValue("asset");
      const json = JSON.stringify(body);
      const opts = () => ({ method: "POST", headers: { "Content-Type": "application/json", ...keyHeader() }, body: json });
      const dq = new URLSearchParams({ output_units: $("length-units").value });
      if (formValue("plant-model") !== null) dq.set("plant_model", formValue("plant-model"));
      if (formValue("recorded-at") !== null) dq.set("recorded_at", formValue("recorded-at") + "Z");
      if (formValue("tags") !== null) dq.set("tags", formValue("tags"));
      if (formValue("note") !== null) dq.set("note", formValue("note"));
      const sq = new URLSearchParams({ output_units: $("length-units").value });
      if ($("transient-baseline").checked) sq.set("baseline", "true");
      if (formValue("recorded-at") !== null) sq.set("recorded_at", formValue("recorded-at") + "Z");
      if (formValue("note") !== null) sq.set("note", formValue("note"));
      return { diagnose: [`/diagnose?${dq}`, opts()], plot: ["/ui/plot-data", opts()],
        transient: [`/ui/transient-plots?output_units=${$("length-units").value}&centreline_reference=${$("centreline-ref").value}`, opts()],
        asset: body.asset_id || null,
        startup: (a) => [`/assets/${encodeURIComponent(a)}/startup?${sq}`, opts()] };
    }
    let files = Array.from($("file").files);
    const q = new URLSearchParams();
    if (source === "example") {
      const ex = state.examples.find((e) => e.name === $("example").value);
      if (!ex || !ex.blob) throw new Error("The example recordings could not be loaded from the service; reload the page.");
      files = [new File([ex.blob], ex.name)];
      for (const [key, value] of Object.entries(ex.query || {})) q.set(key, String(value));
    }
    if (!files.length) throw new Error("Choose a waveform file (CSV, NPY, HDF5 or UFF), or switch the source to an example or “Paste JSON”.");
    for (const [key, id] of Object.entries(numeric)) if (formValue(id) !== null) q.set(key, formValue(id));
    for (const [key, id] of [["units", "units"], ["bearings", "bearings"], ["angles_deg", "angles"],
      ["speed_range_rpm", "speed-range"], ["acquisitions", "acquisitions"], ["keyphasor_channel", "keyphasor-channel"],
      ["channel_map", "channel-map"], ["sensitivity", "sensitivity"], ["gap_voltage_v", "gap-voltage"]]) {
      if (formValue(id) !== null) q.set(key, formValue(id));
    }
    if (formValue("sample-index") !== null && formValue("sample-index") !== "0") q.set("sample_index", formValue("sample-index"));
    if ($("dc-removed").checked) q.set("dc_removed", "true");
    const asset = formValue("asset");
    if (asset) q.set("asset_id", asset);       // the plots too are read with the asset's probe configuration
    const qp = new URLSearchParams(q);
    // what is stored with the recording (the diagnosis only): its time (UTC), operating state and an event note
    if (formValue("recorded-at") !== null) q.set("recorded_at", formValue("recorded-at") + "Z");
    if (formValue("tags") !== null) q.set("tags", formValue("tags"));
    if (formValue("note") !== null) q.set("note", formValue("note"));
    // the machine's plant model: the verdict is judged against the model's training families (diagnosis only)
    if (formValue("plant-model") !== null) q.set("plant_model", formValue("plant-model"));
    q.set("output_units", $("length-units").value);
    const opts = () => { const fd = new FormData(); for (const f of files) fd.append("file", f, f.name); return { method: "POST", body: fd, headers: keyHeader() }; };
    const qt = new URLSearchParams(qp);
    qt.set("output_units", $("length-units").value);
    qt.set("centreline_reference", $("centreline-ref").value);
    // storing a start-up on the asset: the reader's query, its time and note, baseline or not
    const sq = new URLSearchParams(qt);
    sq.delete("asset_id"); sq.delete("centreline_reference");
    if ($("transient-baseline").checked) sq.set("baseline", "true");
    if (formValue("recorded-at") !== null) sq.set("recorded_at", formValue("recorded-at") + "Z");
    if (formValue("note") !== null) sq.set("note", formValue("note"));
    return { diagnose: [`/diagnose?${q}`, opts()], plot: [`/ui/plot-data?${qp}`, opts()],
      transient: [`/ui/transient-plots?${qt}`, opts()], asset,
      startup: (a) => [`/assets/${encodeURIComponent(a)}/startup?${sq}`, opts()] };
  }

  async function onDiagnose(ev) {
    ev.preventDefault();
    setError($("form-error"), "");
    let req;
    try { req = buildRequests(); } catch (exc) { fail(exc.message); return; }
    $("diagnose-btn").disabled = true; show($("busy"), true);
    document.body.dataset.state = "busy";
    const plotPromise = api(...req.plot).then((p) => ({ p }), (e) => ({ e }));
    try {
      const verdict = await api(...req.diagnose);
      state.verdict = verdict;
      renderVerdict(verdict);
      const { p, e } = await plotPromise;
      state.plots = p || null;
      show($("plots"), true);
      setError($("plots-error"), e ? `The orbit and spectrum pictures could not be drawn. ${e.message}` : "");
      renderPlots();
      if (req.asset) { $("trend-asset").value = req.asset; await loadTrend(req.asset); }
      document.body.dataset.state = "done";
    } catch (exc) {
      await plotPromise;
      fail(exc.message);
    } finally {
      $("diagnose-btn").disabled = false; show($("busy"), false);
    }
  }

  // a start-up or coast-down: POST /ui/transient-plots (the same body), its PNGs and summary
  async function onTransient() {
    setError($("form-error"), "");
    setError($("transient-error"), "");
    let req;
    try { req = buildRequests(); } catch (exc) { setError($("form-error"), exc.message); return; }
    $("transient-btn").disabled = true; $("busy").textContent = "tracking and plotting…"; show($("busy"), true);
    document.body.dataset.state = "busy";
    $("transient-figures").replaceChildren(); $("transient-peaks").replaceChildren(); $("transient-notes").replaceChildren();
    $("transient-info").textContent = ""; $("transient-conventions").textContent = "";
    show($("transient"), true);
    try {
      renderTransient(await api(...req.transient));
      document.body.dataset.state = "done";
    } catch (exc) {
      setError($("transient-error"), `The start-up plots could not be drawn. ${exc.message}`);
      document.body.dataset.state = "error";
    } finally {
      $("transient-btn").disabled = false; show($("busy"), false); $("busy").textContent = "diagnosing…";
    }
  }

  // store the uploaded start-up on the asset: POST /assets/{id}/startup (the same body), then its comparison
  async function onStoreStartup() {
    setError($("transient-store-error"), "");
    show($("transient-stored"), false);
    const asset = formValue("asset");
    if (!asset) { setError($("transient-store-error"), "Type the asset id in the form above: the start-up is stored on that asset."); return; }
    if (!$("diagnose-key").value) { setError($("transient-store-error"), "Type the API key in the form above: storing a start-up changes the asset's verdicts."); return; }
    let req;
    try { req = buildRequests(); } catch (exc) { setError($("transient-store-error"), exc.message); return; }
    $("transient-store-btn").disabled = true; $("busy").textContent = "storing the start-up…"; show($("busy"), true);
    document.body.dataset.state = "busy";
    try {
      renderStoredStartup(await api(...req.startup(asset)));
      if ($("trend-asset").value.trim() === asset) await loadStartups(asset);
      document.body.dataset.state = "done";
    } catch (exc) {
      setError($("transient-store-error"), `The start-up was not stored. ${exc.message}`);
      document.body.dataset.state = "error";
    } finally {
      $("transient-store-btn").disabled = false; show($("busy"), false); $("busy").textContent = "diagnosing…";
    }
  }

  function renderStoredStartup(r) {
    const what = r.is_baseline ? "the asset's baseline start-up" : "a later start-up";
    let text = `Stored as start-up #${r.startup_id} of ${r.asset_id}, ${what}; ${r.comparison}.`;
    const v = r.asset_verdict;
    if (v) text += ` The asset's latest verdict with it: ${v.severity} (${v.status})${v.headline && v.headline.text ? ` — ${v.headline.text}` : ""}.`;
    $("transient-stored-info").textContent = text;
    const rows = $("transient-stored-rows");
    rows.replaceChildren();
    for (const e of r.evidence_rows || []) rows.append(el("li", { class: `effect-${e.effect}`, text: e.text }));
    for (const x of r.reasons || []) rows.append(el("li", { text: x.message || x.code }));
    show($("transient-stored"), true);
  }

  // an asset's stored start-ups (GET /assets/{id}/startups): which is the baseline, which is compared with it
  async function loadStartups(asset) {
    const list = $("trend-startups");
    list.replaceChildren();
    let r;
    try {
      r = await api(`/assets/${encodeURIComponent(asset)}/startups`);
    } catch (exc) {
      if (exc.status !== 404) throw exc;
      $("trend-startups-info").textContent = "No start-up stored for this asset: upload a run-up or coast-down, " +
        "draw its plots and store it as the asset's baseline start-up.";
      show($("trend-startups-box"), true);
      return;
    }
    $("trend-startups-info").textContent = "The service keeps each start-up's evidence, not its waveform: " +
      "upload the recording again to see its plots.";
    for (const s of r.startups) {
      const [lo, hi] = s.speed_range_rpm || [NaN, NaN];
      const role = s.startup_id === r.baseline_startup_id ? "baseline start-up" :
        (s.startup_id === r.compared_startup_id ? "compared with the baseline in the verdicts" : "earlier");
      const rise = Object.entries((s.evidence || {}).half_rise_rpm || {})
        .map(([b, v]) => `b${b} ${Number(v).toFixed(0)}`).join(", ");
      list.append(el("li", { "data-startup-id": String(s.startup_id), text: `#${s.startup_id} ${when(s.recorded_at || s.created_at)}: ${s.kind || "run"}, ` +
        `${fixed(lo, 0)}–${fixed(hi, 0)} r/min, ${s.peaks.length} peak${s.peaks.length === 1 ? "" : "s"}` +
        (rise ? `; centreline half-rise at ${rise} r/min` : "") + ` — ${role}` + (s.note ? ` (${s.note})` : "") }));
    }
    show($("trend-startups-box"), true);
  }

  function renderTransient(t) {
    const unit = t.units === "mil" ? "mil" : "µm";
    const [lo, hi] = t.speed_range_rpm;
    $("transient-info").textContent = `${t.kind}, ${lo.toFixed(0)}–${hi.toFixed(0)} r/min, ${t.n_steps} steps tracked, ` +
      `speed from the ${t.speed_source}. Not a diagnosis: the verdict comes from a steady recording.`;
    const k = t.units === "mil" ? 1 / 25.4 : 1;
    for (const p of t.peaks) {
      $("transient-peaks").append(el("li", { text: `${p.order}X peak at bearing ${p.bearing} @ ${p.angle_deg}°: ` +
        `${(p.amp_um_pp * k).toFixed(t.units === "mil" ? 2 : 1)} ${unit} pk-pk at ${p.speed_rpm.toFixed(0)} r/min` }));
    }
    if (!t.peaks.length) $("transient-peaks").append(el("li", { text: "no 1X/2X resonance peak inside the run" }));
    for (const n of t.notes) $("transient-notes").append(el("li", { text: n }));
    $("transient-conventions").textContent = `Conventions: ${t.conventions}`;
    for (const f of t.figures) {
      $("transient-figures").append(el("figure", { "data-name": f.name },
        el("img", { src: `data:image/png;base64,${f.png_base64}`, alt: f.title || f.name }),
        el("figcaption", { text: f.name.replace(/_/g, " ") })));
    }
  }

  function fail(message) {
    // never leave an earlier verdict or pictures next to a new error
    state.verdict = null; state.plots = null;
    show($("verdict"), false); show($("plots"), false);
    $("bearing-plots").replaceChildren();
    setError($("form-error"), message);
    document.body.dataset.state = "error";
  }

  // ---- trend ------------------------------------------------------------------------------------
  function bandsFor(points) {
    const latest = points.length ? points[points.length - 1].model_version : null;
    const cards = (state.models && state.models.versions) || [];
    const card = cards.find((c) => c.version === latest) || cards.find((c) => c.active);
    if (card && card.bands && card.bands.edges) return card.bands;
    if (state.verdict && state.verdict.bands) return state.verdict.bands;
    return { edges: [0.05, 0.15, 0.35], names: ["aligned", "slight", "moderate", "severe"] };
  }

  function renderTrend() {
    const h = state.history;
    if (!h) return;
    const pts = h.points;
    // the recording time when the upload gave one (a backfilled recording sits in its place), else the time stored
    const t = pts.map((p) => { const s = p.trend_time || p.time; return Date.parse(s.endsWith("Z") || /[+-]\d\d:?\d\d$/.test(s) ? s : s + "Z"); });
    let [t0, t1] = extent([t]);
    const padT = Math.max((t1 - t0) * 0.06, 2000);     // at least 2 s either side: points never sit on the frame
    t0 -= padT; t1 += padT;
    const day = new Date(t0);
    const xlab = `time (UTC), from ${day.getUTCFullYear()}-${pad(day.getUTCMonth() + 1)}-${pad(day.getUTCDate())}`;
    const bands = bandsFor(pts);
    const edges = bands.edges, names = bands.names;
    const d = pts.map((p) => p.misalignment), lo = pts.map((p) => p.misalignment_low), hi = pts.map((p) => p.misalignment_high);
    const ymax = Math.max(extent([d, hi])[1] * 1.1, (edges[edges.length - 1] || 0.35) * 1.3);
    const hb = names.map((name, i) => ({ from: i ? edges[i - 1] : 0, to: i < edges.length ? edges[i] : ymax * 2,
      color: SEVERITY_COLORS[name] || FALLBACK_BAND_COLORS[i % FALLBACK_BAND_COLORS.length], label: name }));
    drawPlot($("trend-delta"), {
      x: { label: xlab, min: t0, max: t1, time: true }, y: { label: "misalignment Δ = δ/c (–)", min: 0, max: ymax },
      hbands: hb,
      series: [{ x: t, y: d, lo, hi, color: "#1b1f24", width: 1.5, markers: true, size: 4.5,
        colors: pts.map((p) => SEVERITY_COLORS[p.severity] || "#1b1f24"), hollowAt: pts.map((p) => Boolean(p.ood)),
        label: "Δ estimate with interval" }],
      legendExtra: pts.some((p) => p.ood) ? [{ label: "hollow: out of distribution", color: "#1b1f24", mode: "markers", hollow: true }] : [],
    });
    const bearings = [1, 2, 3, 4].filter((b) => pts.some((p) => (p.amplitudes_um_pp || {})[`b${b}_1x_major_um_pp`] !== undefined));
    for (const k of ["1x", "2x"]) {
      const series = bearings.map((b, i) => ({ x: t, y: scaled(pts.map((p) => { const v = (p.amplitudes_um_pp || {})[`b${b}_${k}_major_um_pp`]; return v === undefined ? null : v; })),
        color: COLORS.bearing[(b - 1) % 4], width: 1.8, markers: true, size: 3.5, label: `bearing ${b}` }));
      const [, top] = extent(series.map((s) => s.y));
      drawPlot($(`trend-${k}`), { x: { label: xlab, min: t0, max: t1, time: true },
        y: { label: `${k.toUpperCase()} orbit major axis, ${lengthUnit().name} pk-pk`, min: 0, max: top > 0 ? top * 1.15 : 1 }, series });
    }
  }

  // the assets grouped site → unit → train (GET /assets); a click shows an asset's trend
  async function loadAssets() {
    setError($("hier-error"), "");
    try {
      const assets = await api("/assets");
      const groups = new Map();
      for (const a of assets) {
        const key = [a.site || "(no site)", a.unit || "(no unit)", a.train || "(no train)"].join(" → ");
        if (!groups.has(key)) groups.set(key, []);
        groups.get(key).push(a);
      }
      const items = [...groups.entries()].sort(([x], [y]) => x.localeCompare(y)).map(([key, list]) =>
        el("li", {}, el("span", { class: "where", text: key + ": " }), ...list.map((a) => {
          const b = el("button", { type: "button", class: "linklike", "data-asset": a.asset_id,
            text: `${a.asset_id} (${a.diagnoses} recording${a.diagnoses === 1 ? "" : "s"}` +
              (a.latest ? `, latest ${when(a.latest)}` : "") + ")" });
          b.addEventListener("click", () => { $("trend-asset").value = a.asset_id; loadTrend(a.asset_id); });
          return b;
        })));
      if (!items.length) items.push(el("li", { text: "No asset yet: a diagnosis stored with an asset id makes one." }));
      $("assets-tree").replaceChildren(...items);
    } catch (exc) {
      setError($("hier-error"), plainWords(exc.message));
    }
  }

  async function onHierarchy(ev) {
    ev.preventDefault();
    setError($("hier-error"), "");
    const asset = $("trend-asset").value.trim();
    if (!asset) { setError($("hier-error"), "Type the asset id above first."); return; }
    const body = {};
    for (const [k, id] of [["site", "hier-site"], ["unit", "hier-unit"], ["train", "hier-train"]]) {
      const v = $(id).value.trim();
      if (v) body[k] = v;
    }
    try {
      await api(`/assets/${encodeURIComponent(asset)}/hierarchy`, { method: "PUT", body: JSON.stringify(body),
        headers: { "Content-Type": "application/json", "X-API-Key": $("hier-key").value } });
      await loadAssets();
    } catch (exc) {
      setError($("hier-error"), plainWords(exc.message));
    }
  }

  async function loadTrend(asset) {
    setError($("trend-error"), "");
    if (!asset) { setError($("trend-error"), "Type the asset id that was sent with the diagnoses."); return; }
    try {
      if (!state.models) await loadModels();
      const h = await api(`/assets/${encodeURIComponent(asset)}/history?limit=1000`);
      state.history = h;
      show($("trend-plots"), true);
      const last = h.points[h.points.length - 1];
      $("trend-info").textContent = `${h.count} diagnos${h.count === 1 ? "is" : "es"} of ${h.asset_id}` +
        (last ? `; latest: ${last.severity}, Δ = ${fixed(last.misalignment, 3)} (model ${last.model_version}).` : ".");
      renderTrend();
      const report = `/assets/${encodeURIComponent(h.asset_id)}/report`;
      $("trend-report-pdf").href = report; $("trend-report-html").href = `${report}?format=html`;
      show($("trend-report"), true);
      await loadBaseline(asset, h);
    } catch (exc) {
      state.history = null;
      show($("trend-plots"), false); show($("trend-report"), false);
      $("trend-info").textContent = "";
      setError($("trend-error"), exc.message);
    }
    // an asset's start-ups, also when it has no stored diagnosis yet
    try { await loadStartups(asset); } catch (exc) {
      $("trend-startups-info").textContent = `The asset's start-ups could not be read. ${exc.message}`;
      show($("trend-startups-box"), true);
    }
  }

  // set the asset's baseline from the page: the latest stored diagnosis, or the automatic proposal
  async function setBaseline(how) {
    setError($("baseline-error"), "");
    const asset = $("trend-asset").value.trim();
    const h = state.history;
    if (!asset || !h) { setError($("baseline-error"), "Show an asset's trend first."); return; }
    const key = $("baseline-key").value;
    if (!key) { setError($("baseline-error"), "Type the API key: setting a baseline changes the asset's alarms."); return; }
    let query = "auto=true";
    let path = "baseline";
    if (how === "latest" || how === "add") {
      const last = h.points.length ? h.points[h.points.length - 1] : null;
      if (!last || last.id === null || last.id === undefined) {
        setError($("baseline-error"), "This asset has no stored diagnosis to make the baseline."); return;
      }
      query = `diagnosis_id=${last.id}`;
      if (how === "add") path = "baseline/recordings";
    }
    try {
      await api(`/assets/${encodeURIComponent(asset)}/${path}?${query}`, { method: "POST", headers: { "X-API-Key": key } });
      await loadTrend(asset);
    } catch (exc) {
      setError($("baseline-error"), plainWords(exc.message));
    }
  }

  async function loadBaseline(asset, h) {
    const b = await api(`/assets/${encodeURIComponent(asset)}/baseline`);
    const ev = await api(`/assets/${encodeURIComponent(asset)}/events?limit=50`);
    const base = b.baseline;
    let text;
    if (base) {
      const n = base.n_recordings || base.diagnosis_ids.length;
      text = `Set ${when(base.set_at)} from ${base.source}, made of ${n} recording${n === 1 ? "" : "s"} ` +
        `(diagnoses ${base.diagnosis_ids.join(", ")}), ` +
        `${fixed(base.speed_rpm, 0)} r/min (recordings within ±5 % are compared), model ${base.model_version}.`;
      const basis = base.thresholds_basis || {};
      const origin = b.thresholds_origin || {};
      const words = (k) => {
        const v = b.thresholds[k];
        if (v === null) return `${changeName(k)} off`;
        const m = /^(1x|2x)_change_um_pp$/.exec(k);
        if (m) return `${m[1].toUpperCase()} vector change ${num(v * lengthUnit().k, 3)} ${lengthUnit().name} pk-pk`;
        if (k === "dc_shift_um") return `centreline shift ${num(v * lengthUnit().k, 3)} ${lengthUnit().name}`;
        return `${changeName(k)} ${num(v, 3)}`;
      };
      // a repeatability threshold replaces its per-clearance twin (null): the twin is not listed
      const own = Object.keys(origin).filter((k) => origin[k] === "repeatability" && b.thresholds[k] !== null);
      const edited = Object.keys(origin).filter((k) => origin[k] === "edited");
      const parts = [];
      if (own.length) parts.push("from its baseline recordings' repeatability: " + own.map(words).join(", "));
      if (edited.length) parts.push("edited: " + edited.map(words).join(", "));
      const why = {
        too_few_recordings: `this baseline has ${n} recording${n === 1 ? "" : "s"}; ${basis.needed || 3} at one speed set this asset's own (add the latest diagnosis, or the automatic baseline)`,
        recordings_not_comparable: "this baseline's recordings are more than 10 % apart in speed",
        nothing_measured: "this baseline's recordings carry no 1X/2X phase (no keyphasor) and no centreline",
      }[basis.reason];
      text += parts.length ? ` Alarm thresholds of this asset ${parts.join("; ")}; the others shipped.` :
        " Alarm thresholds: the shipped, fleet-wide ones" + (why ? ` — ${why}` : "") +
        ": a change of a few µm on a small machine stays under them.";
    } else if (b.proposal && b.proposal.diagnosis_ids) {
      text = `None set. Automatic proposal: diagnoses ${b.proposal.diagnosis_ids.join(", ")} at ` +
        `${fixed(b.proposal.speed_rpm, 0)} r/min (${b.proposal.how}).`;
    } else {
      text = `None set. ${plainWords((b.proposal && b.proposal.reason) || "")}`;
    }
    $("trend-baseline").textContent = text;
    const alarms = (h && h.alarms) || [];
    const last = h && h.points.length ? h.points[h.points.length - 1] : null;
    const items = alarms.map((a) => el("li", { class: a.event,
      text: `${when(a.time)}: alarm ${a.event}` + (a.quantities.length ? ` (${a.quantities.map(changeName).join(", ")})` : "") +
        ` — diagnosis ${a.diagnosis_id}` }));
    if (!items.length) items.push(el("li", { text: base ? "No alarm raised." : "No baseline: no change alarms." }));
    // setpoint and change alarm events (GET /assets/{id}/events, newest first), with their acknowledgement
    for (const e of (ev && ev.events) || []) {
      const label = { overall_um_pp: "overall", x1_um_pp: "1X", x2_um_pp: "2X", misalignment: "misalignment Δ" }[e.quantity] || e.quantity;
      const what = e.quantity === "change" ? "changed since the baseline" : label +
        (e.value !== null ? ` ${num(e.quantity.endsWith("_um_pp") ? e.value * lengthUnit().k : e.value, 3)}` +
          (e.quantity.endsWith("_um_pp") ? ` ${lengthUnit().name} pk-pk` : "") : "") +
        (e.setpoint !== null ? ` (${e.level} setpoint ${num(e.quantity.endsWith("_um_pp") ? e.setpoint * lengthUnit().k : e.setpoint, 3)})` : "");
      items.push(el("li", { class: `event ${e.event}`, text: `${when(e.time)}: ${e.level} ${e.event}: ${what}` +
        (e.event === "raised" ? (e.acked_at ? ` — acknowledged ${when(e.acked_at)}${e.ack_note ? " (" + e.ack_note + ")" : ""}` : " — not acknowledged") : "") }));
    }
    // event notes and operating state given with the recordings (POST /diagnose ?note= &tags=)
    for (const p of ((h && h.points) || []).filter((x) => x.note || (x.tags && Object.keys(x.tags).length))) {
      const tags = Object.entries(p.tags || {}).map(([k, v]) => `${k.replace(/_/g, " ")} ${v}`).join(", ");
      items.push(el("li", { class: "note", text: `${when(p.trend_time || p.time)}: ${p.note || ""}` +
        (tags ? `${p.note ? " — " : ""}${tags}` : "") + ` (diagnosis ${p.id})` }));
    }
    if (last && last.change) {
      const q = last.change.quantities || {};
      const shown = Object.entries(q).filter(([, x]) => x.value !== null).map(([k, x]) =>
        `${changeName(k)} ${changeValue(x, x.value)}${x.exceeded ? " (over " + changeValue(x, x.threshold) + ")" : ""}`);
      items.push(el("li", { class: "latest", text: `Latest change: ${shown.join("; ")}` }));
    }
    $("trend-alarms").replaceChildren(...items);
    for (const n of document.querySelectorAll(".api-base")) n.textContent = window.location.origin;
    show($("trend-baseline-box"), true);
  }

  // ---- models, health ---------------------------------------------------------------------------
  function evalSummary(card) {
    const m = card.metrics && card.metrics.all_mixed_average && card.metrics.all_mixed_average.model;
    if (!m) return "no held-out evaluation in the model card";
    const parts = [];
    if (m.macro_f1 !== undefined) parts.push(`macro-F1 ${num(m.macro_f1)}`);
    if (m.delta_mae !== undefined) parts.push(`Δ MAE ${num(m.delta_mae)}`);
    if (m.interval_coverage !== undefined) parts.push(`interval coverage ${num(m.interval_coverage)}`);
    if (m.ece !== undefined) parts.push(`ECE ${num(m.ece)}`);
    if (m.ood_flag_rate !== undefined) parts.push(`OOD flag rate ${num(m.ood_flag_rate)}`);
    const held = card.metrics.held_out ? ` (${card.metrics.held_out})` : "";
    const pr = card.plant_report;
    const plant = !pr ? "" : pr.pending ? "; plant report pending" :
      `; on ${pr.plant}: ${pr.better ? "better than" : "NOT better than"} ${pr.compared_with}` +
      (pr.pooled && pr.pooled.new ? ` (macro-F1 ${num(pr.pooled.new.macro_f1)} vs ${num(pr.pooled.active.macro_f1)})` : "");
    return parts.join(", ") + held + plant;
  }
  function trainingSummary(card) {
    const td = card.training_data || {};
    const parts = [];
    if (td.n_rows_used !== undefined) parts.push(`${td.n_rows_used} recordings`);
    if (td.n_plants !== undefined) parts.push(`${td.n_plants} plants`);
    if (td.speed_rpm_range) parts.push(`${num(td.speed_rpm_range[0], 4)}–${num(td.speed_rpm_range[1], 4)} r/min`);
    if (td.misalignment_range) parts.push(`Δ ${num(td.misalignment_range[0])}–${num(td.misalignment_range[1])}`);
    if (td.mechanisms) parts.push(td.mechanisms.join("/"));
    if (card.note) parts.push(card.note);
    return parts.join(", ") || "—";
  }
  async function loadModels() {
    setError($("models-error"), "");
    try {
      const m = await api("/models");
      state.models = m;
      const tb = $("models-table").tBodies[0];
      tb.replaceChildren(...m.versions.slice().reverse().map((c) => el("tr", { "data-version": c.version, class: c.active ? "active" : "" },
        el("th", { scope: "row" }, el("code", { text: c.version })),
        el("td", { text: (c.active ? "active" : "—") + (c.activated_by ? ` (activated by ${c.activated_by === "forced" ? "force" : "its plant report"})` : "") }),
        el("td", { text: c.created || c.created_at || "—" }),
        el("td", { text: trainingSummary(c) }),
        el("td", { text: evalSummary(c) }))));
      if (!m.versions.length) tb.append(el("tr", {}, el("td", { colspan: "5", text: "No model is registered yet." })));
    } catch (exc) {
      setError($("models-error"), exc.message);
    }
  }
  async function rollbackModel(ev) {
    ev.preventDefault();
    setError($("rollback-error"), "");
    $("rollback-done").textContent = "";
    const before = state.models && state.models.active;
    try {
      const m = await api("/models/rollback", { method: "POST", headers: { "X-API-Key": $("rollback-key").value } });
      $("rollback-done").textContent = `Active model: ${m.active}` + (before ? ` (was ${before})` : "");
      await loadModels();
      loadHealth();
    } catch (exc) {
      setError($("rollback-error"), exc.message);
    }
  }
  async function loadHealth() {
    const h = $("health");
    try {
      const r = await fetch("/health");
      const body = await r.json();
      h.textContent = `service ${body.status} · version ${body.version} · active model ${body.model_version || "none"}` +
        (body.detail ? ` · ${body.detail}` : "");
      h.classList.toggle("bad", body.status !== "ok");
    } catch (exc) {
      h.textContent = `service unreachable (${exc.message})`;
      h.classList.add("bad");
    }
  }

  // ---- examples -----------------------------------------------------------------------------------
  async function loadExamples() {
    try {
      const list = await api("/ui/examples");
      state.examples = await Promise.all(list.map(async (e) => {
        const resp = await fetch(`/ui/examples/${encodeURIComponent(e.name)}`);
        return { ...e, blob: resp.ok ? await resp.blob() : null };
      }));
      $("example").replaceChildren(...state.examples.map((e) => el("option", { value: e.name, text: `${e.name}: ${e.title}` })));
    } catch (exc) {
      state.examples = [];
      $("example").replaceChildren(el("option", { value: "", text: `examples unavailable (${exc.message})` }));
    }
  }

  // ---- plant: shaft train ------------------------------------------------------------------------
  async function loadTrainPresets() {
    try {
      const list = await api("/trains/presets");
      state.trainPresets = list;
      $("plant-preset").replaceChildren(...list.map((p) => el("option", { value: p.name,
        text: `${p.name} (rated ${p.rated_speed_rpm.join(" / ")} r/min)` })));
      $("plant-preset").value = list.some((p) => p.name === "gen200_2pole") ? "gen200_2pole" : (list[0] || {}).name || "";
    } catch (exc) {
      setError($("plant-error"), `Presets unavailable: ${exc.message}`);
    }
  }
  function renderTrainSummary(s) {
    const rotors = s.rotors.map((r) => `${r.name} ${fixed(r.length_m, 2)} m, ${fixed(r.mass_kg / 1000, 1)} t, ` +
      `${r.n_bearings} bearing${r.n_bearings === 1 ? "" : "s"}`).join("; ");
    $("plant-info").textContent = `${s.source}: ${s.n_stations} stations, ${s.coupling} coupling; ${rotors}.`;
    const m = $("plant-margin");
    m.textContent = `At ${fixed(s.speed_rpm, 0)} r/min: log decrement ${fixed(s.log_decrement, 3)} of the least-damped ` +
      `mode (${fixed(s.mode_frequency_hz, 1)} Hz, ${s.mode_forward ? "forward" : "backward"}) — ` +
      (s.stable ? "stable." : `UNSTABLE. ${s.warning || ""}`);
    m.classList.toggle("bad", !s.stable);
    const tb = $("plant-bearings").tBodies[0];
    tb.replaceChildren(...s.bearings.map((b) => el("tr", { "data-bearing": b.name },
      el("th", { scope: "row", text: b.name }), el("td", { text: b.rotor }), el("td", { text: b.type }),
      el("td", { text: fixed(b.z_m, 2) }), el("td", { text: fixed(b.load_vertical_kn, 1) }),
      el("td", { text: fixed(b.load_horizontal_kn, 1) }), el("td", { text: fixed(b.eccentricity, 2) }),
      el("td", { text: fixed(b.attitude_angle_deg, 1) }))));
    show($("plant-result"), true);
  }
  async function onTrainSummary(ev) {
    ev.preventDefault();
    setError($("plant-error"), "");
    show($("plant-result"), false);
    document.body.dataset.plant = "busy";
    const source = document.querySelector("input[name=plant_source]:checked").value;
    const body = {};
    const speed = $("plant-speed").value.trim();
    if (speed) body.speed_rpm = Number(speed);
    if (source === "preset") {
      body.preset = $("plant-preset").value;
    } else {
      const f = $("plant-file").files[0];
      const refuse = (text) => { setError($("plant-error"), text); document.body.dataset.plant = "error"; };
      if (!f) { refuse("Choose a shaft-line file (TOML) first."); return; }
      if (f.size > 100000) { refuse(`The file is ${f.size} bytes; a shaft line is at most 100000.`); return; }
      if (!speed) { refuse("Give the speed (r/min): a shaft-line file carries no rated speed."); return; }
      body.shaftline_toml = await f.text();
    }
    $("plant-btn").disabled = true;
    document.body.dataset.plant = "busy";
    try {
      renderTrainSummary(await api("/trains/summary", { method: "POST",
        headers: { "Content-Type": "application/json", ...keyHeader() }, body: JSON.stringify(body) },
        "The shaft train cannot be used"));
      document.body.dataset.plant = "done";
    } catch (exc) {
      setError($("plant-error"), exc.message);
      document.body.dataset.plant = "error";
    } finally {
      $("plant-btn").disabled = false;
    }
  }

  // ---- wiring -------------------------------------------------------------------------------------
  document.addEventListener("DOMContentLoaded", () => {
    document.body.dataset.state = "idle";
    $("activate-base").textContent = window.location.origin;
    document.querySelectorAll("input[name=source]").forEach((r) => r.addEventListener("change", () => {
      const source = document.querySelector("input[name=source]:checked").value;
      show($("file-fields"), source === "file"); show($("json-fields"), source === "json");
      show($("example-fields"), source === "example");
    }));
    $("diagnose-form").addEventListener("submit", onDiagnose);
    $("transient-btn").addEventListener("click", onTransient);
    $("transient-store-btn").addEventListener("click", onStoreStartup);
    for (const id of ["show-raw", "show-1x", "show-2x", "show-1x2x", "spectrum-scale"]) $(id).addEventListener("change", renderPlots);
    $("length-units").addEventListener("change", () => { renderPlots(); renderTrend(); });
    $("trend-form").addEventListener("submit", (ev) => { ev.preventDefault(); loadTrend($("trend-asset").value.trim()); });
    $("assets-box").addEventListener("toggle", () => { if ($("assets-box").open) loadAssets(); });
    $("hierarchy-form").addEventListener("submit", onHierarchy);
    $("rollback-form").addEventListener("submit", rollbackModel);
    $("baseline-form").addEventListener("submit", (ev) => ev.preventDefault());
    $("baseline-latest-btn").addEventListener("click", () => setBaseline("latest"));
    $("baseline-auto-btn").addEventListener("click", () => setBaseline("auto"));
    $("baseline-add-btn").addEventListener("click", () => setBaseline("add"));
    loadHealth();
    loadModels();
    loadExamples();
    document.querySelectorAll("input[name=plant_source]").forEach((r) => r.addEventListener("change", () => {
      const file = document.querySelector("input[name=plant_source]:checked").value === "file";
      show($("plant-file-fields"), file); show($("plant-preset-fields"), !file);
    }));
    $("plant-form").addEventListener("submit", onTrainSummary);
    loadTrainPresets();
  });

  // for the end-to-end tests and the console
  window.rotordiag = { state, drawPlot, renderPlots, renderTrend, loadTrend, renderTransient };
})();
