// Coons body parts (paper 002, issue 13) end to end, in real headless
// Chromium against the real server: the editor adds the demo body (the cube
// whose morph target is the spool), both pages draw it from body frames;
// dragging a lattice handle with the mouse moves that lattice point for a
// second page (a viewer) — its handle, and its boundary's corner, are where
// the stored document says; the time slider shows the viewer the morph; a
// plate bound to a body from the parts panel (FFD) follows a lattice point
// moved through the protocol, and is unbound from the panel.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createDesign, serverAndBrowser, openClient } from './harness.mjs';
import { domainOf, fdDet, lattice, point } from './volume-oracle.mjs';

let server;
let browser;
const dataDir = serverAndBrowser('vsculpt-body-', (s, b) => {
  server = s;
  browser = b;
});

/** The newest body frame's lattice of part `id` on `page` ([x, y, z, …]), its revision and its boundary positions. */
const bodyOn = (page, id) =>
  page.evaluate((id) => {
    const b = window.vsculpt.bodyView.bodies.get(id);
    return b && b.frame ? { revision: b.frame.revision, t: b.frame.t, counts: b.frame.counts, lattice: Array.from(b.frame.lattice), positions: Array.from(b.frame.positions) } : null;
  }, id);

/** Waits until `page` shows part `id`'s body with a revision above `after` (and `t` when given). */
async function waitBody(page, id, after = 0, t = null) {
  await page.waitForFunction(
    ([id, after, t]) => {
      const b = window.vsculpt.bodyView.bodies.get(id);
      return b && b.frame && b.frame.revision > after && (t === null || Math.abs(b.frame.t - t) < 1e-6);
    },
    [id, after, t],
    { timeout: 15000 },
  );
  return bodyOn(page, id);
}

test('a lattice point dragged in one page moves for a viewer; the morph slider reaches the viewer', async () => {
  const d = await createDesign(server, dataDir, { name: 'bodies', nu: 8, nv: 8 });
  const editor = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.editor}`);
  const viewer = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.viewer}`);
  await editor.click('#add-spool');
  const handle = await editor.waitForFunction(() => [...window.vsculpt.bodyView.bodies.keys()][0] ?? null, null, { timeout: 15000 });
  const id = await handle.jsonValue();
  assert.ok(Number.isInteger(id));
  const before = await waitBody(viewer, id);
  const mine = await waitBody(editor, id);
  assert.deepEqual(mine.lattice, before.lattice);
  assert.deepEqual(before.counts, [5, 5, 7]);
  // The corner (nu−1, nv−1, nw−1): the last lattice point; at t = 0 the cube's (30, 30, 30).
  const corner = before.lattice.length / 3 - 1;
  for (const x of before.lattice.slice(3 * corner)) assert.ok(Math.abs(x - 30) < 1e-4, `corner at ${before.lattice.slice(3 * corner)}`);

  // Drag it with the mouse: its handle's place on screen, then 60 px right and 40 px up.
  const at = await editor.evaluate((corner) => {
    const { view, bodyView } = window.vsculpt;
    const [id] = [...bodyView.bodies.keys()];
    const p = bodyView.latticePoint(id, corner);
    const r = view.renderer.domElement.getBoundingClientRect();
    const q = new view.camera.position.constructor(...p).project(view.camera);
    return { x: r.left + ((q.x + 1) / 2) * r.width, y: r.top + ((1 - q.y) / 2) * r.height };
  }, corner);
  await editor.mouse.move(at.x, at.y);
  await editor.mouse.down();
  for (let k = 1; k <= 6; k++) await editor.mouse.move(at.x + 10 * k, at.y - (20 / 3) * k);
  await editor.mouse.up();

  // The stored document has the point moved; the viewer's frame shows exactly it.
  const moved = await waitBody(viewer, id, before.revision);
  const res = await fetch(`${server.base}/api/designs/${d.id}?token=${d.tokens.editor}`);
  const doc = (await res.json()).design;
  const stored = doc.parts.find((p) => p.id === id).body.lattice.points[corner];
  const shown = moved.lattice.slice(3 * corner, 3 * corner + 3);
  const delta = stored.map((x, a) => x - before.lattice[3 * corner + a]);
  assert.ok(Math.hypot(...delta) > 1, `the corner moved by ${delta}`);
  for (let a = 0; a < 3; a++) assert.ok(Math.abs(shown[a] - stored[a]) < 1e-4, `viewer ${shown} vs stored ${stored}`);
  // Only that point moved.
  for (let k = 0; k < before.lattice.length; k++) {
    if (Math.floor(k / 3) !== corner) assert.equal(moved.lattice[k], before.lattice[k], `lattice value ${k}`);
  }
  // The viewer's boundary follows: a boundary vertex sits on the moved corner (a clamped body passes through its corners), none at the old one.
  const near = (pos, p) => {
    for (let v = 0; v < pos.length; v += 3) if (Math.hypot(pos[v] - p[0], pos[v + 1] - p[1], pos[v + 2] - p[2]) < 1e-3) return true;
    return false;
  };
  assert.ok(near(moved.positions, stored), 'a boundary vertex at the moved corner');
  assert.ok(!near(moved.positions, [30, 30, 30]), 'no boundary vertex at the old corner');
  // The editor shows the same.
  const echoed = await waitBody(editor, id, mine.revision);
  assert.deepEqual(echoed.lattice, moved.lattice);

  // The time slider: the viewer gets the body at t = 0.5.
  await editor.evaluate(() => {
    const s = document.getElementById('body-morph-t');
    s.value = '0.5';
    s.dispatchEvent(new Event('input'));
  });
  const half = await waitBody(viewer, id, moved.revision, 0.5);
  assert.equal(half.t, 0.5);
  assert.notDeepEqual(half.positions, moved.positions);
  assert.equal(await viewer.evaluate(() => document.getElementById('body-morph-value').textContent), 't = 0.50');
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});

test('a plate bound to a body from the parts panel follows a lattice point moved through the protocol; unbinding from the panel', async () => {
  const d = await createDesign(server, dataDir, { name: 'ffd', nu: 6, nv: 6 });
  const editor = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.editor}`);
  const viewer = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.viewer}`);
  const docOf = async () => (await (await fetch(`${server.base}/api/designs/${d.id}?token=${d.tokens.editor}`)).json()).design;
  const plate = (await docOf()).parts[0];
  const pts = plate.body.surface.points;
  // A degree-2 box body around the plate (Greville points: the map is affine, the plate well inside).
  const lo = [0, 1, 2].map((a) => Math.min(...pts.map((p) => p[a])));
  const hi = [0, 1, 2].map((a) => Math.max(...pts.map((p) => p[a])));
  const size = Math.max(...hi.map((h, a) => h - lo[a]));
  const box = [0, 1, 2].map((a) => [lo[a] - 0.1 * size, hi[a] + 0.1 * size]);
  const points = [];
  for (const i of [0, 0.5, 1]) for (const j of [0, 0.5, 1]) for (const k of [0, 0.5, 1]) {
    points.push([i, j, k].map((s, a) => box[a][0] + s * (box[a][1] - box[a][0])));
  }
  const kv = { degree: 2, knots: [0, 0, 0, 1, 1, 1] };
  await editor.evaluate((lattice) => window.vsculpt.send({ type: 'create_part', spec: { name: 'cage', shape: { kind: 'body', body: { lattice: { u: lattice.kv, v: lattice.kv, w: lattice.kv, points: lattice.points } } } } }), { kv, points });
  const bodyId = await (await editor.waitForFunction(() => [...window.vsculpt.bodyView.bodies.keys()][0] ?? null, null, { timeout: 15000 })).jsonValue();
  await waitBody(viewer, bodyId);

  // Bind from the panel: select the plate, choose the body, press bind.
  await editor.click(`#parts [data-part="${plate.id}"] button[data-act="select"]`);
  await editor.click('#ffd-tool summary');
  await editor.waitForFunction((id) => !document.querySelector('#ffd button[name="ffd-bind"]').disabled && document.querySelector('select[name="ffd-body"]').value === String(id), bodyId, { timeout: 15000 });
  await editor.click('#ffd button[name="ffd-bind"]');
  await viewer.waitForFunction(() => [...window.vsculpt.design.relations.values()].some((r) => r.kind === 'ffd'), null, { timeout: 15000 });
  const relation = await viewer.evaluate(() => [...window.vsculpt.design.relations.values()].find((r) => r.kind === 'ffd'));
  assert.deepEqual([relation.body, relation.part], [bodyId, plate.id]);
  assert.match(await viewer.textContent('#relations'), /ffd: .* follows body cage/);
  // The editor's panel follows the relation when its own copy of it arrives (it may come after the viewer's).
  await editor.waitForFunction(() => document.querySelector('#ffd button[name="ffd-bind"]').disabled, null, { timeout: 15000 });
  assert.equal(await editor.isVisible('#ffd button[name="ffd-unbind"]'), true);

  // The drawing as the viewer holds it: the plate's frame points and its drawn mesh's bounds.
  const drawn = (page, id) =>
    page.evaluate((id) => {
      const { design, partsView } = window.vsculpt;
      const g = partsView.drawings.get(id).mesh.geometry;
      g.computeBoundingBox();
      return { points: Array.from(design.parts.get(id).geometry.points), min: g.boundingBox.min.toArray(), max: g.boundingBox.max.toArray(), revision: design.parts.get(id).geometry.revision ?? null };
    }, id);
  const before = await drawn(viewer, plate.id);
  // The centre lattice point up by a fifth of the plate's size, through the protocol.
  const dz = 0.2 * size;
  await editor.evaluate(([part, dz]) => window.vsculpt.send({ type: 'body_edit', part, edit: { select: { point: [1, 1, 1] }, delta: [0, 0, dz] } }), [bodyId, dz]);
  await viewer.waitForFunction(
    ([id, first]) => {
      const g = window.vsculpt.design.parts.get(id).geometry;
      return g && Array.from(g.points).some((x, i) => x !== first[i]);
    },
    [plate.id, before.points],
    { timeout: 15000 },
  );
  await viewer.waitForFunction(
    ([id, top]) => {
      const g = window.vsculpt.partsView.drawings.get(id).mesh.geometry;
      g.computeBoundingBox();
      return g.boundingBox.max.z > top;
    },
    [plate.id, before.max[2] + 0.02 * dz],
    { timeout: 15000 },
  );
  const after = await drawn(viewer, plate.id);
  // The page shows what the server stored: the control points moved up (by at most dz · N₁(½)³ = dz / 8), none down.
  const stored = (await docOf()).parts.find((p) => p.id === plate.id).body.surface.points.flat();
  stored.forEach((x, i) => assert.ok(Math.abs(after.points[i] - x) <= 1e-5 * (1 + Math.abs(x)), `point ${i}: ${after.points[i]} vs ${x}`));
  const lift = stored.filter((_, i) => i % 3 === 2).map((z, k) => z - pts[k][2]);
  assert.ok(Math.max(...lift) > 0.05 * dz && Math.max(...lift) <= dz / 8 + 1e-9 * size && Math.min(...lift) >= -1e-9 * size, `lifts ${Math.min(...lift)}…${Math.max(...lift)}`);
  assert.ok(after.max[2] > before.max[2] + 0.02 * dz, `drawn top ${before.max[2]} → ${after.max[2]}`);

  // Unbind from the panel: the relation goes, the plate keeps its shape.
  await editor.click('#ffd button[name="ffd-unbind"]');
  await viewer.waitForFunction(() => ![...window.vsculpt.design.relations.values()].some((r) => r.kind === 'ffd'), null, { timeout: 15000 });
  assert.deepEqual((await docOf()).parts.find((p) => p.id === plate.id).body.surface.points.flat(), stored);
  assert.deepEqual([...editor.errors, ...viewer.errors], []);
  await editor.close();
  await viewer.close();
});

test('a body frame built byte by byte from the README table decodes; a wrong length, index, direction, degree or knot is refused', async () => {
  const { decodeFrame } = await import('../src/frame.js');
  // N = 2·2·2 lattice points, V = 3 vertices, T = 1 triangle, L = 1 line of S = 2 samples, degrees (1, 1, 1), knots (0, 0, 1, 1) ×3.
  const [N, V, T, L, S] = [8, 3, 1, 1, 2];
  const K = 12;
  const spline = 64 + 12 * N + 24 * V + 12 * T + 4 * L + 12 * L * S;
  const len = spline + 12 + 4 * K;
  const buf = new ArrayBuffer(len);
  const dv = new DataView(buf);
  [0x56, 0x53, 0x47, 0x46].forEach((b, i) => dv.setUint8(i, b));
  dv.setUint8(4, 4);
  dv.setUint8(5, 2);
  dv.setUint16(6, 1, true);
  dv.setBigUint64(8, 7n, true);
  dv.setBigUint64(16, 9n, true);
  dv.setBigUint64(24, 42n, true);
  dv.setFloat32(32, 0.25, true);
  [2, 2, 2, V, T, L, S].forEach((x, i) => dv.setUint32(36 + 4 * i, x, true));
  let o = 64;
  const f32 = (...xs) => xs.forEach((x) => { dv.setFloat32(o, x, true); o += 4; });
  const u32 = (...xs) => xs.forEach((x) => { dv.setUint32(o, x, true); o += 4; });
  for (let n = 0; n < 8; n++) f32(n >> 2, ((n >> 1) & 1) * 2, (n & 1) * 3); // lattice: the box [0,1]×[0,2]×[0,3]
  f32(0, 0, 0, 1, 0, 0, 0, 1, 0); // positions
  f32(0, 0, 1, 0, 0, 1, 0, 0, 1); // normals
  u32(0, 1, 2); // triangle
  u32(2); // line held at constant w
  f32(0, 0, 0, 1, 1, 1); // its samples
  assert.equal(o, spline);
  u32(1, 1, 1); // degrees
  for (let d = 0; d < 3; d++) f32(0, 0, 1, 1); // knots
  assert.equal(o, len);
  const f = decodeFrame(buf);
  assert.equal(f.kind, 'body');
  assert.deepEqual([f.design, f.part, f.revision, f.flags, f.t], [7, 9, 42, 1, 0.25]);
  assert.deepEqual(f.counts, [2, 2, 2]);
  assert.deepEqual(Array.from(f.lattice.subarray(3, 6)), [0, 0, 3]);
  assert.deepEqual(Array.from(f.lattice.subarray(18, 21)), [1, 2, 0]);
  assert.deepEqual(Array.from(f.triangles), [0, 1, 2]);
  assert.deepEqual(Array.from(f.lineDirs), [2]);
  assert.deepEqual(Array.from(f.linePoints), [0, 0, 0, 1, 1, 1]);
  assert.deepEqual(f.degrees, [1, 1, 1]);
  assert.deepEqual(f.knots.map((k) => Array.from(k)), [[0, 0, 1, 1], [0, 0, 1, 1], [0, 0, 1, 1]]);
  // The volume it carries: the box, det J = 1·2·3 everywhere.
  const { BSplineVolume } = await import('../src/body-volume.js');
  const e = BSplineVolume.fromFrame(f).eval(0.5, 0.25, 0.75);
  assert.deepEqual(e.p, [0.5, 0.5, 2.25]);
  assert.equal(e.det, 6);
  assert.throws(() => decodeFrame(buf.slice(0, len - 4)), /bytes/);
  const patched = (at, x, float = false) => {
    const b = buf.slice(0);
    if (float) new DataView(b).setFloat32(at, x, true);
    else new DataView(b).setUint32(at, x, true);
    return b;
  };
  assert.throws(() => decodeFrame(patched(64 + 12 * N + 24 * V + 8, 3)), /missing vertex/);
  assert.throws(() => decodeFrame(patched(64 + 12 * N + 24 * V + 12 * T, 3)), /direction/);
  assert.throws(() => decodeFrame(patched(spline, 0)), /degree/);
  assert.throws(() => decodeFrame(patched(spline + 4, 6)), /degree/);
  assert.throws(() => decodeFrame(patched(spline + 8, 2)), /bytes|too few/);
  assert.throws(() => decodeFrame(patched(spline + 12 + 4, -1, true)), /knots/);
  assert.throws(() => decodeFrame(patched(spline + 12 + 4 * 9, NaN, true)), /knots/);
});

/** The screen position of model point `p` on `page`. */
const screenOf = (page, p) =>
  page.evaluate((p) => {
    const { view } = window.vsculpt;
    const r = view.renderer.domElement.getBoundingClientRect();
    const q = new view.camera.position.constructor(...p).project(view.camera);
    return { x: r.left + ((q.x + 1) / 2) * r.width, y: r.top + ((1 - q.y) / 2) * r.height };
  }, p);

/** Creates a body part from `spec` on `page` and returns its id once its frame is drawn. */
async function createBody(page, spec) {
  const before = await page.evaluate(() => [...window.vsculpt.bodyView.bodies.keys()]);
  await page.evaluate((spec) => window.vsculpt.send({ type: 'create_part', spec }), spec);
  const h = await page.waitForFunction((before) => [...window.vsculpt.bodyView.bodies.keys()].find((k) => !before.includes(k)) ?? null, before, { timeout: 15000 });
  return h.jsonValue();
}

/** The body as the page evaluates it: its frame's lattice, degrees and knots (plain arrays). */
const frameLattice = (page, id) =>
  page.evaluate((id) => {
    const f = window.vsculpt.bodyView.bodies.get(id).frame;
    return { degrees: f.degrees, knots: f.knots.map((k) => Array.from(k)), counts: f.counts, points: Array.from(f.lattice), positions: Array.from(f.positions), triangles: Array.from(f.triangles) };
  }, id);

/** Distance from point p to triangle (a, b, c) (all [x, y, z]). */
function pointTriangle(p, a, b, c) {
  const sub = (x, y) => x.map((v, i) => v - y[i]);
  const dot = (x, y) => x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
  const ab = sub(b, a);
  const ac = sub(c, a);
  const ap = sub(p, a);
  // Closest point by Ericson's region tests (Real-Time Collision Detection §5.1.5).
  const d1 = dot(ab, ap);
  const d2 = dot(ac, ap);
  const at = (s, t) => Math.hypot(...a.map((v, i) => v + s * ab[i] + t * ac[i] - p[i]));
  if (d1 <= 0 && d2 <= 0) return at(0, 0);
  const bp = sub(p, b);
  const d3 = dot(ab, bp);
  const d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return at(1, 0);
  const vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(d1 / (d1 - d3), 0);
  const cp = sub(p, c);
  const d5 = dot(ab, cp);
  const d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return at(0, 1);
  const vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(0, d2 / (d2 - d6));
  const va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const w = (d4 - d3) / (d4 - d3 + (d5 - d6));
    return at(1 - w, w);
  }
  const den = 1 / (va + vb + vc);
  return at(vb * den, vc * den);
}

/** The six boundary faces of lattice `L` as a triangle mesh of n × n quads each, by the independent evaluator. */
function boundaryMesh(L, n) {
  const dom = domainOf(L);
  const positions = [];
  const triangles = [];
  for (let d = 0; d < 3; d++) {
    const [a, b] = [0, 1, 2].filter((e) => e !== d);
    for (const end of [0, 1]) {
      const base = positions.length / 3;
      for (let i = 0; i <= n; i++) {
        for (let j = 0; j <= n; j++) {
          const t = [0, 0, 0];
          t[d] = dom[d][end];
          t[a] = dom[a][0] + ((dom[a][1] - dom[a][0]) * i) / n;
          t[b] = dom[b][0] + ((dom[b][1] - dom[b][0]) * j) / n;
          positions.push(...point(L, t));
        }
      }
      for (let i = 0; i < n; i++) {
        for (let j = 0; j < n; j++) {
          const q = base + i * (n + 1) + j;
          triangles.push(q, q + 1, q + n + 1, q + 1, q + n + 2, q + n + 1);
        }
      }
    }
  }
  return { positions, triangles };
}

/** Distance from p to the triangle mesh (flat positions, triangles); triangles whose bounding sphere is farther than the best so far are skipped. */
function meshDistance(p, positions, triangles) {
  let best = Infinity;
  const v = (i) => [positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]];
  for (let t = 0; t < triangles.length; t += 3) {
    const [a, b, c] = [v(triangles[t]), v(triangles[t + 1]), v(triangles[t + 2])];
    const m = [0, 1, 2].map((e) => (a[e] + b[e] + c[e]) / 3);
    const r = Math.max(...[a, b, c].map((q) => Math.hypot(q[0] - m[0], q[1] - m[1], q[2] - m[2])));
    if (Math.hypot(p[0] - m[0], p[1] - m[1], p[2] - m[2]) - r >= best) continue;
    best = Math.min(best, pointTriangle(p, a, b, c));
  }
  return best;
}

test('the cutting plane: an affine body shows det J = det A on its section; the spool shows the kernel’s det J and an independent one, its outline on the boundary', async () => {
  const d = await createDesign(server, dataDir, { name: 'sections', nu: 8, nv: 8 });
  const editor = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.editor}`);
  const viewer = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.viewer}`);
  // An affine map of the unit cube, x = A·(u, v, w) + b (control points at the Greville abscissae), det A = 24·36·48·(1 − 0.1·0.2)… computed below.
  const A = [
    [40, 8, 0],
    [0, 30, 6],
    [5, 0, 20],
  ];
  const b = [-10, 5, 2];
  const detA = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) + A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  const L = lattice([2, 1, 3], [[0, 0, 0, 0.4, 1, 1, 1], [0, 0, 1, 1], [0, 0, 0, 0, 0.5, 1, 1, 1, 1]], (t) => [0, 1, 2].map((r) => A[r][0] * t[0] + A[r][1] * t[1] + A[r][2] * t[2] + b[r]));
  const knots = (k, p) => ({ degree: p, knots: k });
  const points = [];
  for (let i = 0; i < L.points.length; i += 3) points.push(L.points.slice(i, i + 3));
  const body = { lattice: { u: knots(L.knots[0], 2), v: knots(L.knots[1], 1), w: knots(L.knots[2], 3), points } };
  const affine = await createBody(editor, { name: 'affine block', shape: { kind: 'body', body } });
  await viewer.waitForFunction((id) => window.vsculpt.bodyView.bodies.get(id)?.frame, affine, { timeout: 15000 });

  // The viewer (no editing) turns the plane on through the panel: y at 40 % of the body's extent.
  await viewer.selectOption('#body-morph-part', String(affine));
  await viewer.check('#body-section-on');
  await viewer.selectOption('#body-section-axis', '1');
  await viewer.evaluate(() => {
    const s = document.getElementById('body-section-offset');
    s.value = '0.4';
    s.dispatchEvent(new Event('input'));
  });
  const flat = await viewer.evaluate(() => {
    const { bodyView } = window.vsculpt;
    const s = bodyView.lastSection;
    const b = bodyView.bodies.get(s.part);
    return {
      part: s.part, axis: s.axis, offset: s.offset, det: Array.from(s.section.det), y: Array.from(s.section.positions.filter((_, i) => i % 3 === 1)),
      triangles: s.section.triangles.length, visible: b.section.visible, clipped: (b.mesh.material.clippingPlanes || []).length,
      legend: !document.getElementById('body-section-legend').hidden, min: document.getElementById('body-section-min').textContent, max: document.getElementById('body-section-max').textContent,
      colours: Array.from(b.section.geometry.attributes.color.array.slice(0, 6)),
    };
  });
  assert.equal(flat.part, affine);
  assert.equal(flat.axis, 1);
  assert.ok(flat.triangles > 0 && flat.visible && flat.legend, 'the section and its legend are shown');
  assert.equal(flat.clipped, 1, 'the boundary beyond the plane is clipped');
  // f32 control points: det J within 1e-5 relative.
  for (const x of flat.det) assert.ok(Math.abs(x - detA) < 1e-5 * detA, `det J ${x} vs det A ${detA}`);
  for (const y of flat.y) assert.ok(Math.abs(y - flat.offset) < 1e-3, `a section vertex at y = ${y}, the plane at ${flat.offset}`);
  assert.equal(flat.min, detA.toPrecision(3));
  assert.equal(flat.max, detA.toPrecision(3));
  // One colour: the middle of the scale everywhere.
  assert.ok(Math.abs(flat.colours[0] - flat.colours[3]) < 1e-6);

  // The spool (the preset's morph target) as a body of its own: det J varies.
  const spec = await (await fetch(`${server.base}/api/demo-parts/spool`)).json();
  const spoolBody = { lattice: spec.shape.body.morph_target };
  const spool = await createBody(editor, { name: 'spool', shape: { kind: 'body', body: spoolBody } });
  await viewer.waitForFunction((id) => window.vsculpt.bodyView.bodies.get(id)?.frame, spool, { timeout: 15000 });
  await viewer.selectOption('#body-morph-part', String(spool));
  await viewer.selectOption('#body-section-axis', '0');
  await viewer.evaluate(() => {
    const s = document.getElementById('body-section-offset');
    s.value = '0.55';
    s.dispatchEvent(new Event('input'));
  });
  const cut = await viewer.evaluate(() => {
    const s = window.vsculpt.bodyView.lastSection;
    return { part: s.part, axis: s.axis, offset: s.offset, det: Array.from(s.section.det), params: Array.from(s.section.params), positions: Array.from(s.section.positions), outline: Array.from(s.section.outline), min: s.section.detMin, max: s.section.detMax };
  });
  assert.equal(cut.part, spool);
  assert.equal(cut.axis, 0);
  assert.ok(cut.max / cut.min > 1.2, `the spool's section shows a varying det J: ${cut.min} … ${cut.max}`);
  const F = await frameLattice(viewer, spool);
  // det J at every 7th section vertex against finite differences of an independent evaluation of the same lattice.
  let checked = 0;
  for (let v = 0; v < cut.det.length; v += 7) {
    const fd = fdDet(F, cut.params.slice(3 * v, 3 * v + 3));
    assert.ok(Math.abs(cut.det[v] - fd) < 1e-6 * cut.max, `det J at section vertex ${v}: ${cut.det[v]} vs ${fd}`);
    checked++;
  }
  assert.ok(checked > 20);
  // The outline lies on the body's boundary: its six faces tessellated here from the independent
  // evaluator, 48 × 48 quads per face (chords within about 0.03 mm of the surface; the server's 16 × 16
  // mesh is 0.4 mm off in places); inner vertices of the section are far from it.
  const B = boundaryMesh(F, 48);
  F.positions = B.positions;
  F.triangles = B.triangles;
  const diag = Math.hypot(...[0, 1, 2].map((e) => {
    const xs = F.positions.filter((_, i) => i % 3 === e);
    return Math.max(...xs) - Math.min(...xs);
  }));
  const tol = 1e-3 * diag;
  const outline = [...new Set(cut.outline)];
  assert.ok(outline.length > 20);
  for (const v of outline) {
    const dist = meshDistance(cut.positions.slice(3 * v, 3 * v + 3), F.positions, F.triangles);
    assert.ok(dist < tol, `outline vertex ${v} is ${dist} from the boundary (tolerance ${tol})`);
  }
  const onOutline = new Set(cut.outline);
  let far = 0;
  for (let v = 0; v < cut.det.length && far <= 5; v += 5) if (!onOutline.has(v) && meshDistance(cut.positions.slice(3 * v, 3 * v + 3), F.positions, F.triangles) > 20 * tol) far++;
  assert.ok(far > 5, 'the section has an inside away from the boundary');

  // The kernel's det J (the VTU export's grid: 4 cells per knot span, uniform parameters) against the page's evaluator.
  const vtu = await (await fetch(`${server.base}/api/designs/${d.id}/export.vtu?part=${spool}&token=${d.tokens.viewer}`)).text();
  const arrayOf = (name) => {
    const m = new RegExp(`<DataArray[^>]*Name="${name}"[^>]*>([^<]*)</DataArray>`).exec(vtu);
    return m[1].trim().split(/\s+/).map(Number);
  };
  const kernelDet = arrayOf('det_J');
  const kernelPts = /<Points>\s*<DataArray[^>]*>([^<]*)<\/DataArray>/.exec(vtu)[1].trim().split(/\s+/).map(Number);
  const spans = F.knots.map((k, dd) => {
    let c = 0;
    for (let i = F.degrees[dd]; i < F.counts[dd]; i++) if (k[i + 1] > k[i]) c++;
    return Math.max(4, 4 * c);
  });
  assert.equal(kernelDet.length, (spans[0] + 1) * (spans[1] + 1) * (spans[2] + 1));
  const mine = await viewer.evaluate(async ([id, n]) => {
    const { BSplineVolume } = await import('/src/body-volume.js');
    const vol = BSplineVolume.fromFrame(window.vsculpt.bodyView.bodies.get(id).frame);
    const dom = vol.domain();
    const out = [];
    for (let a = 0; a <= n[0]; a++) for (let b = 0; b <= n[1]; b++) for (let c = 0; c <= n[2]; c++) {
      const t = [a, b, c].map((x, dd) => dom[dd][0] + ((dom[dd][1] - dom[dd][0]) * x) / n[dd]);
      const e = vol.eval(...t);
      out.push([...e.p, e.det]);
    }
    return out;
  }, [spool, spans]);
  const kmax = Math.max(...kernelDet.map(Math.abs));
  for (let q = 0; q < mine.length; q++) {
    assert.ok(Math.abs(mine[q][3] - kernelDet[q]) < 1e-4 * kmax, `det J at grid point ${q}: page ${mine[q][3]}, kernel ${kernelDet[q]}`);
    for (let e = 0; e < 3; e++) assert.ok(Math.abs(mine[q][e] - kernelPts[3 * q + e]) < 1e-3, `grid point ${q}: page ${mine[q]}, kernel ${kernelPts.slice(3 * q, 3 * q + 3)}`);
  }
  // Off again: no section, nothing clipped.
  await viewer.uncheck('#body-section-on');
  const off = await viewer.evaluate((id) => {
    const b = window.vsculpt.bodyView.bodies.get(id);
    return { visible: b.section.visible, clipped: (b.mesh.material.clippingPlanes || []).length };
  }, spool);
  assert.deepEqual(off, { visible: false, clipped: 0 });
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});

test('the lattice gizmo: a face selected by a click and dragged along x moves for a viewer; a drag that folds the body is refused and the page shows where', async () => {
  const d = await createDesign(server, dataDir, { name: 'gizmo', nu: 8, nv: 8 });
  const editor = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.editor}`);
  const viewer = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.viewer}`);
  await editor.click('#add-spool');
  const id = await (await editor.waitForFunction(() => [...window.vsculpt.bodyView.bodies.keys()][0] ?? null, null, { timeout: 15000 })).jsonValue();
  const before = await waitBody(viewer, id);
  await waitBody(editor, id);
  const [nu, nv, nw] = before.counts;
  const corner = nu * nv * nw - 1;

  // Face mode; a click on the corner handle selects its first face, u_max (i = nu − 1: the cube's x = 30 side).
  await editor.selectOption('#body-select-mode', 'face');
  const at = await screenOf(editor, before.lattice.slice(3 * corner, 3 * corner + 3));
  await editor.mouse.click(at.x, at.y);
  assert.equal(await editor.evaluate(() => document.getElementById('body-selection').textContent), `face u_max: ${nv * nw} points`);
  const origin = await editor.evaluate(() => window.vsculpt.bodyView.gizmoOrigin());
  assert.ok(origin && Math.abs(origin[0] - 30) < 1e-3 && Math.abs(origin[1]) < 1e-3 && Math.abs(origin[2]) < 1e-3, `the gizmo at the face's centre: ${origin}`);

  // Drag the gizmo's X arrow: a point on it, then along its direction on screen.
  const arrow = async (page, length) => {
    const o = await page.evaluate(() => window.vsculpt.bodyView.gizmoOrigin());
    const dist = await page.evaluate((o) => window.vsculpt.view.camera.position.distanceTo(new window.vsculpt.view.camera.position.constructor(...o)), o);
    const p0 = await screenOf(page, o);
    const p1 = await screenOf(page, [o[0] + dist * 0.07, o[1], o[2]]);
    const unit = await screenOf(page, [o[0] + 1, o[1], o[2]]);
    return { from: p1, dir: [p1.x - p0.x, p1.y - p0.y], perMm: Math.hypot(unit.x - p0.x, unit.y - p0.y), length };
  };
  const dragAlong = async (page, a, mm, held = async () => {}) => {
    const n = Math.hypot(...a.dir);
    const px = mm * a.perMm;
    await page.mouse.move(a.from.x, a.from.y);
    await page.mouse.down();
    for (let k = 1; k <= 10; k++) await page.mouse.move(a.from.x + (a.dir[0] / n) * px * (k / 10), a.from.y + (a.dir[1] / n) * px * (k / 10));
    await held();
    await page.mouse.up();
  };
  // The cutting plane on (y = its middle): while the gizmo is held, the section is of the previewed lattice.
  await editor.check('#body-section-on');
  await editor.selectOption('#body-section-axis', '1');
  const sectionReach = () => editor.evaluate(() => {
    const s = window.vsculpt.bodyView.lastSection.section;
    return Math.max(...s.positions.filter((_, i) => i % 3 === 0));
  });
  assert.ok(Math.abs((await sectionReach()) - 30) < 1e-3, 'the cube\'s section reaches x = 30');
  let preview = null;
  await dragAlong(editor, await arrow(editor), 12, async () => {
    const held = await editor.evaluate(() => window.vsculpt.bodyView.gizmoOrigin()[0] - 30);
    preview = { held, reach: await sectionReach() };
  });
  assert.ok(preview.held > 6, `the gizmo was held ${preview.held} mm along`);
  assert.ok(Math.abs(preview.reach - (30 + preview.held)) < 1e-3, `the previewed section reaches x = ${preview.reach}`);
  const moved = await waitBody(viewer, id, before.revision);
  const res = await fetch(`${server.base}/api/designs/${d.id}?token=${d.tokens.editor}`);
  const stored = (await res.json()).design.parts.find((p) => p.id === id).body.lattice.points;
  const dx = moved.lattice[3 * corner] - before.lattice[3 * corner];
  assert.ok(dx > 6 && dx < 18, `the face moved ${dx} mm along x`);
  for (let n = 0; n < nu * nv * nw; n++) {
    const onFace = Math.floor(n / (nv * nw)) === nu - 1;
    const want = onFace ? [before.lattice[3 * n] + dx, before.lattice[3 * n + 1], before.lattice[3 * n + 2]] : before.lattice.slice(3 * n, 3 * n + 3);
    for (let e = 0; e < 3; e++) {
      assert.ok(Math.abs(moved.lattice[3 * n + e] - want[e]) < 1e-3, `point ${n}: ${moved.lattice.slice(3 * n, 3 * n + 3)} vs ${want}`);
      assert.ok(Math.abs(stored[n][e] - moved.lattice[3 * n + e]) < 1e-4, `point ${n}: stored ${stored[n]}`);
    }
  }
  // The viewer's body follows: its boundary now reaches x = 30 + dx.
  const xs = moved.positions.filter((_, i) => i % 3 === 0);
  assert.ok(Math.abs(Math.max(...xs) - (30 + dx)) < 1e-3, `the boundary reaches x = ${Math.max(...xs)}`);
  await editor.waitForFunction(([id, rev]) => window.vsculpt.bodyView.bodies.get(id).frame.revision > rev, [id, before.revision]);
  assert.ok(Math.abs((await sectionReach()) - (30 + dx)) < 1e-3, 'the section of the edited body');

  // A drag of the same face 90 mm back, past the opposite face: the server refuses it as a fold.
  const back = await arrow(editor);
  await dragAlong(editor, { ...back, dir: [-back.dir[0], -back.dir[1]] }, 90);
  await editor.waitForFunction(() => window.vsculpt.bodyView.refused !== null, null, { timeout: 15000 });
  const refused = await editor.evaluate(() => {
    const bv = window.vsculpt.bodyView;
    return { ...bv.refused, shown: !document.getElementById('body-fold').hidden, text: document.getElementById('body-fold').textContent, mark: bv.foldMark.visible ? bv.foldMark.position.toArray() : null, toasts: window.vsculpt.state.toasts.map((t) => t.text) };
  });
  assert.ok(refused.shown, 'the refusal is shown in the panel');
  assert.match(refused.text, /folds the body at \(u, v, w\) = .* x = \(/);
  assert.ok(refused.at, 'the place of the fold is read from the message');
  assert.deepEqual(refused.mark, refused.at, 'a mark where it folds');
  const m = /x = \(([^)]*)\)/.exec(refused.text)[1].split(',').map(Number);
  assert.deepEqual(refused.at, m);
  // The refused edit moved face u_max back along x, past u_min; where it folds lies in the refused
  // body, so within its lattice's bounding box (a B-spline volume lies in its control points' hull).
  assert.deepEqual(refused.edit.select, { face: 'u_max' });
  const [ddx, ddy, ddz] = refused.edit.delta;
  assert.ok(ddx < -60 && Math.abs(ddy) < 1e-9 && Math.abs(ddz) < 1e-9, `the refused delta ${refused.edit.delta}`);
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let n = 0; n < nu * nv * nw; n++) {
    const shift = Math.floor(n / (nv * nw)) === nu - 1 ? refused.edit.delta : [0, 0, 0];
    for (let e = 0; e < 3; e++) {
      lo[e] = Math.min(lo[e], moved.lattice[3 * n + e] + shift[e]);
      hi[e] = Math.max(hi[e], moved.lattice[3 * n + e] + shift[e]);
    }
  }
  for (let e = 0; e < 3; e++) assert.ok(refused.at[e] >= lo[e] - 1e-3 && refused.at[e] <= hi[e] + 1e-3, `fold at ${refused.at}, the refused lattice spans ${lo} … ${hi}`);
  // And not where nothing moved: beyond the old u_min face's place there is only the moved face's side.
  assert.ok(refused.at[0] < 30 + dx, `fold at ${refused.at}`);
  assert.ok(refused.toasts.some((t) => t.includes('folds the body')));
  // Nothing changed: the stored lattice is the first edit's, the editor's handles are back on it.
  const again = (await (await fetch(`${server.base}/api/designs/${d.id}?token=${d.tokens.editor}`)).json()).design.parts.find((p) => p.id === id).body.lattice.points;
  assert.deepEqual(again, stored);
  const handles = await editor.evaluate((id) => Array.from(window.vsculpt.bodyView.bodies.get(id).handles.geometry.attributes.position.array), id);
  for (let k = 0; k < handles.length; k++) assert.ok(Math.abs(handles[k] - moved.lattice[k]) < 1e-4, `handle value ${k} back`);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});
