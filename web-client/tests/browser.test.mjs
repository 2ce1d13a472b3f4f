// End-to-end in real headless Chromium against the real server: the page
// draws the design's parts, an editor creates a position constraint by clicking the
// selected surface part and drags it with the gizmo, the server's REST API shows the
// surface moved, curvature and zebra views change the picture, a viewer sees
// the change live and cannot edit, and the page reconnects by itself after
// the server restarts.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { mkdtempSync, mkdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { webDir, serverBinProblem, startServer, stopServer, launchChromium, openClient, gizmoZArrow, isLocal, shownPoints } from './harness.mjs';

const artifacts = join(webDir, 'test-artifacts');
const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-web-'));
let server;
let links;
let browser;

before(async () => {
  const problem = serverBinProblem();
  assert.equal(problem, null, problem);
  mkdirSync(artifacts, { recursive: true });
  server = await startServer({ dataDir });
  links = server;
  browser = await launchChromium();
});

after(async () => {
  if (browser) await browser.close();
  await stopServer(server);
  rmSync(dataDir, { recursive: true, force: true });
});

const open = (url, setup) => openClient(browser, url, setup);

/** Fraction of canvas pixels that differ from the background colour, and a colour histogram key. */
async function pixels(page) {
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  return page.evaluate(() => {
    const src = window.vsculpt.view.renderer.domElement;
    const c = document.createElement('canvas');
    c.width = src.width;
    c.height = src.height;
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let drawn = 0;
    let red = 0;
    let dark = 0;
    for (let i = 0; i < d.length; i += 4) {
      const bg = Math.abs(d[i] - 0x20) + Math.abs(d[i + 1] - 0x24) + Math.abs(d[i + 2] - 0x2b) < 12;
      if (!bg) drawn++;
      if (!bg && d[i] > d[i + 2] + 40) red++;
      if (!bg && d[i] < 40 && d[i + 1] < 40 && d[i + 2] < 40) dark++;
    }
    const n = d.length / 4;
    // Every 7th pixel's colour, for comparing two pictures of one view.
    const sample = [];
    for (let i = 0; i < d.length; i += 28) sample.push(d[i], d[i + 1], d[i + 2]);
    return { drawn: drawn / n, red: red / n, dark: dark / n, sample };
  });
}

async function designJson(token) {
  const res = await fetch(`${links.base}/api/designs/1?token=${token}`);
  assert.equal(res.status, 200);
  return res.json();
}

const tokenOf = (url) => new URL(url).searchParams.get('token');

test('editor: draws, creates by clicking, drags with the gizmo, analysis views; viewer follows live and cannot edit', async () => {
  const editor = await open(links.editor);
  const shot = await pixels(editor);
  await editor.screenshot({ path: join(artifacts, 'editor.png') });
  assert.ok(shot.drawn > 0.05, `surface drawn: ${shot.drawn}`);

  const viewer = await open(links.viewer);
  assert.equal(await viewer.evaluate(() => window.vsculpt.state.access), 'viewer');
  assert.equal(await viewer.isVisible('#commit'), false, 'viewer has no edit controls');

  // Click the middle of the surface in "point icon" mode: a position constraint.
  const before = await editor.evaluate(() => window.vsculpt.state.icons.size);
  await editor.selectOption('#create', 'point');
  await editor.selectOption('#create-role', 'position');
  const centre = await editor.evaluate(() => {
    const v = window.vsculpt.view;
    const { partsView, state } = window.vsculpt;
    const geometry = partsView.drawings.get(state.selectedPart).mesh.geometry;
    const s = geometry.boundingSphere;
    const p = s.center.clone();
    // The selected surface's point under its bounding-sphere centre: nearest vertex to it in xy.
    const pos = geometry.attributes.position.array;
    let best = 0;
    let bd = Infinity;
    for (let i = 0; i < pos.length; i += 3) {
      const dd = (pos[i] - p.x) ** 2 + (pos[i + 1] - p.y) ** 2;
      if (dd < bd) {
        bd = dd;
        best = i;
      }
    }
    p.set(pos[best], pos[best + 1], pos[best + 2]).project(v.camera);
    const r = v.renderer.domElement.getBoundingClientRect();
    return { x: r.left + ((p.x + 1) / 2) * r.width, y: r.top + ((1 - p.y) / 2) * r.height };
  });
  await editor.mouse.click(centre.x, centre.y);
  await editor.waitForFunction((n) => window.vsculpt.state.icons.size > n, before, { timeout: 10000 });
  const icon = await editor.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  const created = await editor.evaluate((id) => window.vsculpt.state.icons.get(id), icon);
  assert.equal(created.role.kind, 'position');
  assert.equal(created.part, await editor.evaluate(() => window.vsculpt.state.selectedPart), 'created on the selected part');

  // Select it by clicking its handle, then drag the gizmo's Z arrow upward.
  await editor.selectOption('#create', 'none');
  await editor.evaluate((id) => window.vsculpt.select(id), icon);
  const restBefore = await designJson(tokenOf(links.editor));
  const zHandle = await gizmoZArrow(editor);
  await editor.mouse.move(zHandle.from.x, zHandle.from.y);
  await editor.mouse.down();
  for (let k = 1; k <= 10; k++) await editor.mouse.move(zHandle.from.x, zHandle.from.y - 6 * k);
  await editor.mouse.up();
  await editor.waitForFunction(
    (id) => {
      const i = window.vsculpt.state.icons.get(id);
      return i && i.state === 'passive' && window.vsculpt.state.frames > 1;
    },
    icon,
    { timeout: 10000 },
  );
  await new Promise((r) => setTimeout(r, 500));
  const restAfter = await designJson(tokenOf(links.editor));
  assert.notDeepEqual(restAfter.design, restBefore.design, 'the gizmo drag moved the surface on the server');
  const moved = await editor.evaluate((id) => window.vsculpt.state.icons.get(id).target, icon);
  assert.ok(moved[2] > created.target[2] + 1e-3, `dragged upward: ${created.target} → ${moved}`);
  // The drag's frames were tessellated by the worker and shown in place (no fallback to the main thread).
  const perf = await editor.evaluate(() => window.vsculpt.perf);
  assert.equal(perf.workerFailed, null);
  assert.ok(perf.shown > 0 && perf.shown <= perf.submitted, `worker frames shown: ${JSON.stringify(perf)}`);
  assert.ok(editor.requests.some((u) => u.endsWith('/tess-worker.js')), 'the worker script was loaded');
  await editor.screenshot({ path: join(artifacts, 'editor-dragged.png') });

  // The viewer saw it live: same revision and control points.
  await viewer.waitForFunction((id) => window.vsculpt.state.icons.has(id), icon, { timeout: 10000 });
  const [pe, pv] = await Promise.all([editor, viewer].map((p) => shownPoints(p)));
  assert.deepEqual(pv, pe);

  // A viewer's edit is refused by the server.
  await viewer.evaluate((id) => window.vsculpt.send({ type: 'set_state', icon: id, state: 'sleeping' }), icon);
  await viewer.waitForFunction(() => (window.vsculpt.state.lastError || '').startsWith('forbidden'), null, { timeout: 10000 });
  assert.equal(await editor.evaluate((id) => window.vsculpt.state.icons.get(id).state, icon), 'passive');

  // Curvature and zebra views change the picture. They colour surfaces; the demo's spool body keeps
  // its own shading, so it is hidden on this page for the comparison.
  await editor.evaluate(() => {
    for (const b of window.vsculpt.bodyView.bodies.values()) b.group.visible = false;
  });
  const shaded = await pixels(editor);
  await editor.selectOption('#mode', 'mean');
  const mean = await pixels(editor);
  await editor.screenshot({ path: join(artifacts, 'mean-curvature.png') });
  await editor.selectOption('#mode', 'zebra');
  const zebra = await pixels(editor);
  await editor.screenshot({ path: join(artifacts, 'zebra.png') });
  // The mean-curvature view recolours the surface: most drawn pixels change
  // colour (the demo shell's curvature varies smoothly, so which hue
  // dominates depends on the shape; that it is recoloured does not).
  const recoloured = (a, b) => {
    let k = 0;
    for (let i = 0; i < a.sample.length; i += 3) {
      const dc = Math.abs(a.sample[i] - b.sample[i]) + Math.abs(a.sample[i + 1] - b.sample[i + 1]) + Math.abs(a.sample[i + 2] - b.sample[i + 2]);
      if (dc > 60) k++;
    }
    return k / (a.sample.length / 3);
  };
  const counts = (p) => ({ drawn: p.drawn, red: p.red, dark: p.dark });
  assert.ok(recoloured(shaded, mean) > 0.5 * shaded.drawn, `curvature colours: ${JSON.stringify({ shaded: counts(shaded), mean: counts(mean), recoloured: recoloured(shaded, mean) })}`);
  assert.ok(zebra.dark > shaded.dark + 0.01, `zebra stripes: ${JSON.stringify({ shaded: counts(shaded), zebra: counts(zebra) })}`);
  assert.deepEqual(editor.errors, []);
  await viewer.close();
  await editor.close();
});

/** Installs iwer's emulated Meta Quest 3 (from the registry package the server serves) as the page's WebXR runtime. */
async function emulateQuest3(page) {
  await page.evaluate(async () => {
    const { XRDevice, metaQuest3 } = await import('/vendor/iwer/build/iwer.module.js');
    const dev = new XRDevice(metaQuest3);
    dev.installRuntime({ forceInstall: true });
    window.__xrdev = dev;
  });
}

async function enterVr(page) {
  await page.click('#enter-vr');
  await page.waitForFunction(() => window.vsculpt.view.renderer.xr.isPresenting, null, { timeout: 15000 });
}

test('VR (iwer emulated Quest 3): controller models from our server, the design at real size on a table, squeeze on an icon, a 0.2 m hand motion moves it 200 mm', async () => {
  const page = await open(links.editor);
  await emulateQuest3(page);
  // A position constraint in the middle of the surface.
  const before = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.5, v: 0.5 }, { kind: 'position' }));
  await page.waitForFunction((n) => window.vsculpt.state.icons.size > n, before, { timeout: 10000 });
  const icon = await page.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  const start = await page.evaluate((id) => window.vsculpt.state.icons.get(id).target, icon);

  await enterVr(page);
  // Both controllers get their glTF model from /vendor/webxr-profiles on our server; the stand-ins hide.
  await page.waitForFunction(() => window.vsculpt.xr.modelsLoaded >= 2, null, { timeout: 20000 });
  assert.deepEqual(await page.evaluate(() => window.vsculpt.xr.controllers.map((c) => c.fallback.visible)), [false, false]);
  const base = new URL(links.base).origin;
  const models = page.requests.filter((u) => u.startsWith(`${base}/vendor/webxr-profiles/`) && u.endsWith('.glb'));
  assert.ok(models.length >= 1, `a controller glTF fetched from the server: ${page.requests.filter((u) => !u.includes('/src/')).join(' ')}`);
  assert.ok(page.requests.includes(`${base}/vendor/webxr-profiles/profilesList.json`), 'the profile list came from the server');
  // Real scale, y up, on a table in front of the headset, which is outside it.
  const placed = await page.evaluate(() => {
    const v = window.vsculpt.view;
    const local = v.bounds().clone();
    const world = local.clone().applyMatrix4(v.model.matrixWorld);
    const eye = v.renderer.xr.getCamera().getWorldPosition(new v.camera.position.constructor());
    const size = (b) => [b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z];
    return { local: size(local), world: size(world), bottom: world.min.y, inside: world.containsPoint(eye), eye: eye.toArray() };
  });
  assert.equal(placed.inside, false, `the headset (${placed.eye}) is outside the model`);
  // Model x (mm) → world x (m); model y → world −z; model z (up) → world y (up).
  const want = [placed.local[0] / 1000, placed.local[2] / 1000, placed.local[1] / 1000];
  placed.world.forEach((w, k) => assert.ok(Math.abs(w - want[k]) < 1e-6, `real size along ${k}: ${w} m vs ${want[k]} m`));
  assert.ok(Math.abs(placed.bottom - 0.9) < 1e-6, `on a 0.9 m table: bottom at ${placed.bottom}`);
  const frames = () => page.evaluate(() => new Promise((r) => setTimeout(r, 300)));
  // Put the right controller's grip on the icon: correct the emulator's pose by
  // the offset between where it was put and where three's grip group ended up.
  for (let k = 0; k < 3; k++) {
    await frames();
    await page.evaluate((p) => {
      const v = window.vsculpt;
      const at = v.view.model.localToWorld(new v.view.camera.position.constructor(...p));
      const grip = v.xr.gripPosition(1);
      const c = window.__xrdev.controllers.right;
      c.position.set(c.position.x + at.x - grip.x, c.position.y + at.y - grip.y, c.position.z + at.z - grip.z);
    }, start);
  }
  await frames();
  const restBefore = await designJson(tokenOf(links.editor));
  await page.evaluate(() => window.__xrdev.controllers.right.updateButtonValue('squeeze', 1));
  await page.waitForFunction((id) => window.vsculpt.xr.grab && window.vsculpt.xr.grab.id === id, icon, { timeout: 10000 });
  // Raise the hand 0.2 m in small steps, then let go.
  for (let k = 1; k <= 10; k++) {
    await page.evaluate(() => {
      window.__xrdev.controllers.right.position.y += 0.02;
    });
    await page.evaluate(() => new Promise((r) => setTimeout(r, 60)));
  }
  await frames();
  await page.evaluate(() => window.__xrdev.controllers.right.updateButtonValue('squeeze', 0));
  await page.waitForFunction(() => window.vsculpt.xr.grab === null, null, { timeout: 10000 });
  assert.ok((await page.evaluate(() => window.vsculpt.xr.drags)) > 0, 'drag messages were sent');
  await page.waitForFunction(
    ([id, z]) => {
      const i = window.vsculpt.state.icons.get(id);
      return i && i.target[2] > z + 150;
    },
    [icon, start[2]],
    { timeout: 10000 },
  );
  // Raised 0.2 m in the room = 200 mm up in the model (z), nothing sideways.
  const moved = await page.evaluate((id) => window.vsculpt.state.icons.get(id).target, icon);
  assert.ok(Math.abs(moved[2] - start[2] - 200) < 0.5, `moved up ${moved[2] - start[2]} mm`);
  assert.ok(Math.hypot(moved[0] - start[0], moved[1] - start[1]) < 0.5, `sideways ${moved[0] - start[0]}, ${moved[1] - start[1]} mm`);
  await new Promise((r) => setTimeout(r, 500));
  const restAfter = await designJson(tokenOf(links.editor));
  assert.notDeepEqual(restAfter.design, restBefore.design, 'the VR drag moved the surface on the server');
  await page.screenshot({ path: join(artifacts, 'vr.png') });
  assert.deepEqual(page.errors, []);
  await page.evaluate(() => window.vsculpt.view.renderer.xr.getSession().end());
  assert.deepEqual(page.requests.filter((u) => !isLocal(u)), [], 'no request left this machine');
  await page.close();
});

test('VR: squeezing where no icon is grabs the model: it follows the hand, and a second hand scales it', async () => {
  const page = await open(links.editor);
  await emulateQuest3(page);
  await enterVr(page);
  const frames = () => page.evaluate(() => new Promise((r) => setTimeout(r, 300)));
  // Both hands high above the table, pointing ahead over the model: nothing within reach or under the rays.
  await page.evaluate(() => {
    const { left, right } = window.__xrdev.controllers;
    left.position.set(-0.2, 2.0, 0);
    right.position.set(0.2, 2.0, 0);
  });
  await frames();
  const at = () => page.evaluate(() => ({ p: window.vsculpt.view.model.position.toArray(), s: window.vsculpt.view.model.scale.x }));
  const start = await at();
  await page.evaluate(() => window.__xrdev.controllers.right.updateButtonValue('squeeze', 1));
  await page.waitForFunction(() => window.vsculpt.xr.modelGrab !== null, null, { timeout: 10000 });
  assert.equal(await page.evaluate(() => window.vsculpt.xr.grab), null, 'no icon grabbed');
  await page.evaluate(() => {
    window.__xrdev.controllers.right.position.x += 0.1;
  });
  await frames();
  const moved = await at();
  assert.ok(Math.abs(moved.p[0] - start.p[0] - 0.1) < 1e-3, `followed the hand: ${moved.p[0] - start.p[0]} m`);
  assert.ok(Math.abs(moved.s - start.s) < 1e-9, 'one hand does not scale');
  // The left hand joins; spreading the hands scales the model by the ratio of their distances.
  await page.evaluate(() => window.__xrdev.controllers.left.updateButtonValue('squeeze', 1));
  await page.waitForFunction(() => window.vsculpt.xr.modelGrab && window.vsculpt.xr.modelGrab.second, null, { timeout: 10000 });
  const d0 = await page.evaluate(() => window.vsculpt.xr.modelGrab.second.distance);
  await page.evaluate(() => {
    window.__xrdev.controllers.left.position.x -= 0.5;
  });
  await frames();
  const d1 = await page.evaluate(() => window.vsculpt.xr.handDistance());
  const scaled = await at();
  assert.ok(d1 / d0 > 1.5, `the hands spread: ${d0} → ${d1} m`);
  assert.ok(Math.abs(scaled.s / start.s - d1 / d0) < 1e-3, `scaled ×${scaled.s / start.s}, hands ×${d1 / d0}`);
  await page.evaluate(() => {
    window.__xrdev.controllers.left.updateButtonValue('squeeze', 0);
    window.__xrdev.controllers.right.updateButtonValue('squeeze', 0);
  });
  await page.waitForFunction(() => window.vsculpt.xr.modelGrab === null, null, { timeout: 10000 });
  assert.deepEqual(page.errors, []);
  await page.evaluate(() => window.vsculpt.view.renderer.xr.getSession().end());
  assert.equal(await page.evaluate(() => window.vsculpt.view.model.scale.x), 1, 'back on the screen in model units');
  await page.close();
});

test('VR: a controller model that cannot be loaded is logged and the simple controller stays', async () => {
  const page = await open(links.editor, (p) => p.route('**/vendor/webxr-profiles/**/*.glb', (r) => r.fulfill({ status: 404, body: 'gone' })));
  await emulateQuest3(page);
  await enterVr(page);
  await page.waitForFunction(() => window.vsculpt.xr.modelLoader.failures >= 1, null, { timeout: 20000 });
  await page.evaluate(() => new Promise((r) => setTimeout(r, 300)));
  assert.equal(await page.evaluate(() => window.vsculpt.xr.modelsLoaded), 0);
  assert.deepEqual(await page.evaluate(() => window.vsculpt.xr.controllers.map((c) => c.fallback.visible)), [true, true]);
  assert.ok(page.warnings.some((w) => w.includes('did not load') && w.includes('simple controller')), `logged: ${page.warnings.join(' | ')}`);
  assert.deepEqual(page.errors, []);
  await page.evaluate(() => window.vsculpt.view.renderer.xr.getSession().end());
  await page.close();
});

test('the first framing shows the whole demo: the mouse\'s four parts and the spool beside it are all in the view', async () => {
  // A body frame is drawn as it arrives, before the surfaces' tessellation: framing the first drawing
  // framed the spool alone (the mouse off to the left), or the mouse alone (the spool cut off on the right).
  const page = await open(links.editor);
  await page.waitForFunction(() => [...window.vsculpt.bodyView.bodies.values()].some((b) => b.frame), null, { timeout: 15000 });
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const shown = await page.evaluate(() => {
    const { view, partsView, bodyView } = window.vsculpt;
    const V = view.camera.position.constructor;
    // The largest |x| or |y| of a box's corners in normalised device coordinates (≤ 1: on screen).
    const extent = (box) => {
      let m = 0;
      for (const x of [box.min.x, box.max.x]) {
        for (const y of [box.min.y, box.max.y]) {
          for (const z of [box.min.z, box.max.z]) {
            const q = new V(x, y, z).project(view.camera);
            m = Math.max(m, Math.abs(q.x), Math.abs(q.y));
          }
        }
      }
      return m;
    };
    const parts = [...partsView.drawings.values()].map((d) => extent(d.mesh.geometry.boundingBox));
    const bodies = [...bodyView.bodies.values()].map((b) => {
      if (!b.mesh.geometry.boundingBox) b.mesh.geometry.computeBoundingBox();
      return extent(b.mesh.geometry.boundingBox);
    });
    return { parts, bodies, framed: view.framedWhole };
  });
  assert.equal(shown.parts.length, 4, 'the mouse: shell, two side panels, feature line');
  assert.equal(shown.bodies.length, 1, 'the spool');
  for (const e of [...shown.parts, ...shown.bodies]) assert.ok(e <= 1, `a part reaches ${e} of the half-view: ${JSON.stringify(shown)}`);
  assert.ok(shown.framed, 'the framing waited for every part');
  // And it is framed, not lost in the distance: the whole spans a good part of the view.
  assert.ok(Math.max(...shown.parts, ...shown.bodies) > 0.5, JSON.stringify(shown));
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('after a gizmo drag the orbit controls hold no stale rotation: moving the mouse with no button keeps the camera', async () => {
  const page = await open(links.editor);
  const before = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.35, v: 0.6 }, { kind: 'position' }));
  await page.waitForFunction((n) => window.vsculpt.state.icons.size > n, before, { timeout: 10000 });
  const icon = await page.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  await page.evaluate((id) => window.vsculpt.select(id), icon);
  const z = await gizmoZArrow(page);
  const camera = () => page.evaluate(() => window.vsculpt.view.camera.position.toArray());
  // OrbitControls.update re-derives the position every frame (round-off of ~1e-13 relative); a jump is far larger.
  const moved = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]) > 1e-9 * Math.hypot(...b);
  const start = await camera();
  const target = await page.evaluate((id) => window.vsculpt.state.icons.get(id).target, icon);
  // Count the rotations the orbit controls begin.
  await page.evaluate(() => {
    window.__orbitStarts = 0;
    window.vsculpt.view.controls.addEventListener('start', () => window.__orbitStarts++);
  });
  await page.mouse.move(z.from.x, z.from.y);
  await page.mouse.down();
  for (let k = 1; k <= 8; k++) await page.mouse.move(z.from.x + 3 * k, z.from.y - 6 * k);
  // While the gizmo is held, the orbit controls have begun nothing (state NONE = -1).
  assert.deepEqual(await page.evaluate(() => [window.__orbitStarts, window.vsculpt.view.controls.state]), [0, -1]);
  await page.mouse.up();
  assert.equal(await page.evaluate(() => window.vsculpt.view.controls.enabled), true, 'orbit controls enabled again after the drag');
  await page.waitForFunction(([id, z0]) => window.vsculpt.state.icons.get(id).target[2] > z0 + 1e-3, [icon, target[2]], { timeout: 10000 });
  const afterDrag = await camera();
  assert.ok(!moved(afterDrag, start), `the gizmo drag itself did not orbit the camera: ${start} → ${afterDrag}`);
  // No button held: these moves must not rotate the view.
  for (let k = 1; k <= 10; k++) await page.mouse.move(z.from.x - 25 * k, z.from.y + 10 * k);
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const afterMoves = await camera();
  assert.ok(!moved(afterMoves, start), `the camera did not move: ${start} → ${afterMoves}`);
  // The orbit controls still work afterwards: a left-button drag on empty background rotates. Empty:
  // the canvas itself is there (the body panel sits over the view's lower left when the design has a body).
  const bg = await page.evaluate(() => {
    const canvas = window.vsculpt.view.renderer.domElement;
    const r = canvas.getBoundingClientRect();
    for (const [fx, fy] of [[0.1, 0.93], [0.9, 0.93], [0.5, 0.93], [0.9, 0.15], [0.1, 0.15]]) {
      const at = { x: Math.round(r.left + fx * r.width), y: Math.round(r.top + fy * r.height) };
      if (document.elementFromPoint(at.x, at.y) === canvas && document.elementFromPoint(at.x + 100, at.y) === canvas) return at;
    }
    return null;
  });
  assert.ok(bg, 'a place where the view is not covered');
  await page.mouse.move(bg.x, bg.y);
  await page.mouse.down();
  for (let k = 1; k <= 5; k++) await page.mouse.move(bg.x + 20 * k, bg.y);
  await page.mouse.up();
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const orbited = await camera();
  assert.ok(moved(orbited, start), `an ordinary drag still orbits: ${start} → ${orbited}`);
  assert.equal(await page.evaluate(() => window.__orbitStarts), 1);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('?worker=0: geometry frames are tessellated on the main thread and shown', async () => {
  const page = await open(`${links.editor}&worker=0`);
  const before = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.6, v: 0.4 }, { kind: 'load' }));
  await page.waitForFunction((n) => window.vsculpt.state.icons.size > n, before, { timeout: 10000 });
  const icon = await page.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  // The mean height of the drawn mesh (its vertex z), which a load pulled up raises wherever it is;
  // installed in the page once, so the wait below can call it.
  await page.evaluate((id) => {
    const { partsView, state } = window.vsculpt;
    const part = state.icons.get(id).part;
    window.__meanZ = () => {
      const a = partsView.drawings.get(part).mesh.geometry.attributes.position.array;
      let z = 0;
      for (let k = 2; k < a.length; k += 3) z += a[k];
      return z / (a.length / 3);
    };
  }, icon);
  const z0 = await page.evaluate(() => window.__meanZ());
  await page.evaluate((id) => {
    const { send, state } = window.vsculpt;
    const xyz = state.icons.get(id).xyz;
    send({ type: 'drag_start', icon: id });
    for (let k = 1; k <= 5; k++) send({ type: 'drag', icon: id, xyz: [xyz[0], xyz[1], xyz[2] + 0.2 * k] });
    send({ type: 'drag_end', icon: id });
  }, icon);
  await page.waitForFunction((z) => window.vsculpt.perf.shown > 0 && window.__meanZ() > z + 1e-6, z0, { timeout: 10000 });
  const perf = await page.evaluate(() => window.vsculpt.perf);
  assert.equal(perf.workerFailed, null);
  assert.ok(perf.shown <= perf.submitted, JSON.stringify(perf));
  assert.ok(!page.requests.some((u) => u.endsWith('/tess-worker.js')), 'no worker was started');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a curve icon is drawn on the surface with its curvature comb', async () => {
  const page = await open(links.editor);
  const before = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.evaluate(() =>
    window.vsculpt.createIcon(
      { kind: 'curve', curve: { knots: { degree: 2, knots: [0, 0, 0, 1, 1, 1] }, points: [[0.2, 0.2], [0.5, 0.8], [0.8, 0.3]] } },
      { kind: 'position' },
    ),
  );
  await page.waitForFunction((n) => window.vsculpt.state.icons.size > n, before, { timeout: 10000 });
  const id = await page.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  assert.equal(await page.evaluate((i) => window.vsculpt.state.icons.get(i).anchor.kind, id), 'curve');
  await page.waitForFunction(
    (i) => {
      const g = window.vsculpt.view.scene.getObjectByName('icons');
      const obj = g && g.children.find((c) => c.userData.iconId === i);
      return obj && obj.children.some((c) => c.isLineSegments && c.geometry.attributes.position.count === 128);
    },
    id,
    { timeout: 10000 },
  );
  await page.screenshot({ path: join(artifacts, 'curve-comb.png') });
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the page reconnects by itself after the server restarts', async () => {
  const page = await open(links.editor);
  const port = new URL(links.base).port;
  await stopServer(server);
  await page.waitForFunction(() => document.getElementById('status').className.includes('reconnecting'), null, { timeout: 10000 });
  server = await startServer({ listen: `127.0.0.1:${port}`, dataDir });
  await page.waitForFunction(() => document.getElementById('status').className.includes('connected') && !document.getElementById('status').className.includes('re'), null, { timeout: 20000 });
  // Every part has its shape: a surface or curve its geometry, a body (drawn by the body view from its frames) its frame.
  const shapeless = await page.evaluate(() =>
    [...window.vsculpt.design.parts.values()].filter((p) => (p.kind === 'body' ? !(window.vsculpt.bodyView.bodies.get(p.id) || {}).frame : !p.geometry)).map((p) => `${p.kind} ${p.id}`),
  );
  assert.ok(await page.evaluate(() => window.vsculpt.design.parts.size > 0));
  assert.deepEqual(shapeless, [], 'every part has its shape after reconnecting');
  await page.close();
});

test('the token leaves the address bar at once, and a reload still joins', async () => {
  const token = tokenOf(links.editor);
  const page = await open(links.editor);
  const url = new URL(page.url());
  assert.equal(url.searchParams.get('token'), null, page.url());
  assert.equal(url.searchParams.get('design'), String(new URL(links.editor).searchParams.get('design')));
  assert.ok(!page.url().includes(token));
  assert.ok(!(await page.evaluate(() => history.state && JSON.stringify(history.state)) || '').includes(token));
  await page.reload();
  await page.waitForFunction(() => window.vsculpt && window.vsculpt.state.access === 'editor', null, { timeout: 30000 });
  assert.ok(!page.url().includes(token));
  await page.close();
});
