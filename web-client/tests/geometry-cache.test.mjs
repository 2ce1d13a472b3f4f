// The browser's geometry cache (issue 18, a warm first picture): a page keeps
// the frames of its compact join in IndexedDB under the name the server's
// welcome gave them; reloaded, it draws them before the server has said
// anything, offers the name in its hello, and the server, finding it still
// names the design's frames, sends none. The shape on screen is then the
// server's: the design's control points equal the REST document's, and the
// drawn meshes equal those of a page that joined without the cache. When the
// design changed in between (another client's drag), the server sends the new
// frames and the page ends up drawing the new shape, not the kept one. The
// demo (surfaces, a curve, a body part's frames) goes through the cache
// without a page error.
// Real server, real headless Chromium; the other client is tests/ws-client.mjs
// (Node 20 has WebSocket behind a flag: without it this file runs itself again
// with the flag).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { createDesign, serverAndBrowser, shownPoints, documentPoints } from './harness.mjs';
import { connect } from './ws-client.mjs';

let server;
let browser;
let dataDir;
if (typeof WebSocket === 'undefined') {
  test('the geometry cache (run again with --experimental-websocket)', () => {
    const r = spawnSync(process.execPath, ['--experimental-websocket', '--test', fileURLToPath(import.meta.url)], { stdio: 'inherit' });
    assert.equal(r.status, 0, 'the geometry cache tests failed');
  });
} else {
  dataDir = serverAndBrowser('vsculpt-geometry-cache-', (s, b) => {
    server = s;
    browser = b;
  });
  test('a warm visit draws the kept frames, the server confirms them and sends none, and the shape is the server\'s', warmVisit);
  test('a design changed since the frames were kept gets the new shape, not the kept one', changedDesign);
  test('the demo (surfaces, a curve, a body) draws from the kept frames without a page error, and is the server\'s', demoVisit);
}

/** Resolves once the page has joined, drawn its first picture, and every surface's drawing shows its part's current shape. */
function settled(page) {
  return page.waitForFunction(
    () => {
      const v = window.vsculpt;
      if (!v || v.perf.firstPicture === null || !v.state.access || !v.design.joined) return false;
      for (const p of v.design.parts.values()) {
        if (p.kind !== 'surface') continue;
        const d = v.partsView.drawings.get(p.id);
        if (!d || d.filled !== p.geometry) return false;
      }
      return true;
    },
    null,
    { timeout: 60000 },
  );
}

/** Each surface part's drawn mesh: { id: [x, y, z, …] } (the vertex positions the GPU is given). */
function drawnMeshes(page) {
  return page.evaluate(() =>
    Object.fromEntries(
      [...window.vsculpt.partsView.drawings.values()]
        .filter((d) => d.kind === 'surface')
        .map((d) => {
          const pos = d.mesh.geometry.attributes.position;
          return [d.id, Array.from(pos.array.subarray(0, pos.count * 3))];
        }),
    ),
  );
}

/** The design's control points as the REST API has them now. */
async function restPoints(design) {
  const res = await fetch(`${server.base}/api/designs/${design.id}?token=${design.tokens.viewer}`);
  return documentPoints((await res.json()).design);
}

/** Opens `url` in a new page of `context`, counting the binary messages its socket receives. */
async function open(context, url) {
  const page = await context.newPage();
  page.binaryFrames = 0;
  page.on('websocket', (ws) => ws.on('framereceived', (f) => typeof f.payload !== 'string' && page.binaryFrames++));
  await page.goto(url);
  return page;
}

/** The drawn meshes of a page that joins without the cache (its frames all from the server), in a context of its own. */
async function freshMeshes(url) {
  const context = await browser.newContext({ viewport: { width: 1100, height: 700 } });
  try {
    const page = await open(context, `${url}&geometry_cache=0`);
    await settled(page);
    assert.ok(page.binaryFrames > 0, 'the fresh page got its frames from the server');
    return await drawnMeshes(page);
  } finally {
    await context.close();
  }
}

/** Value by value within `tol` of the largest (1e-6 against the REST document: frames carry 32-bit floats). */
function assertSamePoints(actual, expected, what, tol = 1e-6) {
  assert.deepEqual(Object.keys(actual).sort(), Object.keys(expected).sort(), `${what}: parts`);
  for (const [id, xs] of Object.entries(expected)) {
    assert.equal(actual[id].length, xs.length, `${what}: part ${id} size`);
    const size = Math.max(1e-12, ...xs.map(Math.abs));
    for (let i = 0; i < xs.length; i++) assert.ok(Math.abs(actual[id][i] - xs[i]) <= tol * size, `${what}: part ${id} value ${i}: ${actual[id][i]} vs ${xs[i]}`);
  }
}

/** A warm visit: drawn from the cache, confirmed, no frame sent, the server's shape. */
async function warmVisit() {
  const design = await createDesign(server, dataDir, { name: 'kept', nu: 14, nv: 11 });
  const url = `${server.base}/?design=${design.id}&token=${design.tokens.viewer}`;
  const context = await browser.newContext({ viewport: { width: 1100, height: 700 } });
  try {
    // Cold: nothing kept, the frames come from the server and are kept under the welcome's name.
    const page = await open(context, url);
    await settled(page);
    const cold = await page.evaluate(async () => ({ ...window.vsculpt.link.cacheUse, saved: await window.vsculpt.link.cacheUse.saved }));
    assert.equal(cold.replayed, 0);
    assert.equal(cold.offered, null);
    assert.match(cold.saved, /^[0-9a-f]{64}$/, 'the join\'s frames were kept under a SHA-256 name');
    assert.ok(page.binaryFrames > 0);

    // Warm: the kept frames are drawn, offered and confirmed; no frame crosses the socket.
    page.binaryFrames = 0;
    await page.reload();
    await settled(page);
    const warm = await page.evaluate(() => window.vsculpt.link.cacheUse);
    assert.ok(warm.replayed > 0, 'frames were drawn from the cache');
    assert.equal(warm.offered, cold.saved);
    assert.equal(warm.confirmed, true, 'the server found the kept frames current');
    assert.equal(page.binaryFrames, 0, 'the server sent no frame: the picture came from the cache');
    // A kept picture of a surface alone: only the studio program is prewarmed (no lines to draw).
    assert.deepEqual(await page.evaluate(() => window.vsculpt.link.cacheUse.kinds), [1]);
    assert.equal(await page.evaluate(() => window.vsculpt.perf.prewarmPlain), false);
    assertSamePoints(await shownPoints(page), await restPoints(design), 'control points against the REST document');
    assertSamePoints(await drawnMeshes(page), await freshMeshes(url), 'drawn meshes against a page without the cache', 0);
  } finally {
    await context.close();
  }
}

/** The demo's parts of every kind through the cache: its viewer link, reloaded. */
async function demoVisit() {
  const context = await browser.newContext({ viewport: { width: 1100, height: 700 } });
  try {
    const page = await open(context, server.viewer);
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    await settled(page);
    await page.evaluate(() => window.vsculpt.link.cacheUse.saved);
    page.binaryFrames = 0;
    await page.reload();
    await settled(page);
    const use = await page.evaluate(() => window.vsculpt.link.cacheUse);
    assert.ok(use.replayed >= 5, `frames drawn from the cache: ${use.replayed}`);
    // Curves and a body among the kept frames: their plain (line) programs are prewarmed too.
    assert.ok((await page.evaluate(() => window.vsculpt.link.cacheUse.kinds)).some((k) => k !== 1));
    assert.equal(await page.evaluate(() => window.vsculpt.perf.prewarmPlain), true);
    assert.equal(use.confirmed, true);
    assert.equal(page.binaryFrames, 0);
    assert.deepEqual(errors, []);
    const demo = new URL(server.viewer);
    const id = Number(demo.searchParams.get('design'));
    const res = await fetch(`${server.base}/api/designs/${id}?token=${demo.searchParams.get('token')}`);
    assertSamePoints(await shownPoints(page), documentPoints((await res.json()).design), 'control points against the REST document');
    assertSamePoints(await drawnMeshes(page), await freshMeshes(server.viewer), 'drawn meshes against a page without the cache', 0);
  } finally {
    await context.close();
  }
}

/** A visit after another client's drag: the new shape. */
async function changedDesign() {
  const design = await createDesign(server, dataDir, { name: 'changed', nu: 12, nv: 10 });
  const url = `${server.base}/?design=${design.id}&token=${design.tokens.viewer}`;
  const context = await browser.newContext({ viewport: { width: 1100, height: 700 } });
  let ed = null;
  try {
    const page = await open(context, url);
    await settled(page);
    const keptName = await page.evaluate(() => window.vsculpt.link.cacheUse.saved);
    const keptPoints = await shownPoints(page);
    await page.close();

    // Another client drags the surface while the page is closed.
    ed = connect(server.base, design.id, design.tokens.editor);
    await ed.ready;
    const snap = await ed.waitText((m) => m.type === 'snapshot');
    const part = snap.parts[0].id;
    const created = ed.waitText((m) => m.req === 1);
    ed.send({ type: 'create_icon', part, req: 1, spec: { anchor: { kind: 'point', u: 0.5, v: 0.5 }, role: { kind: 'load' } } });
    const ack = await created;
    assert.equal(ack.type, 'ack', JSON.stringify(ack));
    for (const [req, msg] of [[2, { type: 'drag_start', part, icon: ack.icon }], [3, { type: 'drag', part, icon: ack.icon, xyz: [0.5, 0.5, 0.4] }], [4, { type: 'drag_end', part, icon: ack.icon }]]) {
      const answered = ed.waitText((m) => m.req === req);
      ed.send({ ...msg, req });
      assert.equal((await answered).type, 'ack');
    }
    const now = await restPoints(design);
    assert.notDeepEqual(now, keptPoints, 'the drag changed the surface');

    // The page comes back: it draws what it kept, offers it, is refused, and ends on the new shape.
    const again = await open(context, url);
    await settled(again);
    const use = await again.evaluate(async () => ({ ...window.vsculpt.link.cacheUse, saved: await window.vsculpt.link.cacheUse.saved }));
    assert.ok(use.replayed > 0, 'the kept frames were drawn first');
    assert.equal(use.offered, keptName);
    assert.equal(use.confirmed, false, 'the server did not take the stale name');
    assert.ok(again.binaryFrames > 0, 'the server sent the frames');
    assert.match(use.saved, /^[0-9a-f]{64}$/);
    assert.notEqual(use.saved, keptName, 'the new frames were kept under a new name');
    assertSamePoints(await shownPoints(again), now, 'control points against the REST document');
    assertSamePoints(await drawnMeshes(again), await freshMeshes(url), 'drawn meshes against a page without the cache', 0);
  } finally {
    if (ed) ed.ws.close();
    await context.close();
  }
}
