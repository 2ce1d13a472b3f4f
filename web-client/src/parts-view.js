// The drawings of a design's parts in the 3D view: each surface part a mesh
// tessellated from its control net, in its own colour or the view's analysis
// mode, with its control net on demand; each curve part a tube along its
// B-spline with its curvature comb; the seam of each join a highlighted tube
// along the joined edge; a locked part labelled as locked, the selected one
// lit. Hidden parts are neither drawn nor pickable.

import * as THREE from 'three';
import { Tessellator, curveDerivs, surfaceDerivs } from './bspline.js';
import { curvePartSamples, combSegments } from './comb.js';
import { domainOf } from './design.js';
import { label } from './icons.js';
import { curvatureColor } from './view.js';

/** Most vertices one surface's tessellation may have. */
const VERTEX_BUDGET = 50000;
/** The colour of a seam (a joined edge). */
export const SEAM_COLOUR = 0xffd54f;
/** The colour of a bound line (a surface's parameter line following a curve part). */
export const BINDING_COLOUR = 0x4dd0e1;

/** Samples of a surface tessellation: about 4 vertices per control point along each direction, within a budget of 50 000 vertices (81×159 gets 162×318; BENCHMARKS.md, web client). */
export function density(s) {
  let su = 4 * s.nu;
  let sv = 4 * s.nv;
  const scale = Math.min(1, Math.sqrt(VERTEX_BUDGET / (su * sv)));
  su = Math.max(2 * s.nu, Math.round(su * scale), 8);
  sv = Math.max(2 * s.nv, Math.round(sv * scale), 8);
  return [su, sv];
}

/** A curve part as a three.js curve over [0, 1] (its knot domain mapped there), for TubeGeometry. */
class PartCurve extends THREE.Curve {
  constructor(g) {
    super();
    this.g = g;
    [[this.a, this.b]] = domainOf(g);
  }

  getPoint(t, target = new THREE.Vector3()) {
    return target.set(...curveDerivs(this.g, this.a + (this.b - this.a) * t).p);
  }
}

/** Points along the parameter line of surface geometry `g` where `line` ({ u } or { v }) is held fixed. */
export function linePoints(g, line, n = 48) {
  const [[u0, u1], [v0, v1]] = domainOf(g);
  const out = [];
  for (let k = 0; k < n; k++) {
    const s = k / (n - 1);
    const uv = line.u !== undefined ? [line.u, v0 + (v1 - v0) * s] : [u0 + (u1 - u0) * s, line.v];
    out.push(surfaceDerivs(g, uv[0], uv[1]).p);
  }
  return out;
}

/** Points along edge `edge` (u_min, u_max, v_min, v_max: the parameter held fixed) of surface geometry `g`. */
export function edgePoints(g, edge, n = 48) {
  const [[u0, u1], [v0, v1]] = domainOf(g);
  const line = { u_min: { u: u0 }, u_max: { u: u1 }, v_min: { v: v0 }, v_max: { v: v1 } }[edge];
  if (!line) throw new Error(`unknown edge ${edge}`);
  return linePoints(g, line, n);
}

/** Half the diagonal of the box around every part's control points (the design's size), at least 1e-6. */
function designRadius(design) {
  const box = new THREE.Box3();
  const p = new THREE.Vector3();
  for (const part of design.parts.values()) {
    const pts = part.geometry && part.geometry.points;
    if (!pts) continue;
    for (let i = 0; i < pts.length; i += 3) box.expandByPoint(p.set(pts[i], pts[i + 1], pts[i + 2]));
  }
  return box.isEmpty() ? 1 : Math.max(box.getSize(p).length() / 2, 1e-6);
}

function disposeTree(obj) {
  obj.traverse((o) => {
    if (o.geometry) o.geometry.dispose();
    if (o.material && !o.material.shared) {
      if (o.material.map) o.material.map.dispose();
      o.material.dispose();
    }
  });
}

export class PartsView {
  /** @param {import('./view.js').View} view */
  constructor(view) {
    this.view = view;
    this.group = new THREE.Group();
    this.group.name = 'parts';
    this.seams = new THREE.Group();
    this.seams.name = 'seams';
    view.model.add(this.group, this.seams);
    /** Drawings by part id: { id, kind, group, mesh, shaded, tess?, net?, comb?, lock, visible, deviation? }. */
    this.drawings = new Map();
    this.showNet = false;
    /** The design's size (half its diagonal), for tube, comb and seam sizes. */
    this.scale = 1;
    /** The part whose surface is coloured by its deviation in compare mode. */
    this.compared = null;
    /** How many shapes were filled on the main thread (counted for the tests and benches). */
    this.fills = 0;
    view.colored.shared = true;
    view.zebra.shared = true;
    view.bounds = () => this.box();
    view.onModeChange = () => this.restyle();
  }

  /**
   * Brings the drawings in line with `design`: adds and removes drawings,
   * sets colour, visibility (a part is drawn when it is visible and not in
   * `hidden`), lock label and selection, and fills here on the main thread
   * every drawn part whose shape changed; then the seams.
   */
  sync(design, { hidden = new Set(), selected = null } = {}) {
    for (const [id, d] of this.drawings) {
      const part = design.parts.get(id);
      if (!part || !part.geometry || part.kind !== d.kind) this.drop(id);
    }
    this.scale = designRadius(design);
    for (const part of design.parts.values()) {
      if (!part.geometry) continue;
      let d = this.drawings.get(part.id);
      if (!d) {
        d = this.create(part);
        this.drawings.set(part.id, d);
      }
      d.part = part;
      d.visible = part.visible && !hidden.has(part.id);
      d.selected = part.id === selected;
      // Only a shape not drawn yet is filled (an icon or part event leaves the other parts' meshes alone); a
      // curve also when the design's size, and so its tube's radius, changed; a hidden part when it is shown.
      const stale = d.filled !== part.geometry || (d.kind === 'curve' && d.filledScale !== this.scale);
      if (d.visible && stale) this.fill(part.id, part.geometry);
      this.style(d);
    }
    this.drawSeams(design);
    this.view.drawn();
  }

  create(part) {
    const group = new THREE.Group();
    group.name = `part-${part.id}`;
    group.userData.partId = part.id;
    const shaded = this.view.studio.light(new THREE.MeshStandardMaterial({ color: part.colour, metalness: 0.1, roughness: 0.45, side: THREE.DoubleSide }));
    const mesh = new THREE.Mesh(new THREE.BufferGeometry(), shaded);
    mesh.name = part.kind === 'curve' ? `tube-${part.id}` : `surface-${part.id}`;
    mesh.userData.partId = part.id;
    group.add(mesh);
    const d = { id: part.id, kind: part.kind, group, mesh, shaded, tess: null, lock: null };
    if (part.kind === 'surface') {
      d.net = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x6fa8ff }));
      d.net.visible = false;
      group.add(d.net);
    } else {
      const combMat = new THREE.LineBasicMaterial({ color: 0xff80ff, transparent: true, opacity: 0.8 });
      d.comb = new THREE.Group();
      d.comb.name = `comb-${part.id}`;
      d.comb.add(new THREE.LineSegments(new THREE.BufferGeometry(), combMat), new THREE.Line(new THREE.BufferGeometry(), combMat));
      group.add(d.comb);
    }
    this.group.add(group);
    return d;
  }

  drop(id) {
    const d = this.drawings.get(id);
    if (!d) return;
    this.group.remove(d.group);
    disposeTree(d.group);
    this.drawings.delete(id);
    if (this.compared === id) this.compared = null;
  }

  /** Colour, mode material, selection glow, visibility and the lock label of one drawing. */
  style(d) {
    const part = d.part;
    d.group.visible = d.visible;
    d.shaded.color.set(part.colour);
    d.shaded.emissive.set(d.selected ? part.colour : 0x000000);
    d.shaded.emissiveIntensity = d.selected ? 0.25 : 0;
    const mode = this.view.mode;
    if (d.kind === 'surface') {
      if (mode === 'zebra') d.mesh.material = this.view.zebra;
      else if (mode === 'mean' || mode === 'gauss' || (mode === 'deviation' && this.compared === d.id)) d.mesh.material = this.view.colored;
      else d.mesh.material = d.shaded;
      this.updateColors(d);
    }
    const text = part.locked ? `locked · ${part.name}` : null;
    if (d.lock && d.lock.userData.text !== text) {
      d.group.remove(d.lock);
      disposeTree(d.lock);
      d.lock = null;
    }
    if (text && !d.lock) {
      d.lock = label(text, { color: '#ffcc80', height: 0.028 });
      d.lock.name = `lock-${part.id}`;
      d.group.add(d.lock);
    }
    if (d.lock) {
      const box = d.mesh.geometry.boundingBox;
      if (box) d.lock.position.set((box.min.x + box.max.x) / 2, (box.min.y + box.max.y) / 2, box.max.z + 0.05 * this.scale);
    }
  }

  restyle() {
    for (const d of this.drawings.values()) this.style(d);
  }

  /** Vertex colours of a surface drawing in the curvature and deviation modes. */
  updateColors(d) {
    const t = d.tess;
    const mode = this.view.mode;
    if (!t || d.mesh.material !== this.view.colored) return;
    const values = mode === 'mean' ? t.mean : mode === 'gauss' ? t.gauss : d.deviation;
    if (!values || values.length !== t.mean.length) return;
    const colors = d.mesh.geometry.attributes.color.array;
    for (let i = 0; i < values.length; i++) curvatureColor(values[i], this.view.range, colors, i * 3);
    d.mesh.geometry.attributes.color.needsUpdate = true;
  }

  /** The tessellator of surface part `id` when it fits geometry `g` (the per-frame path fills it in place), else null. */
  tessFor(id, g) {
    const d = this.drawings.get(id);
    return d && d.kind === 'surface' && d.tess && d.tess.fits(g) ? d.tess : null;
  }

  /** Fills part `id`'s drawing from geometry `g` here on the main thread (a new tessellation when the layout changed). */
  fill(id, g) {
    const d = this.drawings.get(id);
    if (!d) return false;
    this.fills++;
    if (d.kind === 'surface') {
      if (!d.tess || !d.tess.fits(g)) d.tess = new Tessellator(g, ...density(g));
      d.tess.fill(g);
      this.surfaceFilled(id, d.tess, g);
    } else {
      this.fillCurve(d, g);
    }
    return true;
  }

  /** `tess` now holds surface part `id`'s shape `g`: the mesh (buffers reused), its bounds, colours and net. */
  surfaceFilled(id, tess, g) {
    const d = this.drawings.get(id);
    if (!d || d.tess !== tess) return;
    const geo = d.mesh.geometry;
    if (geo.userData.tess !== tess) {
      geo.setAttribute('position', new THREE.BufferAttribute(tess.positions, 3));
      geo.setAttribute('normal', new THREE.BufferAttribute(tess.normals, 3));
      geo.setAttribute('uv', new THREE.BufferAttribute(tess.uvs, 2));
      geo.setAttribute('color', new THREE.BufferAttribute(new Float32Array(tess.positions.length), 3));
      geo.setIndex(new THREE.BufferAttribute(tess.indices, 1));
      geo.userData.tess = tess;
    }
    geo.attributes.position.needsUpdate = true;
    geo.attributes.normal.needsUpdate = true;
    this.view.shadow.invalidate();
    const b = tess.box;
    if (!geo.boundingBox) geo.boundingBox = new THREE.Box3();
    if (!geo.boundingSphere) geo.boundingSphere = new THREE.Sphere();
    geo.boundingBox.min.set(b[0], b[1], b[2]);
    geo.boundingBox.max.set(b[3], b[4], b[5]);
    geo.boundingBox.getBoundingSphere(geo.boundingSphere);
    this.updateColors(d);
    this.setNet(d, g);
    d.filled = g;
  }

  /** A curve part's tube (rebuilt: a few thousand vertices) and curvature comb. */
  fillCurve(d, g) {
    const segments = Math.min(512, Math.max(64, 8 * g.n));
    const tube = new THREE.TubeGeometry(new PartCurve(g), segments, 0.012 * this.scale, 10, false);
    tube.computeBoundingBox();
    tube.computeBoundingSphere();
    d.mesh.geometry.dispose();
    d.mesh.geometry = tube;
    const comb = combSegments(curvePartSamples(g, 64), 0.15 * this.scale);
    const [teeth, outline] = d.comb.children;
    teeth.geometry.setAttribute('position', new THREE.Float32BufferAttribute(comb.teeth, 3));
    outline.geometry.setAttribute('position', new THREE.Float32BufferAttribute(comb.outline, 3));
    teeth.geometry.computeBoundingSphere();
    outline.geometry.computeBoundingSphere();
    d.filled = g;
    d.filledScale = this.scale;
  }

  /** A surface drawing's control net (copied into a reused buffer; skipped while nets are hidden). */
  setNet(d, g) {
    d.netSurface = g;
    d.net.visible = this.showNet;
    if (!this.showNet) return;
    const geo = d.net.geometry;
    const { nu, nv } = g;
    if (geo.userData.nu !== nu || geo.userData.nv !== nv) {
      const segments = [];
      for (let i = 0; i < nu; i++) {
        for (let j = 0; j < nv; j++) {
          if (j + 1 < nv) segments.push(i * nv + j, i * nv + j + 1);
          if (i + 1 < nu) segments.push(i * nv + j, (i + 1) * nv + j);
        }
      }
      geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(nu * nv * 3), 3));
      geo.setIndex(segments);
      geo.userData.nu = nu;
      geo.userData.nv = nv;
    }
    geo.attributes.position.array.set(g.points);
    geo.attributes.position.needsUpdate = true;
    geo.computeBoundingSphere();
  }

  setShowNet(on) {
    this.showNet = on;
    for (const d of this.drawings.values()) if (d.kind === 'surface' && d.netSurface) this.setNet(d, d.netSurface);
  }

  /**
   * The seams: along edge `a` of every join, a tube in the seam colour
   * (drawn when either part is); along the bound line of every binding, a
   * thinner tube in the binding colour (drawn with its surface).
   */
  drawSeams(design) {
    for (const s of [...this.seams.children]) {
      this.seams.remove(s);
      disposeTree(s);
    }
    for (const r of design.relations.values()) {
      if (r.kind === 'binding') {
        const surface = design.parts.get(r.surface);
        const ds = this.drawings.get(r.surface);
        if (!surface || !surface.geometry || surface.kind !== 'surface' || !ds || !ds.visible || !r.line) continue;
        const pts = linePoints(surface.geometry, r.line).map((p) => new THREE.Vector3(...p));
        const bound = new THREE.Mesh(
          new THREE.TubeGeometry(new THREE.CatmullRomCurve3(pts), 96, 0.006 * this.scale, 8, false),
          new THREE.MeshBasicMaterial({ color: BINDING_COLOUR }),
        );
        bound.name = `binding-${r.id}`;
        bound.userData.relation = r.id;
        bound.userData.parts = [r.curve, r.surface];
        this.seams.add(bound);
        continue;
      }
      if (r.kind !== 'join') continue;
      const a = design.parts.get(r.a.part);
      const b = design.parts.get(r.b.part);
      const da = this.drawings.get(r.a.part);
      const db = this.drawings.get(r.b.part);
      if (!a || !a.geometry || a.kind !== 'surface' || !((da && da.visible) || (db && db.visible))) continue;
      const pts = edgePoints(a.geometry, r.a.edge).map((p) => new THREE.Vector3(...p));
      const seam = new THREE.Mesh(
        new THREE.TubeGeometry(new THREE.CatmullRomCurve3(pts), 96, 0.008 * this.scale, 8, false),
        new THREE.MeshBasicMaterial({ color: SEAM_COLOUR }),
      );
      seam.name = `seam-${r.id}`;
      seam.userData.relation = r.id;
      seam.userData.parts = [r.a.part, r.b.part];
      seam.userData.points = pts.length;
      this.seams.add(seam);
    }
  }

  /** Draws `tess` (a tessellation of a version's surface) as a faint wireframe ghost; null removes it. */
  setGhost(tess) {
    if (this.ghost) {
      this.view.model.remove(this.ghost);
      this.ghost.geometry.dispose();
      this.ghost.material.dispose();
      this.ghost = null;
    }
    if (!tess) return;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(tess.positions, 3));
    g.setIndex(new THREE.BufferAttribute(tess.indices, 1));
    this.ghost = new THREE.Mesh(g, new THREE.MeshBasicMaterial({ color: 0xffd54f, wireframe: true, transparent: true, opacity: 0.18 }));
    this.ghost.name = 'compare-ghost';
    this.view.model.add(this.ghost);
  }

  /** The meshes a click may hit: the surfaces and tubes of the parts drawn. */
  pickables() {
    return [...this.drawings.values()].filter((d) => d.visible).map((d) => d.mesh);
  }

  /** The bounds of every part drawn. */
  box() {
    const box = new THREE.Box3();
    for (const d of this.drawings.values()) {
      if (d.visible && d.mesh.geometry.boundingBox) box.union(d.mesh.geometry.boundingBox);
    }
    return box;
  }

  /** (u, v) of a hit on a surface mesh or t of a hit on a curve's tube: { part, kind, u, v } or { part, kind, t }. */
  hitParams(hit) {
    const id = hit.object.userData.partId;
    const d = this.drawings.get(id);
    if (!d || !hit.uv) return null;
    if (d.kind === 'surface') return { part: id, kind: 'surface', u: hit.uv.x, v: hit.uv.y };
    const [[a, b]] = domainOf(d.part.geometry);
    return { part: id, kind: 'curve', t: a + (b - a) * hit.uv.x };
  }
}
