// The geometry frame decoder (protocol version 2) against bytes written by
// hand from the README's table ("Binary geometry frame"), never by an
// encoder: a curve part as a literal hex dump, a surface part put together
// field by field at the table's offsets; every truncation, a wrong kind,
// version, magic or a curve with v knots is refused.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { decodeFrame, PROTOCOL_VERSION } from '../src/frame.js';

/** Bytes from a hex dump (whitespace and `|` ignored). */
const hex = (s) => Uint8Array.from(s.replace(/[\s|]/g, '').match(/../g), (b) => parseInt(b, 16)).buffer;

// A quadratic curve part: design 7, part 3, revision 42, from a drag (flags 1),
// 3 control points, 1 icon. u knots at 48 (6 × f64), points at P = 48 + 48 = 96
// (3 × 12 bytes, to 132), icons at I = 132 rounded up to 8 = 136; 160 bytes.
const CURVE = `
  56 53 47 46 | 02 | 02 | 01 00 | 07 00 00 00 00 00 00 00 | 03 00 00 00 00 00 00 00 | 2a 00 00 00 00 00 00 00
  03 00 00 00 | 01 00 00 00 | 02 | 00 | 00 00 | 01 00 00 00
  00 00 00 00 00 00 00 00  00 00 00 00 00 00 00 00  00 00 00 00 00 00 00 00
  00 00 00 00 00 00 f0 3f  00 00 00 00 00 00 f0 3f  00 00 00 00 00 00 f0 3f
  00 00 00 00 00 00 00 3f 00 00 80 3f | 00 00 80 3f 00 00 00 40 00 00 80 3f | 00 00 00 40 00 00 00 00 00 00 80 3f
  00 00 00 00
  09 00 00 00 00 00 00 00 | 00 00 80 3f 00 00 00 3f 00 00 80 3f | 00 00 00 00`;

test('protocol version 2', () => assert.equal(PROTOCOL_VERSION, 2));

test('a curve frame written by hand from the README decodes', () => {
  const buf = hex(CURVE);
  assert.equal(buf.byteLength, 160);
  const f = decodeFrame(buf);
  assert.equal(f.kind, 'curve');
  assert.equal(f.design, 7);
  assert.equal(f.part, 3);
  assert.equal(f.revision, 42);
  assert.equal(f.flags, 1);
  assert.equal(f.n, 3);
  assert.equal(f.degree, 2);
  assert.deepEqual(Array.from(f.knots), [0, 0, 0, 1, 1, 1]);
  assert.deepEqual(Array.from(f.points), [0, 0.5, 1, 1, 2, 1, 2, 0, 1]);
  assert.deepEqual(f.icons, [{ id: 9, xyz: [1, 0.5, 1] }]);
  assert.equal(f.knotsV, undefined, 'a curve has no v knots');
});

test('a curve frame that is cut short, too long, of another version or with v knots is refused', () => {
  const buf = hex(CURVE);
  for (const len of [0, 10, 47, 48, 96, 135, 159]) assert.throws(() => decodeFrame(buf.slice(0, len)), `${len} bytes`);
  const longer = new Uint8Array(168);
  longer.set(new Uint8Array(buf));
  assert.throws(() => decodeFrame(longer.buffer), /header says 160/);
  const patch = (offset, byte) => {
    const b = new Uint8Array(buf.slice(0));
    b[offset] = byte;
    return b.buffer;
  };
  assert.throws(() => decodeFrame(patch(0, 0x55)), /magic/);
  assert.throws(() => decodeFrame(patch(4, 7)), /kind/); // 3 is the mesh frame, 4 the body frame, 5 and 6 the drag stream
  assert.throws(() => decodeFrame(patch(5, 1)), /version/);
  assert.throws(() => decodeFrame(patch(36, 2)), /nv = 1/, 'a curve with nv = 2');
  assert.throws(() => decodeFrame(patch(41, 1)), /degree v = 0/, 'a curve with a v degree');
  assert.throws(() => decodeFrame(patch(40, 3)), /control points/, 'degree 3 on 3 points');
  // Read as a surface (kind 1) the same bytes lack their v knots.
  assert.throws(() => decodeFrame(patch(4, 1)));
});

/**
 * A bilinear 3 × 3 surface part (design 1, part 12, revision 2^40 + 5, the
 * compact join's flag 2), two icons, written at the README's offsets: u knots
 * at 48, v knots at Kv = 48 + 8·5 = 88, points at P = 88 + 40 = 128 (108
 * bytes, to 236), icons at I = 240; 288 bytes.
 */
function surfaceBytes() {
  const buf = new ArrayBuffer(288);
  const dv = new DataView(buf);
  'VSGF'.split('').forEach((c, i) => dv.setUint8(i, c.charCodeAt(0)));
  dv.setUint8(4, 1);
  dv.setUint8(5, 2);
  dv.setUint16(6, 2, true);
  dv.setBigUint64(8, 1n, true);
  dv.setBigUint64(16, 12n, true);
  dv.setBigUint64(24, (1n << 40n) + 5n, true);
  dv.setUint32(32, 3, true);
  dv.setUint32(36, 3, true);
  dv.setUint8(40, 1);
  dv.setUint8(41, 1);
  dv.setUint32(44, 2, true);
  [0, 0, 0.5, 1, 1].forEach((k, i) => dv.setFloat64(48 + 8 * i, k, true));
  [0, 0, 0.25, 1, 1].forEach((k, i) => dv.setFloat64(88 + 8 * i, 2 * k, true));
  for (let i = 0; i < 3; i++) for (let j = 0; j < 3; j++) {
    const o = 128 + 12 * (i * 3 + j);
    dv.setFloat32(o, i, true);
    dv.setFloat32(o + 4, j, true);
    dv.setFloat32(o + 8, i * j, true);
  }
  dv.setBigUint64(240, 4n, true);
  dv.setFloat32(248, 0.25, true);
  dv.setBigUint64(264, 17n, true);
  dv.setFloat32(280, -3, true);
  return buf;
}

test('a surface frame put together at the README offsets decodes, padding and all', () => {
  const f = decodeFrame(surfaceBytes());
  assert.equal(f.kind, 'surface');
  assert.equal(f.design, 1);
  assert.equal(f.part, 12);
  assert.equal(f.revision, 2 ** 40 + 5);
  assert.equal(f.flags, 2);
  assert.deepEqual([f.nu, f.nv, f.degreeU, f.degreeV], [3, 3, 1, 1]);
  assert.deepEqual(Array.from(f.knotsU), [0, 0, 0.5, 1, 1]);
  assert.deepEqual(Array.from(f.knotsV), [0, 0, 0.5, 2, 2]);
  // Row-major, i along u: point (i, j) at i·nv + j.
  assert.deepEqual(Array.from(f.points.slice(3 * 5, 3 * 5 + 3)), [1, 2, 2]);
  assert.deepEqual(Array.from(f.points.slice(3 * 7, 3 * 7 + 3)), [2, 1, 2]);
  assert.deepEqual(f.icons, [{ id: 4, xyz: [0.25, 0, 0] }, { id: 17, xyz: [0, 0, -3] }]);
});

test('a surface frame is refused when cut, padded wrongly or of degree 0', () => {
  const buf = surfaceBytes();
  for (const len of [47, 127, 236, 240, 287]) assert.throws(() => decodeFrame(buf.slice(0, len)), `${len} bytes`);
  const flat = buf.slice(0);
  new DataView(flat).setUint8(41, 0);
  assert.throws(() => decodeFrame(flat), /along v/);
  const big = buf.slice(0);
  new DataView(big).setUint32(32, 5000, true);
  assert.throws(() => decodeFrame(big), /out of range/);
});
