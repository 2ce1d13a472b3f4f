// Ribbon handles of styling-curve network parts (paper 004 §5), drawn and
// dragged in the browser. Every side of every face gets a handle: a ball on
// a stem from the side's middle c(t_m) into the face. Its distance from the
// curve is the side's scale (how far the patch reaches before it turns: the
// cross-boundary derivative's length is multiplied by the scale at the
// middle), its angle about the curve's tangent is the side's twist (the
// tangent plane along the side turned about the curve, the face across
// following). At scale 1 and twist 0 the ball sits `REACH` of the way from
// the side's middle towards the face's centre, in the plane normal to the
// curve there. A drag moves the ball in that plane; on release the page
// sends one `network_edit` set_ribbon (one undoable step) with the scale and
// twist the ball's position gives, clamped to what the server accepts
// (scale in [0.1, 10], |twist| < π/2; near-defaults snap to them), and the
// server's `network_changed` redraws the handles where the server put them.

import * as THREE from 'three';
import { curveDerivs } from './bspline.js';
import { HandleSet } from './network-handles.js';

/** The stem at scale 1: this fraction of the distance to the face's centre. */
export const REACH = 0.3;
/** Scale range the server accepts. */
export const MIN_SCALE = 0.1;
export const MAX_SCALE = 10;
/** Largest twist sent (the server refuses |twist| ≥ π/2). */
export const MAX_TWIST = 1.5;
/** A scale this close to 1, a twist this close to 0 is sent as the default. */
const SNAP_SCALE = 0.02;
const SNAP_TWIST = 0.03;

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = (a) => mul(a, 1 / Math.hypot(a[0], a[1], a[2]));

/**
 * The frame of the handle of side `k` of face `f` of a network (`curves`:
 * bspline.js curves, `network`: the wire's NetworkData): { mid, axis (unit
 * tangent of the curve in its own direction), inward (unit, normal to axis,
 * towards the face's centre), across (axis × inward), reach }, or null for
 * a degenerate side.
 */
export function sideFrame(curves, network, f, k) {
  const face = network.faces[f];
  const mids = face.sides.map((s) => curveDerivs(curves[s.curve], (s.t_start + s.t_end) / 2).p);
  const centre = mul(mids.reduce(add, [0, 0, 0]), 1 / mids.length);
  const side = face.sides[k];
  const d = curveDerivs(curves[side.curve], (side.t_start + side.t_end) / 2);
  const len = Math.hypot(...d.d1);
  if (!(len > 0)) return null;
  const axis = mul(d.d1, 1 / len);
  const v = sub(centre, d.p);
  const normal = sub(v, mul(axis, dot(v, axis)));
  const dist = Math.hypot(...normal);
  if (!(dist > 0)) return null;
  const inward = mul(normal, 1 / dist);
  return { mid: d.p, axis, inward, across: unit(cross(axis, inward)), reach: REACH * dist };
}

/** Where the ball of a side with frame `fr` sits for `scale` and `twist` (model space). */
export function handlePoint(fr, scale, twist) {
  const dir = add(mul(fr.inward, Math.cos(twist)), mul(fr.across, Math.sin(twist)));
  return add(fr.mid, mul(dir, fr.reach * scale));
}

/** The scale and twist a ball at model point `p` gives (clamped and snapped as sent). */
export function handleValues(fr, p) {
  const o = sub(p, fr.mid);
  const x = dot(o, fr.inward);
  const y = dot(o, fr.across);
  let scale = Math.hypot(x, y) / fr.reach;
  let twist = Math.atan2(y, x);
  scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, scale));
  twist = Math.min(MAX_TWIST, Math.max(-MAX_TWIST, twist));
  if (Math.abs(scale - 1) < SNAP_SCALE) scale = 1;
  if (Math.abs(twist) < SNAP_TWIST) twist = 0;
  return { scale, twist };
}

export class RibbonHandles extends HandleSet {
  /** `view`: the View; `send(msg)` sends a message; `canEdit()` whether this page may edit. */
  constructor(view, options) {
    super(view, options);
    /** Called with `on` whenever the handles are shown or hidden (the faces' tuning handles follow). */
    this.onShow = null;
    // `drag`: { part, handle, plane, scale, twist }; `sent`: the last set_ribbon.
    this.ballGeometry = new THREE.SphereGeometry(1, 12, 8);
    this.ballMaterial = new THREE.MeshBasicMaterial({ color: 0xff7a1a, depthTest: false });
    this.stemMaterial = new THREE.LineBasicMaterial({ color: 0xff7a1a, depthTest: false });
  }

  /** Shows or hides every part's handles. */
  show(on) {
    super.show(on);
    if (this.onShow) this.onShow(on);
  }

  /** Network part `id` (its drawing `root` group, bspline.js `curves`, wire `network`) has new curves or handles. */
  update(id, root, curves, network) {
    const group = this.group(id, root, `network-${id}-ribbon-handles`);
    const handles = [];
    (network.faces || []).forEach((face, f) => {
      face.sides.forEach((_, k) => {
        const frame = sideFrame(curves, network, f, k);
        if (!frame) return;
        const h = (network.ribbons && network.ribbons[f] && network.ribbons[f][k]) || { scale: 1, twist: 0 };
        const ball = new THREE.Mesh(this.ballGeometry, this.ballMaterial);
        ball.name = `network-${id}-ribbon-${f}-${k}`;
        ball.renderOrder = 3;
        ball.scale.setScalar(0.12 * frame.reach);
        const stem = this.stem(this.stemMaterial);
        group.add(ball, stem);
        const handle = { face: f, side: k, frame, scale: h.scale, twist: h.twist, ball, stem };
        this.place(handle, h.scale, h.twist);
        handles.push(handle);
      });
    });
    this.parts.set(id, { root: group, handles });
  }

  /** Puts `h`'s ball and stem at `scale`, `twist`. */
  place(h, scale, twist) {
    this.setBall(h, h.frame.mid, handlePoint(h.frame, scale, twist));
  }

  /** Puts `h`'s ball back where its stored values say. */
  restore(h) {
    this.place(h, h.scale, h.twist);
  }

  /** Grabs `hit` (from `nearest`): the ball moves in the plane normal to the curve. */
  grab(hit) {
    if (!this.canEdit() || !hit) return false;
    const fr = hit.handle.frame;
    // The ball moves in the plane normal to the curve at the side's middle.
    const origin = new THREE.Vector3(...fr.mid);
    const normal = new THREE.Vector3(...fr.axis);
    this.view.model.localToWorld(origin);
    normal.transformDirection(this.view.model.matrixWorld);
    this.drag = { part: hit.part, handle: hit.handle, plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, origin), scale: hit.handle.scale, twist: hit.handle.twist };
    return true;
  }

  /** The pointer at canvas pixel (x, y) during a drag: the ball follows (clamped). */
  move(x, y, w, h) {
    const d = this.drag;
    if (!d) return;
    const p = this.pointerOnPlane(x, y, w, h);
    if (!p) return;
    Object.assign(d, handleValues(d.handle.frame, p));
    this.place(d.handle, d.scale, d.twist);
    this.view.drawn();
  }

  /** The release: one set_ribbon with what changed (nothing when nothing did). */
  up() {
    const d = this.drag;
    if (!d) return false;
    this.drag = null;
    const h = d.handle;
    const edit = { op: 'set_ribbon', face: h.face, side: h.side };
    if (d.scale !== h.scale) edit.scale = d.scale;
    if (d.twist !== h.twist) edit.twist = d.twist;
    if (edit.scale === undefined && edit.twist === undefined) return true;
    const req = this.send({ type: 'network_edit', part: d.part, edit });
    if (req === null || req === undefined) this.place(h, h.scale, h.twist);
    else this.sent = { req, part: d.part, handle: h };
    return true;
  }
}
