// The reviewer's "follow the designer", in real headless Chromium against
// the real server: the designer orbits with the mouse, the reviewer's page
// offers to follow the designer, and once asked its camera is the
// designer's exactly after every move; the reviewer's own orbit ends the
// following, after which the designer's moves no longer carry the
// reviewer's view along.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createDesign, serverAndBrowser, openClient } from './harness.mjs';

let server;
let browser;
const dataDir = serverAndBrowser('vsculpt-follow-', (s, b) => {
  server = s;
  browser = b;
});

/** The page's camera as the protocol carries it, read from three.js directly (not through follow.js). */
const camera = (page) =>
  page.evaluate(() => {
    const v = window.vsculpt.view;
    return { eye: v.camera.position.toArray(), target: v.controls.target.toArray(), fov: v.camera.fov };
  });

/** Orbits `page`'s view with a real left-button mouse drag of `dx` pixels across the middle of the canvas. */
async function orbit(page, dx) {
  const box = await page.locator('#viewport canvas').boundingBox();
  const x = box.x + box.width * 0.3;
  const y = box.y + box.height * 0.7;
  await page.mouse.move(x, y);
  await page.mouse.down();
  for (let k = 1; k <= 8; k++) await page.mouse.move(x + (dx * k) / 8, y - k * 3);
  await page.mouse.up();
}

/**
 * Whether cameras a and b are the same to rounding: three.js's orbit
 * controls re-derive the eye from spherical coordinates every frame, which
 * moves it by a few ulps; 1e-9 of the scene's size is far below a pixel and
 * far above that.
 */
function sameTo(a, b, tol = 1e-9) {
  const scale = 1 + Math.max(...a.eye.map(Math.abs), ...a.target.map(Math.abs));
  const off = (x, y) => Math.max(...x.map((v, i) => Math.abs(v - y[i])));
  return off(a.eye, b.eye) <= tol * scale && off(a.target, b.target) <= tol * scale && a.fov === b.fov;
}

/** Waits until `viewer`'s camera is `editor`'s current camera (to rounding); that camera. */
async function sameCamera(editor, viewer) {
  // The editor sends its last position within a tenth of a second of moving.
  const want = await camera(editor);
  await viewer.waitForFunction(
    (c) => {
      // sameTo, in the page.
      const v = window.vsculpt.view;
      const eye = v.camera.position.toArray();
      const target = v.controls.target.toArray();
      const scale = 1 + Math.max(...c.eye.map(Math.abs), ...c.target.map(Math.abs));
      const off = (x, y) => Math.max(...x.map((q, i) => Math.abs(q - y[i])));
      return off(eye, c.eye) <= 1e-9 * scale && off(target, c.target) <= 1e-9 * scale && v.camera.fov === c.fov;
    },
    want,
    { timeout: 20000 },
  );
  return want;
}

test('a reviewer follows the designer’s camera exactly, and their own orbit ends it', async () => {
  const d = await createDesign(server, dataDir, { name: 'follow', nu: 8, nv: 8 });
  const editor = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.editor}&name=Ana`);
  const viewer = await openClient(browser, `${server.base}/?design=${d.id}&token=${d.tokens.viewer}&name=Carl`);

  // The designer's camera reaches the reviewer's page: it offers to follow her.
  await orbit(editor, 120);
  const button = viewer.locator('#follow');
  await viewer.waitForFunction(() => document.querySelector('#follow').textContent === 'follow Ana', null, { timeout: 20000 });
  const before = await camera(viewer);
  assert.ok(!sameTo(before, await camera(editor), 1e-3), 'the two views start apart');
  await button.click();
  assert.equal(await button.getAttribute('aria-pressed'), 'true');
  assert.match(await button.textContent(), /^following Ana/);
  let seen = await sameCamera(editor, viewer);

  // Every later move of the designer is followed, exactly.
  await orbit(editor, -200);
  const moved = await sameCamera(editor, viewer);
  assert.ok(!sameTo(moved, seen, 1e-3), 'the designer really moved');
  seen = moved;

  // The reviewer orbits: following ends, and the designer's next move stays hers.
  await orbit(viewer, 90);
  await viewer.waitForFunction(() => document.querySelector('#follow').getAttribute('aria-pressed') === 'false');
  const own = await camera(viewer);
  await orbit(editor, 150);
  const theirs = await camera(editor);
  await viewer.waitForFunction(
    (eye) => window.vsculpt.state.presence.find((p) => p.name === 'Ana')?.camera?.eye.every((x, i) => Math.abs(x - eye[i]) <= 1e-6 * (1 + Math.abs(eye[i]))),
    theirs.eye,
    { timeout: 20000 },
  );
  const after = await camera(viewer);
  assert.ok(sameTo(after, own), `the reviewer’s view stays where they put it: ${JSON.stringify([after, own])}`);
  assert.ok(!sameTo(after, theirs, 1e-3), 'and is not the designer’s');

  // The presence list offers the same, per person; following from there works too.
  await viewer.click('#presence button[data-follow]');
  await sameCamera(editor, viewer);
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});
