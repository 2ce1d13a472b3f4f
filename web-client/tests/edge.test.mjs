// The edge clamp tool end to end (issue 15), in real headless Chromium
// against the real server: with "edge clamp" chosen, a click near an edge
// of the selected surface creates one position icon anchored on that edge
// in the chosen mode (clamped / simply supported); the server stores it,
// every page draws it along the edge (a tube, with ticks across it when
// clamped), and the held edge does not move while a load is dragged.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { webDir, createDesign, serverAndBrowser, openClient } from './harness.mjs';

const artifacts = join(webDir, 'test-artifacts');
let server;
let browser;
const dataDir = serverAndBrowser('vsculpt-edge-', (s, b) => {
  server = s;
  browser = b;
});

async function documentOf(d) {
  const res = await fetch(`${server.base}/api/designs/${d.id}?token=${d.tokens.editor}`);
  assert.equal(res.status, 200);
  return (await res.json()).design;
}

/** Picks (u, v) in edge mode with `mode`; the new icon's id once the page holds it. */
async function clampAt(page, u, v, mode) {
  const n = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.selectOption('#create', 'edge');
  await page.selectOption('#edge-mode', mode);
  await page.evaluate(([a, b]) => window.vsculpt.pick(a, b), [u, v]);
  await page.waitForFunction((k) => window.vsculpt.state.icons.size === k + 1, n, { timeout: 10000 });
  return page.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
}

/** What the page drew for icon `id`: the edge tube's geometry type and whether clamp ticks are shown. */
const drawing = (page, id) =>
  page.evaluate((i) => {
    const g = window.vsculpt.icons.objects.get(i);
    if (!g) return null;
    const tube = g.getObjectByName(`edge-${i}`);
    return { tube: tube ? tube.geometry.type : null, ticks: !!g.getObjectByName(`clamp-${i}`) };
  }, id);

test('clamping an edge from the page: stored, drawn on every page, held through a drag', async () => {
  const created = await createDesign(server, dataDir, { name: 'edges', nu: 12, nv: 9 });
  const d = { id: created.id, tokens: created.tokens };
  const editor = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.editor}`);
  const viewer = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.viewer}`);
  const part = await editor.evaluate(() => window.vsculpt.state.selectedPart);
  assert.ok(part, 'a part is selected');

  const clamped = await clampAt(editor, 0.03, 0.4, 'clamped');
  const simple = await clampAt(editor, 0.6, 0.97, 'simply_supported');
  const doc = await documentOf(d);
  const icons = doc.parts.find((p) => p.id === part).body.icons;
  assert.deepEqual(
    icons.map((i) => [i.id, i.anchor, i.role.kind]),
    [
      [clamped, { kind: 'edge', edge: 'u_min', clamped: true }, 'position'],
      [simple, { kind: 'edge', edge: 'v_max', clamped: false }, 'position'],
    ],
  );
  // The editor and a viewer draw both along their edges; only the clamp has ticks.
  for (const page of [editor, viewer]) {
    await page.waitForFunction((ids) => ids.every((i) => window.vsculpt.icons.objects.has(i)), [clamped, simple], { timeout: 10000 });
    assert.deepEqual(await drawing(page, clamped), { tube: 'TubeGeometry', ticks: true });
    assert.deepEqual(await drawing(page, simple), { tube: 'TubeGeometry', ticks: false });
  }
  // The wire anchor the page holds (protocol form: edge + mode).
  assert.deepEqual(await editor.evaluate((i) => window.vsculpt.state.icons.get(i).anchor, clamped), { kind: 'edge', edge: 'u_min', mode: 'clamped' });

  // A load in the middle, dragged up: the u_min edge's two rows stay, the plate moves.
  const n = await editor.evaluate(() => window.vsculpt.state.icons.size);
  await editor.selectOption('#create', 'point');
  await editor.selectOption('#create-role', 'load');
  await editor.evaluate(() => window.vsculpt.pick(0.5, 0.5));
  await editor.waitForFunction((k) => window.vsculpt.state.icons.size === k + 1, n, { timeout: 10000 });
  const load = await editor.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  const before = (await documentOf(d)).parts.find((p) => p.id === part).body.surface;
  const at = await editor.evaluate((i) => window.vsculpt.state.icons.get(i).xyz, load);
  await editor.evaluate(([p, i]) => window.vsculpt.send({ type: 'drag_start', part: p, icon: i }), [part, load]);
  for (let k = 1; k <= 3; k++) {
    await editor.evaluate(([p, i, xyz]) => window.vsculpt.send({ type: 'drag', part: p, icon: i, xyz }), [part, load, [at[0], at[1], at[2] + 0.1 * k]]);
  }
  await editor.evaluate(([p, i]) => window.vsculpt.send({ type: 'drag_end', part: p, icon: i }), [part, load]);
  let after;
  for (let tries = 0; tries < 50; tries++) {
    after = (await documentOf(d)).parts.find((p) => p.id === part).body.surface;
    if (after.points.some((p, k) => Math.abs(p[2] - before.points[k][2]) > 1e-3)) break;
    await new Promise((r) => setTimeout(r, 100));
  }
  const nv = after.nv;
  const moved = Math.max(...after.points.map((p, k) => Math.abs(p[2] - before.points[k][2])));
  assert.ok(moved > 1e-3, `the load moved the plate (${moved})`);
  for (let k = 0; k < 2 * nv; k++) {
    const off = Math.hypot(...after.points[k].map((x, c) => x - before.points[k][c]));
    assert.ok(off <= 1e-9, `u_min row ${Math.floor(k / nv)} point ${k % nv} moved by ${off}`);
  }
  await editor.screenshot({ path: join(artifacts, 'edge-clamp.png') });
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});
