// Per-frame tessellation off the main thread: a Web Worker (tess-worker.js)
// fills the newest surface while the page keeps drawing. At most one request
// is in flight and one waits (a newer surface replaces the waiting one:
// latest wins); the output buffers travel to the worker and back as
// transferables and are reused, so a frame allocates nothing but a copy of
// the control points (the frame's own buffer stays with the page).

export class TessellationWorker {
  /**
   * @param {object} o
   * @param {(seq: number, tess: import('./bspline.js').Tessellator) => void} o.onFilled
   *   called when `tess` (the page's tessellator) holds the answer to request `seq`
   * @param {(reason: string) => void} o.onFailure called once if the worker cannot run; later submits return false
   */
  constructor({ onFilled, onFailure }) {
    this.onFilled = onFilled;
    this.onFailure = onFailure;
    this.waiting = null;
    this.inFlight = null;
    this.spare = null;
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
    this.waiting = null;
    this.inFlight = null;
    this.onFailure(reason);
  }

  /** Queues `surface` for tessellation into `tess`'s layout; false when there is no worker (fill on the main thread then). */
  submit(seq, surface, tess) {
    if (!this.worker) return false;
    this.waiting = { seq, surface, tess };
    if (!this.inFlight) this.post();
    return true;
  }

  post() {
    const { seq, surface, tess } = this.waiting;
    this.waiting = null;
    const n = tess.su * tess.sv;
    let out = this.spare;
    this.spare = null;
    if (!out || out.positions.byteLength !== n * 12) {
      out = { positions: new ArrayBuffer(n * 12), normals: new ArrayBuffer(n * 12), mean: new ArrayBuffer(n * 4), gauss: new ArrayBuffer(n * 4) };
    }
    const points = surface.points.slice();
    const s = { degreeU: surface.degreeU, degreeV: surface.degreeV, knotsU: surface.knotsU, knotsV: surface.knotsV, nu: surface.nu, nv: surface.nv, points };
    this.inFlight = { seq, tess };
    this.worker.postMessage({ seq, surface: s, su: tess.su, sv: tess.sv, out }, [out.positions, out.normals, out.mean, out.gauss, points.buffer]);
  }

  done({ seq, out, box }) {
    const job = this.inFlight;
    this.inFlight = null;
    if (job && job.seq === seq) {
      const t = job.tess;
      t.positions.set(new Float32Array(out.positions));
      t.normals.set(new Float32Array(out.normals));
      t.mean.set(new Float32Array(out.mean));
      t.gauss.set(new Float32Array(out.gauss));
      t.box.set(box);
      this.onFilled(seq, t);
    }
    this.spare = out;
    if (this.waiting) this.post();
  }
}
