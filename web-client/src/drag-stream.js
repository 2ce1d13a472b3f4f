// The client side of the drag stream (protocol/README.md, "Drag stream
// (kinds 5 and 6)"): per part the last full geometry frame (the candidate
// reference R) and the last drag basis (ρ); a drag frame becomes a full
// frame object whose net is R + ρ·d, with R's knots, degrees and sizes, so
// the rest of the page treats it as any frame.

export class DragStream {
  constructor() {
    /** Per part: the last full surface or curve frame. */
    this.full = new Map();
    /** Per part: the last drag basis. */
    this.basis = new Map();
  }

  /**
   * Takes a decoded message (frame.js): returns the frame to apply (a full
   * frame as it is, a drag frame turned into one) or null (a basis, or a
   * drag frame that cannot be applied — the server never sends one).
   */
  take(f) {
    if (f.kind === 'drag_basis') {
      this.basis.set(f.part, f);
      return null;
    }
    if (f.kind === 'drag') return this.expand(f);
    if (f.kind === 'surface' || f.kind === 'curve') {
      this.full.set(f.part, f);
      this.basis.delete(f.part);
    }
    return f;
  }

  /** The frame a drag frame stands for, or null. */
  expand(f) {
    const basis = this.basis.get(f.part);
    const ref = this.full.get(f.part);
    if (!basis || !ref || basis.basis !== f.basis || basis.reference !== ref.revision) return null;
    const r = ref.points;
    const rho = basis.rho;
    if (rho.length * 3 !== r.length) return null;
    const points = new Float32Array(r.length);
    const [dx, dy, dz] = f.d;
    for (let k = 0, i = 0; k < rho.length; k++, i += 3) {
      const p = rho[k];
      points[i] = r[i] + p * dx;
      points[i + 1] = r[i + 1] + p * dy;
      points[i + 2] = r[i + 2] + p * dz;
    }
    return { ...ref, revision: f.revision, flags: f.flags, points, icons: f.icons };
  }
}
