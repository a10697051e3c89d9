// tether replay: the 3-D scene (three.js, inlined above as the global THREE).
// z is up; all coordinates are metres, as in the run folder.
"use strict";

const TRAIL_FRAMES = 500;

function hexColour(hex) { return new THREE.Color(hex); }

function lerpStops(stops, u) {
  // colour at u in [0, 1] along evenly spaced stops (THREE.Color list)
  u = Math.min(1, Math.max(0, u));
  const x = u * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(x));
  return stops[i].clone().lerp(stops[i + 1], x - i);
}

class Orbit {
  // A small orbit camera control: drag to rotate, right/shift-drag to pan, wheel to zoom.
  constructor(camera, dom, target, radius, elevation, onChange) {
    this.camera = camera; this.dom = dom; this.onChange = onChange;
    this.home = { target: target.clone(), radius, theta: -Math.PI / 2 + 0.35, phi: elevation };
    this.reset();
    let drag = null;
    dom.addEventListener("contextmenu", (e) => e.preventDefault());
    dom.addEventListener("pointerdown", (e) => {
      drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
      dom.setPointerCapture(e.pointerId);
    });
    dom.addEventListener("pointermove", (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX; drag.y = e.clientY;
      if (drag.pan) this.pan(dx, dy); else this.rotate(dx, dy);
    });
    dom.addEventListener("pointerup", () => { drag = null; });
    dom.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.radius *= Math.exp(e.deltaY * 0.001);
      this.update();
    }, { passive: false });
    dom.addEventListener("dblclick", () => this.reset());
  }
  reset() {
    this.target = this.home.target.clone(); this.radius = this.home.radius;
    this.theta = this.home.theta; this.phi = this.home.phi;
    this.update();
  }
  rotate(dx, dy) {
    this.theta -= dx * 0.006;
    this.phi = Math.min(Math.PI / 2 - 0.001, Math.max(-0.2, this.phi + dy * 0.006));
    this.update();
  }
  pan(dx, dy) {
    const s = this.radius * 0.0015;
    const right = new THREE.Vector3(-Math.sin(this.theta), Math.cos(this.theta), 0);
    const fwd = new THREE.Vector3(-Math.cos(this.theta), -Math.sin(this.theta), 0);
    this.target.addScaledVector(right, -dx * s).addScaledVector(fwd, dy * s);
    this.update();
  }
  update() {
    const c = Math.cos(this.phi), t = this.target;
    this.camera.position.set(
      t.x + this.radius * c * Math.cos(this.theta),
      t.y + this.radius * c * Math.sin(this.theta),
      t.z + this.radius * Math.sin(this.phi));
    this.camera.lookAt(t);
    this.onChange();
  }
}

class ReplayScene {
  constructor(container, run) {
    this.run = run;
    const m = run.meta, pal = m.palette;
    THREE.Object3D.DEFAULT_UP.set(0, 0, 1);
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    container.appendChild(this.renderer.domElement);
    this.container = container;
    this.scene = new THREE.Scene();
    this.scene.background = hexColour(pal.background);
    this.scene.add(new THREE.AmbientLight(0xffffff, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.8);
    sun.position.set(0.4, -0.7, 1.0);
    this.scene.add(sun);

    const lo = new THREE.Vector3(...m.extent_m[0]), hi = new THREE.Vector3(...m.extent_m[1]);
    const size = hi.clone().sub(lo);
    this.size = Math.max(size.x, size.y, size.z, 1);
    // the camera starts on where the robots move, not on the whole world
    const flo = new THREE.Vector3(...m.focus_m[0]), fhi = new THREE.Vector3(...m.focus_m[1]);
    const centre = flo.clone().add(fhi).multiplyScalar(0.5);
    if (m.dim === 2) centre.z = 0;
    const fsize = fhi.clone().sub(flo);
    const focus = Math.min(this.size, Math.max(fsize.x, fsize.y, fsize.z, 2 * m.range_m));
    // robots sized by the link range (the team's scale), not by the world
    this.rad = Math.max(Math.min(0.06 * m.range_m, 0.009 * this.size), 0.02);
    this.camera = new THREE.PerspectiveCamera(45, 1, this.size / 2000, this.size * 50);
    this.linkStops = pal.link_stops.map(hexColour);
    this.groups = { links: [], paths: [], obstacles: [] };
    this.buildGround(lo, hi);
    this.buildObstacles();
    this.buildRobots();
    this.buildStatic();
    this.buildTrails();
    this.buildLinks();
    this.dirty = true;
    this.orbit = new Orbit(this.camera, this.renderer.domElement, centre, focus * 1.35,
      m.dim === 2 ? 1.05 : 0.6, () => { this.dirty = true; });
    this.resize();
    window.addEventListener("resize", () => this.resize());
    const loop = () => {
      if (this.dirty) { this.dirty = false; this.renderer.render(this.scene, this.camera); }
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  resize() {
    const w = this.container.clientWidth || 600, h = this.container.clientHeight || 400;
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.dirty = true;
  }

  buildGround(lo, hi) {
    const m = this.run.meta, w = m.world, pal = m.palette;
    if (w.kind === "map") {
      const nx = w.nx, ny = w.ny, occ = this.run.arrays.map_occupied;
      this.mapPixels = new Uint8Array(nx * ny * 4);
      this.mapColours = ["free", "occupied", "unknown", "unknown_occupied"].map((k) => {
        const c = hexColour(pal[k]); return [c.r * 255, c.g * 255, c.b * 255];
      });
      this.mapTexture = new THREE.DataTexture(this.mapPixels, nx, ny, THREE.RGBAFormat);
      this.mapTexture.magFilter = THREE.NearestFilter;
      this.mapTexture.colorSpace = THREE.SRGBColorSpace;
      this.paintMap(-1, occ);
      const plane = new THREE.Mesh(
        new THREE.PlaneGeometry(nx * w.cell_m, ny * w.cell_m),
        new THREE.MeshBasicMaterial({ map: this.mapTexture }));
      plane.position.set(w.origin_m[0] + nx * w.cell_m / 2, w.origin_m[1] + ny * w.cell_m / 2, -0.01);
      this.scene.add(plane);
      this.groups.obstacles.push(plane);
      return;
    }
    const step = Math.pow(10, Math.floor(Math.log10(this.size / 4)));
    const span = Math.ceil(this.size / step) * step;
    const grid = new THREE.GridHelper(span, Math.round(span / step), 0xbbbbbb, 0xdddddd);
    grid.rotation.x = Math.PI / 2;
    grid.position.set((lo.x + hi.x) / 2, (lo.y + hi.y) / 2, m.dim === 3 ? Math.min(lo.z, 0) : -0.01);
    this.scene.add(grid);
  }

  paintMap(frame, occ) {
    // occupancy + (optionally) knowledge at `frame` into the ground texture
    const first = this.run.arrays.map_first_seen, px = this.mapPixels, cols = this.mapColours;
    occ = occ || this.run.arrays.map_occupied;
    let unknown = 0;
    for (let i = 0; i < occ.length; i++) {
      let s = occ[i];
      if (first && !(first[i] <= frame)) { s += 2; unknown++; }
      const c = cols[s];
      px[4 * i] = c[0]; px[4 * i + 1] = c[1]; px[4 * i + 2] = c[2]; px[4 * i + 3] = 255;
    }
    this.mapTexture.needsUpdate = true;
    this.unknownCells = unknown;
  }

  buildObstacles() {
    const m = this.run.meta, w = m.world;
    if (w.kind !== "boxes" || !w.n) return;
    const b = this.run.arrays.boxes, stops = m.palette.height_stops.map(hexColour);
    const mesh = new THREE.InstancedMesh(new THREE.BoxGeometry(1, 1, 1),
      new THREE.MeshLambertMaterial({ color: 0xffffff }), w.n);
    const mat = new THREE.Matrix4(), q = new THREE.Quaternion();
    for (let k = 0; k < w.n; k++) {
      const o = 6 * k;
      const p = new THREE.Vector3((b[o] + b[o + 3]) / 2, (b[o + 1] + b[o + 4]) / 2, (b[o + 2] + b[o + 5]) / 2);
      const s = new THREE.Vector3(b[o + 3] - b[o], b[o + 4] - b[o + 1], b[o + 5] - b[o + 2]);
      mesh.setMatrixAt(k, mat.compose(p, q, s));
      mesh.setColorAt(k, lerpStops(stops, b[o + 5] / Math.max(w.top_m, 1e-9)));
    }
    this.scene.add(mesh);
    this.groups.obstacles.push(mesh);
  }

  buildRobots() {
    const n = this.run.meta.n_robots;
    this.robots = new THREE.InstancedMesh(new THREE.SphereGeometry(this.rad, 18, 12),
      new THREE.MeshLambertMaterial({ color: 0xffffff }), n);
    this.robots.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
    this.robotColours = this.run.meta.colours.hex.map(hexColour);
    this.leaderColour = hexColour(this.run.meta.palette.leader);
    for (let r = 0; r < n; r++) this.robots.setColorAt(r, this.robotColours[0]);
    this.robots.frustumCulled = false;
    this.scene.add(this.robots);
  }

  buildStatic() {
    const m = this.run.meta, pal = m.palette, lift = m.dim === 2 ? this.rad : 0;
    if (m.base_m) {
      const bs = new THREE.Mesh(new THREE.BoxGeometry(2.4 * this.rad, 2.4 * this.rad, 2.4 * this.rad),
        new THREE.MeshLambertMaterial({ color: hexColour(pal.base_station) }));
      bs.position.set(m.base_m[0][0], m.base_m[0][1], m.base_m[0][2] + lift);
      this.scene.add(bs);
    }
    this.targets = [];
    for (const t of m.targets_m || []) {
      const g = new THREE.Mesh(new THREE.OctahedronGeometry(1.6 * this.rad),
        new THREE.MeshLambertMaterial({ color: hexColour(pal.target) }));
      g.position.set(t[0], t[1], t[2] + lift);
      this.scene.add(g);
      this.targets.push(g);
    }
    if (m.planned_path_m) {
      const pts = m.planned_path_m.map((p) => new THREE.Vector3(p[0], p[1], p[2] + 0.02));
      const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts),
        new THREE.LineDashedMaterial({ color: hexColour(pal.path), dashSize: this.size / 80, gapSize: this.size / 120 }));
      line.computeLineDistances();
      this.scene.add(line);
      this.groups.paths.push(line);
    }
  }

  buildTrails() {
    // one segment per (frame, robot), frame-major, so a draw range shows every trail up to a frame
    const run = this.run, F = run.meta.n_frames, n = run.meta.n_robots, P = run.positions;
    const lift = run.meta.dim === 2 ? 0.01 : 0;
    const pos = new Float32Array(Math.max(F - 1, 0) * n * 6);
    for (let f = 0; f + 1 < F; f++) {
      for (let r = 0; r < n; r++) {
        const a = (f * n + r) * 3, b = ((f + 1) * n + r) * 3, o = (f * n + r) * 6;
        const ok = run.valid[f * n + r] && run.valid[(f + 1) * n + r];
        for (let d = 0; d < 3; d++) {
          pos[o + d] = P[a + d] + (d === 2 ? lift : 0);
          pos[o + 3 + d] = (ok ? P[b + d] : P[a + d]) + (d === 2 ? lift : 0);
        }
      }
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute("position", new THREE.BufferAttribute(pos, 3));
    this.trails = new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ color: 0x666666, transparent: true, opacity: 0.35 }));
    this.trails.frustumCulled = false;
    this.scene.add(this.trails);
    this.groups.paths.push(this.trails);
  }

  buildLinks() {
    const off = this.run.arrays.link_off;
    let most = 0;
    for (let f = 0; f + 1 < off.length; f++) most = Math.max(most, off[f + 1] - off[f]);
    this.linkPos = new Float32Array(Math.max(most, 1) * 6);
    this.linkCol = new Float32Array(Math.max(most, 1) * 6);
    const geo = new THREE.BufferGeometry();
    geo.setAttribute("position", new THREE.BufferAttribute(this.linkPos, 3).setUsage(THREE.DynamicDrawUsage));
    geo.setAttribute("color", new THREE.BufferAttribute(this.linkCol, 3).setUsage(THREE.DynamicDrawUsage));
    geo.setDrawRange(0, 0);
    this.links = new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ vertexColors: true }));
    this.links.frustumCulled = false;
    this.scene.add(this.links);
    this.groups.links.push(this.links);
  }

  nodePosition(f, i, out) {
    const m = this.run.meta, n = m.n_robots, lift = m.dim === 2 ? this.rad : 0;
    if (i >= n) return out.set(m.base_m[0][0], m.base_m[0][1], m.base_m[0][2] + lift);
    const P = this.run.positions, a = (f * n + i) * 3;
    return out.set(P[a], P[a + 1], P[a + 2] + lift);
  }

  setFrame(f) {
    const run = this.run, m = run.meta, n = m.n_robots, A = run.arrays;
    const mat = new THREE.Matrix4(), v = new THREE.Vector3(), w = new THREE.Vector3();
    const q = new THREE.Quaternion(), one = new THREE.Vector3(1, 1, 1), zero = new THREE.Vector3(0, 0, 0);
    for (let r = 0; r < n; r++) {
      this.nodePosition(f, r, v);
      this.robots.setMatrixAt(r, mat.compose(v, q, run.valid[f * n + r] ? one : zero));
      let c = this.robotColours[A.colour_idx ? A.colour_idx[f * n + r] : 0];
      if (m.leader === r) c = this.leaderColour;
      this.robots.setColorAt(r, c);
    }
    this.robots.instanceMatrix.needsUpdate = true;
    this.robots.instanceColor.needsUpdate = true;
    const lo = A.link_off[f], hi = A.link_off[f + 1], ij = A.link_ij;
    for (let k = lo; k < hi; k++) {
      this.nodePosition(f, ij[2 * k], v);
      this.nodePosition(f, ij[2 * k + 1], w);
      const margin = A.link_w ? A.link_w[k] / 255 : 1 - v.distanceTo(w) / m.range_m;
      const c = lerpStops(this.linkStops, margin), o = (k - lo) * 6;
      this.linkPos.set([v.x, v.y, v.z, w.x, w.y, w.z], o);
      this.linkCol.set([c.r, c.g, c.b, c.r, c.g, c.b], o);
    }
    const g = this.links.geometry;
    g.attributes.position.needsUpdate = true;
    g.attributes.color.needsUpdate = true;
    g.setDrawRange(0, (hi - lo) * 2);
    const from = Math.max(0, f - TRAIL_FRAMES);  // the last TRAIL_FRAMES frames of each trail
    this.trails.geometry.setDrawRange(from * n * 2, (f - from) * n * 2);
    if (A.map_first_seen) this.paintMap(f);
    this.showTargets(f);
    if (this.follow) this.orbit.target.copy(this.centroid(f)), this.orbit.update();
    this.frame = f;
    this.dirty = true;
  }

  showTargets(f) {
    // a target appears when it is added (or appears), and turns to a wireframe once reached
    const when = this.run.meta.target_frames;
    if (!when) return;
    this.targets.forEach((g, k) => {
      const [shown, done] = when[k];
      g.visible = shown >= 0 && f >= shown;
      g.material.wireframe = done >= 0 && f >= done;
    });
  }

  targetStates() {
    // per target: 0 hidden, 1 open, 2 reached or dropped (as drawn now)
    return this.targets.map((g) => (!g.visible ? 0 : g.material.wireframe ? 2 : 1));
  }

  centroid(f) {
    const n = this.run.meta.n_robots, c = new THREE.Vector3(), v = new THREE.Vector3();
    let k = 0;
    for (let r = 0; r < n; r++) {
      if (!this.run.valid[f * n + r]) continue;
      c.add(this.nodePosition(f, r, v)); k++;
    }
    return k ? c.multiplyScalar(1 / k) : this.orbit.target.clone();
  }

  spread(f) {
    // largest distance of a robot from the team's centroid at frame f (m)
    const n = this.run.meta.n_robots, c = this.centroid(f), v = new THREE.Vector3();
    let most = 0;
    for (let r = 0; r < n; r++) if (this.run.valid[f * n + r]) most = Math.max(most, this.nodePosition(f, r, v).distanceTo(c));
    return most;
  }

  setFollow(on) {
    this.follow = on;
    if (on) {
      this.orbit.radius = Math.min(this.orbit.radius, Math.max(4 * this.spread(this.frame || 0), 3 * this.run.meta.range_m));
      this.orbit.target.copy(this.centroid(this.frame || 0));
    } else {
      this.orbit.target.copy(this.orbit.home.target);
      this.orbit.radius = this.orbit.home.radius;
    }
    this.orbit.update();
  }

  setVisible(group, on) {
    for (const o of this.groups[group]) o.visible = on;
    this.dirty = true;
  }

  markerPositions() {
    // where the robot markers are drawn now (read back from the instanced mesh)
    const out = [], mat = new THREE.Matrix4(), p = new THREE.Vector3();
    for (let r = 0; r < this.run.meta.n_robots; r++) {
      this.robots.getMatrixAt(r, mat);
      p.setFromMatrixPosition(mat);
      out.push([p.x, p.y, p.z]);
    }
    return out;
  }
}
