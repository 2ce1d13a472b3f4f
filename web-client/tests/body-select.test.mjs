// What a click on a lattice handle selects for the gizmo (src/body-view.js,
// BodyView.selectionsAt), against selections written out by hand for a
// 3 × 4 × 5 lattice (storage index (i·4 + j)·5 + k): a corner offers its
// three faces in face mode and its three edges in edge mode, an edge point
// its two faces and one edge, an inner point only itself.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { BodyView } from '../src/body-view.js';

const counts = [3, 4, 5];
const index = (i, j, k) => (i * 4 + j) * 5 + k;
/** Every storage index whose (i, j, k) passes `f`, ascending. */
const where = (f) => {
  const out = [];
  for (let i = 0; i < 3; i++) for (let j = 0; j < 4; j++) for (let k = 0; k < 5; k++) if (f(i, j, k)) out.push(index(i, j, k));
  return out;
};

test('a corner: its point, its three faces, its three edges, as body_edit selections with their points', () => {
  const c = index(2, 3, 4);
  assert.deepEqual(BodyView.selectionsAt(counts, c, 'point').map((s) => [s.select, s.indices]), [[{ point: [2, 3, 4] }, [c]]]);
  const faces = BodyView.selectionsAt(counts, c, 'face');
  assert.deepEqual(faces.map((s) => s.select), [{ face: 'u_max' }, { face: 'v_max' }, { face: 'w_max' }]);
  assert.deepEqual(faces[0].indices, where((i) => i === 2));
  assert.deepEqual(faces[1].indices, where((i, j) => j === 3));
  assert.deepEqual(faces[2].indices, where((i, j, k) => k === 4));
  assert.equal(faces[0].indices.length, 4 * 5);
  const edges = BodyView.selectionsAt(counts, c, 'edge');
  assert.deepEqual(edges.map((s) => s.select), [{ edge: ['u_max', 'v_max'] }, { edge: ['u_max', 'w_max'] }, { edge: ['v_max', 'w_max'] }]);
  assert.deepEqual(edges[0].indices, [index(2, 3, 0), index(2, 3, 1), index(2, 3, 2), index(2, 3, 3), index(2, 3, 4)]);
  assert.deepEqual(edges[1].indices, [index(2, 0, 4), index(2, 1, 4), index(2, 2, 4), index(2, 3, 4)]);
  assert.deepEqual(edges[2].indices, [index(0, 3, 4), index(1, 3, 4), index(2, 3, 4)]);
});

test('an edge point offers two faces and one edge; a face point one face and, in edge mode, itself; an inner point only itself', () => {
  const e = index(0, 2, 0); // on u_min and w_min
  assert.deepEqual(BodyView.selectionsAt(counts, e, 'face').map((s) => s.select), [{ face: 'u_min' }, { face: 'w_min' }]);
  const edge = BodyView.selectionsAt(counts, e, 'edge');
  assert.deepEqual(edge.map((s) => s.select), [{ edge: ['u_min', 'w_min'] }]);
  assert.deepEqual(edge[0].indices, [index(0, 0, 0), index(0, 1, 0), index(0, 2, 0), index(0, 3, 0)]);
  const f = index(1, 0, 2); // on v_min only
  assert.deepEqual(BodyView.selectionsAt(counts, f, 'face').map((s) => s.select), [{ face: 'v_min' }]);
  assert.deepEqual(BodyView.selectionsAt(counts, f, 'edge').map((s) => s.select), [{ point: [1, 0, 2] }]);
  const inner = index(1, 2, 3);
  for (const mode of ['point', 'face', 'edge']) assert.deepEqual(BodyView.selectionsAt(counts, inner, mode).map((s) => [s.select, s.indices]), [[{ point: [1, 2, 3] }, [inner]]]);
});
