// Styling-curve network parts (paper 004): their curves drawn as lines from
// the part's `network` (snapshot, part_created, network_changed), their
// filled patches from the server's mesh frames (kind 3), and the mouse drag
// of a point of a curve (`network_edit` drag_point: the server keeps the
// curve's meetings where they are). One drag message in flight at a time;
// the newest pointer position goes next. Fairing a part's faces is
// `fairAll` (one `network_edit` fair per face); each runs as a job on the
// server, whose `fairing_progress` and `fairing_ended` (to every client)
// keep `jobs` current (a snapshot's `fairing` lists those running when a
// client joins); `cancelJobs` cancels them. In a measure mode of the view
// (mesh-curvature.js: H, K, k1, k2 and their variations) the patches are
// coloured by the measure estimated on the drawn mesh; in zebra mode they
// get the view's stripes, so tangent-plane continuity across the curves
// shows. The sides' ribbon handles (ribbon-handles.js) and the faces'
// tuning handles (tuning-handles.js) are drawn with each part, shown and
// hidden together, and grabbed (the nearer one) before its curves.

import * as THREE from 'three';
import { curveDerivs } from './bspline.js';
import { curvatureColor } from './view.js';
import { isMeasure, measureOf, meshCurvature } from './mesh-curvature.js';
import { RibbonHandles } from './ribbon-handles.js';
import { TuningHandles } from './tuning-handles.js';

/** Samples per curve for drawing and picking. */
const SAMPLES = 200;
/** How near (pixels) the pointer must be to a curve to grab it. */
const GRAB_PX = 12;

/** The curve of a wire `CurveData` as bspline.js evaluates it. */
function curveOf(c) {
  return { degree: c.knots.degree, knots: Float64Array.from(c.knots.knots), n: c.points.length, points: Float64Array.from(c.points.flat()) };
}

/** Points of `c` at SAMPLES + 1 parameters: { t: Float64Array, xyz: Float32Array }. */
function sample(c) {
  const [a, b] = [c.knots[c.degree], c.knots[c.n]];
  const t = new Float64Array(SAMPLES + 1);
  const xyz = new Float32Array(3 * (SAMPLES + 1));
  for (let k = 0; k <= SAMPLES; k++) {
    t[k] = a + ((b - a) * k) / SAMPLES;
    const p = curveDerivs(c, t[k]).p;
    xyz.set(p, 3 * k);
  }
  return { t, xyz };
}

export class NetworkView {
  /**
   * `view`: the View (scene, camera, canvas, controls); `send(msg)` sends a
   * message and returns its req (null when offline); `canEdit()` whether
   * this page may edit.
   */
  constructor(view, { send, canEdit }) {
    this.view = view;
    this.send = send;
    this.canEdit = canEdit;
    this.group = new THREE.Group();
    this.group.name = 'networks';
    view.model.add(this.group);
    /** Per network part id: { network, curves: [{ curve, samples, line }], mesh, frame }. */
    this.parts = new Map();
    /** Mesh frames of parts not known yet, by part id. */
    this.pending = new Map();
    /** The drag under way: { part, curve, t, plane, pending, inFlight }. */
    this.drag = null;
    /** Fairing jobs running on the server, by `part:face`: their newest `fairing_progress`. */
    this.jobs = new Map();
    /** The last `fairing_ended`. */
    this.lastEnded = null;
    /** The sides' ribbon handles (hidden until `handles.show(true)`). */
    this.handles = new RibbonHandles(view, { send, canEdit });
    /** The faces' tuning handles (tuning-handles.js), shown and hidden with the ribbon handles. */
    this.tuning = new TuningHandles(view, { send, canEdit });
    this.handles.onShow = (on) => this.tuning.show(on);
    const previousMode = view.onModeChange;
    view.onModeChange = () => {
      previousMode.call(view);
      this.restyle();
    };
    const previous = view.bounds;
    view.bounds = () => {
      const box = previous() || new THREE.Box3();
      for (const p of this.parts.values()) for (const c of p.curves) box.expandByObject(c.line);
      return box.isEmpty() ? null : box;
    };
    const canvas = view.renderer.domElement;
    canvas.addEventListener('pointerdown', (e) => this.down(e), { capture: true });
    canvas.addEventListener('pointermove', (e) => this.move(e));
    window.addEventListener('pointerup', () => this.up());
  }

  /** Follows the design's network parts (after a snapshot or part events): drawings added, replaced, removed. */
  sync(design, hidden = new Set()) {
    for (const id of [...this.parts.keys()]) {
      const part = design.parts.get(id);
      if (!part || part.kind !== 'network') this.remove(id);
    }
    // Frames kept from before the snapshot for parts that turned out not to
    // be networks (a DSM part's mesh) are not ours.
    for (const id of [...this.pending.keys()]) {
      const part = design.parts.get(id);
      if (part && part.kind !== 'network') this.pending.delete(id);
    }
    for (const part of design.parts.values()) {
      if (part.kind !== 'network' || !part.network) continue;
      const d = this.parts.get(part.id);
      if (!d || d.network !== part.network) this.setNetwork(part.id, part.network, part.colour);
      const shown = part.visible && !hidden.has(part.id);
      this.parts.get(part.id).root.visible = shown;
    }
  }

  remove(id) {
    const d = this.parts.get(id);
    if (!d) return;
    this.handles.remove(id);
    this.tuning.remove(id);
    this.group.remove(d.root);
    d.root.traverse((o) => o.geometry && o.geometry.dispose());
    this.parts.delete(id);
  }

  /** Part `id`'s curves are now those of `network` (the wire's NetworkData). */
  setNetwork(id, network, colour = '#5b8bd9') {
    let d = this.parts.get(id);
    if (!d) {
      const root = new THREE.Group();
      root.name = `network-${id}`;
      this.group.add(root);
      d = { id, root, curves: [], mesh: null, frame: null, colour };
      this.parts.set(id, d);
    }
    for (const c of d.curves) {
      d.root.remove(c.line);
      c.line.geometry.dispose();
    }
    d.network = network;
    d.curves = network.curves.map((wire, k) => {
      const curve = curveOf(wire);
      const samples = sample(curve);
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(samples.xyz, 3));
      const line = new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0xffd24a }));
      line.name = `network-${id}-curve-${k}`;
      line.renderOrder = 2;
      d.root.add(line);
      return { curve, samples, line };
    });
    this.handles.update(id, d.root, d.curves.map((c) => c.curve), network);
    this.tuning.update(id, d.root, d.curves.map((c) => c.curve), network);
    const waiting = this.pending.get(id);
    if (waiting) {
      this.pending.delete(id);
      this.mesh(waiting);
    }
    this.view.drawn();
  }

  /** A mesh frame of part `f.part`: its patches. False when the part is not a network drawn here. */
  mesh(f) {
    const d = this.parts.get(f.part);
    if (!d) {
      // The compact join sends frames before the snapshot: kept until the part is known.
      this.pending.set(f.part, f);
      return false;
    }
    if (d.frame && d.frame.revision > f.revision) return true;
    d.frame = f;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(f.positions, 3));
    g.setAttribute('normal', new THREE.BufferAttribute(f.normals, 3));
    g.setIndex(new THREE.BufferAttribute(f.indices, 1));
    g.computeBoundingSphere();
    if (d.mesh) {
      d.mesh.geometry.dispose();
      d.mesh.geometry = g;
    } else {
      const material = new THREE.MeshStandardMaterial({ color: d.colour, metalness: 0.1, roughness: 0.5, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
      d.mesh = new THREE.Mesh(g, material);
      d.mesh.name = `network-${f.part}-patches`;
      d.root.add(d.mesh);
    }
    if (!d.shaded) d.shaded = d.mesh.material;
    this.style(d);
    this.view.drawn();
    return true;
  }

  /** Every part's patches drawn for the view's mode (and range). */
  restyle() {
    for (const d of this.parts.values()) this.style(d);
  }

  /**
   * Part `d`'s patches for the view's mode: zebra stripes (the view's shared
   * material: tangent-plane continuity across the curves shows), vertex
   * colours of a measure (blue −range → white 0 → red +range; grey where it
   * could not be estimated), or shaded in the part's colour.
   */
  style(d) {
    if (!d.mesh) return;
    const mode = this.view.mode;
    if (mode === 'zebra') d.mesh.material = this.view.zebra;
    else if (isMeasure(mode)) {
      this.colour(d, mode);
      d.mesh.material = this.view.colored;
    } else d.mesh.material = d.shaded;
  }

  /** Measure `mode` at every vertex of part `id`'s drawn patches (Float64Array), or null when none are drawn. */
  values(id, mode) {
    const d = this.parts.get(id);
    if (!d || !d.frame) return null;
    if (!d.curvature || d.curvature.frame !== d.frame) {
      d.curvature = meshCurvature(d.frame.positions, d.frame.normals, d.frame.indices);
      d.curvature.frame = d.frame;
    }
    return measureOf(d.curvature, mode);
  }

  /** The values of measure `mode` on every shown part's patches. */
  shownValues(mode) {
    return [...this.parts.values()].filter((d) => d.root.visible && d.frame).map((d) => this.values(d.id, mode));
  }

  colour(d, mode) {
    const v = this.values(d.id, mode);
    const g = d.mesh.geometry;
    let attr = g.getAttribute('color');
    if (!attr || attr.count !== v.length) {
      attr = new THREE.BufferAttribute(new Float32Array(3 * v.length), 3);
      g.setAttribute('color', attr);
    }
    const out = attr.array;
    for (let i = 0; i < v.length; i++) {
      if (Number.isFinite(v[i])) curvatureColor(v[i], this.view.range, out, 3 * i);
      else out.fill(0.5, 3 * i, 3 * i + 3);
    }
    attr.needsUpdate = true;
  }

  /** Pointer position in pixels of the canvas. */
  pixel(e) {
    const r = this.view.renderer.domElement.getBoundingClientRect();
    return [e.clientX - r.left, e.clientY - r.top, r.width, r.height];
  }

  /** The curve sample nearest the pointer on screen within GRAB_PX: { part, curve, t, xyz } or null. */
  nearest(e) {
    const [x, y, w, h] = this.pixel(e);
    const v = new THREE.Vector3();
    let best = null;
    for (const d of this.parts.values()) {
      if (!d.root.visible) continue;
      d.curves.forEach((c, k) => {
        const s = c.samples;
        for (let i = 0; i < s.t.length; i++) {
          v.set(s.xyz[3 * i], s.xyz[3 * i + 1], s.xyz[3 * i + 2]);
          const world = v.clone();
          this.view.model.localToWorld(world);
          v.copy(world).project(this.view.camera);
          const px = ((v.x + 1) / 2) * w;
          const py = ((1 - v.y) / 2) * h;
          const dist = Math.hypot(px - x, py - y);
          if (dist <= GRAB_PX && (!best || dist < best.dist)) best = { part: d.id, curve: k, t: s.t[i], world, dist };
        }
      });
    }
    return best;
  }

  down(e) {
    if (!this.canEdit() || e.button !== 0) return;
    // The nearer of the ribbon and tuning handles under the pointer.
    const px = this.pixel(e);
    const [ribbon, tuning] = [this.handles.nearest(...px), this.tuning.nearest(...px)];
    const grabbed = tuning && (!ribbon || tuning.dist < ribbon.dist) ? this.tuning.grab(tuning) : this.handles.grab(ribbon);
    if (grabbed) {
      e.stopImmediatePropagation();
      this.view.controls.enabled = false;
      return;
    }
    const hit = this.nearest(e);
    if (!hit) return;
    // Neither the orbit controls nor the icon picking see this press.
    e.stopImmediatePropagation();
    this.view.controls.enabled = false;
    const normal = new THREE.Vector3();
    this.view.camera.getWorldDirection(normal);
    this.drag = { part: hit.part, curve: hit.curve, t: hit.t, plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, hit.world), pending: null, inFlight: false };
  }

  move(e) {
    if (this.handles.drag) {
      this.handles.move(...this.pixel(e));
      return;
    }
    if (this.tuning.drag) {
      this.tuning.move(...this.pixel(e));
      return;
    }
    if (!this.drag) return;
    const [x, y, w, h] = this.pixel(e);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(new THREE.Vector2((x / w) * 2 - 1, 1 - (y / h) * 2), this.view.camera);
    const world = ray.ray.intersectPlane(this.drag.plane, new THREE.Vector3());
    if (!world) return;
    this.drag.pending = this.view.model.worldToLocal(world.clone()).toArray();
    this.flush();
  }

  /** Sends the newest pointer position unless a drag message is still unanswered. */
  flush() {
    const d = this.drag;
    if (!d || d.inFlight || !d.pending) return;
    const xyz = d.pending;
    d.pending = null;
    const req = this.send({ type: 'network_edit', part: d.part, edit: { op: 'drag_point', curve: d.curve, t: d.t, xyz } });
    if (req !== null && req !== undefined) {
      d.inFlight = req;
    }
  }

  /** The server answered request `req` (ack or error, `failed`): the next drag position may go. */
  answered(req, failed = false) {
    this.handles.answered(req, failed);
    this.tuning.answered(req, failed);
    if (this.drag && this.drag.inFlight === req) {
      this.drag.inFlight = false;
      this.flush();
    }
  }

  up() {
    if (this.handles.up() || this.tuning.up()) {
      this.view.controls.enabled = true;
      return;
    }
    if (!this.drag) return;
    this.drag = null;
    this.view.controls.enabled = true;
  }

  /**
   * Fairs every face of network part `id` toward its boundary's mean
   * curvature (`options`: `measure` — 'mean' or 'gaussian' —, `relaxation`,
   * `tolerance` of the request). Returns the number of requests sent.
   */
  fairAll(id, maxIterations = 100, options = {}) {
    const d = this.parts.get(id);
    if (!d) return 0;
    let sent = 0;
    d.network.faces.forEach((_, face) => {
      if (this.send({ type: 'network_edit', part: id, edit: { op: 'fair', face, measure: 'mean', goal: 'from_boundary', max_iterations: maxIterations, ...options } }) !== null) sent++;
    });
    return sent;
  }

  /** A `fairing_progress` or `fairing_ended` from the server. */
  fairing(msg) {
    const key = `${msg.part}:${msg.face}`;
    if (msg.type === 'fairing_progress') this.jobs.set(key, msg);
    else {
      this.jobs.delete(key);
      this.lastEnded = msg;
    }
  }

  /**
   * A snapshot's `fairing`: the jobs running now (each with its latest
   * progress) replace those known; a job missing from it has ended.
   */
  setJobs(list) {
    this.jobs.clear();
    for (const j of list) this.jobs.set(`${j.part}:${j.face}`, { type: 'fairing_progress', ...j });
  }

  /** The jobs running on network part `id` (every part's when `id` is null). */
  jobsOf(id = null) {
    return [...this.jobs.values()].filter((j) => id === null || j.part === id);
  }

  /** Cancels the jobs of part `id` (every part's when null); returns how many cancels were sent. */
  cancelJobs(id = null) {
    let sent = 0;
    for (const j of this.jobsOf(id)) if (this.send({ type: 'cancel_fairing', part: j.part, face: j.face }) !== null) sent++;
    return sent;
  }

  /** The jobs' progress: { count, fraction (mean), iteration (largest) }. */
  progress(id = null) {
    const jobs = this.jobsOf(id);
    if (!jobs.length) return { count: 0, fraction: 0, iteration: 0 };
    return {
      count: jobs.length,
      fraction: jobs.reduce((s, j) => s + j.fraction, 0) / jobs.length,
      iteration: Math.max(...jobs.map((j) => j.iteration)),
    };
  }
}
