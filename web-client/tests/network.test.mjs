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
// `fairing_progress`, so nothing else could tell it). A ribbon handle
// dragged with the mouse sets its side's scale and then its twist: checked
// on the server's stored part (REST), in the viewer's network, and in the
// viewer's patches, whose exact boundary normal at the side's middle turns
// about the curve the way the ball was turned. A face's tuning handle
// dragged with the mouse along its normal sets the face's centre offset:
// checked on the server's stored part, and in the viewer's patches, whose
// boundary stays while the interior moves along the offset, the centre by
// all of it.

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
    return { gap, quantum: f.step * 0.5 * Math.sqrt(3) + 1e-5, boundary: boundary.size, vertices: [...boundary], mid: curveDerivs(d.curves[0].curve, 0.5).p, revision: f.revision };
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

/**
 * In `page`: the ribbon handle of side `side` of face `face` as the test
 * derives it from the curves alone (the side's middle c(t_m), the curve's
 * unit tangent there, the unit direction normal to it towards the mean of
 * the face's side middles, the stem 0.3 of that distance), and the screen
 * positions of the ball at (scale, twist) for each pair of `at`; with
 * `face` null, the side whose three points are inside the canvas and
 * farthest apart on screen.
 */
function handleScreen(page, face, side, at) {
  return page.evaluate(
    async ([face, side, at]) => {
      const { curveDerivs } = await import('/src/bspline.js');
      const v = window.vsculpt.view;
      const d = window.vsculpt.networkView.parts.get(1);
      const r = v.renderer.domElement.getBoundingClientRect();
      const curves = d.curves.map((c) => c.curve);
      const frame = (f, k) => {
        const sides = d.network.faces[f].sides;
        const mid = (s) => curveDerivs(curves[s.curve], (s.t_start + s.t_end) / 2);
        const c = [0, 1, 2].map((x) => sides.reduce((a, s) => a + mid(s).p[x], 0) / sides.length);
        const m = mid(sides[k]);
        const l = Math.hypot(...m.d1);
        const axis = m.d1.map((x) => x / l);
        const w = c.map((x, i) => x - m.p[i]);
        const along = w.reduce((a, x, i) => a + x * axis[i], 0);
        const n = w.map((x, i) => x - along * axis[i]);
        const dist = Math.hypot(...n);
        const inward = n.map((x) => x / dist);
        const across = [axis[1] * inward[2] - axis[2] * inward[1], axis[2] * inward[0] - axis[0] * inward[2], axis[0] * inward[1] - axis[1] * inward[0]];
        return { mid: m.p, axis, inward, across, reach: 0.3 * dist };
      };
      const screen = (fr, [scale, twist]) => {
        const p = [0, 1, 2].map((i) => fr.mid[i] + fr.reach * scale * (Math.cos(twist) * fr.inward[i] + Math.sin(twist) * fr.across[i]));
        const q = v.model.localToWorld(new v.camera.position.constructor(...p)).project(v.camera);
        return { x: r.left + ((q.x + 1) / 2) * r.width, y: r.top + ((1 - q.y) / 2) * r.height };
      };
      const inside = (s) => s.x > r.left + 30 && s.x < r.right - 30 && s.y > r.top + 30 && s.y < r.bottom - 30;
      let best = null;
      // A side with a meeting inside it has more than one edge: its twist
      // peaks in each edge's middle, not at the side's (left out).
      const inner = (s) => d.network.meetings.some((m) => m.curves.some(([c, t]) => c === s.curve && t > Math.min(s.t_start, s.t_end) + 1e-9 && t < Math.max(s.t_start, s.t_end) - 1e-9));
      d.network.faces.forEach((fc, f) =>
        fc.sides.forEach((sd, k) => {
          if (face !== null && (f !== face || k !== side)) return;
          if (face === null && inner(sd)) return;
          const fr = frame(f, k);
          const pts = at.map((a) => screen(fr, a));
          let sep = Infinity;
          for (let i = 0; i < pts.length; i++) for (let j = 0; j < i; j++) sep = Math.min(sep, Math.hypot(pts[i].x - pts[j].x, pts[i].y - pts[j].y));
          if (face === null && !pts.every(inside)) return;
          if (!best || sep > best.sep) best = { face: f, side: k, frame: fr, pts, sep };
        }),
      );
      return best;
    },
    [face, side, at],
  );
}

/** Drags with the mouse from screen point `a` to `b` in 10 steps. */
async function mouseDrag(page, a, b) {
  await page.mouse.move(a.x, a.y);
  await page.mouse.down();
  for (let k = 1; k <= 10; k++) await page.mouse.move(a.x + ((b.x - a.x) * k) / 10, a.y + ((b.y - a.y) * k) / 10);
  await page.mouse.up();
}

/** The network part as the server keeps it (REST, with the editor's token from `url`). */
async function storedNetwork(url) {
  const q = new URL(url).searchParams;
  const res = await fetch(`${server.base}/api/designs/${q.get('design')}?token=${encodeURIComponent(q.get('token'))}`);
  assert.equal(res.status, 200);
  const body = await res.json();
  return body.design.parts.find((p) => p.id === 1).body;
}

/** In `page`: the drawn frame's vertex nearest model point `p` (or vertex `index`): its index, distance, normal, the frame's quantisation bound and revision. */
function vertexNear(page, p, index = null) {
  return page.evaluate(
    ([p, index]) => {
      const f = window.vsculpt.networkView.parts.get(1).frame;
      let best = index;
      if (best === null) {
        let dist = Infinity;
        for (let i = 0; i < f.positions.length / 3; i++) {
          const q = Math.hypot(f.positions[3 * i] - p[0], f.positions[3 * i + 1] - p[1], f.positions[3 * i + 2] - p[2]);
          if (q < dist) [dist, best] = [q, i];
        }
      }
      const n = [0, 1, 2].map((x) => f.normals[3 * best + x]);
      const q = [0, 1, 2].map((x) => f.positions[3 * best + x] - p[x]);
      return { index: best, dist: Math.hypot(...q), quantum: f.step * Math.sqrt(3) + 1e-5, normal: n, revision: f.revision };
    },
    [p, index],
  );
}

test('a ribbon handle dragged with the mouse sets its side\'s scale, then its twist: on the server, in another browser, and in the patches\' tangent plane', async () => {
  const d = await bottleDesign('bottle-ribbons');
  const editor = await openNetwork(d.editor);
  const viewer = await openNetwork(d.viewer);
  // Hidden until asked for: a press where a handle would be grabs nothing.
  assert.equal(await editor.evaluate(() => window.vsculpt.networkView.handles.shown), false);
  await editor.click('#ribbon-handles');
  assert.equal(await editor.evaluate(() => document.querySelector('#ribbon-handles').getAttribute('aria-pressed')), 'true');

  // The side whose ball at scale 1, at scale 2 and at (2, twist 0.5) are on screen and farthest apart.
  const h = await handleScreen(editor, null, null, [[1, 0], [2, 0], [2, 0.5]]);
  assert.ok(h && h.sep > 25, `no handle to drag on screen: ${JSON.stringify(h)}`);
  // The page draws the ball where the test puts it (3D, model space).
  const ball = await editor.evaluate(([f, k]) => window.vsculpt.networkView.handles.parts.get(1).handles.find((x) => x.face === f && x.side === k).ball.position.toArray(), [h.face, h.side]);
  const expect1 = h.frame.mid.map((x, i) => x + h.frame.reach * h.frame.inward[i]);
  assert.ok(Math.hypot(...ball.map((x, i) => x - expect1[i])) < 1e-9 * (1 + h.frame.reach), `ball at ${ball}, expected ${expect1}`);
  const boundary = await vertexNear(viewer, h.frame.mid);
  assert.ok(boundary.dist <= boundary.quantum, `no mesh vertex at the side's middle: ${boundary.dist} (quantum ${boundary.quantum})`);

  // Scale: the ball dragged out to twice its reach.
  await mouseDrag(editor, h.pts[0], h.pts[1]);
  let stored = await storedNetwork(d.editor);
  for (let k = 0; k < 100 && !(stored.ribbons && stored.ribbons.scales.length); k++) {
    await new Promise((r) => setTimeout(r, 100));
    stored = await storedNetwork(d.editor);
  }
  assert.equal(stored.ribbons.scales.length, 1, JSON.stringify(stored.ribbons));
  const [sf, ss, scale] = stored.ribbons.scales[0];
  assert.deepEqual([sf, ss], [h.face, h.side]);
  assert.ok(Math.abs(scale - 2) < 0.1, `stored scale ${scale}`);
  assert.deepEqual(stored.ribbons.twists || [], [], 'a drag along the stem set a twist');
  await viewer.waitForFunction(([f, k, s]) => {
    const n = window.vsculpt.networkView.parts.get(1).network;
    return n.ribbons && n.ribbons[f][k].scale === s;
  }, [h.face, h.side, scale], { timeout: 15000 });
  let scaled = await vertexNear(viewer, h.frame.mid, boundary.index);
  for (let k = 0; k < 50 && scaled.revision <= boundary.revision; k++) {
    await new Promise((r) => setTimeout(r, 100));
    scaled = await vertexNear(viewer, h.frame.mid, boundary.index);
  }
  assert.ok(scaled.revision > boundary.revision, 'no new patches after the scale');
  // The editor's handles are redrawn where the server put them.
  await editor.waitForFunction(([f, k, s]) => {
    const n = window.vsculpt.networkView.parts.get(1).network;
    return n.ribbons && n.ribbons[f][k].scale === s;
  }, [h.face, h.side, scale], { timeout: 15000 });

  // Twist: the ball turned about the curve by 0.5 rad.
  const t = await handleScreen(editor, h.face, h.side, [[scale, 0], [2, 0.5]]);
  await mouseDrag(editor, t.pts[0], t.pts[1]);
  for (let k = 0; k < 100 && !(stored.ribbons.twists && stored.ribbons.twists.length); k++) {
    await new Promise((r) => setTimeout(r, 100));
    stored = await storedNetwork(d.editor);
  }
  assert.ok(stored.ribbons.twists.length >= 1, JSON.stringify(stored.ribbons));
  for (const [, twist] of stored.ribbons.twists) assert.ok(Math.abs(twist - 0.5) < 0.06, `stored twist ${twist}`);
  await viewer.waitForFunction(([f, k]) => {
    const n = window.vsculpt.networkView.parts.get(1).network;
    return n.ribbons && Math.abs(n.ribbons[f][k].twist) > 0.3;
  }, [h.face, h.side], { timeout: 15000 });
  let twisted = await vertexNear(viewer, h.frame.mid, boundary.index);
  for (let k = 0; k < 50 && twisted.revision <= scaled.revision; k++) {
    await new Promise((r) => setTimeout(r, 100));
    twisted = await vertexNear(viewer, h.frame.mid, boundary.index);
  }
  // The tangent plane at the side's middle turned about the curve's
  // tangent the way the ball did (the boundary normals are the patch's own).
  const a = h.frame.axis;
  const proj = (n) => {
    const s = n.reduce((x, y, i) => x + y * a[i], 0);
    return n.map((x, i) => x - s * a[i]);
  };
  const [n0, n1] = [proj(scaled.normal), proj(twisted.normal)];
  const c = [n0[1] * n1[2] - n0[2] * n1[1], n0[2] * n1[0] - n0[0] * n1[2], n0[0] * n1[1] - n0[1] * n1[0]];
  const angle = Math.atan2(c.reduce((x, y, i) => x + y * a[i], 0), n0.reduce((x, y, i) => x + y * n1[i], 0));
  console.log(`ribbon handle face ${h.face} side ${h.side}: scale ${scale}, twist ${stored.ribbons.twists.map((x) => x[1])}, normal at the side's middle turned ${angle.toFixed(4)} rad about the curve`);
  assert.ok(angle > 0.25 && angle < 0.56, `normal turned ${angle} rad about the curve's tangent`);
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});

/**
 * In `page`: every face's tuning handle as the test derives it from the
 * curves alone (the face's centre: the mean of its sides' middles; its
 * normal: the Newell normal of those middles on the network's `up` side;
 * the ball 0.25 of the middles' mean distance from the centre out along
 * the normal) with the screen positions of the ball at centre offsets 0
 * and `lifts` × that height along the normal; the face whose two points
 * are inside the canvas and farthest apart on screen.
 */
function tuningScreen(page, lifts) {
  return page.evaluate(
    async (lifts) => {
      const { curveDerivs } = await import('/src/bspline.js');
      const v = window.vsculpt.view;
      const d = window.vsculpt.networkView.parts.get(1);
      const r = v.renderer.domElement.getBoundingClientRect();
      const screen = (p) => {
        const q = v.model.localToWorld(new v.camera.position.constructor(...p)).project(v.camera);
        return { x: r.left + ((q.x + 1) / 2) * r.width, y: r.top + ((1 - q.y) / 2) * r.height };
      };
      const inside = (s) => s.x > r.left + 30 && s.x < r.right - 30 && s.y > r.top + 30 && s.y < r.bottom - 30;
      let best = null;
      d.network.faces.forEach((fc, f) => {
        const mids = fc.sides.map((s) => curveDerivs(d.curves[s.curve].curve, (s.t_start + s.t_end) / 2).p);
        const c = [0, 1, 2].map((x) => mids.reduce((a, m) => a + m[x], 0) / mids.length);
        const n = [0, 0, 0];
        mids.forEach((m, k) => {
          const a = m.map((x, i) => x - c[i]);
          const b = mids[(k + 1) % mids.length].map((x, i) => x - c[i]);
          n[0] += a[1] * b[2] - a[2] * b[1];
          n[1] += a[2] * b[0] - a[0] * b[2];
          n[2] += a[0] * b[1] - a[1] * b[0];
        });
        const len = Math.hypot(...n);
        const up = d.network.up;
        const sign = n[0] * up[0] + n[1] * up[1] + n[2] * up[2] < 0 ? -1 : 1;
        const normal = n.map((x) => (sign * x) / len);
        const lift = (0.25 * mids.reduce((a, m) => a + Math.hypot(...m.map((x, i) => x - c[i])), 0)) / mids.length;
        const at = (s) => c.map((x, i) => x + (1 + s) * lift * normal[i]);
        const pts = [screen(at(0)), screen(at(lifts))];
        const sep = Math.hypot(pts[0].x - pts[1].x, pts[0].y - pts[1].y);
        if (!pts.every(inside)) return;
        if (!best || sep > best.sep) best = { face: f, sides: fc.sides.length, normal, lift, ball: at(0), pts, sep };
      });
      return best;
    },
    lifts,
  );
}

test('a tuning handle dragged with the mouse moves its face\'s interior along the handle and keeps every boundary', async () => {
  const d = await bottleDesign('bottle-tuning');
  const editor = await openNetwork(d.editor);
  const viewer = await openNetwork(d.viewer);
  assert.equal(await editor.evaluate(() => window.vsculpt.networkView.tuning.shown), false);
  await editor.click('#ribbon-handles');
  assert.equal(await editor.evaluate(() => window.vsculpt.networkView.tuning.shown), true, 'the tuning handles show with the ribbon handles');

  const lifts = 1.5;
  const h = await tuningScreen(editor, lifts);
  assert.ok(h && h.sep > 25, `no tuning handle to drag on screen: ${JSON.stringify(h)}`);
  // The page draws the ball where the test puts it.
  const ball = await editor.evaluate((f) => window.vsculpt.networkView.tuning.parts.get(1).handles.find((x) => x.face === f).ball.position.toArray(), h.face);
  assert.ok(Math.hypot(...ball.map((x, i) => x - h.ball[i])) < 1e-9 * (1 + h.lift), `ball at ${ball}, expected ${h.ball}`);
  const before = await viewer.evaluate(() => {
    const f = window.vsculpt.networkView.parts.get(1).frame;
    return { positions: Array.from(f.positions), revision: f.revision, quantum: f.step * 0.5 * Math.sqrt(3) + 1e-5 };
  });
  // The frame's boundary vertices (edges of one triangle: each face's mesh is its own).
  const edges = await measure(viewer);
  assert.equal(edges.revision, before.revision);
  const boundary = new Set(edges.vertices);

  await mouseDrag(editor, h.pts[0], h.pts[1]);
  let stored = await storedNetwork(d.editor);
  for (let k = 0; k < 100 && !(stored.ribbons && stored.ribbons.tuning && stored.ribbons.tuning.length); k++) {
    await new Promise((r) => setTimeout(r, 100));
    stored = await storedNetwork(d.editor);
  }
  assert.equal(stored.ribbons.tuning.length, 1, JSON.stringify(stored.ribbons));
  const [face, handles] = stored.ribbons.tuning[0];
  assert.equal(face, h.face);
  assert.equal(handles.length, h.sides + 1);
  const h0 = handles[0];
  const want = h.normal.map((x) => x * lifts * h.lift);
  assert.ok(Math.hypot(...h0.map((x, i) => x - want[i])) < 0.05 * Math.hypot(...want), `stored centre offset ${h0}, expected ${want}`);
  for (const c of handles.slice(1)) assert.deepEqual(c, [0, 0, 0], 'a corner handle changed');
  assert.deepEqual(stored.ribbons.scales, [], 'the drag grabbed a ribbon handle');

  // The viewer's new patches: the boundary of every face where it was;
  // every vertex moved along h₀ by at most |h₀| (the centre's weight is 1
  // at the domain's centre, between 0 and 1 elsewhere), the centre by |h₀|.
  await viewer.waitForFunction((rev) => window.vsculpt.networkView.parts.get(1).frame.revision > rev, before.revision, { timeout: 15000 });
  const after = await viewer.evaluate(() => Array.from(window.vsculpt.networkView.parts.get(1).frame.positions));
  assert.equal(after.length, before.positions.length);
  const len = Math.hypot(...h0);
  const dir = h0.map((x) => x / len);
  const q = 2 * before.quantum;
  let largest = 0;
  let boundaryMove = 0;
  let offLine = 0;
  for (let i = 0; i < after.length / 3; i++) {
    const m = [0, 1, 2].map((x) => after[3 * i + x] - before.positions[3 * i + x]);
    const along = m[0] * dir[0] + m[1] * dir[1] + m[2] * dir[2];
    const size = Math.hypot(...m);
    largest = Math.max(largest, size);
    if (boundary.has(i)) boundaryMove = Math.max(boundaryMove, size);
    offLine = Math.max(offLine, Math.hypot(...m.map((x, k) => x - along * dir[k])));
    assert.ok(along > -q, `vertex ${i} moved against the handle by ${along}`);
  }
  console.log(`tuning handle face ${h.face} (${h.sides} sides): |h0| ${len.toFixed(4)}, largest move ${largest.toFixed(4)}, boundary ${boundaryMove.toExponential(2)}, off the handle's line ${offLine.toExponential(2)} (quantum ${before.quantum.toExponential(2)})`);
  assert.ok(boundaryMove <= q, `a boundary vertex moved by ${boundaryMove}`);
  assert.ok(offLine <= q, `a vertex moved off the handle's line by ${offLine}`);
  assert.ok(largest <= len + q, `a vertex moved ${largest}, more than |h0| = ${len}`);
  // The five-sided and four-sided faces' meshes have a vertex at the domain's centre.
  if (h.sides > 3) assert.ok(largest >= len - q, `the centre moved ${largest}, not |h0| = ${len}`);
  assert.ok(largest > 10 * q, 'the interior did not move');
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});
