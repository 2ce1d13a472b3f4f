// The browser's B-spline evaluation against exact identities and a
// reference evaluation (the frame decoder has tests/frame.test.mjs).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { basisDerivs, surfaceDerivs, curvature, Tessellator } from '../src/bspline.js';

const knots = [0, 0, 0, 0, 0.2, 0.5, 0.5, 0.8, 1, 1, 1, 1];

test('partition of unity and derivatives summing to zero', () => {
  for (let k = 0; k <= 100; k++) {
    const b = basisDerivs(knots, 3, k / 100);
    const sum = (a) => a.reduce((x, y) => x + y, 0);
    assert.ok(Math.abs(sum(b.d[0]) - 1) < 1e-14);
    assert.ok(Math.abs(sum(b.d[1])) < 1e-10);
    assert.ok(Math.abs(sum(b.d[2])) < 1e-8);
  }
});

test('Piegl & Tiller example 2.3 values', () => {
  const b = basisDerivs([0, 0, 0, 1, 2, 3, 4, 4, 5, 5, 5], 2, 2.5);
  assert.equal(b.first, 2);
  assert.deepEqual(Array.from(b.d[0]).map((x) => Math.round(x * 1e12) / 1e12), [0.125, 0.75, 0.125]);
  assert.deepEqual(Array.from(b.d[1]).map((x) => Math.round(x * 1e12) / 1e12), [-0.5, 0, 0.5]);
});

function plane(nu, nv) {
  // Control points at the Greville abscissae reproduce w(u,v) = (2u, 3v, 0).
  const kv = (n) => {
    const k = [0, 0, 0, 0];
    for (let i = 1; i < n - 3; i++) k.push(i / (n - 3));
    k.push(1, 1, 1, 1);
    return k;
  };
  const ku = kv(nu);
  const kvv = kv(nv);
  const g = (k, i) => (k[i + 1] + k[i + 2] + k[i + 3]) / 3;
  const points = [];
  for (let i = 0; i < nu; i++) for (let j = 0; j < nv; j++) points.push(2 * g(ku, i), 3 * g(kvv, j), 0);
  return { degreeU: 3, degreeV: 3, knotsU: ku, knotsV: kvv, nu, nv, points: Float32Array.from(points) };
}

test('a plane is reproduced exactly, flat, with normal +z', () => {
  const s = plane(7, 6);
  for (const [u, v] of [[0, 0], [0.3, 0.7], [1, 1], [0.55, 0.1]]) {
    const d = surfaceDerivs(s, u, v);
    assert.ok(Math.abs(d.p[0] - 2 * u) < 1e-6 && Math.abs(d.p[1] - 3 * v) < 1e-6);
    const c = curvature(d);
    assert.ok(Math.abs(c.normal[2] - 1) < 1e-9 && c.mean === 0 && c.gauss === 0);
  }
});

test('derivatives match finite differences and the tessellator matches direct evaluation', () => {
  const s = plane(8, 7);
  for (let k = 0; k < s.points.length; k += 3) s.points[k + 2] = Math.sin(k * 0.37);
  const h = 1e-5;
  const d = surfaceDerivs(s, 0.4, 0.6);
  const dp = surfaceDerivs(s, 0.4 + h, 0.6);
  const dm = surfaceDerivs(s, 0.4 - h, 0.6);
  for (let x = 0; x < 3; x++) {
    assert.ok(Math.abs((dp.p[x] - dm.p[x]) / (2 * h) - d.u[x]) < 1e-5);
    assert.ok(Math.abs((dp.u[x] - dm.u[x]) / (2 * h) - d.uu[x]) < 1e-3);
  }
  const t = new Tessellator(s, 9, 11);
  t.fill(s);
  assert.equal(t.indices.length, 6 * 8 * 10);
  for (const idx of [0, 23, 98]) {
    const e = surfaceDerivs(s, t.uvs[idx * 2], t.uvs[idx * 2 + 1]);
    const c = curvature(e);
    for (let x = 0; x < 3; x++) {
      assert.ok(Math.abs(t.positions[idx * 3 + x] - e.p[x]) < 1e-5);
      assert.ok(Math.abs(t.normals[idx * 3 + x] - c.normal[x]) < 1e-5);
    }
    assert.ok(Math.abs(t.mean[idx] - c.mean) < 1e-4 * (1 + Math.abs(c.mean)));
  }
});

test('curvature comb: a parabola drawn on a plane has the analytic curvature', async () => {
  const { curvatureSamples, combSegments } = await import('../src/comb.js');
  // w(u, v) = (2u, 3v, 0); the (u, v) curve u = t, v = t² (Bézier (0,0), (½,0), (1,1))
  // traces x = 2t, y = 3t², whose curvature is 12 / (4 + 36 t²)^{3/2}.
  const plane = { degreeU: 1, knotsU: [0, 0, 1, 1], nu: 2, degreeV: 1, knotsV: [0, 0, 1, 1], nv: 2, points: [0, 0, 0, 0, 3, 0, 2, 0, 0, 2, 3, 0] };
  const curve = { knots: { degree: 2, knots: [0, 0, 0, 1, 1, 1] }, points: [[0, 0, 0], [0.5, 0, 0], [1, 1, 0]] };
  const samples = curvatureSamples(plane, curve, 11);
  samples.forEach((s, i) => {
    const t = i / 10;
    const exact = 12 / (4 + 36 * t * t) ** 1.5;
    assert.ok(Math.abs(s.kappa - exact) < 1e-12, `t=${t}: ${s.kappa} vs ${exact}`);
    assert.ok(Math.abs(s.point[0] - 2 * t) < 1e-12 && Math.abs(s.point[1] - 3 * t * t) < 1e-12);
  });
  // The parabola bends toward +y at t = 0, so the tooth points to −y there.
  assert.ok(samples[0].vector[1] > 0);
  const { teeth } = combSegments(samples, 0.5);
  assert.ok(Math.abs(teeth[4] - (0 - 0.5)) < 1e-12, `tooth end y: ${teeth[4]}`);
});

/** Deterministic pseudo-random numbers in [0, 1) (mulberry32), so a failure reproduces. */
function random(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/** A clamped knot vector of n control points with random, strictly increasing interior knots. */
function randomKnots(rnd, n, p) {
  const inner = Array.from({ length: n - p - 1 }, () => rnd()).sort((a, b) => a - b);
  return [...Array(p + 1).fill(-0.5), ...inner.map((x) => -0.5 + 2 * x), ...Array(p + 1).fill(1.5)];
}

test('the fast tessellator equals the reference evaluation to 1e-12 on random surfaces', () => {
  const rnd = random(20240505);
  for (const [nu, nv, pu, pv, su, sv] of [[11, 9, 3, 2, 23, 19], [7, 13, 2, 3, 17, 29], [6, 6, 4, 1, 12, 7]]) {
    const s = {
      degreeU: pu,
      degreeV: pv,
      knotsU: randomKnots(rnd, nu, pu),
      knotsV: randomKnots(rnd, nv, pv),
      nu,
      nv,
      points: Float64Array.from({ length: nu * nv * 3 }, (_, k) => (k % 3 === 0 ? Math.floor(k / 3 / nv) : k % 3 === 1 ? (k / 3) % nv : 0) + (rnd() - 0.5) * 0.8),
    };
    const t = new Tessellator(s, su, sv, { float64: true });
    assert.ok(t.fits(s));
    t.fill(s);
    const close = (a, b, what) => assert.ok(Math.abs(a - b) <= 1e-12 * (1 + Math.abs(b)), `${what}: ${a} vs ${b} (${nu}x${nv}, degrees ${pu}/${pv})`);
    let curved = 0;
    for (let idx = 0; idx < su * sv; idx++) {
      // The sample parameters in double precision (t.uvs holds them as f32 for the GPU).
      const [u, v] = [t.us[Math.floor(idx / sv)], t.vs[idx % sv]];
      assert.ok(Math.abs(t.uvs[idx * 2] - u) < 1e-6 && Math.abs(t.uvs[idx * 2 + 1] - v) < 1e-6);
      const e = surfaceDerivs(s, u, v);
      const c = curvature(e);
      assert.ok(c, `regular at vertex ${idx}`);
      for (let x = 0; x < 3; x++) {
        close(t.positions[idx * 3 + x], e.p[x], `position ${idx}.${x}`);
        close(t.normals[idx * 3 + x], c.normal[x], `normal ${idx}.${x}`);
      }
      close(t.mean[idx], c.mean, `mean curvature ${idx}`);
      close(t.gauss[idx], c.gauss, `Gaussian curvature ${idx}`);
      if (Math.abs(c.mean) > 1e-3) curved++;
    }
    assert.ok(curved > su * sv / 2, 'the random surface is curved almost everywhere');
    // The (u, v) grid spans the whole domain, and the bounds are those of the positions.
    assert.equal(t.us[0], s.knotsU[pu]);
    assert.equal(t.vs[sv - 1], s.knotsV[nv]);
    for (let x = 0; x < 3; x++) {
      const coords = t.positions.filter((_, k) => k % 3 === x);
      assert.equal(t.box[x], Math.min(...coords));
      assert.equal(t.box[3 + x], Math.max(...coords));
    }
    // A moved control point changes the next fill in place; another knot layout does not fit.
    const before = t.positions.slice();
    s.points[((nu >> 1) * nv + (nv >> 1)) * 3 + 2] += 1;
    t.fill(s);
    assert.notDeepEqual(t.positions, before);
    assert.equal(t.fits({ ...s, knotsU: s.knotsU.map((k, i) => (i === pu + 1 ? k + 1e-9 : k)) }), false);
  }
});

test('a curve part: a quadratic Bézier has its analytic point, derivatives and curvature', async () => {
  const { curveDerivs } = await import('../src/bspline.js');
  const { curvePartSamples } = await import('../src/comb.js');
  // Control points (0,0,0), (1,2,0), (2,0,0): c(t) = (2t, 4t(1−t), 0), c' = (2, 4 − 8t, 0), c'' = (0, −8, 0);
  // κ = |c' × c''| / |c'|³ = 16 / (4 + (4 − 8t)²)^{3/2}.
  const curve = { degree: 2, knots: [0, 0, 0, 1, 1, 1], n: 3, points: [0, 0, 0, 1, 2, 0, 2, 0, 0] };
  for (let k = 0; k <= 20; k++) {
    const t = k / 20;
    const d = curveDerivs(curve, t);
    const want = { p: [2 * t, 4 * t * (1 - t), 0], d1: [2, 4 - 8 * t, 0], d2: [0, -8, 0] };
    for (const key of ['p', 'd1', 'd2']) for (let x = 0; x < 3; x++) assert.ok(Math.abs(d[key][x] - want[key][x]) < 1e-12, `${key} at ${t}`);
  }
  const samples = curvePartSamples(curve, 11);
  samples.forEach((s, i) => {
    const t = i / 10;
    const exact = 16 / (4 + (4 - 8 * t) ** 2) ** 1.5;
    assert.ok(Math.abs(s.kappa - exact) < 1e-12, `κ at ${t}: ${s.kappa} vs ${exact}`);
  });
  // The arch bends down (toward −y) at its top.
  assert.ok(samples[5].vector[1] < 0);
});
