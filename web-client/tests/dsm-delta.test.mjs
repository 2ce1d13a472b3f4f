// The mesh delta (kind 8) in the page's own modules, against bytes written
// by hand from the README's tables ("Binary mesh frame (kind 3)" for the
// base, "Binary mesh delta (kind 8)" for the delta), never by an encoder:
// decoded, applied to its base, and the result checked against the frame
// worked out by hand from the rules; corrupt deltas and deltas of a base the
// page does not hold are refused or ignored.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { decodeFrame } from '../src/frame.js';
import { MeshDeltas, applyMeshDelta, decodeMeshDelta } from '../src/dsm-delta.js';

const hex = (s) => Uint8Array.from(s.replace(/[\s|]/g, '').match(/../g), (b) => parseInt(b, 16)).buffer;

// Base: design 7, part 9, revision 300, flags 0; 6 vertices (vertex k at
// quanta (k, 10k, 100k), normal +x for even k, +z for odd), 3 triangles
// (0 1 2) (2 3 4) (3 4 5); origin (-1, 0.5, 2), step 0.25; u16 indices.
const BASE = `
  56 53 47 46 | 03 | 02 | 00 00 | 07 00 00 00 00 00 00 00 | 09 00 00 00 00 00 00 00 | 2c 01 00 00 00 00 00 00
  06 00 00 00 | 03 00 00 00 | 00 00 80 bf  00 00 00 3f  00 00 00 40 | 00 00 80 3e | 02 | 00 00 00 00 00 00 00
  00 00 00 00 00 00 | 01 00 0a 00 64 00 | 02 00 14 00 c8 00 | 03 00 1e 00 2c 01 | 04 00 28 00 90 01 | 05 00 32 00 f4 01
  ff 7f 00 00 00 00 | 00 00 00 00 ff 7f | ff 7f 00 00 00 00 | 00 00 00 00 ff 7f | ff 7f 00 00 00 00 | 00 00 00 00 ff 7f
  00 00 01 00 02 00 | 02 00 03 00 04 00 | 03 00 04 00 05 00`;

// Revision 301 from base 300, flags 1: V 6, T 3; vertex runs (2, 3) (literal, 2)
// (0, 1); triangle runs (1, 1) (literal, 2); literal vertices (7, 8, 9) with
// normal -y and (65535, 0, 1) with +x; literal triangles (0 3 4) (4 3 5).
const DELTA = `
  56 53 47 46 | 08 | 02 | 01 00 | 07 00 00 00 00 00 00 00 | 09 00 00 00 00 00 00 00 | 2d 01 00 00 00 00 00 00
  2c 01 00 00 00 00 00 00 | 06 00 00 00 | 03 00 00 00 | 03 00 00 00 | 02 00 00 00 | 02 00 00 00 | 02 00 00 00
  00 00 80 bf  00 00 00 3f  00 00 00 40 | 00 00 80 3e | 02 | 00 00 00 00 00 00 00
  02 00 00 00 03 00 00 00 | ff ff ff ff 02 00 00 00 | 00 00 00 00 01 00 00 00
  01 00 00 00 01 00 00 00 | ff ff ff ff 02 00 00 00
  07 00 08 00 09 00 | ff ff 00 00 01 00
  00 00 01 80 00 00 | ff 7f 00 00 00 00
  00 00 03 00 04 00 | 04 00 03 00 05 00`;

/** World position of quanta q on the frames' cube. */
const at = (q) => [-1 + q[0] * 0.25, 0.5 + q[1] * 0.25, 2 + q[2] * 0.25];

test('a mesh delta written by hand from the README applies to its base', () => {
  const base = decodeFrame(hex(BASE));
  assert.equal(base.kind, 'mesh');
  const buf = hex(DELTA);
  assert.equal(buf.byteLength, 88 + 8 * 5 + 12 * 2 + 6 * 2);
  const d = decodeFrame(buf);
  assert.equal(d.kind, 'mesh_delta');
  assert.deepEqual([d.design, d.part, d.revision, d.base, d.flags, d.vertices, d.triangles], [7, 9, 301, 300, 1, 6, 3]);
  const f = applyMeshDelta(base, d);
  assert.deepEqual([f.kind, f.part, f.revision, f.flags, f.step], ['mesh', 9, 301, 1, 0.25]);
  const quanta = [[2, 20, 200], [3, 30, 300], [4, 40, 400], [7, 8, 9], [65535, 0, 1], [0, 0, 0]];
  assert.deepEqual(Array.from(f.positions), quanta.flatMap(at));
  assert.deepEqual(Array.from(f.normals), [1, 0, 0, 0, 0, 1, 1, 0, 0, 0, -1, 0, 1, 0, 0, 1, 0, 0]);
  assert.ok(f.indices instanceof Uint16Array);
  // Base triangle 1 = (2 3 4) renumbered (0 1 2), then the literal ones.
  assert.deepEqual(Array.from(f.indices), [0, 1, 2, 0, 3, 4, 4, 3, 5]);
});

test('corrupt deltas are refused; a delta of a base not held is ignored', () => {
  const good = new Uint8Array(hex(DELTA));
  const bad = (edit) => {
    const b = good.slice();
    edit(b);
    return b.buffer;
  };
  assert.throws(() => decodeMeshDelta(bad((b) => { b[88 + 4] = 0; })), /empty/);
  assert.throws(() => decodeMeshDelta(bad((b) => { b[40] = 7; })), /header says/);
  assert.throws(() => decodeMeshDelta(bad((b) => { b[80] = 4; })), /index width/);
  assert.throws(() => decodeMeshDelta(bad((b) => { b[85] = 1; })), /padding/);
  assert.throws(() => decodeMeshDelta(bad((b) => { b[b.length - 2] = 6; })), /beyond/);
  for (let n = 0; n < good.length; n++) assert.throws(() => decodeFrame(good.slice(0, n).buffer));
  const base = decodeFrame(hex(BASE));
  // Base vertex 1 copied twice; a run beyond the base; a copied triangle
  // naming a base vertex no run copies; a triangle run beyond the base.
  const applies = (edit) => applyMeshDelta(base, decodeMeshDelta(bad(edit)));
  assert.throws(() => applies((b) => { b[88] = 1; b[88 + 16] = 1; }), /twice/);
  assert.throws(() => applies((b) => { b[88] = 4; }), /copies vertices/);
  assert.throws(() => applies((b) => { b[88 + 24] = 0; }), /does not keep/);
  assert.throws(() => applies((b) => { b[88 + 24] = 3; }), /copies triangles/);

  const meshes = new MeshDeltas();
  const delta = decodeFrame(hex(DELTA));
  assert.equal(meshes.take(delta), null, 'no base held');
  assert.equal(meshes.ignored, 1);
  const other = decodeFrame(bad(() => {}));
  assert.equal(meshes.take(base), base);
  const made = meshes.take(other);
  assert.equal(made.revision, 301);
  // Now 301 is held: the same delta (base 300) no longer applies.
  assert.equal(meshes.take(decodeFrame(hex(DELTA))), null);
  assert.equal(meshes.ignored, 2);
  assert.equal(meshes.applied, 1);
});
