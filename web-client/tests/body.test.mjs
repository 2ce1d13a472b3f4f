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
  assert.equal(await editor.isDisabled('#ffd button[name="ffd-bind"]'), true);
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

test('a body frame built byte by byte from the README table decodes; a wrong length, index or direction is refused', async () => {
  const { decodeFrame } = await import('../src/frame.js');
  // N = 2·1·1 lattice points, V = 3 vertices, T = 1 triangle, L = 1 line of S = 2 samples.
  const [N, V, T, L, S] = [2, 3, 1, 1, 2];
  const len = 64 + 12 * N + 24 * V + 12 * T + 4 * L + 12 * L * S;
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
  [2, 1, 1, V, T, L, S].forEach((x, i) => dv.setUint32(36 + 4 * i, x, true));
  let o = 64;
  const f32 = (...xs) => xs.forEach((x) => { dv.setFloat32(o, x, true); o += 4; });
  const u32 = (...xs) => xs.forEach((x) => { dv.setUint32(o, x, true); o += 4; });
  f32(0, 0, 0, 1, 2, 3); // lattice
  f32(0, 0, 0, 1, 0, 0, 0, 1, 0); // positions
  f32(0, 0, 1, 0, 0, 1, 0, 0, 1); // normals
  u32(0, 1, 2); // triangle
  u32(2); // line held at constant w
  f32(0, 0, 0, 1, 1, 1); // its samples
  assert.equal(o, len);
  const f = decodeFrame(buf);
  assert.equal(f.kind, 'body');
  assert.deepEqual([f.design, f.part, f.revision, f.flags, f.t], [7, 9, 42, 1, 0.25]);
  assert.deepEqual(f.counts, [2, 1, 1]);
  assert.deepEqual(Array.from(f.lattice), [0, 0, 0, 1, 2, 3]);
  assert.deepEqual(Array.from(f.triangles), [0, 1, 2]);
  assert.deepEqual(Array.from(f.lineDirs), [2]);
  assert.deepEqual(Array.from(f.linePoints), [0, 0, 0, 1, 1, 1]);
  assert.throws(() => decodeFrame(buf.slice(0, len - 4)), /bytes/);
  const badIndex = buf.slice(0);
  new DataView(badIndex).setUint32(64 + 12 * N + 24 * V + 8, 3, true);
  assert.throws(() => decodeFrame(badIndex), /missing vertex/);
  const badDir = buf.slice(0);
  new DataView(badDir).setUint32(64 + 12 * N + 24 * V + 12 * T, 3, true);
  assert.throws(() => decodeFrame(badDir), /direction/);
});
