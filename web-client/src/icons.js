// Icons drawn as paper 003 draws them: red sphere = position constraint,
// green sphere = load, yellow sphere labelled R/V/R2/V2/RV = derivative
// constraint, a 3D arrow along N = normal constraint, a polyline for a curve
// icon (with its curvature comb), an outlined patch for a region icon, a
// tube along a held edge (with ticks across it when clamped); on a
// curve part, a sphere at a param icon's t and the stretch t0…t1 of a span
// icon drawn along the curve; grey when sleeping, larger and glowing while
// driving. A position constraint the surface does not meet shows its target
// as a hollow marker joined to the surface, labelled with the miss. Each
// icon is drawn against the geometry of its own part.

import * as THREE from 'three';
import { curveDerivs, surfaceDerivs } from './bspline.js';
import { curvatureSamples, combSegments } from './comb.js';
import { domainOf } from './design.js';

const COLORS = { position: 0xe53935, load: 0x43a047, derivative: 0xfdd835, normal: 0x1e88e5 };
const GREY = 0x8a8a8a;

/**
 * A text label that keeps its size on screen (about 20 px tall whatever the
 * model's size or the zoom): light text on a dark rounded plate, drawn over
 * the surface.
 */
export function label(text, { color = '#fff', height = 0.03 } = {}) {
  const c = document.createElement('canvas');
  const g0 = c.getContext('2d');
  g0.font = 'bold 40px sans-serif';
  c.width = Math.ceil(g0.measureText(text).width) + 24;
  c.height = 56;
  const g = c.getContext('2d');
  g.fillStyle = 'rgba(20, 24, 30, 0.8)';
  g.beginPath();
  g.roundRect(0, 0, c.width, c.height, 12);
  g.fill();
  g.fillStyle = color;
  g.font = 'bold 40px sans-serif';
  g.textAlign = 'center';
  g.textBaseline = 'middle';
  g.fillText(text, c.width / 2, c.height / 2 + 2);
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: new THREE.CanvasTexture(c), depthTest: false, sizeAttenuation: false }));
  sprite.scale.set((height * c.width) / c.height, height, 1);
  sprite.renderOrder = 10;
  sprite.userData.text = text;
  return sprite;
}

/** How far a point icon's surface point may be from its target before the miss is drawn, relative to the handle size. */
export const MISS_SHOWN = 0.05;

/** (u, v) points along a curve anchor, evaluated from its B-spline in the domain. */
function curveUv(anchor, n = 48) {
  const { knots, points } = anchor.curve;
  const s = {
    degreeU: knots.degree,
    knotsU: knots.knots,
    nu: points.length,
    degreeV: 1,
    knotsV: [0, 0, 1, 1],
    nv: 2,
    points: points.flatMap((p) => [p[0], p[1], 0, p[0], p[1], 0]),
  };
  const [a, b] = [knots.knots[0], knots.knots[knots.knots.length - 1]];
  return Array.from({ length: n }, (_, k) => surfaceDerivs(s, a + ((b - a) * k) / (n - 1), 0).p);
}

export class IconLayer {
  constructor(scene) {
    this.group = new THREE.Group();
    this.group.name = 'icons';
    scene.add(this.group);
    this.objects = new Map();
    this.size = 0.05;
  }

  /**
   * Rebuilds the drawing of every icon in `icons` (a Map id → icon with
   * `part`) against its part's geometry, `geometryOf(partId)` (null: the
   * part has no shape yet); icons not in `icons` (e.g. of hidden parts) go.
   */
  update(icons, geometryOf, selected) {
    for (const [id, obj] of this.objects) {
      if (!icons.has(id)) {
        this.remove(obj);
        this.objects.delete(id);
      }
    }
    for (const icon of icons.values()) {
      let obj = this.objects.get(icon.id);
      if (obj) this.remove(obj);
      obj = this.draw(icon, geometryOf(icon.part), icon.id === selected);
      obj.userData.iconId = icon.id;
      this.objects.set(icon.id, obj);
      this.group.add(obj);
    }
  }

  /** Takes an icon's drawing out of the scene and frees its GPU resources. */
  remove(obj) {
    this.group.remove(obj);
    obj.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
      if (o.material) {
        if (o.material.map) o.material.map.dispose();
        o.material.dispose();
      }
    });
  }

  draw(icon, geometry, selected) {
    const surface = geometry && geometry.kind === 'surface' ? geometry : null;
    const curve = geometry && geometry.kind === 'curve' ? geometry : null;
    const g = new THREE.Group();
    const kind = icon.role.kind;
    const sleeping = icon.state === 'sleeping';
    const driving = icon.state === 'driving';
    const color = sleeping ? GREY : COLORS[kind];
    const mat = new THREE.MeshStandardMaterial({ color, emissive: driving || selected ? color : 0x000000, emissiveIntensity: driving ? 0.6 : 0.3 });
    const r = this.size * (driving ? 1.5 : 1);
    const handle = new THREE.Mesh(new THREE.SphereGeometry(r, 20, 14), mat);
    handle.position.set(...icon.xyz);
    handle.userData.iconId = icon.id;
    handle.name = `icon-${icon.id}`;
    g.add(handle);
    if (kind === 'derivative') {
      const l = label(icon.role.which, { color: '#fdd835' });
      l.position.set(icon.xyz[0], icon.xyz[1], icon.xyz[2] + 2.2 * r);
      g.add(l);
    }
    // A position constraint the solve could not meet (contradictory icons):
    // its target as a hollow marker, joined to where the surface is, with the miss.
    if (kind === 'position' && (icon.anchor.kind === 'point' || icon.anchor.kind === 'param') && !sleeping) {
      const at = new THREE.Vector3(...icon.xyz);
      const target = new THREE.Vector3(...icon.target);
      const miss = at.distanceTo(target);
      if (miss > MISS_SHOWN * r) {
        const marker = new THREE.Mesh(
          new THREE.SphereGeometry(r * 1.2, 12, 8),
          new THREE.MeshBasicMaterial({ color, wireframe: true }),
        );
        marker.position.copy(target);
        marker.name = `target-${icon.id}`;
        const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints([at, target]), new THREE.LineDashedMaterial({ color, dashSize: r, gapSize: r / 2 }));
        line.computeLineDistances();
        const l = label(`misses by ${miss.toPrecision(3)}`, { color: '#ff8a80', height: 0.025 });
        l.position.copy(target).add(new THREE.Vector3(0, 0, 2.5 * r));
        l.name = `miss-${icon.id}`;
        g.add(marker, line, l);
      }
    }
    if (kind === 'normal') {
      const dir = new THREE.Vector3(...icon.target).normalize();
      g.add(new THREE.ArrowHelper(dir, new THREE.Vector3(...icon.xyz), 6 * this.size, color, 2 * this.size, this.size));
    }
    if (surface && icon.anchor.kind === 'curve') {
      const pts = curveUv(icon.anchor).map(([u, v]) => new THREE.Vector3(...surfaceDerivs(surface, u, v).p));
      g.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color, linewidth: 2 })));
      // The curvature comb along the curve icon.
      const comb = combSegments(curvatureSamples(surface, icon.anchor.curve, 64), 8 * this.size);
      const combMat = new THREE.LineBasicMaterial({ color: 0xff80ff, transparent: true, opacity: 0.8 });
      const teeth = new THREE.BufferGeometry();
      teeth.setAttribute('position', new THREE.Float32BufferAttribute(comb.teeth, 3));
      const outline = new THREE.BufferGeometry();
      outline.setAttribute('position', new THREE.Float32BufferAttribute(comb.outline, 3));
      g.add(new THREE.LineSegments(teeth, combMat), new THREE.Line(outline, combMat));
    }
    if (curve && icon.anchor.kind === 'span') {
      const { t0, t1 } = icon.anchor;
      const pts = Array.from({ length: 33 }, (_, k) => new THREE.Vector3(...curveDerivs(curve, t0 + ((t1 - t0) * k) / 32).p));
      const stretch = new THREE.Mesh(
        new THREE.TubeGeometry(new THREE.CatmullRomCurve3(pts), 48, this.size * 0.45, 8, false),
        new THREE.MeshStandardMaterial({ color, emissive: color, emissiveIntensity: selected ? 0.5 : 0.2 }),
      );
      stretch.name = `span-${icon.id}`;
      g.add(stretch);
    }
    if (surface && icon.anchor.kind === 'edge') {
      // The held edge, drawn along the surface; a clamped edge also shows
      // the held strip's inner border (its tangent plane is held) as ticks.
      const [[u0, u1], [v0, v1]] = domainOf(surface);
      const at = (s) => ({
        u_min: [u0, v0 + (v1 - v0) * s],
        u_max: [u1, v0 + (v1 - v0) * s],
        v_min: [u0 + (u1 - u0) * s, v0],
        v_max: [u0 + (u1 - u0) * s, v1],
      })[icon.anchor.edge];
      const n = 48;
      const pts = Array.from({ length: n + 1 }, (_, k) => new THREE.Vector3(...surfaceDerivs(surface, ...at(k / n)).p));
      const held = new THREE.Mesh(
        new THREE.TubeGeometry(new THREE.CatmullRomCurve3(pts), 64, this.size * (icon.anchor.mode === 'clamped' ? 0.6 : 0.35), 8, false),
        new THREE.MeshStandardMaterial({ color, emissive: color, emissiveIntensity: selected ? 0.5 : 0.2 }),
      );
      held.name = `edge-${icon.id}`;
      g.add(held);
      if (icon.anchor.mode === 'clamped') {
        const ticks = [];
        for (let k = 0; k <= 16; k++) {
          const p = surfaceDerivs(surface, ...at(k / 16));
          const across = icon.anchor.edge.startsWith('u') ? p.u : p.v;
          const len = Math.hypot(...across) || 1;
          const sign = icon.anchor.edge.endsWith('min') ? 1 : -1;
          const q = p.p.map((x, i) => x + (sign * 3 * this.size * across[i]) / len);
          ticks.push(...p.p, ...q);
        }
        const geo = new THREE.BufferGeometry();
        geo.setAttribute('position', new THREE.Float32BufferAttribute(ticks, 3));
        const t = new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ color }));
        t.name = `clamp-${icon.id}`;
        g.add(t);
      }
    }
    if (surface && icon.anchor.kind === 'region') {
      const { u0, v0, u1, v1 } = icon.anchor;
      const loop = [];
      const n = 16;
      for (let k = 0; k <= n; k++) loop.push([u0 + ((u1 - u0) * k) / n, v0]);
      for (let k = 0; k <= n; k++) loop.push([u1, v0 + ((v1 - v0) * k) / n]);
      for (let k = 0; k <= n; k++) loop.push([u1 - ((u1 - u0) * k) / n, v1]);
      for (let k = 0; k <= n; k++) loop.push([u0, v1 - ((v1 - v0) * k) / n]);
      const pts = loop.map(([u, v]) => new THREE.Vector3(...surfaceDerivs(surface, u, v).p));
      g.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color })));
    }
    return g;
  }

  /** The handle meshes, for picking. */
  handles() {
    return [...this.objects.values()].map((g) => g.children[0]);
  }

  /** Moves handles to new positions from a geometry frame. */
  move(frameIcons) {
    for (const fi of frameIcons) {
      const obj = this.objects.get(fi.id);
      if (obj) obj.children[0].position.set(...fi.xyz);
    }
  }
}
