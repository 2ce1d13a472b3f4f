// Per-frame tessellation off the main thread: a Web Worker (tess-worker.js)
// fills the newest shape of each surface part while the page keeps drawing.
// At most one request is in flight; per part, at most one waits (a newer
// shape of that part replaces its waiting one: latest wins per part, and a
// frame of one part never displaces another's). The output buffers travel to
// the worker and back as transferables and are reused per part, so a frame
// allocates nothing but a copy of the control points (the frame's own buffer
// stays with the page).

export class TessellationWorker {
  /**
   * @param {object} o
   * @param {(key: number, seq: number, tess: import('./bspline.js').Tessellator, surface: object) => void} o.onFilled
   *   called when `tess` (the page's tessellator of part `key`) holds the answer to request `seq`, the shape `surface` submitted
   * @param {(reason: string) => void} o.onFailure called once if the worker cannot run; later submits return false
   */
  constructor({ onFilled, onFailure }) {
    this.onFilled = onFilled;
    this.onFailure = onFailure;
    /** Waiting requests by part, in the order their parts first asked. */
    this.waiting = new Map();
    this.inFlight = null;
    /** Returned output buffers by part, reused for its next request. */
    this.spare = new Map();
    try {
      this.worker = new Worker(new URL('./tess-worker.js', import.meta.url), { type: 'module' });
    } catch (e) {
      this.fail(`cannot start the tessellation worker: ${e.message}`);
      return;
    }
    this.worker.onmessage = (e) => this.done(e.data);
    this.worker.onerror = (e) => {
      e.preventDefault();
      this.fail(`the tessellation worker failed: ${e.message || 'script error'}`);
    };
  }

  fail(reason) {
    console.warn(`vsculpt: ${reason}; tessellating on the main thread`);
    if (this.worker) this.worker.terminate();
    this.worker = null;
    this.waiting.clear();
    this.inFlight = null;
    this.onFailure(reason);
  }

  /** Queues surface `surface` of part `key` for tessellation into `tess`'s layout; false when there is no worker (fill on the main thread then). */
  submit(key, seq, surface, tess) {
    if (!this.worker) return false;
    this.waiting.delete(key);
    this.waiting.set(key, { key, seq, surface, tess });
    if (!this.inFlight) this.post();
    return true;
  }

  post() {
    const [key, job] = this.waiting.entries().next().value;
    this.waiting.delete(key);
    const { seq, surface, tess } = job;
    const n = tess.su * tess.sv;
    let out = this.spare.get(key);
    this.spare.delete(key);
    if (!out || out.positions.byteLength !== n * 12) {
      out = { positions: new ArrayBuffer(n * 12), normals: new ArrayBuffer(n * 12), mean: new ArrayBuffer(n * 4), gauss: new ArrayBuffer(n * 4) };
    }
    const points = surface.points.slice();
    const s = { degreeU: surface.degreeU, degreeV: surface.degreeV, knotsU: surface.knotsU, knotsV: surface.knotsV, nu: surface.nu, nv: surface.nv, points };
    this.inFlight = { key, seq, tess, surface };
    this.worker.postMessage({ key, seq, surface: s, su: tess.su, sv: tess.sv, out }, [out.positions, out.normals, out.mean, out.gauss, points.buffer]);
  }

  /** Forgets part `key` (deleted): its waiting request and spare buffers. */
  forget(key) {
    this.waiting.delete(key);
    this.spare.delete(key);
    if (this.worker) this.worker.postMessage({ forget: key });
  }

  done({ key, seq, out, box }) {
    const job = this.inFlight;
    this.inFlight = null;
    if (job && job.key === key && job.seq === seq) {
      const t = job.tess;
      t.positions.set(new Float32Array(out.positions));
      t.normals.set(new Float32Array(out.normals));
      t.mean.set(new Float32Array(out.mean));
      t.gauss.set(new Float32Array(out.gauss));
      t.box.set(box);
      this.onFilled(key, seq, t, job.surface);
    }
    this.spare.set(key, out);
    if (this.waiting.size && this.worker) this.post();
  }
}
