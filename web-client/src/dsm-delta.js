// Mesh deltas (protocol/README.md, "Binary mesh delta (kind 8)"), asked for
// with `mesh_delta=1`: a part's mesh frame as the changes from the last mesh
// frame the page holds of that part (its base, named by revision) — runs of
// vertices and triangles copied from the base (a copied triangle's indices
// renumbered) or taken from the delta's literal records. `MeshDeltas` keeps
// the last mesh frame of each part and turns a delta into the frame it
// stands for, the same object decodeMeshFrame (frame.js) gives, so the rest
// of the page treats it as any mesh frame; a delta whose base the page does
// not hold is ignored (the server never sends one).

export const KIND_MESH_DELTA = 8;
const HEADER = 88;
/** A run's source meaning "the next literal records". */
const LITERAL = 0xffffffff;
/** Size limits of protocol/src/mesh_frame.rs. */
const MAX_VERTICES = 4 << 20;
const MAX_TRIANGLES = 8 << 20;

/**
 * Decodes a mesh delta (magic, kind and version already checked by the
 * caller): { kind: 'mesh_delta', design, part, revision, base, flags,
 * origin, step, vertices, triangles (the new frame's counts), vertexRuns,
 * triangleRuns (Uint32Array: source, count, …), positions (Uint16Array),
 * normals (Int16Array), indices (literal triangles, Uint16Array or
 * Uint32Array) }. Throws an Error on any malformed input.
 */
export function decodeMeshDelta(buf) {
  if (!(buf instanceof ArrayBuffer) || buf.byteLength < HEADER) throw new Error('mesh delta too short');
  const dv = new DataView(buf);
  const u32 = (o) => dv.getUint32(o, true);
  const [nv, nt, rv, rt, lv, lt] = [40, 44, 48, 52, 56, 60].map(u32);
  if (nv > MAX_VERTICES || nt > MAX_TRIANGLES || rv > nv || rt > nt || lv > nv || lt > nt) throw new Error('mesh delta sizes out of range');
  const origin = [dv.getFloat32(64, true), dv.getFloat32(68, true), dv.getFloat32(72, true)];
  const step = dv.getFloat32(76, true);
  if (!origin.every(Number.isFinite) || !Number.isFinite(step) || step < 0) throw new Error('mesh delta origin or step is not finite');
  const ib = dv.getUint8(80);
  if (ib !== (nv <= 65535 ? 2 : 4)) throw new Error(`index width ${ib} does not fit ${nv} vertices`);
  for (let i = 81; i < HEADER; i++) if (dv.getUint8(i) !== 0) throw new Error('mesh delta header padding is not zero');
  const total = HEADER + 8 * (rv + rt) + 12 * lv + 3 * ib * lt;
  if (buf.byteLength !== total) throw new Error(`mesh delta is ${buf.byteLength} bytes, header says ${total}`);
  const runs = new Uint32Array(buf, HEADER, 2 * (rv + rt));
  const vertexRuns = runs.subarray(0, 2 * rv);
  const triangleRuns = runs.subarray(2 * rv);
  const sums = (r, n, ln, what) => {
    let all = 0;
    let lit = 0;
    for (let k = 0; k < r.length; k += 2) {
      if (r[k + 1] === 0) throw new Error(`mesh delta has an empty ${what} run`);
      all += r[k + 1];
      if (r[k] === LITERAL) lit += r[k + 1];
    }
    if (all !== n || lit !== ln) throw new Error(`mesh delta's ${what} runs make ${all} (${lit} literal), its header says ${n} (${ln})`);
  };
  sums(vertexRuns, nv, lv, 'vertex');
  sums(triangleRuns, nt, lt, 'triangle');
  const l = HEADER + 8 * (rv + rt);
  const positions = new Uint16Array(buf, l, 3 * lv);
  const normals = new Int16Array(buf, l + 6 * lv, 3 * lv);
  const indices = ib === 2 ? new Uint16Array(buf, l + 12 * lv, 3 * lt) : new Uint32Array(buf, l + 12 * lv, 3 * lt);
  for (let i = 0; i < indices.length; i++) if (indices[i] >= nv) throw new Error(`index ${indices[i]} beyond the ${nv} vertices`);
  return {
    kind: 'mesh_delta',
    flags: dv.getUint16(6, true),
    design: Number(dv.getBigUint64(8, true)),
    part: Number(dv.getBigUint64(16, true)),
    revision: Number(dv.getBigUint64(24, true)),
    base: Number(dv.getBigUint64(32, true)),
    origin,
    step,
    vertices: nv,
    triangles: nt,
    vertexRuns,
    triangleRuns,
    positions,
    normals,
    indices,
  };
}

/**
 * The mesh frame `delta` stands for, made from `base` (a decoded mesh
 * frame with `quanta` and `normalQuanta`): the same object decodeMeshFrame
 * gives for the whole frame. Throws if `base` is not its base or the runs do
 * not fit it.
 */
export function applyMeshDelta(base, delta) {
  if (base.part !== delta.part || base.revision !== delta.base) throw new Error(`mesh delta of revision ${delta.base}, base is ${base.revision}`);
  if (base.step !== delta.step || base.origin.some((o, a) => o !== delta.origin[a])) throw new Error("mesh delta's cube is not its base's");
  const bv = base.quanta.length / 3;
  const bt = base.indices.length / 3;
  const nv = delta.vertices;
  const q = new Uint16Array(3 * nv);
  const qn = new Int16Array(3 * nv);
  const map = new Int32Array(bv).fill(-1);
  let at = 0;
  let lit = 0;
  const vr = delta.vertexRuns;
  for (let k = 0; k < vr.length; k += 2) {
    const [s, n] = [vr[k], vr[k + 1]];
    if (s === LITERAL) {
      q.set(delta.positions.subarray(3 * lit, 3 * (lit + n)), 3 * at);
      qn.set(delta.normals.subarray(3 * lit, 3 * (lit + n)), 3 * at);
      lit += n;
      at += n;
      continue;
    }
    if (s + n > bv) throw new Error(`mesh delta copies vertices ${s}..${s + n} of a base of ${bv}`);
    for (let i = s; i < s + n; i++) {
      if (map[i] !== -1) throw new Error(`mesh delta copies base vertex ${i} twice`);
      map[i] = at++;
    }
    q.set(base.quanta.subarray(3 * s, 3 * (s + n)), 3 * (at - n));
    qn.set(base.normalQuanta.subarray(3 * s, 3 * (s + n)), 3 * (at - n));
  }
  const indices = nv <= 65535 ? new Uint16Array(3 * delta.triangles) : new Uint32Array(3 * delta.triangles);
  let t = 0;
  lit = 0;
  const tr = delta.triangleRuns;
  for (let k = 0; k < tr.length; k += 2) {
    const [s, n] = [tr[k], tr[k + 1]];
    if (s === LITERAL) {
      indices.set(delta.indices.subarray(3 * lit, 3 * (lit + n)), 3 * t);
      lit += n;
      t += n;
      continue;
    }
    if (s + n > bt) throw new Error(`mesh delta copies triangles ${s}..${s + n} of a base of ${bt}`);
    for (let i = 3 * s; i < 3 * (s + n); i++) {
      const m = map[base.indices[i]];
      if (m < 0) throw new Error(`mesh delta copies a base triangle naming vertex ${base.indices[i]}, which it does not keep`);
      indices[3 * t + (i - 3 * s)] = m;
    }
    t += n;
  }
  const positions = new Float32Array(3 * nv);
  const normals = new Float32Array(3 * nv);
  for (let i = 0; i < 3 * nv; i++) {
    positions[i] = delta.origin[i % 3] + q[i] * delta.step;
    normals[i] = qn[i] / 32767;
  }
  const { design, part, revision, flags, origin, step } = delta;
  return { kind: 'mesh', part, design, revision, flags, origin, step, positions, normals, indices, quanta: q, normalQuanta: qn };
}

/** Per part, the last mesh frame the page holds; deltas applied to it. */
export class MeshDeltas {
  constructor() {
    /** By part: the last mesh frame (whole or made from a delta). */
    this.held = new Map();
    /** Deltas applied. */
    this.applied = 0;
    /** Deltas that could not be applied (their base was not held). */
    this.ignored = 0;
  }

  /**
   * Takes a decoded message (frame.js): a mesh frame is kept and returned,
   * a delta becomes the frame it stands for (or null when its base is not
   * held: the page keeps its frame until a whole one comes); anything else
   * is returned as it is.
   */
  take(f) {
    if (!f) return f;
    if (f.kind === 'mesh') {
      this.held.set(f.part, f);
      return f;
    }
    if (f.kind !== 'mesh_delta') return f;
    const base = this.held.get(f.part);
    if (!base || base.revision !== f.base) {
      this.ignored++;
      return null;
    }
    const made = applyMeshDelta(base, f);
    this.held.set(f.part, made);
    this.applied++;
    return made;
  }
}
