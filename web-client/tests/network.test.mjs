// A styling-curve network part end to end (issue 14), in real headless
// Chromium against the real server: the bottle template's nine curves and
// six patches are drawn in an editor and a viewer; a point of the bottom
// ring is dragged with the mouse in the editor; the viewer then shows the
// moved curve and patches whose boundary lies on the curves (every boundary
// vertex of its mesh frame within the frame's quantisation of a curve,
// measured by Newton's method on the curves the viewer was sent); the
// fairing button fairs the faces and the boundary stays on the curves.
// Fairing runs as a job: both browsers show its progress, the editor's
// fair button turns into a cancel button (the viewer's is not shown) that
// cancels it and changes nothing; a finished fairing is drawn. A client
// joining while jobs run finds them in its snapshot (its page drops every
// `fairing_progress`, so nothing else could tell it).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { serverAndBrowser } from './harness.mjs';

let server;
let browser;
const dataDir = serverAndBrowser('vsculpt-network-', (s, b) => {
  server = s;
  browser = b;
});

/** A new design holding the bottle network (REST, admin token). */
async function bottleDesign(name) {
  const admin = readFileSync(join(dataDir, 'admin-token'), 'utf8').trim();
  const res = await fetch(`${server.base}/api/designs`, {
    method: 'POST',
    headers: { authorization: `Bearer ${admin}`, 'content-type': 'application/json' },
    body: JSON.stringify({ name, template: 'bottle' }),
  });
  assert.equal(res.status, 201, await res.clone().text());
  const d = await res.json();
  return {
    editor: `${server.base}/?design=${d.id}&token=${d.tokens.editor}`,
    viewer: `${server.base}/?design=${d.id}&token=${d.tokens.viewer}`,
  };
}

/** Opens `url` and waits until the network part's curves and patches are drawn and the shell is gone; `init` runs in the page before its scripts. */
async function openNetwork(url, init = null) {
  const page = await browser.newPage({ viewport: { width: 1100, height: 700 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.errors = errors;
  if (init) await page.addInitScript(init);
  await page.goto(url);
  await page.waitForFunction(
    () => {
      const v = window.vsculpt;
      const d = v && v.networkView.parts.get(1);
      return v.design.joined && v.state.access && d && d.frame && d.curves.length === 9 && !document.querySelector('#shell:not(.done)');
    },
    null,
    { timeout: 30000 },
  );
  return page;
}

/**
 * In the page: the largest distance from a boundary vertex of the network's
 * mesh frame (edges of one triangle) to the nearest of its curves, the
 * frame's quantisation bound, and curve 0 at t = 0.5.
 */
function measure(page) {
  return page.evaluate(async () => {
    const { curveDerivs } = await import('/src/bspline.js');
    const d = window.vsculpt.networkView.parts.get(1);
    const f = d.frame;
    const count = new Map();
    for (let i = 0; i < f.indices.length; i += 3) {
      for (let k = 0; k < 3; k++) {
        const a = f.indices[i + k];
        const b = f.indices[i + ((k + 1) % 3)];
        const key = Math.min(a, b) * 4294967296 + Math.max(a, b);
        count.set(key, (count.get(key) || 0) + 1);
      }
    }
    const boundary = new Set();
    for (const [key, n] of count) {
      if (n !== 1) continue;
      boundary.add(Math.floor(key / 4294967296));
      boundary.add(key % 4294967296);
    }
    const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const dist = (c, p) => {
      const [a, b] = [c.knots[c.degree], c.knots[c.n]];
      let t = a;
      let best = Infinity;
      for (let k = 0; k <= 400; k++) {
        const s = a + ((b - a) * k) / 400;
        const q = sub(curveDerivs(c, s).p, p);
        if (dot(q, q) < best) [best, t] = [dot(q, q), s];
      }
      for (let it = 0; it < 20; it++) {
        const g = curveDerivs(c, t);
        const r = sub(g.p, p);
        const df = dot(g.d1, g.d1) + dot(r, g.d2);
        if (Math.abs(df) < 1e-300) break;
        t = Math.min(b, Math.max(a, t - dot(r, g.d1) / df));
      }
      return Math.sqrt(dot(sub(curveDerivs(c, t).p, p), sub(curveDerivs(c, t).p, p)));
    };
    let gap = 0;
    for (const i of boundary) {
      const p = [f.positions[3 * i], f.positions[3 * i + 1], f.positions[3 * i + 2]];
      gap = Math.max(gap, Math.min(...d.curves.map((c) => dist(c.curve, p))));
    }
    return { gap, quantum: f.step * 0.5 * Math.sqrt(3) + 1e-5, boundary: boundary.size, mid: curveDerivs(d.curves[0].curve, 0.5).p, revision: f.revision };
  });
}

/** Screen position of curve 0's point at t = 0.5 in `page`. */
function screenOfMid(page) {
  return page.evaluate(async () => {
    const { curveDerivs } = await import('/src/bspline.js');
    const v = window.vsculpt.view;
    const c = window.vsculpt.networkView.parts.get(1).curves[0].curve;
    const p = curveDerivs(c, 0.5).p;
    const r = v.renderer.domElement.getBoundingClientRect();
    const q = v.model.localToWorld(new v.camera.position.constructor(...p)).project(v.camera);
    return { x: r.left + ((q.x + 1) / 2) * r.width, y: r.top + ((1 - q.y) / 2) * r.height };
  });
}

test('a curve point dragged in one browser: the other browser\'s patches still meet the moved curve; fairing keeps the boundary', async () => {
  const d = await bottleDesign('bottle');
  const editor = await openNetwork(d.editor);
  const viewer = await openNetwork(d.viewer);
  const before = await measure(viewer);
  assert.ok(before.boundary > 100, `boundary vertices: ${before.boundary}`);
  assert.ok(before.gap <= before.quantum, `patches off the curves before the drag by ${before.gap}`);

  const at = await screenOfMid(editor);
  await editor.mouse.move(at.x, at.y);
  await editor.mouse.down();
  for (let k = 1; k <= 10; k++) await editor.mouse.move(at.x + 4 * k, at.y - 3 * k);
  await editor.mouse.up();

  // The viewer shows the moved curve and patches on it (waits for a
  // consistent pair: network_changed comes before its frame).
  await viewer.waitForFunction(
    async (mid0) => {
      const { curveDerivs } = await import('/src/bspline.js');
      const d = window.vsculpt.networkView.parts.get(1);
      const p = curveDerivs(d.curves[0].curve, 0.5).p;
      return Math.hypot(p[0] - mid0[0], p[1] - mid0[1], p[2] - mid0[2]) > 0.02;
    },
    before.mid,
    { timeout: 15000 },
  );
  let after = await measure(viewer);
  for (let k = 0; k < 50 && after.gap > after.quantum; k++) {
    await new Promise((r) => setTimeout(r, 100));
    after = await measure(viewer);
  }
  assert.ok(after.gap <= after.quantum, `the viewer's patches miss the moved curve by ${after.gap} (quantum ${after.quantum})`);
  const moved = Math.hypot(after.mid[0] - before.mid[0], after.mid[1] - before.mid[1], after.mid[2] - before.mid[2]);
  assert.ok(moved > 0.02, `curve moved by ${moved}`);

  // The fairing button: every face faired, the boundary still on the curves.
  await editor.click('#fair-network');
  await viewer.waitForFunction(() => window.vsculpt.networkView.parts.get(1).network.faired.length === 6, null, { timeout: 30000 });
  let faired = await measure(viewer);
  for (let k = 0; k < 50 && (faired.revision <= after.revision || faired.gap > faired.quantum); k++) {
    await new Promise((r) => setTimeout(r, 100));
    faired = await measure(viewer);
  }
  assert.ok(faired.gap <= faired.quantum, `faired patches miss the curves by ${faired.gap}`);
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});

/** The drawn patches' positions of network part 1 in `page`, and their frame's revision. */
function drawn(page) {
  return page.evaluate(() => {
    const d = window.vsculpt.networkView.parts.get(1);
    return { positions: Array.from(d.mesh.geometry.getAttribute('position').array), revision: d.frame.revision };
  });
}

test('fairing runs as a job: progress in both browsers, the button cancels it, a finished fairing is drawn', async () => {
  const d = await bottleDesign('bottle-job');
  const editor = await openNetwork(d.editor);
  const viewer = await openNetwork(d.viewer);
  const before = await drawn(viewer);
  assert.equal(await editor.evaluate(() => document.querySelector('#fair-network').textContent), 'fair network');

  // Long runs of every face (steps of 0.1 %: tens of thousands of sweeps), sent as the button sends them.
  const sent = await editor.evaluate(() => window.vsculpt.networkView.fairAll(1, 100000, { relaxation: 0.001, tolerance: 1e-14 }));
  assert.equal(sent, 6);
  // The editor's button shows the progress and becomes a cancel button.
  await editor.waitForFunction(() => /^cancel fairing \(\d+ %\)$/.test(document.querySelector('#fair-network').textContent) && !document.querySelector('#fairing').hidden, null, { timeout: 15000 });
  // The viewer sees the progress (sweeps counting up), read-only: no fair button shown.
  await viewer.waitForFunction(
    () => !document.querySelector('#fairing').hidden && /^fairing 6 faces: \d+ % \(sweep [1-9]\d*\)$/.test(document.querySelector('#fair-status').textContent) && document.querySelector('#fair-progress').value >= 0,
    null,
    { timeout: 15000 },
  );
  assert.equal(await viewer.evaluate(() => document.querySelector('#fair-network').offsetParent), null, 'a viewer sees no fair button');
  assert.equal(await viewer.evaluate(() => window.vsculpt.networkView.jobs.size), 6);

  // A viewer joining now, whose page never hears a `fairing_progress` (its
  // socket drops them), learns of the six jobs from its snapshot alone.
  const late = await openNetwork(d.viewer, () => {
    const Native = window.WebSocket;
    window.droppedProgress = 0;
    window.WebSocket = class extends Native {
      set onmessage(handler) {
        super.onmessage = (ev) => {
          if (typeof ev.data === 'string' && ev.data.startsWith('{"type":"fairing_progress"')) window.droppedProgress++;
          else handler(ev);
        };
      }
      get onmessage() {
        return super.onmessage;
      }
    };
  });
  await late.waitForFunction(() => window.vsculpt.networkView.jobs.size === 6 && !document.querySelector('#fairing').hidden && /^fairing 6 faces: \d+ % \(sweep \d+\)$/.test(document.querySelector('#fair-status').textContent), null, { timeout: 15000 });
  const lateJobs = await late.evaluate(() => window.vsculpt.networkView.jobsOf(1).map((j) => [j.face, j.max_iterations]).sort((a, b) => a[0] - b[0]));
  assert.deepEqual(lateJobs, [0, 1, 2, 3, 4, 5].map((f) => [f, 100000]));
  await late.waitForFunction(() => window.droppedProgress > 0, null, { timeout: 15000 });

  // The button cancels every job: both browsers see them end, nothing changed.
  await editor.click('#fair-network');
  for (const page of [editor, viewer, late]) {
    await page.waitForFunction(() => window.vsculpt.networkView.jobs.size === 0 && document.querySelector('#fairing').hidden, null, { timeout: 15000 });
    assert.equal(await page.evaluate(() => window.vsculpt.networkView.lastEnded.outcome), 'cancelled');
    assert.equal(await page.evaluate(() => window.vsculpt.networkView.parts.get(1).network.faired.length), 0);
  }
  assert.deepEqual(late.errors, []);
  await late.close();
  assert.equal(await editor.evaluate(() => document.querySelector('#fair-network').textContent), 'fair network');
  const cancelled = await drawn(viewer);
  assert.equal(cancelled.revision, before.revision, 'a cancelled fairing sent new patches');
  assert.deepEqual(cancelled.positions, before.positions);

  // The button again (100 sweeps): the faired patches are drawn in the viewer.
  await editor.click('#fair-network');
  await viewer.waitForFunction(() => {
    const d = window.vsculpt.networkView.parts.get(1);
    return d.network.faired.length === 6 && window.vsculpt.networkView.jobs.size === 0;
  }, null, { timeout: 30000 });
  let after = await drawn(viewer);
  for (let k = 0; k < 50 && after.revision <= before.revision; k++) {
    await new Promise((r) => setTimeout(r, 100));
    after = await drawn(viewer);
  }
  assert.ok(after.revision > before.revision, 'no faired patches drawn');
  assert.equal(after.positions.length, before.positions.length);
  const moved = after.positions.reduce((m, x, i) => Math.max(m, Math.abs(x - before.positions[i])), 0);
  assert.ok(moved > 1e-4, `the drawn patches moved by ${moved}`);
  assert.equal(await viewer.evaluate(() => window.vsculpt.networkView.lastEnded.outcome), 'applied');
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});
