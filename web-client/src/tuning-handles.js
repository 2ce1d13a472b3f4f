// Tuning handles of styling-curve network parts (paper 004's u²v² terms),
// drawn and dragged in the browser. Every face gets one handle: a ball on
// a stem from the face's centre (the mean of its sides' middles) along the
// face's normal (the Newell normal of those middles, on the network's `up`
// side). The ball sits `LIFT` of the face's radius out along the normal,
// plus the face's centre tuning offset h₀ — the offset the server adds to
// the patch with a weight that is 1 at the domain's centre and vanishes
// with its gradient on the boundary, so the interior moves and the
// boundary curves and their tangent planes stay. A drag slides the ball
// along the normal line (a slider in 3D); on release the page sends one
// `network_edit` set_tuning (one undoable step) with the face's handles,
// the centre's replaced (the corners' kept), and the server's
// `network_changed` redraws the handles where the server put them.

import * as THREE from 'three';
import { curveDerivs } from './bspline.js';
import { HandleSet } from './network-handles.js';

/** The ball's height over the face's centre at zero offset, as a fraction of the face's radius. */
export const LIFT = 0.25;
/** Coordinates beyond this are refused by the server. */
const MAX_COORD = 1e9;

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

/**
 * The frame of face `f`'s tuning handle (`curves`: bspline.js curves,
 * `network`: the wire's NetworkData): { centre, normal (unit), lift }, or
 * null for a degenerate face.
 */
export function faceFrame(curves, network, f) {
  const face = network.faces[f];
  const mids = face.sides.map((s) => curveDerivs(curves[s.curve], (s.t_start + s.t_end) / 2).p);
  const centre = mul(mids.reduce(add, [0, 0, 0]), 1 / mids.length);
  let normal = [0, 0, 0];
  mids.forEach((m, k) => {
    normal = add(normal, cross(sub(m, centre), sub(mids[(k + 1) % mids.length], centre)));
  });
  const len = Math.hypot(...normal);
  const radius = mids.reduce((s, m) => s + Math.hypot(...sub(m, centre)), 0) / mids.length;
  if (!(len > 0) || !(radius > 0)) return null;
  normal = mul(normal, 1 / len);
  if (network.up && dot(normal, network.up) < 0) normal = mul(normal, -1);
  return { centre, normal, lift: LIFT * radius };
}

/** Where the ball of a face with frame `fr` and centre offset `h0` sits (model space). */
export function tuningPoint(fr, h0) {
  return add(add(fr.centre, mul(fr.normal, fr.lift)), h0);
}

/** The centre offset a ball dragged (along the normal) to model point `p` gives, from offset `h0`. */
export function tuningOffset(fr, h0, p) {
  const s = dot(sub(p, tuningPoint(fr, h0)), fr.normal);
  return add(h0, mul(fr.normal, s)).map((x) => Math.min(MAX_COORD, Math.max(-MAX_COORD, x)));
}

export class TuningHandles extends HandleSet {
  /** `view`: the View; `send(msg)` sends a message; `canEdit()` whether this page may edit. */
  constructor(view, options) {
    super(view, options);
    // `drag`: { part, handle, plane, offset }; `sent`: the last set_tuning.
    this.ballGeometry = new THREE.OctahedronGeometry(1);
    this.ballMaterial = new THREE.MeshBasicMaterial({ color: 0x3ad17a, depthTest: false });
    this.stemMaterial = new THREE.LineBasicMaterial({ color: 0x3ad17a, depthTest: false });
  }

  /** Network part `id` (its drawing `root` group, bspline.js `curves`, wire `network`) has new curves or handles. */
  update(id, root, curves, network) {
    const group = this.group(id, root, `network-${id}-tuning-handles`);
    const handles = [];
    (network.faces || []).forEach((face, f) => {
      const frame = faceFrame(curves, network, f);
      if (!frame) return;
      const stored = network.tuning && network.tuning[f];
      const tuning = stored && stored.length === face.sides.length + 1 ? stored.map((h) => [...h]) : Array.from({ length: face.sides.length + 1 }, () => [0, 0, 0]);
      const ball = new THREE.Mesh(this.ballGeometry, this.ballMaterial);
      ball.name = `network-${id}-tuning-${f}`;
      ball.renderOrder = 3;
      ball.scale.setScalar(0.3 * frame.lift);
      const stem = this.stem(this.stemMaterial);
      group.add(ball, stem);
      const handle = { face: f, frame, tuning, ball, stem };
      this.place(handle, tuning[0]);
      handles.push(handle);
    });
    this.parts.set(id, { root: group, handles });
  }

  /** Puts `h`'s ball and stem at centre offset `h0`. */
  place(h, h0) {
    this.setBall(h, h.frame.centre, tuningPoint(h.frame, h0));
  }

  /** Puts `h`'s ball back where its stored offset says. */
  restore(h) {
    this.place(h, h.tuning[0]);
  }

  /** Grabs `hit` (from `nearest`): the ball slides along the face's normal line. */
  grab(hit) {
    if (!this.canEdit() || !hit) return false;
    const fr = hit.handle.frame;
    // The plane through the normal line that faces the camera most.
    const origin = new THREE.Vector3(...hit.handle.ball.position.toArray());
    const axis = new THREE.Vector3(...fr.normal);
    this.view.model.localToWorld(origin);
    axis.transformDirection(this.view.model.matrixWorld);
    const look = new THREE.Vector3();
    this.view.camera.getWorldDirection(look);
    const normal = look.clone().addScaledVector(axis, -look.dot(axis));
    // Looking along the normal: any plane through the line.
    if (normal.lengthSq() < 1e-12) normal.set(1, 0, 0).cross(axis);
    if (normal.lengthSq() < 1e-12) normal.set(0, 1, 0).cross(axis);
    normal.normalize();
    this.drag = { part: hit.part, handle: hit.handle, plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, origin), offset: hit.handle.tuning[0] };
    return true;
  }

  /** The pointer at canvas pixel (x, y) during a drag: the ball follows along the normal. */
  move(x, y, w, h) {
    const d = this.drag;
    if (!d) return;
    const p = this.pointerOnPlane(x, y, w, h);
    if (!p) return;
    d.offset = tuningOffset(d.handle.frame, d.handle.tuning[0], p);
    this.place(d.handle, d.offset);
    this.view.drawn();
  }

  /** Sends face `face`'s handles of part `part` with the centre offset `h0` (the corners kept); the request's req or null. */
  set(part, face, h0) {
    const p = this.parts.get(part);
    const handle = p && p.handles.find((x) => x.face === face);
    if (!handle) return null;
    const handles = [h0, ...handle.tuning.slice(1)];
    const req = this.send({ type: 'network_edit', part, edit: { op: 'set_tuning', face, handles } });
    if (req === null || req === undefined) {
      this.place(handle, handle.tuning[0]);
      return null;
    }
    this.place(handle, h0);
    this.sent = { req, part, handle };
    return req;
  }

  /** The release: one set_tuning when the offset changed. */
  up() {
    const d = this.drag;
    if (!d) return false;
    this.drag = null;
    const h = d.handle;
    if (d.offset.every((x, i) => x === h.tuning[0][i])) return true;
    this.set(d.part, h.face, d.offset);
    return true;
  }
}
