// The 3D view: renderer, lights, orbit camera, the display modes the part
// drawings use (shaded in each part's colour, mean / Gaussian curvature map,
// zebra stripes, deviation from a version), framing the design, and placing
// it on a table in VR. The drawings themselves are parts-view.js's. The
// shaded view is lit by a studio (studio.js): its environment light on the
// shaded materials, and on request (the reviewer's page) a contact shadow
// on the ground.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { ContactShadow, StudioEnvironment } from './studio.js';

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

/** How long the first framing waits for parts still missing after the first drawing (ms). */
export const FRAME_WAIT_MS = 5000;

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
    /** Shared by every surface drawing in the curvature and deviation modes (vertex colours) and in zebra mode. */
    this.colored = new THREE.MeshStandardMaterial({ vertexColors: true, metalness: 0.0, roughness: 0.6, side: THREE.DoubleSide });
    this.zebra = new THREE.ShaderMaterial({ uniforms: { stripes: { value: 8 } }, vertexShader: zebraVertex, fragmentShader: zebraFragment, side: THREE.DoubleSide });
    // Everything in the design's own units and axes (millimetres, z up) hangs
    // under `model`: the identity on a screen; in VR it places the design at
    // real size on a table, y up (placeOnTable).
    this.model = new THREE.Group();
    this.model.name = 'model';
    this.scene.add(this.model);
    /** The studio's environment light (for the shaded materials: studio.light(material)) and ground shadow. */
    this.studio = new StudioEnvironment();
    this.shadow = new ContactShadow(this.renderer, this.model);
    /** Whether the shaded view shows the contact shadow (the reviewer's page). */
    this.groundShadow = false;
    this.mode = 'shaded';
    this.range = 1;
    /**
     * Whether everything the design holds is drawn (app.js sets it): the
     * first framing waits for it, so the view frames the whole design and
     * not whichever part happened to be drawn first.
     */
    this.ready = () => true;
    /** Whether the camera has framed the design (the whole of it, or what was drawn FRAME_WAIT_MS after the first drawing). */
    this.fitted = false;
    /** Whether that framing had the whole design (then it is final). */
    this.framedWhole = false;
    /** When something was first drawn (performance.now()), or null. */
    this.firstDrawn = null;
    /** Whether the person has turned or moved the view themselves (a late framing then leaves it alone). */
    this.userMoved = false;
    this.controls.addEventListener('start', () => {
      this.userMoved = true;
    });
    /** The axis-aligned bounds of what is drawn (a THREE.Box3, or null when nothing is): set by the part drawings. */
    this.bounds = () => null;
    window.addEventListener('resize', () => {
      this.camera.aspect = container.clientWidth / container.clientHeight;
      this.camera.updateProjectionMatrix();
      this.renderer.setSize(container.clientWidth, container.clientHeight);
    });
  }

  /** The sphere around the drawn bounds, or null. */
  /**
   * Compiles the first picture's shader programs before there is anything
   * to draw (the page calls it as its code finishes loading): the
   * studio-lit shaded surface, the one costly program every design's first
   * picture draws, and the plain programs a warm visit's first picture
   * also draws from the geometry cache (a curve's comb, a body's coloured
   * iso-lines, seams). On a software renderer each takes tens to a few
   * hundred milliseconds, which would otherwise come after the geometry.
   * Only these probes are compiled (in a scene of their own with copies of
   * this scene's lights, which the programs' keys count), not the whole
   * scene, whose hidden helpers the first picture never draws; then drawn
   * once under the page shell, since a software renderer builds a
   * program's pipeline at its first draw. Uses the browser's parallel
   * compile where it has one (`compileAsync`, KHR_parallel_shader_compile).
   * The programs are found again by their cache keys (the material's kind
   * and options, the attributes, the lights), not by the material object.
   * Resolves when they are compiled. `plain: false` compiles the studio
   * program alone and draws nothing (a cold visit: measured, the plain
   * programs and the draw then only delayed the demo's cold picture).
   */
  prewarm({ plain = true } = {}) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute([0, 0, 0, 1, 0, 0, 0, 1, 0], 3));
    g.setAttribute('normal', new THREE.Float32BufferAttribute([0, 0, 1, 0, 0, 1, 0, 0, 1], 3));
    const shaded = this.studio.light(new THREE.MeshStandardMaterial({ side: THREE.DoubleSide }));
    // The plain programs a warm visit's first picture also draws (from the geometry cache, before
    // the snapshot): a curve's comb (lines), a body's iso-lines (lines with vertex colours), seams.
    const lines = [new THREE.LineBasicMaterial(), new THREE.LineBasicMaterial({ vertexColors: true }), new THREE.MeshBasicMaterial()];
    const probes = new THREE.Scene();
    // (A program's key depends on the attributes drawn: only the iso-lines' probe has colours.)
    const coloured = new THREE.BufferGeometry();
    coloured.setAttribute('position', g.getAttribute('position'));
    coloured.setAttribute('color', new THREE.Float32BufferAttribute([1, 1, 1, 1, 1, 1, 1, 1, 1], 3));
    probes.add(new THREE.Mesh(g, shaded));
    if (plain) probes.add(new THREE.LineSegments(g, lines[0]), new THREE.LineSegments(coloured, lines[1]), new THREE.Mesh(g, lines[2]));
    // The scene's lights (copies): the programs' keys count them, for the compile and for the draw.
    for (const light of this.scene.children.filter((o) => o.isLight)) probes.add(light.clone());
    const done = () => {
      // One draw of the probe, under the page shell: a software renderer builds the program's
      // pipeline for this canvas at its first draw (a few hundred ms on SwiftShader, even when
      // the browser's program cache made the link itself quick); the next frame clears it.
      try {
        if (plain) this.renderer.render(probes, this.camera);
      } catch (e) {
        console.warn('shader prewarm draw failed', e);
      }
      this.studio.materials.delete(shaded);
      g.dispose();
      coloured.dispose();
      // The materials are not disposed: that would release the programs
      // (three counts each program's users) before the parts take them.
    };
    let compiled;
    try {
      compiled = this.renderer.compileAsync ? this.renderer.compileAsync(probes, this.camera) : Promise.resolve(this.renderer.compile(probes, this.camera));
    } catch (e) {
      compiled = Promise.reject(e);
    }
    return compiled.then(done, (e) => {
      done();
      console.warn('shader prewarm failed', e);
    });
  }

  boundingSphere() {
    const box = this.bounds();
    return box && !box.isEmpty() ? box.getBoundingSphere(new THREE.Sphere()) : null;
  }

  /** Something was drawn: the camera frames the design once it is all drawn (settle). */
  drawn() {
    this.shadow.invalidate();
    if (this.firstDrawn === null && this.boundingSphere()) this.firstDrawn = performance.now();
    this.settle();
  }

  /**
   * The first framing (called per drawing and per frame until it is final):
   * once every part is drawn (`ready`) the camera frames them all; if some
   * part is still missing FRAME_WAIT_MS after the first drawing, it frames
   * what is drawn, and frames the whole again when the rest comes unless
   * the person has moved the view by then.
   */
  settle() {
    if (this.framedWhole || this.firstDrawn === null || !this.boundingSphere()) return;
    const ready = this.ready();
    if (!ready && (this.fitted || performance.now() - this.firstDrawn < FRAME_WAIT_MS)) return;
    if (!this.fitted || !this.userMoved) this.fit();
    this.fitted = true;
    this.framedWhole = ready;
  }

  /** Called when the mode, the range or the values to colour by change (parts-view.js listens). */
  onModeChange() {}

  /**
   * Compare mode: surfaces coloured by their deviation from a version
   * (signed, along the normal; blue below, red above, white where equal,
   * saturated at `range`), the version drawn as a ghost; null ends it.
   * The drawings hold the values (parts-view.js).
   */
  setDeviation(on, range) {
    if (!on) {
      if (this.mode === 'deviation') this.setMode(this.modeBeforeCompare || 'shaded');
      return;
    }
    if (this.mode !== 'deviation') this.modeBeforeCompare = this.mode;
    this.range = range;
    this.setMode('deviation');
  }

  setMode(mode) {
    this.mode = mode;
    this.onModeChange();
  }

  setRange(range) {
    this.range = range;
    this.onModeChange();
  }

  /**
   * VR: the design at real size on a table in front of the user — model
   * units (millimetres: `metresPerUnit` 0.001) to metres, z up to WebXR's y
   * up, the bottom of its bounding box at `tableHeight` metres, its centre
   * `distance` metres ahead (−z) of the origin where the headset starts.
   */
  placeOnTable({ metresPerUnit = 0.001, tableHeight = 0.9, distance = 0.7 } = {}) {
    const box = this.bounds();
    const m = this.model;
    m.scale.setScalar(metresPerUnit);
    m.rotation.set(-Math.PI / 2, 0, 0);
    m.position.set(0, 0, 0);
    m.updateMatrixWorld(true);
    if (box && !box.isEmpty()) {
      const centre = box.getCenter(new THREE.Vector3());
      const bottom = new THREE.Vector3(centre.x, centre.y, box.min.z);
      const at = bottom.applyMatrix4(m.matrixWorld);
      m.position.set(-at.x, tableHeight - at.y, -distance - at.z);
    }
    m.updateMatrixWorld(true);
    this.studio.setUp(new THREE.Vector3(0, 1, 0), new THREE.Vector3(0, 0, 1));
  }

  /** Back to the screen: the model in its own units and axes. */
  placeOnScreen() {
    this.model.position.set(0, 0, 0);
    this.model.rotation.set(0, 0, 0);
    this.model.scale.setScalar(1);
    this.model.updateMatrixWorld(true);
    this.studio.setUp(new THREE.Vector3(0, 0, 1), new THREE.Vector3(0, -1, 0));
  }

  /** Frames `sphere` (default: everything drawn). */
  fit(sphere = this.boundingSphere()) {
    const s = sphere;
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
    this.shadow.enabled = this.groundShadow && this.mode === 'shaded';
    this.shadow.update(this.shadow.enabled ? this.bounds() : null);
    const xr = this.renderer.xr;
    if (xr.isPresenting) {
      // The eyes look the same way: the headset's camera orients the studio for both.
      const c = xr.getCamera();
      c.updateMatrixWorld(true);
      c.matrixWorldInverse.copy(c.matrixWorld).invert();
      this.studio.view(c);
    } else {
      this.camera.updateMatrixWorld();
      this.camera.matrixWorldInverse.copy(this.camera.matrixWorld).invert();
      this.studio.view(this.camera);
    }
    this.renderer.render(this.scene, this.camera);
  }
}
