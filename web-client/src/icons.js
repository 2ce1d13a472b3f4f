// Icons drawn as paper 003 draws them: red sphere = position constraint,
// green sphere = load, yellow sphere labelled R/V/R2/V2/RV = derivative
// constraint, a 3D arrow along N = normal constraint, a polyline for a curve
// icon (with its curvature comb), an outlined patch for a region icon; grey when sleeping, larger and
// glowing while driving.

import * as THREE from 'three';
import { surfaceDerivs } from './bspline.js';
import { curvatureSamples, combSegments } from './comb.js';

const COLORS = { position: 0xe53935, load: 0x43a047, derivative: 0xfdd835, normal: 0x1e88e5 };
const GREY = 0x8a8a8a;

function label(text) {
  const c = document.createElement('canvas');
  c.width = 64;
  c.height = 32;
  const g = c.getContext('2d');
  g.fillStyle = '#000';
  g.font = 'bold 24px sans-serif';
  g.textAlign = 'center';
  g.textBaseline = 'middle';
  g.fillText(text, 32, 16);
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: new THREE.CanvasTexture(c), depthTest: false }));
  sprite.scale.set(0.16, 0.08, 1);
  return sprite;
}

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

  /** Rebuilds the drawing of every icon against the current surface. */
  update(icons, surface, selected) {
    for (const [id, obj] of this.objects) {
      if (!icons.has(id)) {
        this.remove(obj);
        this.objects.delete(id);
      }
    }
    for (const icon of icons.values()) {
      let obj = this.objects.get(icon.id);
      if (obj) this.remove(obj);
      obj = this.draw(icon, surface, icon.id === selected);
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

  draw(icon, surface, selected) {
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
      const l = label(icon.role.which);
      l.position.set(icon.xyz[0], icon.xyz[1], icon.xyz[2] + 2.2 * r);
      g.add(l);
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
