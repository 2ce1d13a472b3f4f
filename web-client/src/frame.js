// Decoding of the binary geometry frame of one part (protocol/README.md,
// "Binary geometry frame", version 2): the 48-byte header with design, part
// and revision; a surface part (kind 1: u and v knots, nu × nv net) or a
// curve part (kind 2: u knots only, nu control points, nv = 1, pv = 0);
// zero-copy typed-array views, every size checked. A mesh part (kind 3, a DSM
// part meshed by the server: "Binary mesh frame (kind 3)") has its own
// 64-byte header and quantised positions, i16 normals and u16/u32 indices.
// The drag stream ("Drag stream (kinds 5 and 6)"): a drag basis (ρ of one
// part, kind 5) and drag frames (d and icon positions, kind 6). A mesh delta
// (kind 8, "Binary mesh delta") is decoded by dsm-delta.js.

import { KIND_BODY, decodeBodyFrame } from './body-frame.js';
import { KIND_MESH_DELTA, decodeMeshDelta } from './dsm-delta.js';

const MAGIC = [0x56, 0x53, 0x47, 0x46]; // "VSGF"
export const PROTOCOL_VERSION = 2;
/** Frame kinds (byte 4). */
export const KIND_SURFACE = 1;
export const KIND_CURVE = 2;
export const KIND_MESH = 3;
export const KIND_DRAG_BASIS = 5;
export const KIND_DRAG_FRAME = 6;
/** Flags (bytes 6..8): bit 0 from a drag, bit 1 the shape of the snapshot that follows (compact join). */
export const FLAG_DRAG = 1;
export const FLAG_SNAPSHOT = 2;
const HEADER = 48;
/** Size limits of protocol/src/limits.rs and frame.rs: grid, icons, degree. */
const MAX_GRID = 2048;
const MAX_ICONS = 65536;
const MAX_DEGREE = 15;

/**
 * Decodes a frame from an ArrayBuffer; throws an Error on any malformed
 * input. A surface frame gives { kind: 'surface', part, design, revision,
 * flags, nu, nv, degreeU, degreeV, knotsU, knotsV, points, icons }; a curve
 * frame { kind: 'curve', part, design, revision, flags, n, degree, knots,
 * points, icons }. `points` is a Float32Array of x, y, z; `icons` a list of
 * { id, xyz }.
 */
export function decodeFrame(buf) {
  if (!(buf instanceof ArrayBuffer) || buf.byteLength < HEADER) throw new Error('frame too short');
  const dv = new DataView(buf);
  for (let i = 0; i < 4; i++) if (dv.getUint8(i) !== MAGIC[i]) throw new Error('bad magic');
  const kind = dv.getUint8(4);
  if (kind === KIND_MESH) return decodeMeshFrame(buf);
  if (kind === KIND_BODY) {
    if (dv.getUint8(5) !== PROTOCOL_VERSION) throw new Error(`frame version ${dv.getUint8(5)}, this page speaks ${PROTOCOL_VERSION}`);
    return decodeBodyFrame(buf);
  }
  if (kind === KIND_MESH_DELTA) {
    if (dv.getUint8(5) !== PROTOCOL_VERSION) throw new Error(`frame version ${dv.getUint8(5)}, this page speaks ${PROTOCOL_VERSION}`);
    return decodeMeshDelta(buf);
  }
  if (kind === KIND_DRAG_BASIS) return decodeDragBasis(buf);
  if (kind === KIND_DRAG_FRAME) return decodeDragFrame(buf);
  if (kind !== KIND_SURFACE && kind !== KIND_CURVE) throw new Error(`unknown frame kind ${kind}`);
  if (dv.getUint8(5) !== PROTOCOL_VERSION) throw new Error(`frame version ${dv.getUint8(5)}, this page speaks ${PROTOCOL_VERSION}`);
  const flags = dv.getUint16(6, true);
  const design = Number(dv.getBigUint64(8, true));
  const part = Number(dv.getBigUint64(16, true));
  const revision = Number(dv.getBigUint64(24, true));
  const nu = dv.getUint32(32, true);
  const nv = dv.getUint32(36, true);
  const degreeU = dv.getUint8(40);
  const degreeV = dv.getUint8(41);
  const nIcons = dv.getUint32(44, true);
  const curve = kind === KIND_CURVE;
  if (nu > MAX_GRID || nv > MAX_GRID || nIcons > MAX_ICONS) throw new Error('frame sizes out of range');
  if (curve && (nv !== 1 || degreeV !== 0)) throw new Error('a curve frame has nv = 1 and degree v = 0');
  if (degreeU < 1 || degreeU > MAX_DEGREE || nu < degreeU + 1) throw new Error(`degree ${degreeU} with ${nu} control points along u`);
  if (!curve && (degreeV < 1 || degreeV > MAX_DEGREE || nv < degreeV + 1)) throw new Error(`degree ${degreeV} with ${nv} control points along v`);
  const nku = nu + degreeU + 1;
  const nkv = curve ? 0 : nv + degreeV + 1;
  const ku = HEADER;
  const kv = ku + 8 * nku;
  const pts = kv + 8 * nkv;
  const icons = Math.ceil((pts + 12 * nu * nv) / 8) * 8;
  const total = icons + 24 * nIcons;
  if (buf.byteLength !== total) throw new Error(`frame is ${buf.byteLength} bytes, header says ${total}`);
  const knotsU = new Float64Array(buf, ku, nku);
  const points = new Float32Array(buf, pts, nu * nv * 3);
  const frameIcons = [];
  for (let k = 0; k < nIcons; k++) {
    const o = icons + 24 * k;
    frameIcons.push({
      id: Number(dv.getBigUint64(o, true)),
      xyz: [dv.getFloat32(o + 8, true), dv.getFloat32(o + 12, true), dv.getFloat32(o + 16, true)],
    });
  }
  const common = { part, design, revision, flags, points, icons: frameIcons };
  if (curve) return { kind: 'curve', ...common, n: nu, degree: degreeU, knots: knotsU };
  return { kind: 'surface', ...common, nu, nv, degreeU, degreeV, knotsU, knotsV: new Float64Array(buf, kv, nkv) };
}

const MESH_HEADER = 64;
/** Size limits of protocol/src/mesh_frame.rs. */
const MAX_MESH_VERTICES = 4 << 20;
const MAX_MESH_TRIANGLES = 8 << 20;

/**
 * Decodes a mesh frame (kind 3) from an ArrayBuffer; throws on any malformed
 * input. Gives { kind: 'mesh', part, design, revision, flags, origin, step,
 * positions (Float32Array x, y, z, dequantised), normals (Float32Array, unit),
 * indices (Uint16Array or Uint32Array), quanta (Uint16Array) and normalQuanta
 * (Int16Array) as sent (what a mesh delta copies) }.
 */
export function decodeMeshFrame(buf) {
  if (!(buf instanceof ArrayBuffer) || buf.byteLength < MESH_HEADER) throw new Error('mesh frame too short');
  const dv = new DataView(buf);
  for (let i = 0; i < 4; i++) if (dv.getUint8(i) !== MAGIC[i]) throw new Error('bad magic');
  if (dv.getUint8(4) !== KIND_MESH) throw new Error(`frame kind ${dv.getUint8(4)} is not a mesh`);
  if (dv.getUint8(5) !== PROTOCOL_VERSION) throw new Error(`frame version ${dv.getUint8(5)}, this page speaks ${PROTOCOL_VERSION}`);
  const flags = dv.getUint16(6, true);
  const design = Number(dv.getBigUint64(8, true));
  const part = Number(dv.getBigUint64(16, true));
  const revision = Number(dv.getBigUint64(24, true));
  const nv = dv.getUint32(32, true);
  const nt = dv.getUint32(36, true);
  if (nv > MAX_MESH_VERTICES || nt > MAX_MESH_TRIANGLES) throw new Error('mesh frame sizes out of range');
  const origin = [dv.getFloat32(40, true), dv.getFloat32(44, true), dv.getFloat32(48, true)];
  const step = dv.getFloat32(52, true);
  if (!origin.every(Number.isFinite) || !Number.isFinite(step) || step < 0) throw new Error('mesh frame origin or step is not finite');
  const ib = dv.getUint8(56);
  if (ib !== (nv <= 65535 ? 2 : 4)) throw new Error(`index width ${ib} does not fit ${nv} vertices`);
  for (let i = 57; i < MESH_HEADER; i++) if (dv.getUint8(i) !== 0) throw new Error('mesh frame header padding is not zero');
  const total = MESH_HEADER + 12 * nv + 3 * ib * nt;
  if (buf.byteLength !== total) throw new Error(`mesh frame is ${buf.byteLength} bytes, header says ${total}`);
  const q = new Uint16Array(buf, MESH_HEADER, 3 * nv);
  const qn = new Int16Array(buf, MESH_HEADER + 6 * nv, 3 * nv);
  const indices = ib === 2 ? new Uint16Array(buf, MESH_HEADER + 12 * nv, 3 * nt) : new Uint32Array(buf, MESH_HEADER + 12 * nv, 3 * nt);
  for (let i = 0; i < indices.length; i++) if (indices[i] >= nv) throw new Error(`index ${indices[i]} beyond the ${nv} vertices`);
  const positions = new Float32Array(3 * nv);
  const normals = new Float32Array(3 * nv);
  for (let i = 0; i < 3 * nv; i++) {
    positions[i] = origin[i % 3] + q[i] * step;
    normals[i] = qn[i] / 32767;
  }
  return { kind: 'mesh', part, design, revision, flags, origin, step, positions, normals, indices, quanta: q, normalQuanta: qn };
}

function checkStreamHead(buf, kind, header) {
  if (!(buf instanceof ArrayBuffer) || buf.byteLength < header) throw new Error('drag message too short');
  const dv = new DataView(buf);
  for (let i = 0; i < 4; i++) if (dv.getUint8(i) !== MAGIC[i]) throw new Error('bad magic');
  if (dv.getUint8(4) !== kind) throw new Error(`frame kind ${dv.getUint8(4)} is not ${kind}`);
  if (dv.getUint8(5) !== PROTOCOL_VERSION) throw new Error(`frame version ${dv.getUint8(5)}, this page speaks ${PROTOCOL_VERSION}`);
  return dv;
}

/**
 * Decodes a drag basis (kind 5): { kind: 'drag_basis', design, part, basis,
 * reference, rho (Float32Array, one per control point) }. Throws on any
 * malformed input.
 */
export function decodeDragBasis(buf) {
  const dv = checkStreamHead(buf, KIND_DRAG_BASIS, 48);
  const n = dv.getUint32(40, true);
  if (n > MAX_GRID * MAX_GRID) throw new Error('drag basis size out of range');
  if (buf.byteLength !== 48 + 4 * n) throw new Error(`drag basis is ${buf.byteLength} bytes, header says ${48 + 4 * n}`);
  if (dv.getUint16(6, true) !== 0 || dv.getUint32(44, true) !== 0) throw new Error('drag basis zero bytes are not zero');
  const rho = new Float32Array(buf, 48, n);
  for (let k = 0; k < n; k++) if (!Number.isFinite(rho[k])) throw new Error('drag basis has a non-finite factor');
  return {
    kind: 'drag_basis',
    design: Number(dv.getBigUint64(8, true)),
    part: Number(dv.getBigUint64(16, true)),
    basis: Number(dv.getBigUint64(24, true)),
    reference: Number(dv.getBigUint64(32, true)),
    rho,
  };
}

/**
 * Decodes a drag frame (kind 6): { kind: 'drag', design, part, revision,
 * flags, basis, d: [x, y, z], icons }. Throws on any malformed input.
 */
export function decodeDragFrame(buf) {
  const dv = checkStreamHead(buf, KIND_DRAG_FRAME, 72);
  const m = dv.getUint32(64, true);
  if (m > MAX_ICONS) throw new Error('drag frame icon count out of range');
  if (buf.byteLength !== 72 + 24 * m) throw new Error(`drag frame is ${buf.byteLength} bytes, header says ${72 + 24 * m}`);
  if (dv.getUint32(68, true) !== 0) throw new Error('drag frame zero bytes are not zero');
  const d = [dv.getFloat64(40, true), dv.getFloat64(48, true), dv.getFloat64(56, true)];
  if (!d.every(Number.isFinite)) throw new Error('drag frame d is not finite');
  const icons = [];
  for (let k = 0; k < m; k++) {
    const o = 72 + 24 * k;
    if (dv.getUint32(o + 20, true) !== 0) throw new Error('drag frame icon record padding is not zero');
    icons.push({ id: Number(dv.getBigUint64(o, true)), xyz: [dv.getFloat32(o + 8, true), dv.getFloat32(o + 12, true), dv.getFloat32(o + 16, true)] });
  }
  return {
    kind: 'drag',
    design: Number(dv.getBigUint64(8, true)),
    part: Number(dv.getBigUint64(16, true)),
    revision: Number(dv.getBigUint64(24, true)),
    flags: dv.getUint16(6, true),
    basis: Number(dv.getBigUint64(32, true)),
    d,
    icons,
  };
}
