// The mesh frame decoder (kind 3) against bytes written by hand from the
// README's table ("Binary mesh frame (kind 3)"), never by an encoder; every
// truncation, a bad index width, a vertex index out of range or non-zero
// padding is refused.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { decodeFrame, decodeMeshFrame } from '../src/frame.js';

const hex = (s) => Uint8Array.from(s.replace(/[\s|]/g, '').match(/../g), (b) => parseInt(b, 16)).buffer;

// Design 7, part 9, revision 300, flags 1; 4 vertices, 2 triangles; origin
// (-1, 0.5, 2), step 0.25; u16 indices. 64 + 48 + 12 = 124 bytes.
const MESH = `
  56 53 47 46 | 03 | 02 | 01 00 | 07 00 00 00 00 00 00 00 | 09 00 00 00 00 00 00 00 | 2c 01 00 00 00 00 00 00
  04 00 00 00 | 02 00 00 00 | 00 00 80 bf  00 00 00 3f  00 00 00 40 | 00 00 80 3e | 02 | 00 00 00 00 00 00 00
  00 00 00 00 00 00 | 04 00 00 00 00 00 | 00 00 08 00 00 00 | 00 00 00 00 ff ff
  ff 7f 00 00 00 00 | 00 00 01 80 00 00 | 00 00 00 00 ff 7f | 00 00 00 00 ff 7f
  00 00 01 00 02 00 | 00 00 02 00 03 00`;

test('a mesh frame written by hand from the README decodes', () => {
  const buf = hex(MESH);
  assert.equal(buf.byteLength, 124);
  const f = decodeFrame(buf);
  assert.equal(f.kind, 'mesh');
  assert.deepEqual([f.design, f.part, f.revision, f.flags], [7, 9, 300, 1]);
  assert.deepEqual(f.origin, [-1, 0.5, 2]);
  assert.equal(f.step, 0.25);
  assert.deepEqual(Array.from(f.positions), [-1, 0.5, 2, 0, 0.5, 2, -1, 2.5, 2, -1, 0.5, 2 + 65535 * 0.25]);
  assert.deepEqual(Array.from(f.normals), [1, 0, 0, 0, -1, 0, 0, 0, 1, 0, 0, 1]);
  assert.ok(f.indices instanceof Uint16Array);
  assert.deepEqual(Array.from(f.indices), [0, 1, 2, 0, 2, 3]);
});

test('corrupt mesh frames are refused', () => {
  const good = new Uint8Array(hex(MESH));
  const bad = (edit) => {
    const b = good.slice();
    edit(b);
    return b.buffer;
  };
  assert.throws(() => decodeMeshFrame(bad((b) => { b[64 + 48] = 4; })), /beyond/);
  assert.throws(() => decodeMeshFrame(bad((b) => { b[56] = 4; })), /index width/);
  assert.throws(() => decodeMeshFrame(bad((b) => { b[60] = 1; })), /padding/);
  assert.throws(() => decodeMeshFrame(bad((b) => { b[55] = 0x7f; b[54] = 0xc0; })), /not finite/);
  for (let n = 0; n < good.length; n++) assert.throws(() => decodeFrame(good.slice(0, n).buffer));
});
