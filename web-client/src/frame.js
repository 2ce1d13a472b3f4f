// Decoding of the binary geometry frame (protocol/README.md, "Binary
// geometry frame"): zero-copy typed-array views, every size checked.

const MAGIC = [0x56, 0x53, 0x47, 0x46]; // "VSGF"
export const PROTOCOL_VERSION = 1;

/** Decodes a frame from an ArrayBuffer; throws an Error on any malformed input. */
export function decodeFrame(buf) {
  if (!(buf instanceof ArrayBuffer) || buf.byteLength < 40) throw new Error('frame too short');
  const dv = new DataView(buf);
  for (let i = 0; i < 4; i++) if (dv.getUint8(i) !== MAGIC[i]) throw new Error('bad magic');
  if (dv.getUint8(4) !== 1) throw new Error('unknown frame kind');
  if (dv.getUint8(5) !== PROTOCOL_VERSION) throw new Error('frame version mismatch');
  const flags = dv.getUint16(6, true);
  const design = dv.getBigUint64(8, true);
  const revision = dv.getBigUint64(16, true);
  const nu = dv.getUint32(24, true);
  const nv = dv.getUint32(28, true);
  const degreeU = dv.getUint8(32);
  const degreeV = dv.getUint8(33);
  const nIcons = dv.getUint32(36, true);
  if (nu > 2048 || nv > 2048 || nIcons > 65536 || degreeU < 1 || degreeV < 1) throw new Error('frame sizes out of range');
  if (nu < degreeU + 1 || nv < degreeV + 1) throw new Error('too few control points');
  const nku = nu + degreeU + 1;
  const nkv = nv + degreeV + 1;
  const ku = 40;
  const kv = ku + 8 * nku;
  const pts = kv + 8 * nkv;
  const icons = Math.ceil((pts + 12 * nu * nv) / 8) * 8;
  const total = icons + 24 * nIcons;
  if (buf.byteLength !== total) throw new Error(`frame is ${buf.byteLength} bytes, header says ${total}`);
  const frame = {
    flags,
    design: Number(design),
    revision: Number(revision),
    nu,
    nv,
    degreeU,
    degreeV,
    knotsU: new Float64Array(buf, ku, nku),
    knotsV: new Float64Array(buf, kv, nkv),
    points: new Float32Array(buf, pts, nu * nv * 3),
    icons: [],
  };
  for (let k = 0; k < nIcons; k++) {
    const o = icons + 24 * k;
    frame.icons.push({
      id: Number(dv.getBigUint64(o, true)),
      xyz: [dv.getFloat32(o + 8, true), dv.getFloat32(o + 12, true), dv.getFloat32(o + 16, true)],
    });
  }
  return frame;
}
