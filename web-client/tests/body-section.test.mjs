// The page's B-spline volume evaluator (src/body-volume.js) and the cutting
// plane's section coloured by det J (src/body-section.js), against truth
// computed here independently: an affine map of the unit cube (control
// points at the Greville abscissae, so x = A·(u, v, w) + b exactly and
// det J = det A everywhere; the section's area and perimeter known in closed
// form), and a warped, jittered lattice with non-uniform knots evaluated by
// the recursive Cox–de Boor definition written in this file, det J by finite
// differences of that map.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { BSplineVolume } from '../src/body-volume.js';
import { SectionGrid } from '../src/body-section.js';

import { point, domainOf, fdDet, lattice, lcg } from './volume-oracle.mjs';

/** Every outline vertex is in exactly two segments (closed loops); returns the loops' total length. */
function closedOutline(sec) {
  const uses = new Map();
  for (const v of sec.outline) uses.set(v, (uses.get(v) || 0) + 1);
  for (const [v, n] of uses) assert.equal(n, 2, `outline vertex ${v} in ${n} segments`);
  let len = 0;
  const P = sec.positions;
  for (let s = 0; s < sec.outline.length; s += 2) {
    const [a, b] = [3 * sec.outline[s], 3 * sec.outline[s + 1]];
    len += Math.hypot(P[a] - P[b], P[a + 1] - P[b + 1], P[a + 2] - P[b + 2]);
  }
  return len;
}

function area(sec) {
  const P = sec.positions;
  let s = 0;
  for (let t = 0; t < sec.triangles.length; t += 3) {
    const [a, b, c] = [0, 1, 2].map((q) => 3 * sec.triangles[t + q]);
    const u = [0, 1, 2].map((e) => P[b + e] - P[a + e]);
    const v = [0, 1, 2].map((e) => P[c + e] - P[a + e]);
    s += Math.hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]) / 2;
  }
  return s;
}

// --- an affine map of the unit cube ------------------------------------------

const A = [
  [2, 0.5, 0],
  [0, 1, 0.3],
  [0, 0, 1.5],
];
const b = [1, -2, 0.5];
const affine = (t) => [0, 1, 2].map((r) => A[r][0] * t[0] + A[r][1] * t[1] + A[r][2] * t[2] + b[r]);
const detA = 2 * 1 * 1.5;
const affineKnots = [
  [0, 0, 0, 0.3, 1, 1, 1],
  [0, 0, 0, 0.5, 0.6, 1, 1, 1],
  [0, 0, 0, 0, 1, 1, 1, 1],
];

test('an affine lattice: the evaluator gives A·(u, v, w) + b and det J = det A; the section has det J = det A at every vertex, the known area and perimeter, and its outline on the faces', () => {
  const L = lattice([2, 2, 3], affineKnots, affine);
  const vol = new BSplineVolume(L);
  const rnd = lcg(7);
  for (let n = 0; n < 200; n++) {
    const t = [rnd(), rnd(), rnd()];
    const e = vol.eval(...t);
    const x = affine(t);
    for (let c = 0; c < 3; c++) assert.ok(Math.abs(e.p[c] - x[c]) < 1e-12, `x at ${t}: ${e.p} vs ${x}`);
    assert.ok(Math.abs(e.det - detA) < 1e-12, `det J ${e.det} at ${t}`);
    for (let c = 0; c < 3; c++) assert.ok(Math.abs(e.du[c] - A[c][0]) < 1e-12 && Math.abs(e.dv[c] - A[c][1]) < 1e-12 && Math.abs(e.dw[c] - A[c][2]) < 1e-12);
  }
  const grid = new SectionGrid(vol);
  // x = 2: u = (1 − 0.5 v) / 2 ∈ [0.25, 0.5] for every (v, w) of the unit square, so the section is the
  // parallelogram spanned by A·(−0.25, 1, 0) = (0, 1, 0) and A·(0, 0, 1) = (0, 0.3, 1.5).
  const sec = grid.cut(0, 2);
  assert.ok(sec.triangles.length > 0);
  for (let v = 0; v < sec.det.length; v++) {
    assert.ok(Math.abs(sec.det[v] - detA) < 1e-12, `det J ${sec.det[v]} at vertex ${v}`);
    assert.ok(Math.abs(sec.positions[3 * v] - 2) < 1e-6, `x = ${sec.positions[3 * v]}`); // f32 positions
  }
  assert.ok(Math.abs(sec.detMin - detA) < 1e-12 && Math.abs(sec.detMax - detA) < 1e-12);
  assert.ok(Math.abs(area(sec) - 1.5) < 1e-5, `area ${area(sec)}`);
  const perimeter = closedOutline(sec);
  assert.ok(Math.abs(perimeter - (2 + 2 * Math.sqrt(2.34))) < 1e-5, `perimeter ${perimeter}`);
  // The outline on the body's boundary: inverting the affine map (here, not by the module) puts v or w at 0 or 1.
  const inv = (x) => {
    const w = (x[2] - b[2]) / 1.5;
    const v = x[1] - b[1] - 0.3 * w;
    const u = (x[0] - b[0] - 0.5 * v) / 2;
    return [u, v, w];
  };
  for (const i of sec.outline) {
    const t = inv(Array.from(sec.positions.subarray(3 * i, 3 * i + 3)));
    const onFace = t.some((x) => Math.abs(x) < 1e-6 || Math.abs(x - 1) < 1e-6);
    assert.ok(onFace, `outline vertex ${i} at parameters ${t}`);
  }
  // Inner vertices are not all on the boundary: the section has an inside.
  const outlineSet = new Set(sec.outline);
  assert.ok(sec.det.length > outlineSet.size);
  // The other axes: constant det J too; a plane beyond the body: no section.
  for (const [axis, at] of [[1, 0.3 - 2 + 0.2], [2, 0.5 + 0.7]]) {
    const s = grid.cut(axis, at);
    assert.ok(s.triangles.length > 0);
    for (const d of s.det) assert.ok(Math.abs(d - detA) < 1e-12);
  }
  assert.equal(grid.cut(0, 100).triangles.length, 0);
  const [zlo, zhi] = grid.range(2);
  assert.ok(Math.abs(zlo - 0.5) < 1e-12 && Math.abs(zhi - 2) < 1e-12, `z range ${zlo} … ${zhi}`);
});

test('a warped lattice with non-uniform knots: points and det J at 500 random parameters and at every section vertex equal the independent evaluation; the outline lies on the boundary', () => {
  const knots = [
    [0, 0, 0, 0.2, 0.45, 1, 1, 1],
    [0, 0, 0, 0, 0.3, 0.5, 1, 1, 1, 1],
    [0, 0, 0, 0.6, 1, 1, 1],
  ];
  const warp = ([u, v, w]) => [2 * u + 0.3 * Math.sin(2 * v) + 0.2 * w * w, 1.5 * v + 0.4 * u * w, w * (1 + 0.5 * u * u) + 0.2 * v];
  const rnd = lcg(11);
  const jitter = (i, j, k, counts) => {
    const inner = i > 0 && j > 0 && k > 0 && i < counts[0] - 1 && j < counts[1] - 1 && k < counts[2] - 1;
    return inner ? [0.06 * (rnd() - 0.5), 0.06 * (rnd() - 0.5), 0.06 * (rnd() - 0.5)] : [0, 0, 0];
  };
  const L = lattice([2, 3, 2], knots, warp, jitter);
  const vol = new BSplineVolume(L);
  const pts = lcg(3);
  let detLo = Infinity;
  let detHi = -Infinity;
  for (let n = 0; n < 500; n++) {
    const t = [pts(), pts(), pts()];
    if (n < 8) for (let d = 0; d < 3; d++) t[d] = (n >> d) & 1; // the corners too
    const e = vol.eval(...t);
    const x = point(L, t);
    for (let c = 0; c < 3; c++) assert.ok(Math.abs(e.p[c] - x[c]) < 1e-12, `x at ${t}: ${e.p} vs ${x}`);
    const fd = fdDet(L, t);
    assert.ok(Math.abs(e.det - fd) < 1e-6 * Math.abs(fd), `det J at ${t}: ${e.det} vs finite differences ${fd}`);
    detLo = Math.min(detLo, e.det);
    detHi = Math.max(detHi, e.det);
  }
  assert.ok(detLo > 0 && detHi / detLo > 1.3, `det J varies: ${detLo} … ${detHi}`);

  const grid = new SectionGrid(vol);
  const [lo, hi] = grid.range(1);
  const offset = lo + 0.37 * (hi - lo);
  const sec = grid.cut(1, offset);
  assert.ok(sec.triangles.length > 100, `${sec.triangles.length / 3} triangles`);
  const dom = domainOf(L);
  for (let v = 0; v < sec.det.length; v++) {
    const t = Array.from(sec.params.subarray(3 * v, 3 * v + 3));
    const x = point(L, t);
    assert.ok(Math.abs(x[1] - offset) < 1e-10, `vertex ${v} is ${x[1] - offset} off the plane`);
    for (let c = 0; c < 3; c++) assert.ok(Math.abs(sec.positions[3 * v + c] - x[c]) < 1e-5, `vertex ${v} drawn at x(its parameters)`);
    const fd = fdDet(L, t);
    assert.ok(Math.abs(sec.det[v] - fd) < 1e-6 * Math.abs(fd), `det J at vertex ${v}: ${sec.det[v]} vs ${fd}`);
  }
  assert.ok(sec.detMax / sec.detMin > 1.1, `the section shows a varying det J: ${sec.detMin} … ${sec.detMax}`);
  closedOutline(sec);
  for (const v of new Set(sec.outline)) {
    const t = sec.params.subarray(3 * v, 3 * v + 3);
    assert.ok([0, 1, 2].some((d) => t[d] === dom[d][0] || t[d] === dom[d][1]), `outline vertex ${v} at parameters ${Array.from(t)}`);
  }
  // Every vertex with a parameter on the cube's boundary is on the outline (the section's inside has none).
  const onOutline = new Set(sec.outline);
  for (let v = 0; v < sec.det.length; v++) {
    const t = sec.params.subarray(3 * v, 3 * v + 3);
    if ([0, 1, 2].some((d) => t[d] === dom[d][0] || t[d] === dom[d][1])) assert.ok(onOutline.has(v), `boundary vertex ${v} not on the outline`);
  }
});

test('a malformed lattice is refused with a clear error', () => {
  const ok = lattice([1, 1, 1], [[0, 0, 1, 1], [0, 0, 1, 1], [0, 0, 1, 1]], (t) => t);
  assert.throws(() => new BSplineVolume({ ...ok, points: ok.points.slice(3) }), /lattice/);
  assert.throws(() => new BSplineVolume({ ...ok, knots: [[0, 0, 1], [0, 0, 1, 1], [0, 0, 1, 1]] }), /knots/);
  assert.throws(() => new BSplineVolume({ ...ok, knots: [[0, 1, 0, 1], [0, 0, 1, 1], [0, 0, 1, 1]] }), /decrease/);
  assert.throws(() => new BSplineVolume({ ...ok, degrees: [0, 1, 1] }), /degree/);
});
