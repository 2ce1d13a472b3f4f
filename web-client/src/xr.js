// WebXR immersive VR through three's renderer.xr: the two controllers act as
// the glove does. Squeeze grabs the icon the controller touches or points
// at and drags it with the hand (drag_start / drag / drag_end, like the
// mouse gizmo); the trigger creates a point icon where the controller's ray
// hits the surface. Each controller is drawn with its real model: three's
// XRControllerModelFactory picks the WebXR input profile of the device and
// loads its glTF from our own server (/vendor/webxr-profiles, the npm
// package @webxr-input-profiles/assets; never a CDN). Until a model has
// loaded, or if it cannot be loaded (logged), a simple grip body stands in.
// The loader's code (xr-controller-models.js: three's glTF loader and the
// model factory, ≈ 30 KB compressed) is imported only when VR is entered or
// the page finds a headset after its first picture, so a customer's first
// picture never waits for it.
//
// Real scale: on entering VR the design is put on a table in front of the
// user at its real size (View.placeOnTable: millimetres to metres, z up to
// y up), so a hand moved 0.2 m moves a grabbed icon 200 mm. Squeezing where
// there is no icon grabs the whole model: it follows the hand (move and
// turn), and squeezing with the other hand as well scales it by the change
// of the distance between the hands.
//
// The left hand carries the menu for the icon's role and state (xr-menu.js,
// the paper's 3D menu): X opens it; the right hand's ray and trigger, or the
// left thumbstick, choose in it.

import * as THREE from 'three';
import { XRMenu } from './xr-menu.js';

/** Where the server serves the input profiles and controller models (server/src/web.rs). */
export const PROFILES_PATH = '/vendor/webxr-profiles';

/** A grabbed icon moves this many times the hand's motion, measured in the model's own units (1: real scale). */
const HAND_GAIN = 1;

/** Two VR controllers bound to the design: grab-and-drag icons, trigger-to-create. */
export class XRSculpt {
  /**
   * @param {object} o
   * @param {import('./view.js').View} o.view the 3D view whose renderer.xr is used
   * @param {() => THREE.Object3D[]} o.handles the icons' pickable handles (userData.iconId)
   * @param {(id: number) => number[] | null} o.iconPosition where the dragged point of icon `id` is now
   * @param {(msg: object) => void} o.send sends a protocol message
   * @param {() => THREE.Object3D[]} o.pickables the part meshes a trigger may hit
   * @param {(hit: THREE.Intersection) => void} o.create creates an icon where the trigger's ray hit a part
   * @param {(on: boolean, id: number | null) => void} o.onDragging told when a VR drag starts and ends
   * @param {() => boolean} o.canEdit whether this page may edit
   * @param {object} o.menu what the role and state menu needs besides canEdit (XRMenu's target, rolesFor, setRole, setState)
   */
  constructor(o) {
    Object.assign(this, o);
    this.menu = new XRMenu({ ...o.menu, canEdit: o.canEdit });
    this.raycaster = new THREE.Raycaster();
    this.controllers = [];
    /** The current grab: controller index, icon, start positions of hand (model units) and icon. */
    this.grab = null;
    /** The model held by the hands: { index, offset (grip → model), second: { index, distance, scale } | null }. */
    this.modelGrab = null;
    this.drags = 0;
    /** How many controller models have been loaded and shown. */
    this.modelsLoaded = 0;
    /** The controller models' loader (failures counted) once its code is loaded (loadModels), else null. */
    this.modelLoader = null;
    /** The import of the controller models' code, once asked for (loadModels). */
    this.modelsReady = null;
    const xr = this.view.renderer.xr;
    for (let i = 0; i < 2; i++) {
      const ray = xr.getController(i);
      const grip = xr.getControllerGrip(i);
      ray.add(makeRay());
      const fallback = makeBody();
      grip.add(fallback);
      grip.addEventListener('connected', (e) => this.connected(i, e.data));
      grip.addEventListener('disconnected', () => {
        this.controllers[i].connected = false;
        fallback.visible = true;
      });
      ray.addEventListener('squeezestart', () => this.squeezeStart(i));
      ray.addEventListener('squeezeend', () => this.squeezeEnd(i));
      ray.addEventListener('selectstart', () => this.trigger(i));
      this.view.scene.add(ray, grip);
      this.controllers.push({ ray, grip, model: null, fallback, connected: false, source: null });
    }
  }

  /**
   * Loads the controller models' code once and gives each grip its model; a
   * grip connected meanwhile is told again, so its model loads. Resolves when
   * the models are attached (or, logged, when the code could not load: the
   * simple controllers stay).
   */
  loadModels() {
    this.modelsReady ??= import('./xr-controller-models.js')
      .then(({ controllerModels }) => {
        const { factory, loader } = controllerModels(PROFILES_PATH, (scene) => this.modelLoaded(scene));
        this.modelLoader = loader;
        for (const c of this.controllers) {
          c.model = factory.createControllerModel(c.grip);
          c.grip.add(c.model);
          if (c.connected) c.grip.dispatchEvent({ type: 'connected', data: c.source });
        }
      })
      .catch((e) => console.warn(`vsculpt: the controller models' code did not load (${e && e.message ? e.message : e}); drawing the simple controllers`));
    return this.modelsReady;
  }

  /** After the first picture: where the browser has a headset, load the controller models' code ahead of entering VR. */
  async prefetch() {
    if (navigator.xr && (await navigator.xr.isSessionSupported('immersive-vr').catch(() => false))) await this.loadModels();
  }

  /** A controller connected: its model is on the way; the simple body shows until it arrives. */
  connected(i, source) {
    const c = this.controllers[i];
    c.connected = true;
    c.source = source || null;
    if (source && source.handedness === 'left') this.menuHand = i;
    this.controllers[this.menuIndex()].grip.add(this.menu.group);
    c.fallback.visible = !(c.model && c.model.children.length);
    c.profiles = source && source.profiles ? [...source.profiles] : [];
    if (source && (source.targetRayMode !== 'tracked-pointer' || !source.gamepad || source.hand)) {
      console.warn(`vsculpt: input source ${i} (${c.profiles.join(', ') || 'no profile'}) has no controller model; drawing the simple controller`);
    }
  }

  /** The controller that holds the menu: the left hand's, else the first. */
  menuIndex() {
    return this.menuHand ?? 0;
  }

  /** The menu button under controller i's ray (i not the menu hand), or null. */
  menuButtonAt(i) {
    if (!this.menu.open || i === this.menuIndex()) return null;
    this.aim(i);
    return this.menu.buttonAlong(this.raycaster);
  }

  /** The factory put a loaded model (`scene`) under one controller's grip: hide that controller's stand-in. */
  modelLoaded(scene) {
    for (const c of this.controllers) {
      if (scene.parent === c.model) {
        c.fallback.visible = false;
        this.modelsLoaded++;
      }
    }
  }

  /** Enters an immersive-vr session; resolves false with a reason when the browser has none. */
  async enter() {
    if (!navigator.xr || !(await navigator.xr.isSessionSupported('immersive-vr'))) {
      throw new Error('WebXR immersive VR is not available in this browser');
    }
    await this.loadModels();
    const session = await navigator.xr.requestSession('immersive-vr', { optionalFeatures: ['local-floor'] });
    await this.view.renderer.xr.setSession(session);
    this.view.placeOnTable();
    session.addEventListener('end', () => {
      this.menu.setOpen(false);
      if (this.grab) this.squeezeEnd(this.grab.index);
      this.modelGrab = null;
      this.view.placeOnScreen();
    });
  }

  /** World position of a controller's grip. */
  gripPosition(i) {
    return this.controllers[i].grip.getWorldPosition(new THREE.Vector3());
  }

  /** A controller's grip in the model's own units and axes. */
  gripInModel(i) {
    this.view.model.updateMatrixWorld(true);
    return this.view.model.worldToLocal(this.gripPosition(i));
  }

  /** Sets the raycaster along controller i's target ray. */
  aim(i) {
    const ray = this.controllers[i].ray;
    ray.updateMatrixWorld(true);
    const origin = new THREE.Vector3().setFromMatrixPosition(ray.matrixWorld);
    const dir = new THREE.Vector3(0, 0, -1).transformDirection(ray.matrixWorld);
    this.raycaster.set(origin, dir);
  }

  /** The icon under controller i: the nearest handle within reach of the grip, else the one its ray hits. */
  iconAt(i) {
    const p = this.gripPosition(i);
    const sphere = this.view.boundingSphere();
    const radius = sphere ? sphere.radius * this.view.model.scale.x : 1;
    const reach = Math.max(0.03, radius * 0.08);
    let best = null;
    for (const h of this.handles()) {
      const d = h.getWorldPosition(new THREE.Vector3()).distanceTo(p);
      if (d <= reach && (!best || d < best.d)) best = { id: h.userData.iconId, d };
    }
    if (best) return best.id;
    this.aim(i);
    const hit = this.raycaster.intersectObjects(this.handles(), false)[0];
    return hit ? hit.object.userData.iconId : null;
  }

  squeezeStart(i) {
    if (this.grab) return;
    if (this.modelGrab) {
      // The other hand joins: from now on the distance between the hands scales the model.
      if (this.modelGrab.index !== i) {
        this.modelGrab.second = { index: i, distance: this.handDistance(), scale: this.view.model.scale.x };
      }
      return;
    }
    const id = this.canEdit() ? this.iconAt(i) : null;
    if (id == null) {
      this.grabModel(i);
      return;
    }
    const start = this.iconPosition(id);
    if (!start) return;
    this.grab = { index: i, id, hand: this.gripInModel(i), icon: new THREE.Vector3(...start), last: null };
    this.onDragging(true, id);
    this.send({ type: 'drag_start', icon: id });
  }

  /** The model follows controller i's grip from now on (its pose relative to the grip kept). */
  grabModel(i) {
    const grip = this.controllers[i].grip;
    grip.updateMatrixWorld(true);
    this.view.model.updateMatrixWorld(true);
    const offset = grip.matrixWorld.clone().invert().multiply(this.view.model.matrixWorld);
    this.modelGrab = { index: i, offset, second: null };
  }

  handDistance() {
    return this.gripPosition(0).distanceTo(this.gripPosition(1));
  }

  /** Every frame while the model is held: the grip's pose times the held offset, scaled by the hands' spread. */
  moveModel() {
    const h = this.modelGrab;
    const grip = this.controllers[h.index].grip;
    grip.updateMatrixWorld(true);
    const m = this.view.model;
    grip.matrixWorld.clone().multiply(h.offset).decompose(m.position, m.quaternion, m.scale);
    if (h.second) {
      const s = h.second.scale * (this.handDistance() / Math.max(h.second.distance, 1e-3));
      m.scale.setScalar(Math.min(Math.max(s, 1e-5), 1));
    }
    m.updateMatrixWorld(true);
  }

  squeezeEnd(i) {
    const h = this.modelGrab;
    if (h) {
      if (h.second && (h.second.index === i || h.index === i)) {
        // One hand lets go: the other keeps holding the model at its new scale.
        const keep = h.index === i ? h.second.index : h.index;
        this.grabModel(keep);
      } else if (h.index === i) {
        this.modelGrab = null;
      }
      return;
    }
    const g = this.grab;
    if (!g || g.index !== i) return;
    this.update();
    this.send({ type: 'drag_end', icon: g.id });
    this.grab = null;
    this.onDragging(false, g.id);
  }

  trigger(i) {
    const button = this.menuButtonAt(i);
    if (button) {
      this.menu.choose(button);
      return;
    }
    if (!this.canEdit()) return;
    this.aim(i);
    const hit = this.raycaster.intersectObjects(this.pickables(), false)[0];
    if (hit && hit.uv) this.create(hit);
  }

  /** Called every frame: moves a held model, or sends the grabbed icon's new position when the hand moved. */
  update() {
    if (this.view.renderer.xr.isPresenting) {
      const m = this.menuIndex();
      const source = this.controllers[m].source;
      this.menu.update(source && source.gamepad ? source.gamepad : null, this.menuButtonAt(1 - m));
    }
    if (this.modelGrab) this.moveModel();
    const g = this.grab;
    if (!g) return;
    const delta = this.gripInModel(g.index).sub(g.hand).multiplyScalar(HAND_GAIN);
    const target = g.icon.clone().add(delta);
    if (g.last && g.last.distanceTo(target) < 1e-6) return;
    g.last = target;
    this.drags++;
    this.send({ type: 'drag', icon: g.id, xyz: [target.x, target.y, target.z] });
  }
}

function makeRay() {
  const geometry = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(0, 0, 0), new THREE.Vector3(0, 0, -5)]);
  return new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: 0x88ccff }));
}

function makeBody() {
  const body = new THREE.Mesh(new THREE.CylinderGeometry(0.015, 0.02, 0.1, 16), new THREE.MeshStandardMaterial({ color: 0x333340, roughness: 0.6 }));
  body.rotation.x = Math.PI / 2;
  return body;
}
