// The measure tool, for everyone on the design (a reviewing customer too):
// a click on a surface part reads the surface there — the point, its unit
// normal, mean and Gaussian curvature and the principal radii — and a
// second click reads the distance between the two points; a third starts
// again. Points are evaluated on the B-spline surface itself at the (u, v)
// of the click (bspline.js), not on the drawn triangles. Markers and a line
// in the view show what was measured.

import * as THREE from 'three';
import { curvature, surfaceDerivs } from './bspline.js';

/**
 * The surface `s` (as bspline.js takes it) at (u, v): the point `p`, and
 * where the surface is regular its unit `normal`, `mean` and `gauss`
 * curvature and principal curvatures `k1` ≥ `k2` (H ± √(H² − K)).
 */
export function measurePoint(s, u, v) {
  const d = surfaceDerivs(s, u, v);
  const c = curvature(d);
  if (!c) return { u, v, p: d.p, normal: null, mean: null, gauss: null, k1: null, k2: null };
  const root = Math.sqrt(Math.max(c.mean * c.mean - c.gauss, 0));
  return { u, v, p: d.p, normal: c.normal, mean: c.mean, gauss: c.gauss, k1: c.mean + root, k2: c.mean - root };
}

/** A radius of curvature for display: 1/|k|, or "flat" where k is zero to rounding. */
function radius(k, size) {
  return Math.abs(k) * size < 1e-9 ? 'flat' : (1 / Math.abs(k)).toPrecision(4);
}

const fmt = (x) => x.toPrecision(6);

export class Measure {
  /**
   * @param {object} o
   * @param {import('./view.js').View} o.view
   * @param {HTMLButtonElement} o.button toggles the tool
   * @param {HTMLElement} o.output where the readings are written
   */
  constructor(o) {
    Object.assign(this, o);
    this.active = false;
    /** The measured points: { part, u, v, p, normal, mean, gauss, k1, k2 }. */
    this.points = [];
    this.group = new THREE.Group();
    this.group.name = 'measure';
    this.view.model.add(this.group);
    this.button.addEventListener('click', () => this.setActive(!this.active));
  }

  setActive(on) {
    this.active = on;
    this.button.setAttribute('aria-pressed', String(on));
    this.button.textContent = on ? 'measuring: click the surface' : 'measure';
    if (!on) this.clear();
    this.render();
  }

  clear() {
    this.points = [];
    this.render();
  }

  /** A click at (u, v) on surface part `part` with geometry `surface`. */
  add(part, surface, u, v) {
    if (this.points.length === 2) this.points = [];
    this.points.push({ part, ...measurePoint(surface, u, v) });
    this.render();
  }

  /** The distance between the two points, or null. */
  distance() {
    if (this.points.length < 2) return null;
    const [a, b] = this.points;
    return Math.hypot(a.p[0] - b.p[0], a.p[1] - b.p[1], a.p[2] - b.p[2]);
  }

  render() {
    // The markers and line of the last reading go, with their GPU buffers.
    for (const o of this.group.children) {
      o.geometry.dispose();
      o.material.dispose();
    }
    this.group.clear();
    const box = this.view.bounds();
    const size = box && !box.isEmpty() ? box.getSize(new THREE.Vector3()).length() : 1;
    const lines = this.points.map((m, k) => {
      const at = `${'AB'[k]} (${m.p.map(fmt).join(', ')})`;
      if (m.mean === null) return `${at}: the surface is degenerate here`;
      return `${at}: mean curvature ${fmt(m.mean)}, Gaussian ${fmt(m.gauss)}, principal radii ${radius(m.k1, size)} / ${radius(m.k2, size)}`;
    });
    const d = this.distance();
    if (d !== null) lines.push(`distance A–B ${fmt(d)}`);
    this.output.hidden = !this.active;
    this.output.textContent = this.active ? (lines.length ? lines.join('\n') : 'click a surface to measure there') : '';
    const r = size * 0.006;
    for (const m of this.points) {
      const dot = new THREE.Mesh(new THREE.SphereGeometry(r, 12, 8), new THREE.MeshBasicMaterial({ color: 0xffd54f, depthTest: false }));
      dot.position.set(...m.p);
      dot.renderOrder = 10;
      this.group.add(dot);
    }
    if (this.points.length === 2) {
      const g = new THREE.BufferGeometry().setFromPoints(this.points.map((m) => new THREE.Vector3(...m.p)));
      const line = new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0xffd54f, depthTest: false }));
      line.renderOrder = 10;
      this.group.add(line);
    }
  }
}
