// Decoding of the binary body frame (kind 4; protocol/README.md, "Binary
// body frame (kind 4)"): a Coons body part's lattice at the shown morph
// time, its boundary mesh and its isoparametric lines. 64-byte header,
// every section 4-aligned and viewed without copying; every size checked.

export const KIND_BODY = 4;
const HEADER = 64;
const MAX_LATTICE = 1 << 16;
const MAX_VERTICES = 1 << 20;
const MAX_TRIANGLES = 1 << 21;
const MAX_LINES = 4096;
const MAX_SAMPLES = 1024;

/**
 * Decodes a body frame (magic, kind and version already checked by the
 * caller): { kind: 'body', design, part, revision, flags, t, counts: [nu,
 * nv, nw], lattice, positions, normals (Float32Array x, y, z), triangles
 * (Uint32Array), lineSamples, lineDirs (Uint32Array), linePoints
 * (Float32Array) }. Throws an Error on any malformed input.
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
  const total = pts + 12 * l * s;
  if (buf.byteLength !== total) throw new Error(`body frame has ${buf.byteLength} bytes, its header says ${total}`);
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
  };
}
