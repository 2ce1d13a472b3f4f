// A DSM part (paper 001) end to end, in real headless Chromium against the
// real server: an editor creates one (a sphere-based density primitive
// whose surface is the sphere r = ln(D/D_e)/a), moves it and changes its
// density from the DSM panel's inputs, and adds a second primitive; a second
// browser (a viewer) draws every mesh the server sends, and each one is
// checked vertex by vertex against the primitives' analytic surfaces. The
// page's "add DSM" button makes a drawn part too. A page following a net-node
// drag and a primitive drag through mesh deltas (kind 8) draws, after every
// step, the very mesh the server sends whole to a client without deltas.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createDesign, serverAndBrowser, openClient } from './harness.mjs';
import { decodeMeshFrame } from '../src/frame.js';

let server;
let browser;
const dataDir = serverAndBrowser('vsculpt-dsm-', (s, b) => {
  server = s;
  browser = b;
});

async function freshDesign(name) {
  const d = await createDesign(server, dataDir, { name, nu: 8, nv: 8 });
  return {
    id: d.id,
    tokens: d.tokens,
    editor: `${server.base}/?design=${d.id}&token=${d.tokens.editor}`,
    viewer: `${server.base}/?design=${d.id}&token=${d.tokens.viewer}`,
  };
}

/** Waits until `page` draws a mesh of part `part` newer than revision `after`; that mesh. */
async function meshAfter(page, part, after) {
  const h = await page.waitForFunction(
    ([p, a]) => {
      const f = window.vsculpt.dsmView.frames()[p];
      return f && f.revision > a ? f : null;
    },
    [part, after],
    { timeout: 20000 },
  );
  return h.jsonValue();
}

/** The largest distance of a mesh vertex from the nearest of the spheres [[cx, cy, cz], r]. */
function offSpheres(mesh, spheres) {
  let worst = 0;
  for (let i = 0; i < mesh.positions.length; i += 3) {
    const [x, y, z] = mesh.positions.slice(i, i + 3);
    const d = Math.min(...spheres.map(([c, r]) => Math.abs(Math.hypot(x - c[0], y - c[1], z - c[2]) - r)));
    worst = Math.max(worst, d);
  }
  return worst;
}

/** Vertices within `tol` of sphere s. */
function onSphere(mesh, [c, r], tol) {
  let n = 0;
  for (let i = 0; i < mesh.positions.length; i += 3) {
    const [x, y, z] = mesh.positions.slice(i, i + 3);
    if (Math.abs(Math.hypot(x - c[0], y - c[1], z - c[2]) - r) <= tol) n++;
  }
  return n;
}

/** The tolerance of a mesh frame: its quantisation (half a step per axis) plus f32 rounding. */
const tolerance = (mesh) => mesh.step * 0.5 * Math.sqrt(3) + 1e-5;

test('a dsm part created, moved and reshaped from the panel reaches a second browser on its analytic surface', async () => {
  const d = await freshDesign('dsm');
  const editor = await openClient(browser, d.editor);
  const viewer = await openClient(browser, d.viewer);
  // D = e², a = 2: the equal density surface is the sphere r = ln(e²)/2 = 1.
  const dd = Math.E ** 2;
  const spec = { name: 'blob', shape: { kind: 'dsm', dsm: { de: 1, cells: 24, groups: [{ op: 'add', primitives: [{ id: 1, at: [0, 0, 0], shape: { type: 'density_sphere', density: dd, reducing: 2 } }] }] } } };
  await editor.evaluate((s) => window.vsculpt.send({ type: 'create_part', spec: s }), spec);
  const part = await (await editor.waitForFunction(() => [...window.vsculpt.design.parts.values()].find((p) => p.kind === 'dsm')?.id, null, { timeout: 20000 })).jsonValue();

  let m = await meshAfter(viewer, part, 0);
  assert.ok(m.indices.length / 3 > 200, `${m.indices.length / 3} triangles`);
  assert.ok(offSpheres(m, [[[0, 0, 0], 1]]) <= tolerance(m), `${offSpheres(m, [[[0, 0, 0], 1]])}`);

  // Move it from the editor's DSM panel: select the part, type the new centre, apply.
  await editor.evaluate((id) => window.vsculpt.selectPart(id), part);
  await editor.waitForSelector('#dsm-section:not([hidden]) li[data-id="1"]');
  const row = '#dsm-section li[data-id="1"]';
  await editor.fill(`${row} input[name="at.0"]`, '0.75');
  await editor.fill(`${row} input[name="at.2"]`, '-0.5');
  await editor.click(`${row} button[data-apply="1"]`);
  m = await meshAfter(viewer, part, m.revision);
  // The viewer's panel data follows too (dsm_changed).
  const at = await viewer.evaluate((id) => window.vsculpt.design.parts.get(id).dsm.groups[0].primitives[0].at, part);
  assert.deepEqual(at, [0.75, 0, -0.5]);
  assert.ok(offSpheres(m, [[[0.75, 0, -0.5], 1]]) <= tolerance(m), `moved: ${offSpheres(m, [[[0.75, 0, -0.5], 1]])}`);

  // Change its density from the panel: D = e³ makes r = 3/2.
  // The editor has heard of the move (its own echo) before the next apply.
  await editor.waitForFunction((id) => window.vsculpt.design.parts.get(id).dsm.groups[0].primitives[0].at[0] === 0.75, part);
  await editor.fill(`${row} input[name="density"]`, String(Math.E ** 3));
  await editor.click(`${row} button[data-apply="1"]`);
  m = await meshAfter(viewer, part, m.revision);
  assert.ok(offSpheres(m, [[[0.75, 0, -0.5], 1.5]]) <= tolerance(m), `denser: ${offSpheres(m, [[[0.75, 0, -0.5], 1.5]])}`);

  // Add a geometric sphere (radius 0.5, as the panel makes it) in a group of its own, away from the first.
  await editor.fill('#dsm-section input[name="add-group"]', '1');
  await editor.selectOption('#dsm-section select[name="add-type"]', 'sphere');
  await editor.fill('#dsm-section input[name="add-at.0"]', '4');
  await editor.click('#dsm-section button[data-add]');
  m = await meshAfter(viewer, part, m.revision);
  const spheres = [[[0.75, 0, -0.5], 1.5], [[4, 0, 0], 0.5]];
  assert.ok(offSpheres(m, spheres) <= tolerance(m), `two: ${offSpheres(m, spheres)}`);
  for (const s of spheres) assert.ok(onSphere(m, s, tolerance(m)) > 20, `too few vertices on ${JSON.stringify(s)}`);

  // The viewer drew it: a three.js mesh in its scene, and its panel is read-only.
  assert.ok(await viewer.evaluate((id) => window.vsculpt.dsmView.drawings.get(id).mesh.visible, part));
  await viewer.evaluate((id) => window.vsculpt.selectPart(id), part);
  await viewer.waitForSelector('#dsm-section:not([hidden]) button[data-apply="1"][disabled]');
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});

test('the add DSM button makes a part the page draws', async () => {
  const d = await freshDesign('dsm-button');
  const page = await openClient(browser, d.editor);
  await page.click('#add-dsm');
  const part = await (await page.waitForFunction(() => [...window.vsculpt.design.parts.values()].find((p) => p.kind === 'dsm')?.id, null, { timeout: 20000 })).jsonValue();
  const m = await meshAfter(page, part, 0);
  assert.ok(m.indices.length > 0);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('what the editor has typed and not applied survives a redraw caused by another edit', async () => {
  const d = await freshDesign('dsm-typed');
  const editor = await openClient(browser, d.editor);
  const other = await openClient(browser, d.editor);
  const spec = { name: 'blob', shape: { kind: 'dsm', dsm: { de: 1, cells: 16, groups: [{ op: 'add', primitives: [{ id: 1, at: [0, 0, 0], shape: { type: 'density_sphere', density: 5, reducing: 2 } }] }] } } };
  await editor.evaluate((s) => window.vsculpt.send({ type: 'create_part', spec: s }), spec);
  const part = await (await editor.waitForFunction(() => [...window.vsculpt.design.parts.values()].find((p) => p.kind === 'dsm')?.id, null, { timeout: 20000 })).jsonValue();
  await editor.evaluate((id) => window.vsculpt.selectPart(id), part);
  const row = '#dsm-section li[data-id="1"]';
  await editor.waitForSelector(row);
  await editor.fill(`${row} input[name="density"]`, '9');
  await editor.fill('#dsm-section input[name="add-at.1"]', '2.5');
  // Someone else moves the primitive: the panel redraws with the new centre ...
  await other.waitForFunction((id) => window.vsculpt.design.parts.has(id), part);
  await other.evaluate((id) => window.vsculpt.send({ type: 'dsm_edit', part: id, edit: { op: 'move_primitive', id: 1, at: [1, 2, 3] } }), part);
  await editor.waitForFunction(() => document.querySelector('#dsm-section li[data-id="1"] input[name="at.2"]')?.value === '3', null, { timeout: 20000 });
  // ... and keeps what this editor typed.
  assert.equal(await editor.inputValue(`${row} input[name="density"]`), '9');
  assert.equal(await editor.inputValue('#dsm-section input[name="add-at.1"]'), '2.5');
  assert.equal(await editor.inputValue(`${row} input[name="reducing"]`), '2');
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(other.errors, []);
  await editor.close();
  await other.close();
});

test('a page following drags through mesh deltas draws the mesh the server sends whole', async () => {
  const d = await freshDesign('dsm-delta');
  const editor = await openClient(browser, d.editor);
  const page = await openClient(browser, d.viewer);
  // Beside the page's own link (mesh_delta=1), a plain socket of the same
  // browser without it: every mesh frame whole, kept as bytes by revision.
  await page.evaluate(([design, token]) => {
    window.wholeFrames = {};
    const ws = new WebSocket(`ws://${location.host}/ws`);
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => ws.send(JSON.stringify({ type: 'hello', protocol: 2, token, design, client_kind: 'tool' }));
    ws.onmessage = (ev) => {
      if (typeof ev.data === 'string') return;
      const b = new Uint8Array(ev.data);
      if (b[4] !== 3) return;
      const rev = Number(new DataView(ev.data).getBigUint64(24, true));
      window.wholeFrames[rev] = Array.from(b);
    };
  }, [d.id, d.tokens.viewer]);
  // A slab topped by a 5 × 4 passing-points net, with a hole through it.
  const heights = [0.08, 0.1, 0.1, 0.1, 0.08, 0.1, 0.22, 0.26, 0.22, 0.1, 0.1, 0.22, 0.26, 0.22, 0.1, 0.08, 0.1, 0.1, 0.1, 0.08];
  const dsm = { de: 1, cells: 32, groups: [
    { op: 'add', primitives: [
      { id: 1, at: [0, 0, 0], shape: { type: 'box', half: [1.6, 0.8, 0.3] } },
      { id: 4, at: [0, 0, 0.3], shape: { type: 'net', nu: 5, nv: 4, spacing: [0.7, 0.45], heights, reducing: 3 } },
    ] },
    { op: 'subtract', primitives: [{ id: 5, at: [1.15, 0, 0], shape: { type: 'cylinder', radius: 0.15, half_height: 1.5 } }] },
  ] };
  await editor.evaluate((s) => window.vsculpt.send({ type: 'create_part', spec: s }), { name: 'slab', shape: { kind: 'dsm', dsm } });
  const part = await (await editor.waitForFunction(() => [...window.vsculpt.design.parts.values()].find((p) => p.kind === 'dsm')?.id, null, { timeout: 20000 })).jsonValue();
  let m = await meshAfter(page, part, 0);
  const edits = [
    ...[1, 2, 3].map((k) => ({ op: 'drag_node', id: 4, node: 7, height: 0.26 + 0.02 * k })),
    ...[1, 2, 3].map((k) => ({ op: 'move_primitive', id: 5, at: [1.15, 0.02 * k, 0] })),
  ];
  for (const edit of edits) {
    await editor.evaluate(([p, e]) => window.vsculpt.dsmEdit(p, e), [part, edit]);
    m = await meshAfter(page, part, m.revision);
    const bytes = await (await page.waitForFunction((r) => window.wholeFrames[r], m.revision, { timeout: 20000 })).jsonValue();
    const w = decodeMeshFrame(Uint8Array.from(bytes).buffer);
    assert.equal(w.part, part);
    assert.deepEqual(m.positions, Array.from(w.positions), `positions after ${JSON.stringify(edit)}`);
    assert.deepEqual(m.indices, Array.from(w.indices), `triangles after ${JSON.stringify(edit)}`);
  }
  const counts = await page.evaluate(() => ({ applied: window.vsculpt.link.meshes.applied, ignored: window.vsculpt.link.meshes.ignored }));
  assert.ok(counts.applied >= 3, `${counts.applied} deltas applied`);
  assert.equal(counts.ignored, 0);
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(page.errors, []);
  await editor.close();
  await page.close();
});
