// Decoding of the binary body frame (kind 4; protocol/README.md, "Binary
// body frame (kind 4)"): a Coons body part's lattice at the shown morph
// time, its boundary mesh, its isoparametric lines and the lattice's
// degrees and knots (so the page can evaluate the volume: body-volume.js).
// 64-byte header,
// every section 4-aligned and viewed without copying; every size checked.

export const KIND_BODY = 4;
const HEADER = 64;
const MAX_LATTICE = 1 << 16;
const MAX_VERTICES = 1 << 20;
const MAX_TRIANGLES = 1 << 21;
const MAX_LINES = 4096;
const MAX_SAMPLES = 1024;
const MAX_DEGREE = 5;

/**
 * Decodes a body frame (magic, kind and version already checked by the
 * caller): { kind: 'body', design, part, revision, flags, t, counts: [nu,
 * nv, nw], lattice, positions, normals (Float32Array x, y, z), triangles
 * (Uint32Array), lineSamples, lineDirs (Uint32Array), linePoints
 * (Float32Array), degrees: [p, q, r], knots: [Float32Array ×3] }. Throws
 * an Error on any malformed input.
 */
export function decodeBodyFrame(buf) {
  if (buf.byteLength < HEADER) throw new Error('body frame too short');
  const dv = new DataView(buf);
  const u32 = (o) => dv.getUint32(o, true);
  const counts = [u32(36), u32(40), u32(44)];
  const n = counts[0] * counts[1] * counts[2];
  const [v, t, l, s] = [u32(48), u32(52), u32(56), u32(60)];
  if (n > MAX_LATTICE || v > MAX_VERTICES || t > MAX_TRIANGLES || l > MAX_LINES || s > MAX_SAMPLES) {
    throw new Error('body frame sizes out of range');
  }
  const lat = HEADER;
  const pos = lat + 12 * n;
  const nor = pos + 12 * v;
  const tri = nor + 12 * v;
  const dirs = tri + 12 * t;
  const pts = dirs + 4 * l;
  const spline = pts + 12 * l * s;
  if (buf.byteLength < spline + 12) throw new Error(`body frame has ${buf.byteLength} bytes, too few for its sizes and degrees`);
  const degrees = [u32(spline), u32(spline + 4), u32(spline + 8)];
  if (degrees.some((p) => p < 1 || p > MAX_DEGREE)) throw new Error('body frame degree out of range');
  const lens = degrees.map((p, d) => counts[d] + p + 1);
  const total = spline + 12 + 4 * (lens[0] + lens[1] + lens[2]);
  if (buf.byteLength !== total) throw new Error(`body frame has ${buf.byteLength} bytes, its header says ${total}`);
  const knots = [];
  let at = spline + 12;
  for (let d = 0; d < 3; d++) {
    if (counts[d] < degrees[d] + 1) throw new Error('body frame lattice has too few points for its degree');
    const k = new Float32Array(buf, at, lens[d]);
    for (let i = 0; i < k.length; i++) if (!Number.isFinite(k[i]) || (i > 0 && k[i] < k[i - 1])) throw new Error('body frame knots not finite and non-decreasing');
    knots.push(k);
    at += 4 * lens[d];
  }
  const triangles = new Uint32Array(buf, tri, 3 * t);
  for (let i = 0; i < triangles.length; i++) if (triangles[i] >= v) throw new Error('triangle names a missing vertex');
  const lineDirs = new Uint32Array(buf, dirs, l);
  for (const d of lineDirs) if (d > 2) throw new Error('line direction out of range');
  return {
    kind: 'body',
    flags: dv.getUint16(6, true),
    design: Number(dv.getBigUint64(8, true)),
    part: Number(dv.getBigUint64(16, true)),
    revision: Number(dv.getBigUint64(24, true)),
    t: dv.getFloat32(32, true),
    counts,
    lattice: new Float32Array(buf, lat, 3 * n),
    positions: new Float32Array(buf, pos, 3 * v),
    normals: new Float32Array(buf, nor, 3 * v),
    triangles,
    lineSamples: s,
    lineDirs,
    linePoints: new Float32Array(buf, pts, 3 * l * s),
    degrees,
    knots,
  };
}
