// Coons body parts (paper 002) in the 3D view, from their body frames
// (kind 4): the shaded boundary in the part's colour, isoparametric lines at
// constant u (red), v (green) and w (blue) on it (§2.1), and the lattice
// points as handles.
//
// Editing: a handle pressed and dragged moves that point (with Shift held,
// its face) in the screen's plane; a handle clicked selects, by the chosen
// mode, that point, a face it lies on or an edge it lies on (clicking it
// again cycles through its faces or edges; Escape lets go), and a
// TransformControls gizmo moves the selection. Each drag is sent as one `body_edit` when released;
// the server refuses an edit that folds the body and says where: the page
// shows the message and marks the place, and the handles go back.
//
// Looking inside: a cutting plane at x, y or z = offset shows the body's
// section coloured by det J, the interior distribution the lattice shapes,
// with a legend; the page evaluates the volume itself from the frame's
// lattice, degrees and knots (body-volume.js, body-section.js), and the
// boundary on the far side of the plane is clipped away.
//
// Metamorphosis: a time slider and a play button; the page sends
// `body_morph` and every page of the design gets the frames.

import * as THREE from 'three';
import { TransformControls } from 'three/addons/controls/TransformControls.js';
import { BSplineVolume } from './body-volume.js';
import { SectionGrid } from './body-section.js';

const LINE_COLOURS = [0xe05050, 0x50c050, 0x5080f0];
/** Morph time step per animation frame while playing (about 2 s for 0 → 1 at 60 Hz). */
const PLAY_STEP = 1 / 120;
/** det J varying by less than this fraction over a section counts as constant (the frame's lattice is f32). */
const SPREAD = 1e-5;
/** The faces' names, per direction: [at the start, at the end]. */
const FACE_NAMES = [['u_min', 'u_max'], ['v_min', 'v_max'], ['w_min', 'w_max']];
/** The det J colour scale, low to high (viridis, sampled). */
const SCALE = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551], [0.369, 0.789, 0.383], [0.993, 0.906, 0.144]];

/** The colour of `f` ∈ [0, 1] on the det J scale, as [r, g, b]. */
export function scaleColour(f) {
  const x = Math.min(1, Math.max(0, Number.isFinite(f) ? f : 0.5)) * (SCALE.length - 1);
  const i = Math.min(SCALE.length - 2, Math.floor(x));
  const t = x - i;
  return [0, 1, 2].map((c) => SCALE[i][c] + t * (SCALE[i + 1][c] - SCALE[i][c]));
}

/** Where a refused edit folds the body, from the server's message (`… x = (a, b, c) …`), or null. */
export function foldPlace(message) {
  const m = /x = \(([^)]*)\)/.exec(message || '');
  if (!m) return null;
  const x = m[1].split(',').map(Number);
  return x.length === 3 && x.every(Number.isFinite) ? x : null;
}

export class BodyView {
  /**
   * `view`: the 3D view; `send(msg)`: sends to the server and returns the
   * request id; `canEdit()`: whether this page may edit; `panel`: the
   * element the body controls go in; `partNames()`: the names in use (a new
   * spool gets a fresh one).
   */
  constructor(view, { send, canEdit, panel, partNames = () => new Set() }) {
    this.view = view;
    this.partNames = partNames;
    this.send = send;
    this.canEdit = canEdit;
    /** Drawings by part id: { group, mesh, lines, handles, chosen, section, outline, frame, part, grid }. */
    this.bodies = new Map();
    this.raycaster = new THREE.Raycaster();
    this.raycaster.params.Points.threshold = 0.05;
    this.drag = null;
    this.playing = null;
    /** The cutting plane: shown, axis (0 x, 1 y, 2 z), where along the body's extent (0 … 1). */
    this.cut = { on: false, axis: 0, at: 0.5 };
    /** The last section drawn: { part, axis, offset, section } (for scripts and tests). */
    this.lastSection = null;
    /** The lattice selection: { part, kind: 'point' | 'face' | 'edge', select (body_edit's), indices, from (the clicked index), option }. */
    this.selection = null;
    /** Edits sent and not answered yet, by request id. */
    this.pending = new Map();
    /** The last refused edit: { message, at: [x, y, z] | null, part, edit (body_edit's) }. */
    this.refused = null;
    const prev = view.bounds;
    view.bounds = () => {
      const box = prev() ? prev().clone() : new THREE.Box3();
      // In model units (the parts' boxes are): the geometries' own boxes, not world boxes, which
      // differ once the model is placed in VR (placeOnTable scales and turns it).
      for (const b of this.bodies.values()) {
        if (!b.group.visible) continue;
        for (const o of [b.mesh, b.handles]) if (o.geometry.boundingBox) box.union(o.geometry.boundingBox);
      }
      return box.isEmpty() ? null : box;
    };
    view.renderer.localClippingEnabled = true;
    this.clip = new THREE.Plane(new THREE.Vector3(-1, 0, 0), 0);
    this.controls = this.makeControls(panel);
    this.makeGizmo();
    this.foldMark = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0xff2020, depthTest: false, transparent: true, opacity: 0.8 }));
    this.foldMark.name = 'body-fold';
    this.foldMark.renderOrder = 3;
    this.foldMark.visible = false;
    view.model.add(this.foldMark);
    document.getElementById('add-spool')?.addEventListener('click', () => this.addSpool(this.partNames()));
    const el = view.renderer.domElement;
    el.addEventListener('pointerdown', (e) => this.pointerDown(e), true);
    el.addEventListener('pointermove', (e) => this.pointerMove(e), true);
    el.addEventListener('pointerup', (e) => this.pointerUp(e), true);
    document.addEventListener('keydown', (e) => {
      const t = e.target;
      const typing = t instanceof HTMLElement && (t.isContentEditable || ['INPUT', 'TEXTAREA'].includes(t.tagName));
      if (e.key === 'Escape' && !typing && this.selection && !this.gizmo.dragging) this.deselect();
    });
  }

  makeControls(panel) {
    const box = document.createElement('div');
    box.id = 'body-morph';
    box.hidden = true;
    box.innerHTML = '<div><label>morph <select id="body-morph-part"></select></label> '
      + '<input id="body-morph-t" type="range" min="0" max="1" step="0.01" value="0"> '
      + '<button id="body-morph-play" type="button">play</button> <span id="body-morph-value">t = 0</span></div>'
      + '<div><label><input id="body-section-on" type="checkbox"> section</label> '
      + '<select id="body-section-axis" title="the cutting plane is perpendicular to this axis"><option value="0">x</option><option value="1">y</option><option value="2">z</option></select> '
      + '<input id="body-section-offset" type="range" min="0" max="1" step="0.001" value="0.5" title="where the plane cuts the body"> '
      + '<span id="body-section-value"></span></div>'
      + '<div id="body-section-legend" hidden><span>det J</span> <span id="body-section-min"></span> '
      + '<canvas id="body-section-scale" width="120" height="10"></canvas> <span id="body-section-max"></span></div>'
      + '<div class="edit"><label>select <select id="body-select-mode" title="what a click on a lattice point selects for the gizmo">'
      + '<option value="point">point</option><option value="face">face</option><option value="edge">edge</option></select></label> '
      + '<span id="body-selection"></span></div>'
      + '<div id="body-fold" role="alert" hidden></div>';
    (panel || document.body).appendChild(box);
    const $ = (id) => box.querySelector(`#${id}`);
    const part = $('body-morph-part');
    const slider = $('body-morph-t');
    const play = $('body-morph-play');
    slider.addEventListener('input', () => this.setTime(Number(part.value), Number(slider.value)));
    play.addEventListener('click', () => (this.playing ? this.stop() : this.play(Number(part.value))));
    part.addEventListener('change', () => this.drawSections());
    const on = $('body-section-on');
    const axis = $('body-section-axis');
    const offset = $('body-section-offset');
    on.addEventListener('change', () => this.setSection({ on: on.checked }));
    axis.addEventListener('change', () => this.setSection({ axis: Number(axis.value) }));
    offset.addEventListener('input', () => this.setSection({ at: Number(offset.value) }));
    const mode = $('body-select-mode');
    mode.addEventListener('change', () => this.deselect());
    const scale = $('body-section-scale');
    const ctx = scale.getContext && scale.getContext('2d');
    if (ctx) {
      for (let x = 0; x < scale.width; x++) {
        const [r, g, b] = scaleColour(x / (scale.width - 1));
        ctx.fillStyle = `rgb(${Math.round(255 * r)}, ${Math.round(255 * g)}, ${Math.round(255 * b)})`;
        ctx.fillRect(x, 0, 1, scale.height);
      }
    }
    return {
      box, part, slider, play, value: $('body-morph-value'), on, axis, offset, offsetValue: $('body-section-value'),
      legend: $('body-section-legend'), min: $('body-section-min'), max: $('body-section-max'), mode, selected: $('body-selection'), fold: $('body-fold'),
    };
  }

  makeGizmo() {
    const g = new TransformControls(this.view.camera, this.view.renderer.domElement);
    g.name = 'body-gizmo';
    this.view.scene.add(g.getHelper());
    this.gizmo = g;
    this.proxy = new THREE.Object3D();
    this.proxy.name = 'body-gizmo-proxy';
    g.addEventListener('dragging-changed', (e) => {
      this.view.controls.enabled = !e.value;
      const sel = this.selection;
      if (!sel) return;
      if (e.value) {
        sel.start = this.proxy.position.clone();
        return;
      }
      const delta = this.proxy.position.clone().sub(sel.start || this.proxy.position);
      sel.start = null;
      const req = delta.lengthSq() > 0 ? this.send({ type: 'body_edit', part: sel.part, edit: { select: sel.select, delta: [delta.x, delta.y, delta.z] } }) : null;
      if (req != null) {
        this.pending.set(req, { part: sel.part, edit: { select: sel.select, delta: [delta.x, delta.y, delta.z] } });
        return;
      }
      // Nothing sent: the handles, the section and the gizmo go back to the frame.
      const b = this.bodies.get(sel.part);
      if (b && b.frame) {
        this.fill(b, b.frame);
        this.drawSection(b);
        this.placeGizmo();
      }
    });
    g.addEventListener('objectChange', () => {
      const sel = this.selection;
      const b = sel && this.bodies.get(sel.part);
      if (!b || !b.frame || !sel.start) return;
      // Preview: the selected handles follow the gizmo until the answer's frame comes.
      const d = this.proxy.position.clone().sub(sel.start);
      const pos = b.handles.geometry.attributes.position;
      for (const i of sel.indices) pos.setXYZ(i, b.frame.lattice[3 * i] + d.x, b.frame.lattice[3 * i + 1] + d.y, b.frame.lattice[3 * i + 2] + d.z);
      pos.needsUpdate = true;
      this.showChosen(b);
      // The section follows the previewed lattice: the interior distribution as the edit would make it.
      if (this.cut.on && Number(this.controls.part.value) === b.id) this.drawSection(b, pos.array);
    });
  }

  /** Adds the paper's demo body (a cube whose morph target is the spool made from it), named freshly. */
  async addSpool(names = new Set()) {
    const res = await fetch('/api/demo-parts/spool');
    if (!res.ok) throw new Error(`the spool preset: HTTP ${res.status}`);
    const spec = await res.json();
    let name = spec.name;
    for (let k = 2; names.has(name); k++) name = `${spec.name} ${k}`;
    return this.send({ type: 'create_part', spec: { ...spec, name } });
  }

  /** Sends morph time `t` of body `part`. */
  setTime(part, t) {
    if (!Number.isFinite(part)) return;
    this.send({ type: 'body_morph', part, t });
  }

  /** Plays body `part`'s metamorphosis from its current time to 1 and back to 0. */
  play(part) {
    const b = this.bodies.get(part);
    if (!b) return;
    let t = b.frame.t >= 1 ? 0 : b.frame.t;
    let dir = 1;
    this.controls.play.textContent = 'stop';
    const step = () => {
      if (!this.playing) return;
      t = Math.min(1, Math.max(0, t + dir * PLAY_STEP));
      this.setTime(part, t);
      this.controls.slider.value = String(t);
      if (t >= 1) dir = -1;
      if (t <= 0 && dir < 0) return this.stop();
      this.playing = requestAnimationFrame(step);
    };
    this.playing = requestAnimationFrame(step);
  }

  stop() {
    if (this.playing) cancelAnimationFrame(this.playing);
    this.playing = null;
    this.controls.play.textContent = 'play';
  }

  /** A body frame arrived: the part's drawing takes it. `part` is the design's part (colour, visibility), if known. */
  apply(frame, part) {
    let b = this.bodies.get(frame.part);
    if (!b) {
      b = this.create(frame.part);
      this.bodies.set(frame.part, b);
    }
    b.frame = frame;
    b.grid = null;
    this.fill(b, frame);
    this.style(b, part);
    this.updateControls();
    this.drawSection(b);
    if (this.selection && this.selection.part === frame.part) this.placeGizmo();
    this.view.drawn();
  }

  create(id) {
    const group = new THREE.Group();
    group.name = `body-${id}`;
    // Lit by the studio like the other parts (studio.js).
    const mesh = new THREE.Mesh(
      new THREE.BufferGeometry(),
      this.view.studio.light(new THREE.MeshStandardMaterial({ color: 0xc8ccd4, metalness: 0.1, roughness: 0.5, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1, side: THREE.DoubleSide })),
    );
    mesh.name = `body-boundary-${id}`;
    const lines = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ vertexColors: true }));
    lines.name = `body-iso-${id}`;
    const handles = new THREE.Points(new THREE.BufferGeometry(), new THREE.PointsMaterial({ color: 0xffd040, size: 8, sizeAttenuation: false, depthTest: false }));
    handles.name = `body-lattice-${id}`;
    handles.renderOrder = 2;
    const chosen = new THREE.Points(new THREE.BufferGeometry(), new THREE.PointsMaterial({ color: 0x40e0ff, size: 12, sizeAttenuation: false, depthTest: false }));
    chosen.name = `body-selected-${id}`;
    chosen.renderOrder = 3;
    chosen.visible = false;
    const section = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshBasicMaterial({ vertexColors: true, side: THREE.DoubleSide }));
    section.name = `body-section-${id}`;
    section.visible = false;
    const outline = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x101010 }));
    outline.name = `body-section-outline-${id}`;
    outline.visible = false;
    group.add(mesh, lines, handles, chosen, section, outline);
    this.view.model.add(group);
    return { id, group, mesh, lines, handles, chosen, section, outline, frame: null, grid: null };
  }

  fill(b, f) {
    const g = b.mesh.geometry;
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(f.positions), 3));
    g.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(f.normals), 3));
    g.setIndex(new THREE.BufferAttribute(new Uint32Array(f.triangles), 1));
    g.computeBoundingSphere();
    g.computeBoundingBox();
    // Polylines as segments, coloured by the direction held constant.
    const s = f.lineSamples;
    const nLines = f.lineDirs.length;
    const seg = new Float32Array(nLines * Math.max(0, s - 1) * 6);
    const col = new Float32Array(seg.length);
    let o = 0;
    for (let l = 0; l < nLines; l++) {
      const c = new THREE.Color(LINE_COLOURS[f.lineDirs[l]]);
      for (let k = 0; k + 1 < s; k++) {
        for (const q of [k, k + 1]) {
          const p = 3 * (l * s + q);
          seg.set(f.linePoints.subarray(p, p + 3), o);
          col.set([c.r, c.g, c.b], o);
          o += 3;
        }
      }
    }
    b.lines.geometry.setAttribute('position', new THREE.BufferAttribute(seg, 3));
    b.lines.geometry.setAttribute('color', new THREE.BufferAttribute(col, 3));
    b.lines.geometry.computeBoundingSphere();
    if (!this.drag || this.drag.body !== b) {
      b.handles.geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(f.lattice), 3));
      b.handles.geometry.computeBoundingSphere();
      b.handles.geometry.computeBoundingBox();
    }
    this.showChosen(b);
  }

  style(b, part) {
    if (!part) return;
    b.part = part;
    b.mesh.material.color.set(part.colour);
    b.group.visible = part.visible !== false && !part.hiddenHere;
    b.handles.visible = this.canEdit() && !part.locked;
    if (!b.handles.visible && this.selection && this.selection.part === b.id) this.deselect();
  }

  /** Brings the drawings in line with the design's parts: colour, visibility, removed parts. */
  sync(design, hidden = new Set()) {
    for (const [id, b] of this.bodies) {
      const part = design.parts.get(id);
      if (!part) {
        if (this.selection && this.selection.part === id) this.deselect();
        this.view.model.remove(b.group);
        for (const o of [b.mesh, b.lines, b.handles, b.chosen, b.section, b.outline]) o.geometry.dispose();
        this.bodies.delete(id);
        continue;
      }
      this.style(b, { ...part, hiddenHere: hidden.has(id) });
    }
    this.updateControls();
  }

  /** The body controls show when there is a body; the morph value follows the chosen body's frames. */
  updateControls() {
    const { part, box, value, slider } = this.controls;
    const ids = [...this.bodies.keys()];
    box.hidden = ids.length === 0;
    const label = (id) => this.bodies.get(id).part?.name || `body ${id}`;
    // Rebuilt when a body comes or goes or is renamed (its part may arrive after its first frame).
    const want = JSON.stringify(ids.map((id) => [id, label(id)]));
    if (part.dataset.ids !== want) {
      const was = part.value;
      part.innerHTML = '';
      for (const id of ids) {
        const opt = document.createElement('option');
        opt.value = String(id);
        opt.textContent = label(id);
        part.appendChild(opt);
      }
      if (ids.map(String).includes(was)) part.value = was;
      part.dataset.ids = want;
    }
    const shown = this.bodies.get(Number(part.value));
    if (shown && shown.frame) {
      value.textContent = `t = ${shown.frame.t.toFixed(2)}`;
      if (!this.playing && document.activeElement !== slider) slider.value = String(shown.frame.t);
    }
  }

  // --- the cutting plane ------------------------------------------------------

  /** Changes the cutting plane ({ on, axis, at }: any of them) and redraws the sections. */
  setSection(change) {
    Object.assign(this.cut, change);
    const c = this.controls;
    c.on.checked = this.cut.on;
    c.axis.value = String(this.cut.axis);
    c.offset.value = String(this.cut.at);
    this.drawSections();
  }

  drawSections() {
    for (const b of this.bodies.values()) this.drawSection(b);
    this.view.drawn();
  }

  /**
   * Draws body `b`'s section by the cutting plane when it is on and `b` is
   * the chosen body (its volume sampled once per frame), and clips its
   * boundary beyond the plane; else shows the whole body. With `lattice`
   * (a preview during a gizmo drag) the section is of that lattice instead.
   */
  drawSection(b, lattice = null) {
    const c = this.controls;
    const chosen = Number(c.part.value) === b.id;
    const show = this.cut.on && chosen && b.frame && b.frame.degrees;
    b.section.visible = false;
    b.outline.visible = false;
    for (const m of [b.mesh.material, b.lines.material]) {
      if (!!(m.clippingPlanes && m.clippingPlanes.length) !== !!show) {
        m.clippingPlanes = show ? [this.clip] : null;
        m.needsUpdate = true;
      }
    }
    if (!show) {
      if (chosen) c.legend.hidden = true;
      return;
    }
    if (!b.grid) b.grid = new SectionGrid(BSplineVolume.fromFrame(b.frame));
    const axis = this.cut.axis;
    // The plane stays where the shown body puts it while a preview changes the body.
    const [lo, hi] = b.grid.range(axis);
    const offset = lo + this.cut.at * (hi - lo);
    const grid = lattice ? new SectionGrid(BSplineVolume.fromFrame({ ...b.frame, lattice })) : b.grid;
    const sec = grid.cut(axis, offset);
    this.lastSection = { part: b.id, axis, offset, section: sec };
    // Keep x_axis ≤ offset: the plane's normal points back along the axis.
    const n = new THREE.Vector3();
    n.setComponent(axis, -1);
    this.clip.set(n, offset);
    b.group.updateMatrixWorld(true);
    this.clip.applyMatrix4(b.group.matrixWorld);
    c.offsetValue.textContent = `${'xyz'[axis]} = ${offset.toFixed(2)}`;
    // A spread below f32 rounding of the lattice is no spread: one colour, the scale's middle.
    const range = sec.detMax - sec.detMin;
    const spread = range > SPREAD * Math.max(Math.abs(sec.detMax), Math.abs(sec.detMin));
    const colours = new Float32Array(sec.positions.length);
    for (let v = 0; v < sec.det.length; v++) colours.set(scaleColour(spread ? (sec.det[v] - sec.detMin) / range : 0.5), 3 * v);
    const g = b.section.geometry;
    g.setAttribute('position', new THREE.BufferAttribute(sec.positions, 3));
    g.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    g.setIndex(new THREE.BufferAttribute(sec.triangles, 1));
    g.computeBoundingSphere();
    const og = b.outline.geometry;
    og.setAttribute('position', new THREE.BufferAttribute(sec.positions, 3));
    og.setIndex(new THREE.BufferAttribute(sec.outline, 1));
    og.computeBoundingSphere();
    b.section.visible = sec.triangles.length > 0;
    b.outline.visible = sec.triangles.length > 0;
    c.legend.hidden = sec.triangles.length === 0;
    c.min.textContent = sec.detMin.toPrecision(3);
    c.max.textContent = sec.detMax.toPrecision(3);
  }

  // --- the lattice ------------------------------------------------------------

  /** The world position of lattice point `index` of body `id` as last drawn. */
  latticePoint(id, index) {
    const b = this.bodies.get(id);
    if (!b || !b.frame) return null;
    const a = b.frame.lattice;
    return [a[3 * index], a[3 * index + 1], a[3 * index + 2]];
  }

  /** (i, j, k) of storage index `index` of a lattice of `counts`. */
  static ijk(counts, index) {
    const [, nv, nw] = counts;
    return [Math.floor(index / (nv * nw)), Math.floor(index / nw) % nv, index % nw];
  }

  /** The faces of the lattice that `ijk` lies on, as [direction, at the end] pairs. */
  static facesOf(counts, ijk) {
    const out = [];
    for (let d = 0; d < 3; d++) {
      if (ijk[d] === 0) out.push([d, false]);
      else if (ijk[d] === counts[d] - 1) out.push([d, true]);
    }
    return out;
  }

  /** The face of the lattice that `ijk` lies on (the first found), or null for an inner point. */
  static faceOf(counts, ijk) {
    const f = BodyView.facesOf(counts, ijk)[0];
    return f ? FACE_NAMES[f[0]][f[1] ? 1 : 0] : null;
  }

  /** The storage indices of the points with index `at[d]` along each direction d given in `fixed` ([[d, end], …]). */
  static indicesOn(counts, fixed) {
    const out = [];
    const [nu, nv, nw] = counts;
    for (let i = 0; i < nu; i++) {
      for (let j = 0; j < nv; j++) {
        for (let k = 0; k < nw; k++) {
          const ijk = [i, j, k];
          if (fixed.every(([d, end]) => ijk[d] === (end ? counts[d] - 1 : 0))) out.push((i * nv + j) * nw + k);
        }
      }
    }
    return out;
  }

  /**
   * The selections lattice point `index` offers in `mode`: [{ kind, select
   * (body_edit's), indices, label }] — the point itself; each face it lies
   * on; each edge it lies on (an inner point offers only itself).
   */
  static selectionsAt(counts, index, mode) {
    const ijk = BodyView.ijk(counts, index);
    const point = { kind: 'point', select: { point: ijk }, indices: [index], label: `point (${ijk.join(', ')})` };
    const faces = BodyView.facesOf(counts, ijk);
    const name = ([d, end]) => FACE_NAMES[d][end ? 1 : 0];
    if (mode === 'face' && faces.length) {
      return faces.map((f) => ({ kind: 'face', select: { face: name(f) }, indices: BodyView.indicesOn(counts, [f]), label: `face ${name(f)}` }));
    }
    if (mode === 'edge' && faces.length >= 2) {
      const out = [];
      for (let a = 0; a < faces.length; a++) {
        for (let c = a + 1; c < faces.length; c++) {
          const pair = [faces[a], faces[c]];
          out.push({ kind: 'edge', select: { edge: pair.map(name) }, indices: BodyView.indicesOn(counts, pair), label: `edge ${pair.map(name).join(' × ')}` });
        }
      }
      return out;
    }
    return [point];
  }

  /**
   * Selects by the mode chosen what lattice point `index` of body `part`
   * offers; the same point clicked again takes its next face or edge. The
   * gizmo comes to the selection's centre. Returns the selection.
   */
  choose(part, index) {
    const b = this.bodies.get(part);
    if (!b || !b.frame || !this.canEdit()) return null;
    const mode = this.controls.mode.value;
    const options = BodyView.selectionsAt(b.frame.counts, index, mode);
    const prev = this.selection;
    const again = prev && prev.part === part && prev.from === index && prev.mode === mode;
    const option = again ? (prev.option + 1) % options.length : 0;
    this.selection = { part, from: index, mode, option, ...options[option], start: null };
    this.controls.selected.textContent = `${this.selection.label}: ${this.selection.indices.length} point${this.selection.indices.length === 1 ? '' : 's'}`;
    this.showChosen(b);
    this.placeGizmo();
    return this.selection;
  }

  /** Lets the selection go (the gizmo goes). */
  deselect() {
    const sel = this.selection;
    this.selection = null;
    this.gizmo.detach();
    this.proxy.removeFromParent();
    this.controls.selected.textContent = '';
    const b = sel && this.bodies.get(sel.part);
    if (b) this.showChosen(b);
  }

  /** The selected handles of body `b`, drawn over the others. */
  showChosen(b) {
    const sel = this.selection;
    if (!sel || sel.part !== b.id || !b.frame) {
      b.chosen.visible = false;
      return;
    }
    const src = b.handles.geometry.attributes.position;
    if (!src) return;
    const pts = new Float32Array(3 * sel.indices.length);
    sel.indices.forEach((i, n) => pts.set([src.getX(i), src.getY(i), src.getZ(i)], 3 * n));
    b.chosen.geometry.setAttribute('position', new THREE.BufferAttribute(pts, 3));
    b.chosen.geometry.computeBoundingSphere();
    b.chosen.visible = true;
  }

  /** The gizmo at the selected points' centre (as last drawn). */
  placeGizmo() {
    const sel = this.selection;
    const b = sel && this.bodies.get(sel.part);
    if (!b || !b.frame || this.gizmo.dragging) return;
    const c = new THREE.Vector3();
    for (const i of sel.indices) c.add(new THREE.Vector3(...this.latticePoint(sel.part, i)));
    c.divideScalar(sel.indices.length);
    if (this.proxy.parent !== b.group) b.group.add(this.proxy);
    this.proxy.position.copy(c);
    this.proxy.updateMatrixWorld(true);
    if (this.gizmo.object !== this.proxy) this.gizmo.attach(this.proxy);
  }

  /** The gizmo's origin in world coordinates, or null when nothing is selected. */
  gizmoOrigin() {
    return this.gizmo.object ? this.proxy.getWorldPosition(new THREE.Vector3()).toArray() : null;
  }

  /**
   * Sends the edit that moves lattice point `index` of body `part` by
   * `delta` ([dx, dy, dz]); with `face` true, every point of its face.
   */
  moveLattice(part, index, delta, face = false) {
    const b = this.bodies.get(part);
    if (!b || !b.frame) return null;
    const ijk = BodyView.ijk(b.frame.counts, index);
    const f = face ? BodyView.faceOf(b.frame.counts, ijk) : null;
    const select = f ? { face: f } : { point: ijk };
    const req = this.send({ type: 'body_edit', part, edit: { select, delta } });
    if (req != null) this.pending.set(req, { part, edit: { select, delta } });
    return req;
  }

  /**
   * The server answered request `msg.req` (an `ack` or an `error`): a
   * refused lattice edit is shown — its message and, when it names one, a
   * mark where the body would fold — and the handles go back.
   */
  answered(msg) {
    const p = this.pending.get(msg.req);
    if (!p) return;
    this.pending.delete(msg.req);
    const { fold } = this.controls;
    const b = this.bodies.get(p.part);
    if (msg.type === 'ack') {
      this.refused = null;
      fold.hidden = true;
      this.foldMark.visible = false;
      return;
    }
    const at = foldPlace(msg.message);
    this.refused = { message: msg.message, at, part: p.part, edit: p.edit };
    fold.textContent = `edit refused: ${msg.message}`;
    fold.hidden = false;
    if (at && b) {
      const size = b.mesh.geometry.boundingSphere ? b.mesh.geometry.boundingSphere.radius : 1;
      this.foldMark.position.set(...at);
      this.foldMark.scale.setScalar(Math.max(1e-3, 0.04 * size));
      this.foldMark.visible = true;
    } else {
      this.foldMark.visible = false;
    }
    if (b && b.frame) {
      this.fill(b, b.frame);
      this.drawSection(b);
      if (this.selection && this.selection.part === b.id) this.placeGizmo();
    }
    this.view.drawn();
  }

  pick(e) {
    const el = this.view.renderer.domElement;
    const r = el.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.view.camera);
    const handles = [...this.bodies.values()].filter((b) => b.group.visible && b.handles.visible).map((b) => b.handles);
    const hit = this.raycaster.intersectObjects(handles, false)[0];
    return { hit, ray: this.raycaster.ray, ndc };
  }

  pointerDown(e) {
    if (!this.canEdit() || e.button !== 0) return;
    // Over a handle of the lattice gizmo: the gizmo takes the press, not the orbit controls nor a handle under it.
    const { hit, ndc } = this.pick(e);
    if (this.gizmo.object && this.gizmo.enabled) {
      this.gizmo.pointerHover({ x: ndc.x, y: ndc.y, button: e.button });
      if (this.gizmo.axis !== null) {
        this.view.controls.enabled = false;
        return;
      }
    }
    if (!hit) return;
    const b = [...this.bodies.values()].find((x) => x.handles === hit.object);
    const start = new THREE.Vector3().fromBufferAttribute(hit.object.geometry.attributes.position, hit.index);
    const world = hit.object.localToWorld(start.clone());
    const normal = this.view.camera.getWorldDirection(new THREE.Vector3());
    this.drag = { body: b, index: hit.index, start, plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, world), face: e.shiftKey, to: start.clone(), at: [e.clientX, e.clientY], moved: false };
    this.view.controls.enabled = false;
    // Capture listeners run first on the canvas: the orbit controls and the icon picking do not see this press.
    e.stopImmediatePropagation();
    e.preventDefault();
  }

  pointerMove(e) {
    if (!this.drag) return;
    if (!this.drag.moved && Math.hypot(e.clientX - this.drag.at[0], e.clientY - this.drag.at[1]) <= 4) return;
    this.drag.moved = true;
    const { ray } = this.pick(e);
    const at = ray.intersectPlane(this.drag.plane, new THREE.Vector3());
    if (!at) return;
    const local = this.drag.body.handles.worldToLocal(at);
    this.drag.to.copy(local);
    const pos = this.drag.body.handles.geometry.attributes.position;
    pos.setXYZ(this.drag.index, local.x, local.y, local.z);
    pos.needsUpdate = true;
    e.stopImmediatePropagation();
  }

  pointerUp(e) {
    const d = this.drag;
    if (!d) return;
    this.drag = null;
    this.view.controls.enabled = true;
    if (!d.moved) {
      // A click: select for the gizmo.
      this.choose(d.body.id, d.index);
      e.stopImmediatePropagation();
      return;
    }
    const delta = d.to.clone().sub(d.start);
    if (delta.lengthSq() > 0) this.moveLattice(d.body.id, d.index, [delta.x, delta.y, delta.z], d.face);
    // Until the answer's frame comes, the handles show the last frame (a refused edit puts the point back).
    if (d.body.frame) this.fill(d.body, d.body.frame);
    e.stopImmediatePropagation();
  }
}
