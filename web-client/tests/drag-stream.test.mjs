// The drag stream on the client (protocol/README.md, "Drag stream (kinds 5
// and 6)"): a drag basis and a drag frame written here as hex dumps from the
// README's tables (never by an encoder) decode field by field; the stream
// turns a drag frame into a frame whose net is R + ρ·d on the reference
// frame's grid, refuses what it cannot apply, and every truncation is refused.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { decodeFrame } from '../src/frame.js';
import { DragStream } from '../src/drag-stream.js';

const hex = (s) => Uint8Array.from(s.replace(/[\s|]/g, '').match(/../g), (b) => parseInt(b, 16)).buffer;

// Design 7, part 3, basis 5, reference revision 42, n = 3, ρ = (1, 0.5, −2).
const BASIS = `
  56 53 47 46 | 05 | 02 | 00 00 | 07 00 00 00 00 00 00 00 | 03 00 00 00 00 00 00 00
  05 00 00 00 00 00 00 00 | 2a 00 00 00 00 00 00 00 | 03 00 00 00 | 00 00 00 00
  00 00 80 3f | 00 00 00 3f | 00 00 00 c0`;
// Design 7, part 3, revision 43, drag, basis 5, d = (2, −0.5, 0), icon 11 at (1, 2, 3).
const DRAG = `
  56 53 47 46 | 06 | 02 | 01 00 | 07 00 00 00 00 00 00 00 | 03 00 00 00 00 00 00 00
  2b 00 00 00 00 00 00 00 | 05 00 00 00 00 00 00 00
  00 00 00 00 00 00 00 40 | 00 00 00 00 00 00 e0 bf | 00 00 00 00 00 00 00 00
  01 00 00 00 | 00 00 00 00
  0b 00 00 00 00 00 00 00 | 00 00 80 3f | 00 00 00 40 | 00 00 40 40 | 00 00 00 00`;
// The quadratic curve part of frame.test.mjs: design 7, part 3, revision 42,
// 3 control points (0,0,0) (1,1,1) (10,−1,0.25), no icons.
const CURVE = `
  56 53 47 46 | 02 | 02 | 00 00 | 07 00 00 00 00 00 00 00 | 03 00 00 00 00 00 00 00 | 2a 00 00 00 00 00 00 00
  03 00 00 00 | 01 00 00 00 | 02 | 00 | 00 00 | 00 00 00 00
  00 00 00 00 00 00 00 00  00 00 00 00 00 00 00 00  00 00 00 00 00 00 00 00
  00 00 00 00 00 00 f0 3f  00 00 00 00 00 00 f0 3f  00 00 00 00 00 00 f0 3f
  00 00 00 00 00 00 00 00 00 00 00 00
  00 00 80 3f 00 00 80 3f 00 00 80 3f
  00 00 20 41 00 00 80 bf 00 00 80 3e
  00 00 00 00`;

test('a drag basis and a drag frame decode field by field', () => {
  const b = decodeFrame(hex(BASIS));
  assert.equal(b.kind, 'drag_basis');
  assert.deepEqual([b.design, b.part, b.basis, b.reference], [7, 3, 5, 42]);
  assert.deepEqual([...b.rho], [1, 0.5, -2]);
  const f = decodeFrame(hex(DRAG));
  assert.equal(f.kind, 'drag');
  assert.deepEqual([f.design, f.part, f.revision, f.flags, f.basis], [7, 3, 43, 1, 5]);
  assert.deepEqual(f.d, [2, -0.5, 0]);
  assert.deepEqual(f.icons, [{ id: 11, xyz: [1, 2, 3] }]);
});

test('every truncation, a longer message, reserved bytes and NaN are refused', () => {
  for (const src of [BASIS, DRAG]) {
    const full = new Uint8Array(hex(src));
    for (let n = 0; n < full.length; n++) assert.throws(() => decodeFrame(full.slice(0, n).buffer));
    const longer = new Uint8Array(full.length + 1);
    longer.set(full);
    assert.throws(() => decodeFrame(longer.buffer));
  }
  const b = new Uint8Array(hex(BASIS));
  b[44] = 1;
  assert.throws(() => decodeFrame(b.buffer), /zero/);
  const nan = new Uint8Array(hex(BASIS));
  nan.set([0x00, 0x00, 0xc0, 0x7f], 48);
  assert.throws(() => decodeFrame(nan.buffer), /finite/);
  const d = new Uint8Array(hex(DRAG));
  d.set([0, 0, 0, 0, 0, 0, 0xf0, 0x7f], 40); // +∞
  assert.throws(() => decodeFrame(d.buffer), /finite/);
  const v = new Uint8Array(hex(DRAG));
  v[5] = 1;
  assert.throws(() => decodeFrame(v.buffer), /version/);
});

test('the stream turns a drag frame into R + ρ·d on the reference frame', () => {
  const s = new DragStream();
  const curve = s.take(decodeFrame(hex(CURVE)));
  assert.equal(curve.kind, 'curve');
  assert.equal(s.take(decodeFrame(hex(BASIS))), null);
  const f = s.take(decodeFrame(hex(DRAG)));
  assert.equal(f.kind, 'curve');
  assert.equal(f.revision, 43);
  assert.equal(f.flags, 1);
  assert.deepEqual(f.knots, curve.knots);
  assert.deepEqual([...f.points], [2, -0.5, 0, 2, 0.75, 1, 6, 0, 0.25]);
  assert.deepEqual(f.icons, [{ id: 11, xyz: [1, 2, 3] }]);
  // The reference's own points are untouched.
  assert.deepEqual([...curve.points], [0, 0, 0, 1, 1, 1, 10, -1, 0.25]);
});

test('a drag frame that cannot be applied gives nothing', () => {
  // No basis.
  const s = new DragStream();
  s.take(decodeFrame(hex(CURVE)));
  assert.equal(s.take(decodeFrame(hex(DRAG))), null);
  // A basis whose reference (42) is not the last full frame held (43).
  const t = new DragStream();
  const c = new Uint8Array(hex(CURVE));
  c[24] = 0x2b;
  t.take(decodeFrame(c.buffer));
  t.take(decodeFrame(hex(BASIS)));
  assert.equal(t.take(decodeFrame(hex(DRAG))), null);
  // A full frame after the basis retires it.
  const u = new DragStream();
  u.take(decodeFrame(hex(CURVE)));
  u.take(decodeFrame(hex(BASIS)));
  u.take(decodeFrame(hex(CURVE)));
  assert.equal(u.take(decodeFrame(hex(DRAG))), null);
});
