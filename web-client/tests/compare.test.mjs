// Comparing a surface part with a version (src/compare.js): the part's net
// is found by id in a version document shaped as the REST API serves it
// (written here by hand), a domain mismatch is seen, and the deviation of
// a plate raised by 2 from the flat plate is 2 along its normal everywhere.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { deviation, sameDomain, versionSurface } from '../src/compare.js';
import { Tessellator } from '../src/bspline.js';

const surface = (z, knots = [0, 0, 1, 1]) => ({ u_degree: 1, v_degree: 1, u_knots: knots, v_knots: [0, 0, 1, 1], nu: 2, nv: 2, points: [[0, 0, z], [0, 1, z], [1, 0, z], [1, 1, z]] });
const doc = {
  format: 2,
  name: 'demo',
  parts: [
    { id: 3, name: 'feature line', visible: true, locked: false, colour: '#ff8800', body: { kind: 'curve', curve: { degree: 1, knots: [0, 0, 1, 1], points: [[0, 0, 0], [1, 0, 0]] }, material: { alpha: 0.01, beta: 1 }, icons: [] } },
    { id: 7, name: 'lid', visible: true, locked: false, colour: '#88aa66', body: { kind: 'surface', surface: surface(0), material: {}, icons: [] } },
  ],
  relations: [],
};

test('a version\'s surface part is found by id; a curve or a missing part is none', () => {
  const s = versionSurface(doc, 7);
  assert.deepEqual([s.degreeU, s.degreeV, s.nu, s.nv], [1, 1, 2, 2]);
  assert.deepEqual(Array.from(s.points), [0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0]);
  assert.equal(versionSurface(doc, 3), null);
  assert.equal(versionSurface(doc, 99), null);
});

test('the deviation of a plate raised by 2 is 2 along the normal at every sample; another domain is seen', () => {
  const live = versionSurface({ parts: [{ id: 1, body: { kind: 'surface', surface: surface(2) } }] }, 1);
  const old = versionSurface(doc, 7);
  const t = new Tessellator(live, 5, 4);
  t.fill(live);
  const ref = new Tessellator(old, 5, 4);
  ref.fill(old);
  assert.equal(sameDomain(t, old), true);
  const { deviation: d, max } = deviation(t, ref);
  assert.equal(d.length, 20);
  // The normal of (u, v) ↦ (u, v, 2) is +z: the live plate lies 2 above.
  for (const x of d) assert.ok(Math.abs(x - 2) < 1e-6, `deviation ${x}`);
  assert.ok(Math.abs(max - 2) < 1e-6);
  const out = new Float32Array(20);
  assert.equal(deviation(t, ref, out).deviation, out, 'the buffer is reused');
  const wider = versionSurface({ parts: [{ id: 1, body: { kind: 'surface', surface: surface(0, [0, 0, 2, 2]) } }] }, 1);
  assert.equal(sameDomain(t, wider), false);
});
