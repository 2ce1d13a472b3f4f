// Coons body parts (paper 002) in the 3D view, from their body frames
// (kind 4): the shaded boundary in the part's colour, isoparametric lines at
// constant u (red), v (green) and w (blue) on it (§2.1), and the lattice
// points as handles an editor drags — a drag moves one point, or with Shift
// held the whole face the point lies on, and is sent as one `body_edit` when
// released (the server refuses a fold and says where; the handle then goes
// back). A time slider and a play button show a body's metamorphosis: the
// page sends `body_morph` and every page of the design gets the frames.

import * as THREE from 'three';

const LINE_COLOURS = [0xe05050, 0x50c050, 0x5080f0];
/** Morph time step per animation frame while playing (about 2 s for 0 → 1 at 60 Hz). */
const PLAY_STEP = 1 / 120;

export class BodyView {
  /**
   * `view`: the 3D view; `send(msg)`: sends to the server; `canEdit()`:
   * whether this page may edit; `panel`: the element the morph controls go in;
   * `partNames()`: the names in use (a new spool gets a fresh one).
   */
  constructor(view, { send, canEdit, panel, partNames = () => new Set() }) {
    this.view = view;
    this.partNames = partNames;
    this.send = send;
    this.canEdit = canEdit;
    /** Drawings by part id: { group, mesh, lines, handles, frame, part }. */
    this.bodies = new Map();
    this.raycaster = new THREE.Raycaster();
    this.raycaster.params.Points.threshold = 0.05;
    this.drag = null;
    this.playing = null;
    const prev = view.bounds;
    view.bounds = () => {
      const box = prev() ? prev().clone() : new THREE.Box3();
      for (const b of this.bodies.values()) if (b.group.visible) box.expandByObject(b.group);
      return box.isEmpty() ? null : box;
    };
    this.controls = this.makeControls(panel);
    document.getElementById('add-spool')?.addEventListener('click', () => this.addSpool(this.partNames()));
    const el = view.renderer.domElement;
    el.addEventListener('pointerdown', (e) => this.pointerDown(e), true);
    el.addEventListener('pointermove', (e) => this.pointerMove(e), true);
    el.addEventListener('pointerup', (e) => this.pointerUp(e), true);
  }

  makeControls(panel) {
    const box = document.createElement('div');
    box.id = 'body-morph';
    box.hidden = true;
    box.innerHTML = '<label>morph <select id="body-morph-part"></select></label> '
      + '<input id="body-morph-t" type="range" min="0" max="1" step="0.01" value="0"> '
      + '<button id="body-morph-play" type="button">play</button> <span id="body-morph-value">t = 0</span>';
    (panel || document.body).appendChild(box);
    const part = box.querySelector('#body-morph-part');
    const slider = box.querySelector('#body-morph-t');
    const play = box.querySelector('#body-morph-play');
    slider.addEventListener('input', () => this.setTime(Number(part.value), Number(slider.value)));
    play.addEventListener('click', () => (this.playing ? this.stop() : this.play(Number(part.value))));
    return { box, part, slider, play, value: box.querySelector('#body-morph-value') };
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
    this.fill(b, frame);
    this.style(b, part);
    this.updateControls();
    this.view.drawn();
  }

  create(id) {
    const group = new THREE.Group();
    group.name = `body-${id}`;
    const mesh = new THREE.Mesh(
      new THREE.BufferGeometry(),
      new THREE.MeshStandardMaterial({ color: 0xc8ccd4, metalness: 0.1, roughness: 0.5, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 }),
    );
    mesh.name = `body-boundary-${id}`;
    const lines = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ vertexColors: true }));
    lines.name = `body-iso-${id}`;
    const handles = new THREE.Points(new THREE.BufferGeometry(), new THREE.PointsMaterial({ color: 0xffd040, size: 8, sizeAttenuation: false, depthTest: false }));
    handles.name = `body-lattice-${id}`;
    handles.renderOrder = 2;
    group.add(mesh, lines, handles);
    this.view.model.add(group);
    return { id, group, mesh, lines, handles, frame: null };
  }

  fill(b, f) {
    const g = b.mesh.geometry;
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(f.positions), 3));
    g.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(f.normals), 3));
    g.setIndex(new THREE.BufferAttribute(new Uint32Array(f.triangles), 1));
    g.computeBoundingSphere();
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
    }
  }

  style(b, part) {
    if (!part) return;
    b.part = part;
    b.mesh.material.color.set(part.colour);
    b.group.visible = part.visible !== false && !part.hiddenHere;
    b.handles.visible = this.canEdit() && !part.locked;
  }

  /** Brings the drawings in line with the design's parts: colour, visibility, removed parts. */
  sync(design, hidden = new Set()) {
    for (const [id, b] of this.bodies) {
      const part = design.parts.get(id);
      if (!part) {
        this.view.model.remove(b.group);
        b.mesh.geometry.dispose();
        b.lines.geometry.dispose();
        b.handles.geometry.dispose();
        this.bodies.delete(id);
        continue;
      }
      this.style(b, { ...part, hiddenHere: hidden.has(id) });
    }
    this.updateControls();
  }

  /** The morph controls show when a body has a morph target (the server says so by answering; a body frame's t is 0 until then). */
  updateControls() {
    const { part, box, value, slider } = this.controls;
    const ids = [...this.bodies.keys()];
    box.hidden = ids.length === 0;
    const want = ids.map(String).join(',');
    if (part.dataset.ids !== want) {
      part.innerHTML = '';
      for (const id of ids) {
        const opt = document.createElement('option');
        opt.value = String(id);
        opt.textContent = this.bodies.get(id).part?.name || `body ${id}`;
        part.appendChild(opt);
      }
      part.dataset.ids = want;
    }
    const shown = this.bodies.get(Number(part.value));
    if (shown && shown.frame) {
      value.textContent = `t = ${shown.frame.t.toFixed(2)}`;
      if (!this.playing && document.activeElement !== slider) slider.value = String(shown.frame.t);
    }
  }

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

  /** The face of the lattice that `ijk` lies on (the first found), or null for an inner point. */
  static faceOf(counts, ijk) {
    const names = [['u_min', 'u_max'], ['v_min', 'v_max'], ['w_min', 'w_max']];
    for (let d = 0; d < 3; d++) {
      if (ijk[d] === 0) return names[d][0];
      if (ijk[d] === counts[d] - 1) return names[d][1];
    }
    return null;
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
    return this.send({ type: 'body_edit', part, edit: { select, delta } });
  }

  pick(e) {
    const el = this.view.renderer.domElement;
    const r = el.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.view.camera);
    const handles = [...this.bodies.values()].filter((b) => b.group.visible && b.handles.visible).map((b) => b.handles);
    const hit = this.raycaster.intersectObjects(handles, false)[0];
    return { hit, ray: this.raycaster.ray };
  }

  pointerDown(e) {
    if (!this.canEdit() || e.button !== 0) return;
    const { hit } = this.pick(e);
    if (!hit) return;
    const b = [...this.bodies.values()].find((x) => x.handles === hit.object);
    const start = new THREE.Vector3().fromBufferAttribute(hit.object.geometry.attributes.position, hit.index);
    const world = hit.object.localToWorld(start.clone());
    const normal = this.view.camera.getWorldDirection(new THREE.Vector3());
    this.drag = { body: b, index: hit.index, start, plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, world), face: e.shiftKey, to: start.clone() };
    this.view.controls.enabled = false;
    // Capture listeners run first on the canvas: the orbit controls and the icon picking do not see this press.
    e.stopImmediatePropagation();
    e.preventDefault();
  }

  pointerMove(e) {
    if (!this.drag) return;
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
    const delta = d.to.clone().sub(d.start);
    if (delta.lengthSq() > 0) this.moveLattice(d.body.id, d.index, [delta.x, delta.y, delta.z], d.face);
    // Until the answer's frame comes, the handles show the last frame (a refused edit puts the point back).
    if (d.body.frame) this.fill(d.body, d.body.frame);
    e.stopImmediatePropagation();
  }
}
