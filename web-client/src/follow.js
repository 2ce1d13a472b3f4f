// Following another person's view (the reviewer's "follow the designer").
// This page tells the others where its view camera is, in its presence
// (`presence {camera: {eye, target, fov}}`, model coordinates, +z up), when
// the view changes and at most ten times a second; and it may follow the
// camera of another client, gliding to each camera it receives. Following
// stops as soon as the person orbits, pans or zooms the view themselves, or
// when the followed client leaves. The follow button over the view offers
// the editor to follow; the presence list offers everyone who shows a camera.

/** At most one camera update a tenth of a second, the last one always sent. */
export const SEND_INTERVAL_MS = 100;

/** The camera of `view` as the protocol carries it. */
export function cameraOf(view) {
  const e = view.camera.position;
  const t = view.controls.target;
  return { eye: [e.x, e.y, e.z], target: [t.x, t.y, t.z], fov: view.camera.fov };
}

/** Puts `view`'s camera at `c` exactly (near and far planes from the distance, as fitting does). */
export function setCamera(view, c) {
  view.camera.position.set(...c.eye);
  view.controls.target.set(...c.target);
  view.camera.fov = c.fov;
  const dist = view.camera.position.distanceTo(view.controls.target);
  view.camera.near = dist / 100;
  view.camera.far = dist * 100;
  view.camera.updateProjectionMatrix();
  view.controls.update();
}

const same = (a, b) => a && b && a.fov === b.fov && a.eye.every((x, i) => x === b.eye[i]) && a.target.every((x, i) => x === b.target[i]);

export class Follow {
  /**
   * @param {object} o
   * @param {import('./view.js').View} o.view
   * @param {(msg: object) => boolean} o.send sends a message if connected; false if not
   * @param {HTMLButtonElement} o.button the follow button over the view
   * @param {() => void} o.onChange called when who is followed changes (to redraw the presence list)
   */
  constructor(o) {
    Object.assign(this, o);
    /** The client followed, or null. */
    this.following = null;
    this.me = null;
    this.presence = [];
    this.sent = null;
    this.lastSend = -Infinity;
    this.timer = null;
    this.glide = null;
    this.view.controls.addEventListener('change', () => this.changed());
    // 'start' comes only from the person's own pointer or wheel.
    this.view.controls.addEventListener('start', () => this.stop());
    this.button.addEventListener('click', () => {
      if (this.following !== null) this.stop();
      else {
        const editor = this.candidate();
        if (editor) this.follow(editor.client);
      }
    });
  }

  /** The editor this page would follow: the first other editor that shows a camera. */
  candidate() {
    return this.presence.find((p) => p.client !== this.me && p.access === 'editor' && p.camera) || null;
  }

  /** The presence list changed (`me` is this page's client id). */
  setPresence(presence, me) {
    this.presence = presence;
    this.me = me;
    if (this.following !== null) {
      const p = presence.find((q) => q.client === this.following);
      if (!p) this.stop();
      else if (p.camera) this.glideTo(p.camera);
    }
    this.render();
  }

  /** Follows client `id`'s camera. */
  follow(id) {
    if (id === this.me) return;
    this.following = id;
    const p = this.presence.find((q) => q.client === id);
    if (p && p.camera) this.glideTo(p.camera);
    this.render();
    this.onChange();
  }

  /** Back to a free view. */
  stop() {
    if (this.following === null) return;
    this.following = null;
    if (this.glide) cancelAnimationFrame(this.glide.frame);
    this.glide = null;
    this.render();
    this.onChange();
  }

  /** Moves the camera to `c` over one send interval, ending exactly at `c`. */
  glideTo(c) {
    if (this.glide) cancelAnimationFrame(this.glide.frame);
    const from = cameraOf(this.view);
    if (same(from, c)) return;
    const t0 = performance.now();
    const lerp = (a, b, s) => a.map((x, i) => x + (b[i] - x) * s);
    const step = () => {
      const s = Math.min(1, (performance.now() - t0) / SEND_INTERVAL_MS);
      setCamera(this.view, s < 1 ? { eye: lerp(from.eye, c.eye, s), target: lerp(from.target, c.target, s), fov: from.fov + (c.fov - from.fov) * s } : c);
      this.glide = s < 1 ? { frame: requestAnimationFrame(step) } : null;
    };
    this.glide = { frame: requestAnimationFrame(step) };
  }

  /** The view moved: tell the others, at most every SEND_INTERVAL_MS, the last position always. */
  changed() {
    if (this.timer !== null) return;
    const wait = this.lastSend + SEND_INTERVAL_MS - performance.now();
    if (wait <= 0) this.flush();
    else this.timer = setTimeout(() => {
      this.timer = null;
      this.flush();
    }, wait);
  }

  /** Sends the current camera if it differs from the last one sent. */
  flush() {
    const c = cameraOf(this.view);
    if (same(c, this.sent)) return;
    if (this.send({ type: 'presence', camera: c })) {
      this.sent = c;
      this.lastSend = performance.now();
    }
  }

  /** (Re)joined: the server forgot this page's camera; say it again. */
  joined() {
    this.sent = null;
    this.flush();
  }

  render() {
    const followed = this.following !== null ? this.presence.find((p) => p.client === this.following) : null;
    const editor = this.candidate();
    this.button.hidden = !followed && !editor;
    this.button.setAttribute('aria-pressed', String(!!followed));
    this.button.textContent = followed ? `following ${followed.name} · stop` : editor ? `follow ${editor.name}` : '';
    this.button.title = followed ? 'back to your own view (or just move the view)' : "see the design through the designer's camera";
  }
}
