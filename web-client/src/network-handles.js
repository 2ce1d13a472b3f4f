// What the handles of styling-curve network parts share (ribbon-handles.js,
// tuning-handles.js): per network part a group of handles — a ball on a
// stem — shown or hidden together, picked by their ball's screen distance
// from the pointer, and put back when the server refuses the edit a drag
// sent. A subclass draws its handles (`update`), says where a handle's ball
// sits (`restore(h)` puts it there again) and does the dragging.

import * as THREE from 'three';

/** How near (pixels) the pointer must be to a handle to grab it. */
export const GRAB_PX = 12;

export class HandleSet {
  /** `view`: the View; `send(msg)` sends a message; `canEdit()` whether this page may edit. */
  constructor(view, { send, canEdit }) {
    this.view = view;
    this.send = send;
    this.canEdit = canEdit;
    /** Whether handles are shown. */
    this.shown = false;
    /** Per network part id: { root (THREE.Group), handles: [{ ball, stem, … }] }. */
    this.parts = new Map();
    /** The drag under way, or null. */
    this.drag = null;
    /** The last edit sent and not yet answered: { req, part, handle }. */
    this.sent = null;
  }

  /** Shows or hides every part's handles. */
  show(on) {
    this.shown = on;
    for (const p of this.parts.values()) p.root.visible = on;
    this.view.drawn();
  }

  /** A new group `name` for part `id`'s handles under its drawing `root`. */
  group(id, root, name) {
    this.remove(id);
    const group = new THREE.Group();
    group.name = name;
    group.visible = this.shown;
    root.add(group);
    return group;
  }

  /** A stem (a two-point line) of `material`. */
  stem(material) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6), 3));
    const stem = new THREE.Line(g, material);
    stem.renderOrder = 3;
    return stem;
  }

  /** Puts `h`'s ball at model point `p` and its stem from `from` to it. */
  setBall(h, from, p) {
    h.ball.position.set(...p);
    const a = h.stem.geometry.getAttribute('position');
    a.array.set([...from, ...p]);
    a.needsUpdate = true;
    h.stem.geometry.computeBoundingSphere();
  }

  remove(id) {
    const p = this.parts.get(id);
    if (!p) return;
    p.root.parent && p.root.parent.remove(p.root);
    for (const h of p.handles) h.stem.geometry.dispose();
    this.parts.delete(id);
  }

  /** Screen position (canvas pixels) of model point `p`. */
  screen(p, w, h) {
    const v = new THREE.Vector3(...p);
    this.view.model.localToWorld(v);
    v.project(this.view.camera);
    return [((v.x + 1) / 2) * w, ((1 - v.y) / 2) * h];
  }

  /** The handle under canvas pixel (x, y) within GRAB_PX: { part, handle, dist } or null. */
  nearest(x, y, w, h) {
    if (!this.shown) return null;
    let best = null;
    for (const [id, p] of this.parts) {
      if (!p.root.parent || !p.root.parent.visible) continue;
      for (const handle of p.handles) {
        const [px, py] = this.screen(handle.ball.position.toArray(), w, h);
        const dist = Math.hypot(px - x, py - y);
        if (dist <= GRAB_PX && (!best || dist < best.dist)) best = { part: id, handle, dist };
      }
    }
    return best;
  }

  /** A press at canvas pixel (x, y): true when it grabbed a handle (the caller stops the event). */
  down(x, y, w, h) {
    return this.grab(this.nearest(x, y, w, h));
  }

  /** The model point under canvas pixel (x, y) on the drag's plane, or null. */
  pointerOnPlane(x, y, w, h) {
    const ray = new THREE.Raycaster();
    ray.setFromCamera(new THREE.Vector2((x / w) * 2 - 1, 1 - (y / h) * 2), this.view.camera);
    const world = ray.ray.intersectPlane(this.drag.plane, new THREE.Vector3());
    return world ? this.view.model.worldToLocal(world).toArray() : null;
  }

  /** The server answered request `req` (`failed`: with an error): a refused edit puts the ball back. */
  answered(req, failed) {
    const s = this.sent;
    if (!s || s.req !== req) return;
    this.sent = null;
    const p = this.parts.get(s.part);
    if (failed && p && p.handles.includes(s.handle)) {
      this.restore(s.handle);
      this.view.drawn();
    }
  }
}
