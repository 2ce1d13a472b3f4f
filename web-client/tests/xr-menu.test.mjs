// The VR menu for an icon's role and state (paper 003's 3D menu), in real
// headless Chromium against the real server with iwer's emulated Meta
// Quest 3 as the WebXR runtime: the designer enters VR (the headset outside
// the model), grabs an icon with the right controller's squeeze, opens the
// menu with the left controller's X button, switches the icon's role by
// pointing the right controller's ray at "load" and pulling the trigger, and
// its state by pushing the left thumbstick to "sleeping" and pressing it.
// Every input is an emulated controller's pose or button, nothing calls the
// menu. The server's copy (its REST API) and a second page, a viewer, show
// the new role and state.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { serverAndBrowser, openClient, webDir } from './harness.mjs';

let server;
let browser;
serverAndBrowser('vsculpt-xr-menu-', (s, b) => {
  server = s;
  browser = b;
});

/** Installs iwer's emulated Meta Quest 3 (the registry package the server serves) as the page's WebXR runtime. */
async function emulateQuest3(page) {
  await page.evaluate(async () => {
    const { XRDevice, metaQuest3 } = await import('/vendor/iwer/build/iwer.module.js');
    const dev = new XRDevice(metaQuest3);
    dev.installRuntime({ forceInstall: true });
    window.__xrdev = dev;
  });
}

/** A few emulated frames. */
const frames = (page) => page.evaluate(() => new Promise((r) => setTimeout(r, 300)));

/** Presses and releases emulated controller `hand`'s button `button`. */
async function click(page, hand, button) {
  await page.evaluate(([h, b]) => window.__xrdev.controllers[h].updateButtonValue(b, 1), [hand, button]);
  await frames(page);
  await page.evaluate(([h, b]) => window.__xrdev.controllers[h].updateButtonValue(b, 0), [hand, button]);
  await frames(page);
}

/**
 * Turns the emulated right controller until three's target ray (what the
 * page aims with) points at the centre of the menu's button (kind, name):
 * each step rotates the emulator's pose by the rotation from where the ray
 * points to where it should.
 */
async function pointAt(page, kind, name) {
  for (let k = 0; k < 4; k++) {
    await frames(page);
    await page.evaluate(([kd, nm]) => {
      const { view, xr } = window.vsculpt;
      const V = view.camera.position.constructor;
      const Q = view.camera.quaternion.constructor;
      const target = xr.menu.buttonWorld(kd, nm);
      const ray = xr.controllers[1].ray;
      ray.updateMatrixWorld(true);
      const o = new V().setFromMatrixPosition(ray.matrixWorld);
      const d = new V(0, 0, -1).transformDirection(ray.matrixWorld);
      const turn = new Q().setFromUnitVectors(d, target.sub(o).normalize());
      const c = window.__xrdev.controllers.right.quaternion;
      const q = new Q(c.x, c.y, c.z, c.w).premultiply(turn).normalize();
      c.set(q.x, q.y, q.z, q.w);
    }, [kind, name]);
  }
  await frames(page);
}

async function restIcon(token, id) {
  const res = await fetch(`${server.base}/api/designs/1?token=${token}`);
  assert.equal(res.status, 200);
  const doc = await res.json();
  const found = [];
  const walk = (x) => {
    if (Array.isArray(x)) x.forEach(walk);
    else if (x && typeof x === 'object') {
      if (x.id === id && x.role !== undefined && x.state !== undefined && x.anchor !== undefined) found.push(x);
      Object.values(x).forEach(walk);
    }
  };
  walk(doc);
  assert.equal(found.length, 1, `icon ${id} in the server's design`);
  return found[0];
}

test('VR menu (iwer Quest 3): grab an icon, X opens the menu, the ray and trigger switch its role to load, the thumbstick its state to sleeping; the server and a viewer see both', async () => {
  const page = await openClient(browser, server.editor);
  const viewer = await openClient(browser, server.viewer);
  await emulateQuest3(page);
  const before = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.5, v: 0.5 }, { kind: 'position' }));
  await page.waitForFunction((n) => window.vsculpt.state.icons.size > n, before, { timeout: 10000 });
  const icon = await page.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  const start = await page.evaluate((id) => window.vsculpt.state.icons.get(id).target, icon);
  const token = new URL(server.editor).searchParams.get('token');
  const atStart = await restIcon(token, icon);
  assert.equal(atStart.state, 'passive');
  assert.deepEqual(atStart.role, { kind: 'position' });

  await page.click('#enter-vr');
  await page.waitForFunction(() => window.vsculpt.view.renderer.xr.isPresenting, null, { timeout: 15000 });
  await frames(page);
  // The headset starts outside the model, which stands on the table.
  const placed = await page.evaluate(() => {
    const v = window.vsculpt.view;
    const world = v.bounds().clone().applyMatrix4(v.model.matrixWorld);
    const eye = v.renderer.xr.getCamera().getWorldPosition(new v.camera.position.constructor());
    return { inside: world.containsPoint(eye), eye: eye.toArray(), min: world.min.toArray(), max: world.max.toArray() };
  });
  assert.equal(placed.inside, false, `the headset (${placed.eye}) is outside the model (${placed.min} … ${placed.max})`);
  assert.equal(await page.evaluate(() => window.vsculpt.xr.menu.open), false, 'the menu starts closed');

  // Grab the icon: the right grip on it, squeeze.
  for (let k = 0; k < 3; k++) {
    await frames(page);
    await page.evaluate((p) => {
      const v = window.vsculpt;
      const at = v.view.model.localToWorld(new v.view.camera.position.constructor(...p));
      const grip = v.xr.gripPosition(1);
      const c = window.__xrdev.controllers.right;
      c.position.set(c.position.x + at.x - grip.x, c.position.y + at.y - grip.y, c.position.z + at.z - grip.z);
    }, start);
  }
  await frames(page);
  await page.evaluate(() => window.__xrdev.controllers.right.updateButtonValue('squeeze', 1));
  await page.waitForFunction((id) => window.vsculpt.xr.grab && window.vsculpt.xr.grab.id === id, icon, { timeout: 10000 });

  // X on the left controller opens the menu on the left wrist; it shows the icon in hand, driving while held.
  await click(page, 'left', 'x-button');
  await page.waitForFunction(() => window.vsculpt.xr.menu.open, null, { timeout: 10000 });
  const shown = await page.evaluate(() => {
    const { xr } = window.vsculpt;
    const m = xr.menu;
    const grip = xr.controllers[xr.menuIndex()].grip;
    let onLeft = false;
    m.group.traverseAncestors((a) => (onLeft ||= a === grip));
    return { id: m.target().id, onLeft, hand: xr.controllers[xr.menuIndex()].source.handedness };
  });
  assert.deepEqual(shown, { id: icon, onLeft: true, hand: 'left' });
  await page.waitForFunction((id) => window.vsculpt.state.icons.get(id).state === 'driving', icon, { timeout: 10000 });
  await page.evaluate(() => window.__xrdev.controllers.right.updateButtonValue('squeeze', 0));
  await page.waitForFunction((id) => window.vsculpt.xr.grab === null && window.vsculpt.state.icons.get(id).state === 'passive', icon, { timeout: 10000 });
  assert.equal(await page.evaluate(() => window.vsculpt.xr.menu.target()?.id), icon, 'the icon let go stays in the menu');

  // "driving" cannot be chosen: pointing at it and pulling the trigger sends nothing.
  await pointAt(page, 'state', 'driving');
  await page.waitForFunction(() => window.vsculpt.xr.menu.hover?.name === 'driving', null, { timeout: 10000 });
  const iconsBefore = await page.evaluate(() => window.vsculpt.state.icons.size);
  await click(page, 'right', 'trigger');
  assert.equal(await page.evaluate(() => window.vsculpt.xr.menu.choices), 0);
  assert.equal(await page.evaluate(() => window.vsculpt.state.icons.size), iconsBefore, 'a trigger on the menu creates no icon');

  // The right ray on "load", trigger: the role switches.
  await pointAt(page, 'role', 'load');
  await page.waitForFunction(() => window.vsculpt.xr.menu.hover?.name === 'load', null, { timeout: 10000 });
  await click(page, 'right', 'trigger');
  await page.waitForFunction((id) => window.vsculpt.state.icons.get(id).role.kind === 'load', icon, { timeout: 10000 });
  assert.equal((await restIcon(token, icon)).role.kind, 'load');

  // The left thumbstick pushed up once focuses the last button, "sleeping"; pressing the stick chooses it.
  await page.evaluate(() => window.__xrdev.controllers.left.updateAxes('thumbstick', 0, -1));
  await frames(page);
  await page.evaluate(() => window.__xrdev.controllers.left.updateAxes('thumbstick', 0, 0));
  await frames(page);
  const focus = await page.evaluate(() => {
    const m = window.vsculpt.xr.menu;
    return m.focus === null ? null : m.buttons[m.focus].name;
  });
  assert.equal(focus, 'sleeping');
  await click(page, 'left', 'thumbstick');
  await page.waitForFunction((id) => window.vsculpt.state.icons.get(id).state === 'sleeping', icon, { timeout: 10000 });
  const after = await restIcon(token, icon);
  assert.deepEqual([after.role.kind, after.state], ['load', 'sleeping']);
  // The second page sees the same.
  await viewer.waitForFunction((id) => {
    const i = window.vsculpt.state.icons.get(id);
    return i && i.role.kind === 'load' && i.state === 'sleeping';
  }, icon, { timeout: 10000 });
  assert.equal(await page.evaluate(() => window.vsculpt.xr.menu.choices), 2);

  // The panel as drawn, for a look.
  const png = await page.evaluate(() => window.vsculpt.xr.menu.canvas.toDataURL('image/png'));
  writeFileSync(join(webDir, 'test-artifacts', 'vr-menu.png'), Buffer.from(png.split(',')[1], 'base64'));
  // X again closes it.
  await click(page, 'left', 'x-button');
  assert.equal(await page.evaluate(() => window.vsculpt.xr.menu.open), false);
  assert.deepEqual(page.errors, []);
  assert.deepEqual(viewer.errors, []);
  await page.evaluate(() => window.vsculpt.view.renderer.xr.getSession().end());
  await page.close();
  await viewer.close();
});
