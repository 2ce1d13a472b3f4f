// The VR menu for an icon's role and state, as paper 003's 3D menu: there
// the designer presses a key of the 3D mouse in the left hand to bring up a
// menu that switches an icon's role (constraint ↔ load) and its state
// (driving, passive, sleeping). Here the left controller's X button opens
// and closes a panel held above that wrist. It shows the icon in hand (the
// one grabbed, else the one last grabbed or selected) with its role and
// state, and every role and state as a button. A button is chosen either by
// pointing the other controller's ray at it and pulling the trigger, or with
// the menu hand's thumbstick (a push moves the focus, pressing the stick
// chooses). A choice sends what the desktop panel sends (set_role /
// set_state, through the page's own functions). "driving" cannot be chosen:
// an icon drives while a hand or a bound sensor moves it, so the button
// lights up while the icon is grabbed.

import * as THREE from 'three';

/** Every role a menu offers, in the desktop list's order. */
export const MENU_ROLES = ['position', 'load', 'normal', 'R', 'V', 'R2', 'V2', 'RV'];
/** Every state, in the paper's order. */
export const MENU_STATES = ['driving', 'passive', 'sleeping'];

/** The panel's texture size (px) and its size in the room (m). */
const W = 512;
const H = 448;
const WIDTH_M = 0.16;
/** xr-standard gamepad mapping: button 3 is the thumbstick press, 4 the X (left) / A (right) button. */
const STICK_PRESS = 3;
const MENU_BUTTON = 4;
/** A thumbstick push past this steps the focus once; it re-arms back under RELEASE. */
const PUSH = 0.6;
const RELEASE = 0.3;

/** The buttons' rectangles on the panel (px), by kind and name. */
function layout() {
  const buttons = [];
  const bw = 116;
  const bh = 58;
  MENU_ROLES.forEach((name, k) => buttons.push({ kind: 'role', name, x: 8 + (k % 4) * (bw + 8), y: 120 + Math.floor(k / 4) * (bh + 8), w: bw, h: bh }));
  const sw = 160;
  MENU_STATES.forEach((name, k) => buttons.push({ kind: 'state', name, x: 8 + k * (sw + 8), y: 300, w: sw, h: bh }));
  return buttons;
}

export class XRMenu {
  /**
   * @param {object} o
   * @param {() => object | null} o.target the icon the menu acts on (id, role, state, part) or null
   * @param {(icon: object) => Set<string>} o.rolesFor the roles icon `icon` may take
   * @param {(id: number, role: string) => void} o.setRole switches an icon's role (set_role)
   * @param {(id: number, state: string) => void} o.setState switches an icon's state (set_state)
   * @param {() => boolean} o.canEdit whether this page may edit
   */
  constructor(o) {
    Object.assign(this, o);
    this.buttons = layout();
    this.canvas = document.createElement('canvas');
    this.canvas.width = W;
    this.canvas.height = H;
    this.texture = new THREE.CanvasTexture(this.canvas);
    this.texture.colorSpace = THREE.SRGBColorSpace;
    const height = (WIDTH_M * H) / W;
    this.panel = new THREE.Mesh(new THREE.PlaneGeometry(WIDTH_M, height), new THREE.MeshBasicMaterial({ map: this.texture, side: THREE.DoubleSide, transparent: true }));
    this.panel.name = 'xr-menu';
    // Above the wrist, tilted back towards the eyes.
    this.group = new THREE.Group();
    this.group.position.set(0, 0.05 + height / 2, 0.02);
    this.group.rotation.x = -0.6;
    this.group.add(this.panel);
    this.group.visible = false;
    /** The button the other hand's ray is on, the thumbstick's focus (index into `buttons`), the last drawn key. */
    this.hover = null;
    this.focus = null;
    this.drawnKey = '';
    this.stickArmed = true;
    this.buttonWas = false;
    this.pressWas = false;
    /** How many choices were sent. */
    this.choices = 0;
  }

  get open() {
    return this.group.visible;
  }

  setOpen(on) {
    this.group.visible = on;
    this.hover = null;
    if (on) this.focus = null;
    this.redraw();
  }

  /** Whether button `b` can be chosen now for icon `icon`. */
  enabled(b, icon) {
    if (!icon || !this.canEdit()) return false;
    if (b.kind === 'role') return this.rolesFor(icon).has(b.name);
    return b.name !== 'driving' && icon.state !== 'driving';
  }

  /** Whether button `b` shows icon `icon`'s current role or state. */
  current(b, icon) {
    if (!icon) return false;
    if (b.kind === 'state') return icon.state === b.name;
    return (icon.role.kind === 'derivative' ? icon.role.which : icon.role.kind) === b.name;
  }

  /** Sends the choice of button `b` (nothing when it cannot be chosen or is already so). */
  choose(b) {
    const icon = this.target();
    if (!b || !this.enabled(b, icon) || this.current(b, icon)) return false;
    if (b.kind === 'role') this.setRole(icon.id, b.name);
    else this.setState(icon.id, b.name);
    this.choices++;
    return true;
  }

  /** The button where `raycaster` meets the open panel, or null. */
  buttonAlong(raycaster) {
    if (!this.open) return null;
    const hit = raycaster.intersectObject(this.panel, false)[0];
    if (!hit || !hit.uv) return null;
    const x = hit.uv.x * W;
    const y = (1 - hit.uv.y) * H;
    return this.buttons.find((b) => x >= b.x && x <= b.x + b.w && y >= b.y && y <= b.y + b.h) || null;
  }

  /** Where button (kind, name)'s centre is in the room, for pointing at it. */
  buttonWorld(kind, name) {
    const b = this.buttons.find((c) => c.kind === kind && c.name === name);
    const g = this.panel.geometry.parameters;
    this.panel.updateMatrixWorld(true);
    return new THREE.Vector3(((b.x + b.w / 2) / W - 0.5) * g.width, (0.5 - (b.y + b.h / 2) / H) * g.height, 0).applyMatrix4(this.panel.matrixWorld);
  }

  /**
   * Called every frame with the menu hand's gamepad (or null) and the button
   * under the other hand's ray: X opens and closes, the thumbstick moves the
   * focus over the buttons that can be chosen and its press chooses.
   */
  update(gamepad, hover) {
    const pressed = (k) => !!(gamepad && gamepad.buttons[k] && gamepad.buttons[k].pressed);
    const menuButton = pressed(MENU_BUTTON);
    if (menuButton && !this.buttonWas) this.setOpen(!this.open);
    this.buttonWas = menuButton;
    this.hover = this.open ? hover : null;
    if (this.open && gamepad) {
      const [x, y] = [gamepad.axes[2] || 0, gamepad.axes[3] || 0];
      const push = Math.abs(x) > Math.abs(y) ? x : y;
      if (this.stickArmed && Math.abs(push) > PUSH) {
        this.stickArmed = false;
        this.step(push > 0 ? 1 : -1);
      } else if (Math.abs(x) < RELEASE && Math.abs(y) < RELEASE) {
        this.stickArmed = true;
      }
      const stick = pressed(STICK_PRESS);
      if (stick && !this.pressWas && this.focus !== null) this.choose(this.buttons[this.focus]);
      this.pressWas = stick;
    }
    this.redraw();
  }

  /** Moves the thumbstick focus `d` steps over the buttons that can be chosen (right / down is forward). */
  step(d) {
    const icon = this.target();
    const n = this.buttons.length;
    let k = this.focus === null ? (d > 0 ? -1 : 0) : this.focus;
    for (let tries = 0; tries < n; tries++) {
      k = (k + d + n) % n;
      if (this.enabled(this.buttons[k], icon)) {
        this.focus = k;
        return;
      }
    }
    this.focus = null;
  }

  /** Draws the panel when what it shows has changed. */
  redraw() {
    const icon = this.target();
    const edit = this.canEdit();
    const key = JSON.stringify([this.open, icon && [icon.id, icon.role, icon.state, icon.part, [...this.rolesFor(icon)]], edit, this.hover && this.hover.name, this.focus]);
    if (key === this.drawnKey || !this.open) return;
    this.drawnKey = key;
    const g = this.canvas.getContext('2d');
    g.clearRect(0, 0, W, H);
    g.fillStyle = 'rgba(24, 28, 36, 0.92)';
    g.beginPath();
    g.roundRect(0, 0, W, H, 18);
    g.fill();
    g.fillStyle = '#fff';
    g.font = 'bold 30px sans-serif';
    g.textBaseline = 'middle';
    g.fillText(icon ? `icon ${icon.id} · ${icon.anchor ? icon.anchor.kind : ''}` : 'no icon in hand', 16, 34);
    g.font = '22px sans-serif';
    g.fillStyle = '#aab';
    g.fillText(icon ? (edit ? 'squeeze an icon to pick another' : 'view only') : 'squeeze an icon to pick it', 16, 72);
    g.fillText('role', 16, 106);
    g.fillText('state', 16, 286);
    g.fillText('trigger or stick press: choose · X: close', 16, 402);
    this.buttons.forEach((b, k) => {
      const on = this.current(b, icon);
      const can = this.enabled(b, icon);
      g.fillStyle = on ? '#2f6fd6' : can ? '#3a4150' : '#262a33';
      g.beginPath();
      g.roundRect(b.x, b.y, b.w, b.h, 10);
      g.fill();
      if ((this.hover && this.hover.kind === b.kind && this.hover.name === b.name) || this.focus === k) {
        g.strokeStyle = '#ffd54f';
        g.lineWidth = 5;
        g.stroke();
      }
      g.fillStyle = on || can ? '#fff' : '#6a7080';
      g.font = 'bold 26px sans-serif';
      g.textAlign = 'center';
      g.fillText(b.name, b.x + b.w / 2, b.y + b.h / 2 + 1);
      g.textAlign = 'left';
    });
    this.texture.needsUpdate = true;
  }
}
