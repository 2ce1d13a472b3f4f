// The 3D view: renderer, lights, orbit camera, the surface mesh with its
// display modes (shaded, mean / Gaussian curvature map, zebra stripes) and
// the control net.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const zebraVertex = `
varying vec3 vNormal;
varying vec3 vView;
void main() {
  vec4 mv = modelViewMatrix * vec4(position, 1.0);
  vNormal = normalize(normalMatrix * normal);
  vView = normalize(-mv.xyz);
  gl_Position = projectionMatrix * mv;
}`;
const zebraFragment = `
uniform float stripes;
varying vec3 vNormal;
varying vec3 vView;
void main() {
  vec3 n = normalize(vNormal);
  if (!gl_FrontFacing) n = -n;
  vec3 r = reflect(-normalize(vView), n);
  float s = step(0.5, fract(r.y * stripes));
  gl_FragColor = vec4(vec3(0.08 + 0.9 * s), 1.0);
}`;

/** Diverging colour map: blue (−range) → white (0) → red (+range). */
export function curvatureColor(value, range, out, o) {
  const x = Math.max(-1, Math.min(1, value / (range || 1)));
  if (x >= 0) {
    out[o] = 1;
    out[o + 1] = 1 - x;
    out[o + 2] = 1 - x;
  } else {
    out[o] = 1 + x;
    out[o + 1] = 1 + x;
    out[o + 2] = 1;
  }
}

export class View {
  constructor(container) {
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.renderer.setSize(container.clientWidth, container.clientHeight);
    this.renderer.xr.enabled = true;
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x20242b);
    this.camera = new THREE.PerspectiveCamera(45, container.clientWidth / container.clientHeight, 0.01, 1000);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(3, -3, 3);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(3, -2, 5);
    this.scene.add(sun);
    this.geometry = new THREE.BufferGeometry();
    this.shaded = new THREE.MeshStandardMaterial({ color: 0xb8c4d6, metalness: 0.1, roughness: 0.45, side: THREE.DoubleSide });
    this.colored = new THREE.MeshStandardMaterial({ vertexColors: true, metalness: 0.0, roughness: 0.6, side: THREE.DoubleSide });
    this.zebra = new THREE.ShaderMaterial({ uniforms: { stripes: { value: 8 } }, vertexShader: zebraVertex, fragmentShader: zebraFragment, side: THREE.DoubleSide });
    // Everything in the design's own units and axes (millimetres, z up) hangs
    // under `model`: the identity on a screen; in VR it places the design at
    // real size on a table, y up (placeOnTable).
    this.model = new THREE.Group();
    this.model.name = 'model';
    this.scene.add(this.model);
    this.mesh = new THREE.Mesh(this.geometry, this.shaded);
    this.mesh.name = 'surface';
    this.model.add(this.mesh);
    this.net = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x6fa8ff }));
    this.net.visible = false;
    this.model.add(this.net);
    this.mode = 'shaded';
    this.range = 1;
    this.fitted = false;
    window.addEventListener('resize', () => {
      this.camera.aspect = container.clientWidth / container.clientHeight;
      this.camera.updateProjectionMatrix();
      this.renderer.setSize(container.clientWidth, container.clientHeight);
    });
  }

  /** Puts a tessellation (from bspline.js) into the mesh, reusing buffers; exact bounds. */
  setTessellation(t) {
    this.updateTessellation(t);
    this.geometry.computeBoundingSphere();
    this.geometry.computeBoundingBox();
    if (!this.fitted) {
      this.fit();
      this.fitted = true;
    }
  }

  /**
   * The per-frame path: the tessellation's arrays changed in place; flags the
   * attributes for upload (their buffers are reused, no new geometry) and
   * takes the bounds from the tessellator's box (the sphere around the box).
   */
  updateTessellation(t) {
    const g = this.geometry;
    if (g.userData.tess !== t) {
      g.setAttribute('position', new THREE.BufferAttribute(t.positions, 3));
      g.setAttribute('normal', new THREE.BufferAttribute(t.normals, 3));
      g.setAttribute('uv', new THREE.BufferAttribute(t.uvs, 2));
      g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(t.positions.length), 3));
      g.setIndex(new THREE.BufferAttribute(t.indices, 1));
      g.userData.tess = t;
    }
    g.attributes.position.needsUpdate = true;
    g.attributes.normal.needsUpdate = true;
    this.updateColors();
    const b = t.box;
    if (!g.boundingBox) g.boundingBox = new THREE.Box3();
    if (!g.boundingSphere) g.boundingSphere = new THREE.Sphere();
    g.boundingBox.min.set(b[0], b[1], b[2]);
    g.boundingBox.max.set(b[3], b[4], b[5]);
    g.boundingBox.getBoundingSphere(g.boundingSphere);
  }

  updateColors() {
    const t = this.geometry.userData.tess;
    if (!t || (this.mode !== 'mean' && this.mode !== 'gauss' && this.mode !== 'deviation')) return;
    const values = this.mode === 'mean' ? t.mean : this.mode === 'gauss' ? t.gauss : this.deviation;
    if (!values || values.length !== t.mean.length) return;
    const colors = this.geometry.attributes.color.array;
    for (let i = 0; i < values.length; i++) curvatureColor(values[i], this.range, colors, i * 3);
    this.geometry.attributes.color.needsUpdate = true;
  }

  /**
   * Compare mode: colours each vertex by `deviation` (signed, along the
   * normal; blue below, red above, white where equal, saturated at `range`)
   * and draws `ghost` (a tessellation of the other shape) as a faint
   * wireframe; `null` ends the comparison.
   */
  setDeviation(deviation, range, ghost) {
    this.deviation = deviation;
    if (this.ghost) {
      this.model.remove(this.ghost);
      this.ghost.geometry.dispose();
      this.ghost = null;
    }
    if (!deviation) {
      this.setMode(this.modeBeforeCompare || 'shaded');
      return;
    }
    if (this.mode !== 'deviation') this.modeBeforeCompare = this.mode;
    if (ghost) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(ghost.positions, 3));
      g.setIndex(new THREE.BufferAttribute(ghost.indices, 1));
      this.ghost = new THREE.Mesh(g, new THREE.MeshBasicMaterial({ color: 0xffd54f, wireframe: true, transparent: true, opacity: 0.18 }));
      this.ghost.name = 'compare-ghost';
      this.model.add(this.ghost);
    }
    this.range = range;
    this.setMode('deviation');
  }

  setMode(mode) {
    this.mode = mode;
    this.mesh.material = mode === 'zebra' ? this.zebra : mode === 'shaded' ? this.shaded : this.colored;
    this.updateColors();
  }

  setRange(range) {
    this.range = range;
    this.updateColors();
  }

  /** Shows the control net of `surface` (copied into a reused buffer; skipped while the net is hidden). */
  setNet(surface) {
    this.netSurface = surface;
    if (!this.net.visible) return;
    const g = this.net.geometry;
    const { nu, nv } = surface;
    if (g.userData.nu !== nu || g.userData.nv !== nv) {
      const segments = [];
      for (let i = 0; i < nu; i++) {
        for (let j = 0; j < nv; j++) {
          if (j + 1 < nv) segments.push(i * nv + j, i * nv + j + 1);
          if (i + 1 < nu) segments.push(i * nv + j, (i + 1) * nv + j);
        }
      }
      g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(nu * nv * 3), 3));
      g.setIndex(segments);
      g.userData.nu = nu;
      g.userData.nv = nv;
    }
    g.attributes.position.array.set(surface.points);
    g.attributes.position.needsUpdate = true;
    g.computeBoundingSphere();
  }

  showNet(visible) {
    this.net.visible = visible;
    if (visible && this.netSurface) this.setNet(this.netSurface);
  }

  /**
   * VR: the design at real size on a table in front of the user — model
   * units (millimetres: `metresPerUnit` 0.001) to metres, z up to WebXR's y
   * up, the bottom of its bounding box at `tableHeight` metres, its centre
   * `distance` metres ahead (−z) of the origin where the headset starts.
   */
  placeOnTable({ metresPerUnit = 0.001, tableHeight = 0.9, distance = 0.7 } = {}) {
    const box = this.geometry.boundingBox;
    const m = this.model;
    m.scale.setScalar(metresPerUnit);
    m.rotation.set(-Math.PI / 2, 0, 0);
    m.position.set(0, 0, 0);
    m.updateMatrixWorld(true);
    if (box) {
      const centre = box.getCenter(new THREE.Vector3());
      const bottom = new THREE.Vector3(centre.x, centre.y, box.min.z);
      const at = bottom.applyMatrix4(m.matrixWorld);
      m.position.set(-at.x, tableHeight - at.y, -distance - at.z);
    }
    m.updateMatrixWorld(true);
  }

  /** Back to the screen: the model in its own units and axes. */
  placeOnScreen() {
    this.model.position.set(0, 0, 0);
    this.model.rotation.set(0, 0, 0);
    this.model.scale.setScalar(1);
    this.model.updateMatrixWorld(true);
  }

  fit() {
    const s = this.geometry.boundingSphere;
    if (!s) return;
    this.controls.target.copy(s.center);
    const dist = (s.radius / Math.sin((this.camera.fov * Math.PI) / 360)) * 1.1;
    this.camera.position.copy(s.center).add(new THREE.Vector3(0.6, -0.9, 0.7).normalize().multiplyScalar(dist));
    this.camera.near = dist / 100;
    this.camera.far = dist * 100;
    this.camera.updateProjectionMatrix();
    this.controls.update();
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }
}
