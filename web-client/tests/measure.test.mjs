// The measure tool, in real headless Chromium against the real server, used
// from the reviewer's (viewer's) page: two real clicks on the demo's shell
// read two points and their distance; each point and its curvature are
// checked against this file's own evaluation of the same control net — a
// recursive Cox–de Boor evaluator (not bspline.js's) for the point, and
// central differences of it for the fundamental forms.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { serverAndBrowser, openClient } from './harness.mjs';

let server;
let browser;
serverAndBrowser('vsculpt-measure-', (s, b) => {
  server = s;
  browser = b;
});

/** N_{i,p}(t) by the Cox–de Boor recursion (0/0 = 0; the last span closed at its right end). */
function basis(knots, i, p, t) {
  if (p === 0) {
    const last = knots[knots.length - 1];
    if (t === last) return knots[i] < t && knots[i + 1] === last ? 1 : 0;
    return knots[i] <= t && t < knots[i + 1] ? 1 : 0;
  }
  const a = knots[i + p] - knots[i];
  const b = knots[i + p + 1] - knots[i + 1];
  return (a > 0 ? ((t - knots[i]) / a) * basis(knots, i, p - 1, t) : 0) + (b > 0 ? ((knots[i + p + 1] - t) / b) * basis(knots, i + 1, p - 1, t) : 0);
}

/** The surface point at (u, v). */
function point(s, u, v) {
  const out = [0, 0, 0];
  for (let i = 0; i < s.nu; i++) {
    const bu = basis(s.knotsU, i, s.degreeU, u);
    if (bu === 0) continue;
    for (let j = 0; j < s.nv; j++) {
      const w = bu * basis(s.knotsV, j, s.degreeV, v);
      for (let x = 0; x < 3; x++) out[x] += w * s.points[3 * (i * s.nv + j) + x];
    }
  }
  return out;
}

/** Mean and Gaussian curvature at (u, v) from central differences of `point`. */
function curvatureByDifferences(s, u, v, h = 1e-4) {
  const P = (du, dv) => point(s, u + du * h, v + dv * h);
  const sub = (a, b) => a.map((x, k) => x - b[k]);
  const add = (a, b) => a.map((x, k) => x + b[k]);
  const scale = (a, c) => a.map((x) => x * c);
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const c = P(0, 0);
  const wu = scale(sub(P(1, 0), P(-1, 0)), 1 / (2 * h));
  const wv = scale(sub(P(0, 1), P(0, -1)), 1 / (2 * h));
  const wuu = scale(sub(add(P(1, 0), P(-1, 0)), scale(c, 2)), 1 / (h * h));
  const wvv = scale(sub(add(P(0, 1), P(0, -1)), scale(c, 2)), 1 / (h * h));
  const wuv = scale(sub(sub(add(P(1, 1), P(-1, -1)), P(1, -1)), P(-1, 1)), 1 / (4 * h * h));
  const n0 = cross(wu, wv);
  const n = scale(n0, 1 / Math.hypot(...n0));
  const [E, F, G] = [dot(wu, wu), dot(wu, wv), dot(wv, wv)];
  const [L, M, N] = [dot(wuu, n), dot(wuv, n), dot(wvv, n)];
  const det = E * G - F * F;
  return { mean: (E * N - 2 * F * M + G * L) / (2 * det), gauss: (L * N - M * M) / det };
}

/** Screen position (page pixels) of the surface point at (u, v) of part `part`, as the page projects it. */
function screenAt(page, part, u, v) {
  return page.evaluate(
    ([id, uu, vv]) => {
      const { view, partsView } = window.vsculpt;
      const t = partsView.drawings.get(id).tess;
      // The tessellation vertex nearest (u, v): a point the page really draws.
      let best = 0;
      for (let i = 0; i < t.su * t.sv; i++) {
        const d = (k) => Math.hypot(t.uvs[2 * k] - uu, t.uvs[2 * k + 1] - vv);
        if (d(i) < d(best)) best = i;
      }
      const p = view.camera.position.clone().set(t.positions[3 * best], t.positions[3 * best + 1], t.positions[3 * best + 2]);
      p.project(view.camera);
      const r = view.renderer.domElement.getBoundingClientRect();
      return { x: r.left + ((p.x + 1) / 2) * r.width, y: r.top + ((1 - p.y) / 2) * r.height };
    },
    [part, u, v],
  );
}

test('a reviewer measures on the shell: points, distance and curvature agree with an independent evaluation', async () => {
  const viewer = await openClient(browser, server.viewer);
  const shell = await viewer.evaluate(() => [...window.vsculpt.design.parts.values()].find((p) => p.kind === 'surface').id);
  await viewer.click('#measure');
  assert.equal(await viewer.getAttribute('#measure', 'aria-pressed'), 'true');
  const selectedBefore = await viewer.evaluate(() => [window.vsculpt.state.selected, window.vsculpt.state.selectedPart]);
  for (const [u, v] of [[0.5, 0.5], [0.3, 0.65]]) {
    const at = await screenAt(viewer, shell, u, v);
    await viewer.mouse.click(at.x, at.y);
  }
  await viewer.waitForFunction(() => window.vsculpt.measure.points.length === 2);
  const got = await viewer.evaluate(() => {
    const { measure, design } = window.vsculpt;
    const g = design.parts.get(measure.points[0].part).geometry;
    return {
      points: measure.points,
      distance: measure.distance(),
      text: document.getElementById('measure-out').textContent,
      surface: { ...g, knotsU: [...g.knotsU], knotsV: [...g.knotsV], points: [...g.points] },
      selected: [window.vsculpt.state.selected, window.vsculpt.state.selectedPart],
    };
  });
  const s = got.surface;
  const size = Math.hypot(...[0, 1, 2].map((x) => Math.max(...s.points.filter((_, k) => k % 3 === x)) - Math.min(...s.points.filter((_, k) => k % 3 === x))));
  for (const m of got.points) {
    assert.equal(m.part, shell);
    const p = point(s, m.u, m.v);
    const off = Math.max(...p.map((x, k) => Math.abs(x - m.p[k])));
    assert.ok(off <= 1e-9 * size, `point at (${m.u}, ${m.v}) off by ${off}`);
    const fd = curvatureByDifferences(s, m.u, m.v);
    // Differences of step 1e-4 in (u, v): the second ones are good to ~1e-4 relative.
    const tol = (k) => 1e-3 * Math.abs(k) + 1e-6 / size;
    assert.ok(Math.abs(m.mean - fd.mean) <= tol(fd.mean), `mean ${m.mean} vs ${fd.mean}`);
    assert.ok(Math.abs(m.gauss - fd.gauss) <= tol(fd.gauss) + 1e-3 * fd.mean * fd.mean, `Gaussian ${m.gauss} vs ${fd.gauss}`);
    assert.ok(Math.abs(m.k1 * m.k2 - m.gauss) <= 1e-9 * Math.max(1, Math.abs(m.gauss)) && Math.abs((m.k1 + m.k2) / 2 - m.mean) <= 1e-12 * Math.max(1, Math.abs(m.mean)));
    assert.ok(Math.abs(m.mean) > 1e-6 / size, 'the shell is curved here: the check is not of zeros');
  }
  const [a, b] = got.points.map((m) => point(s, m.u, m.v));
  const d = Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
  assert.ok(Math.abs(got.distance - d) <= 1e-9 * size, `distance ${got.distance} vs ${d}`);
  assert.ok(d > 0.05 * size, 'two different points');
  assert.match(got.text, new RegExp(`distance A–B ${d.toPrecision(6).replace('.', '\\.')}`));
  assert.match(got.text, /^A \(.*mean curvature .*Gaussian .*principal radii/m);
  // Measuring selected nothing; Esc ends the tool and clears its readings.
  assert.deepEqual(got.selected, selectedBefore);
  await viewer.keyboard.press('Escape');
  assert.equal(await viewer.getAttribute('#measure', 'aria-pressed'), 'false');
  assert.equal(await viewer.evaluate(() => window.vsculpt.measure.points.length), 0);
  assert.ok(await viewer.isHidden('#measure-out'));
  assert.deepEqual(viewer.errors, []);
  await viewer.close();
});
