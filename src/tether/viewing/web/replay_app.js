// tether replay: decode the embedded run, wire the controls and the side plots.
"use strict";

const TYPED = { uint8: Uint8Array, uint16: Uint16Array, uint32: Uint32Array, int32: Int32Array,
  float32: Float32Array, float64: Float64Array };

async function decodeRun() {
  const meta = JSON.parse(document.getElementById("tether-meta").textContent);
  const text = atob(document.getElementById("tether-data").textContent.trim());
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
  const buf = await new Response(stream).arrayBuffer();
  const arrays = {};
  for (const a of meta.arrays) arrays[a.name] = new TYPED[a.dtype](buf, a.offset, a.length);
  // positions: uint16 differences along frames, robot by robot -> (frame, robot, xyz) metres
  const F = meta.n_frames, n = meta.n_robots, q = arrays.pos, Q = meta.quant;
  const positions = new Float32Array(F * n * 3), valid = new Uint8Array(F * n).fill(1);
  for (let d = 0; d < 3; d++) {
    for (let r = 0; r < n; r++) {
      let acc = 0;
      const base = (d * n + r) * F;
      for (let f = 0; f < F; f++) {
        acc = (acc + q[base + f]) & 0xffff;
        const i = f * n + r;
        if (acc === Q.missing) valid[i] = 0;
        else positions[i * 3 + d] = Q.lo[d] + acc * Q.scale[d];
      }
    }
  }
  return { meta, arrays, positions, valid };
}

function drawPlot(canvas, t, y, label, cursorT, cursorColour) {
  const dpr = window.devicePixelRatio || 1, w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.round(w * dpr)) { canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr); }
  const g = canvas.getContext("2d");
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, w, h);
  const L = 38, R = 6, T = 6, B = 18;
  let lo = Infinity, hi = -Infinity;
  for (const v of y) if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  if (!Number.isFinite(lo)) { lo = 0; hi = 1; }
  if (hi - lo < 1e-12) { hi += 0.5; lo -= 0.5; }
  const t0 = t[0], t1 = t[t.length - 1] > t0 ? t[t.length - 1] : t0 + 1;
  const X = (v) => L + (v - t0) / (t1 - t0) * (w - L - R), Y = (v) => T + (hi - v) / (hi - lo) * (h - T - B);
  g.strokeStyle = "#ccc"; g.strokeRect(L, T, w - L - R, h - T - B);
  g.fillStyle = "#555"; g.font = "10px system-ui, sans-serif";
  g.fillText(hi.toPrecision(3), 2, T + 8); g.fillText(lo.toPrecision(3), 2, h - B);
  g.fillText(t0.toFixed(0) + " s", L, h - 5); g.fillText(t1.toFixed(0) + " s", w - R - 34, h - 5);
  g.strokeStyle = "#333"; g.lineWidth = 1; g.beginPath();
  let pen = false;
  for (let i = 0; i < t.length; i++) {
    if (!Number.isFinite(y[i])) { pen = false; continue; }
    if (pen) g.lineTo(X(t[i]), Y(y[i])); else g.moveTo(X(t[i]), Y(y[i]));
    pen = true;
  }
  g.stroke();
  g.strokeStyle = cursorColour; g.lineWidth = 1.5; g.beginPath();
  g.moveTo(X(cursorT), T); g.lineTo(X(cursorT), h - B); g.stroke();
  return { x0: L, x1: w - R, t0, t1 };
}

function swatch(colour, kind) {
  const s = document.createElement("span");
  s.className = "sw" + (kind ? " " + kind : "");
  s.style.background = colour;
  return s;
}

function buildLegend(meta) {
  const el = document.getElementById("legend"), pal = meta.palette;
  const add = (node, text) => { const d = document.createElement("div"); d.append(node, text); el.append(d); };
  meta.colours.names.forEach((name, k) => add(swatch(meta.colours.hex[k]), name));
  if (meta.leader !== null && meta.leader !== undefined) add(swatch(pal.leader), "leader (robot " + meta.leader + ")");
  if (meta.base_m) add(swatch(pal.base_station, "sq"), "base station");
  if (meta.targets_m) add(swatch(pal.target, "sq"), "target");
  if (meta.planned_path_m) add(swatch(pal.path, "ln"), "planned path");
  add(swatch("#999", "ln"), "robot trails");
  const g = document.createElement("span");
  g.className = "grad";
  g.style.setProperty("--bad", pal.link_stops[0]); g.style.setProperty("--mid", pal.link_stops[1]);
  g.style.setProperty("--good", pal.link_stops[2]);
  add(g, meta.link_weights ? "link weight: low ... high" : "link: near range ... strong");
  if (meta.world.kind === "map") {
    add(swatch(pal.occupied, "sq"), "occupied");
    if (meta.world.known !== "none") {
      add(swatch(pal.unknown, "sq"), meta.world.known === "exact" ? "unknown (base station map)" : "not yet seen (approx.)");
    }
  }
  if (meta.world.kind === "boxes") add(swatch(pal.height_stops[1], "sq"), "obstacles, darker = taller");
}

async function main() {
  const run = await decodeRun();
  const m = run.meta, A = run.arrays, F = m.n_frames;
  document.getElementById("title").textContent = m.name + (m.strategy ? " (" + m.strategy + ")" : "");
  const notes = [];
  notes.push(m.n_robots + " robots, " + m.dim + "-D, " + m.n_frames_recorded + " recorded steps" +
    (m.stride > 1 ? ", 1 in " + m.stride + " shown (size budget)" : ""));
  notes.push("link margin = 1 - distance / " + m.range_m + " m");
  for (const s of m.notes || []) notes.push(s);
  document.getElementById("notes").textContent = notes.join(" · ");
  buildLegend(m);

  let scene = null;
  try {
    scene = new ReplayScene(document.getElementById("view"), run);
  } catch (err) {
    const e = document.createElement("div");
    e.id = "webgl-error";
    e.textContent = "3-D view unavailable (WebGL: " + err.message + "); the plots still work.";
    document.getElementById("view").append(e);
  }

  const plots = [];
  const plotBox = document.getElementById("plots");
  for (const s of m.series) {
    const h = document.createElement("h2"); h.textContent = s.label;
    const c = document.createElement("canvas"); c.className = "plot"; c.id = "plot-" + s.name;
    plotBox.append(h, c);
    plots.push({ canvas: c, y: A["series_" + s.name], label: s.label, geom: null });
  }
  const slider = document.getElementById("slider"), timeEl = document.getElementById("time");
  slider.max = String(Math.max(F - 1, 0));
  let frame = 0;

  function show(f) {
    frame = Math.max(0, Math.min(F - 1, f | 0));
    slider.value = String(frame);
    const t = A.frame_t[frame];
    const nl = A.link_off[frame + 1] - A.link_off[frame];
    timeEl.textContent = "t = " + t.toFixed(1) + " s · step " + A.frame_steps[frame] + " · " + nl + " links";
    if (scene) scene.setFrame(frame);
    for (const p of plots) p.geom = drawPlot(p.canvas, A.series_t, p.y, p.label, t, m.palette.cursor);
    window.tether.frame = frame;
  }

  function seekTime(t) {
    let lo = 0, hi = F - 1;
    while (lo < hi) { const mid = (lo + hi) >> 1; if (A.frame_t[mid] < t) lo = mid + 1; else hi = mid; }
    if (lo > 0 && Math.abs(A.frame_t[lo - 1] - t) < Math.abs(A.frame_t[lo] - t)) lo -= 1;
    show(lo);
  }
  for (const p of plots) {
    const seek = (e) => {
      if (!p.geom) return;
      const r = p.canvas.getBoundingClientRect(), g = p.geom;
      seekTime(g.t0 + (e.clientX - r.left - g.x0) / (g.x1 - g.x0) * (g.t1 - g.t0));
    };
    p.canvas.addEventListener("pointerdown", (e) => { seek(e); p.canvas.setPointerCapture(e.pointerId); });
    p.canvas.addEventListener("pointermove", (e) => { if (e.buttons) seek(e); });
  }

  slider.addEventListener("input", () => show(parseInt(slider.value, 10)));
  for (const [id, group] of [["show-links", "links"], ["show-paths", "paths"], ["show-obstacles", "obstacles"]]) {
    const box = document.getElementById(id);
    box.addEventListener("change", () => { if (scene) scene.setVisible(group, box.checked); });
  }
  const followBox = document.getElementById("follow");
  followBox.addEventListener("change", () => { if (scene) scene.setFollow(followBox.checked); });
  if (scene && F > 1) {
    // a team that stays small while it travels far: follow it from the start
    const lo = m.focus_m[0], hi = m.focus_m[1];
    const span = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    if (scene.spread(0) < 0.15 * span) { followBox.checked = true; scene.setFollow(true); }
  }
  const playBtn = document.getElementById("play"), speedSel = document.getElementById("speed");
  const baseRate = Math.min(30, Math.max(2, F / 20)); // frames per second at 1x: about 20 s
  let playing = false, last = 0, carry = 0;
  function tick(now) {
    if (!playing) return;
    carry += (now - last) / 1000 * baseRate * parseFloat(speedSel.value);
    last = now;
    if (carry >= 1) {
      const stepBy = Math.floor(carry); carry -= stepBy;
      if (frame + stepBy >= F - 1) { show(F - 1); setPlaying(false); return; }
      show(frame + stepBy);
    }
    requestAnimationFrame(tick);
  }
  function setPlaying(on) {
    if (on && frame >= F - 1) show(0);
    playing = on;
    playBtn.textContent = on ? "Pause" : "Play";
    if (on) { last = performance.now(); carry = 0; requestAnimationFrame(tick); }
  }
  playBtn.addEventListener("click", () => setPlaying(!playing));
  document.addEventListener("keydown", (e) => {
    if (e.target.tagName === "SELECT") return;
    if (e.code === "Space") { e.preventDefault(); setPlaying(!playing); }
    if (e.code === "ArrowRight") show(frame + 1);
    if (e.code === "ArrowLeft") show(frame - 1);
  });
  window.addEventListener("resize", () => show(frame));

  Object.assign(window.tether, {
    nFrames: F,
    meta: m,
    show,
    webgl: scene !== null,
    markerPositions: () => (scene ? scene.markerPositions() : []),
    drawnLinks: () => (scene ? scene.links.geometry.drawRange.count / 2 : 0),
    linkEnds: () => (scene ? Array.from(scene.linkPos.subarray(0, scene.links.geometry.drawRange.count * 3)) : []),
    playing: () => playing,
    visibility: () => {
      const out = {};
      if (scene) for (const [k, v] of Object.entries(scene.groups)) out[k] = v.length ? v[0].visible : null;
      return out;
    },
    unknownCells: () => (scene && scene.mapPixels ? scene.unknownCells : null),
    targetStates: () => (scene ? scene.targetStates() : []),
  });
  show(0);
  window.tether.ready = true;
}

window.tether = { ready: false, error: null };
main().catch((err) => {
  window.tether.error = String(err && err.stack ? err.stack : err);
  document.getElementById("notes").textContent = "replay failed: " + err;
  throw err;
});
