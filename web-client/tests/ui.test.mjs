// The page as a designer and a customer use it (issue 16), in real headless
// Chromium against the real server, each test failing on the client before
// it: a phone-sized screen keeps a usable view and a visible status; a
// server error is a toast that leaves the connection badge alone; while the
// link is down the editing controls are disabled and an edit is refused
// visibly (a commit keeps its message); the keyboard undoes, redoes,
// deletes, cancels a pick and opens the help; a viewer sees it is view-only.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { serverBinProblem, startServer, stopServer, launchChromium, openClient } from './harness.mjs';

const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-ui-'));
let server;
let browser;

before(async () => {
  const problem = serverBinProblem();
  assert.equal(problem, null, problem);
  server = await startServer({ dataDir });
  browser = await launchChromium();
});

after(async () => {
  if (browser) await browser.close();
  await stopServer(server);
  rmSync(dataDir, { recursive: true, force: true });
});

const connected = (page) =>
  page.waitForFunction(() => document.getElementById('status').className === 'status connected', null, { timeout: 20000 });

test('on a phone (390 × 844) the view takes the width, the status shows, the panel opens on demand', async () => {
  const page = await browser.newPage({ viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true });
  await page.goto(server.editor);
  await page.waitForFunction(() => window.vsculpt && window.vsculpt.perf.firstPicture !== null, null, { timeout: 30000 });
  const canvas = await page.evaluate(() => window.vsculpt.view.renderer.domElement.getBoundingClientRect().width);
  assert.ok(canvas >= 380, `3D view ${canvas} px wide`);
  const badgeOnTop = await page.evaluate(() => {
    const r = document.getElementById('status').getBoundingClientRect();
    return document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2)?.id;
  });
  assert.equal(badgeOnTop, 'status', 'the status badge is not covered');
  const panelShown = () => page.evaluate(() => document.getElementById('panel').getBoundingClientRect().top < innerHeight - 10);
  assert.equal(await panelShown(), false, 'the panel starts closed');
  await page.click('#panel-toggle');
  await page.waitForFunction(() => document.getElementById('panel').getBoundingClientRect().top < innerHeight / 2 + 20);
  assert.equal(await panelShown(), true);
  await page.close();
});

test('a server error is a toast; the connection badge still says connected', async () => {
  const page = await openClient(browser, server.editor);
  await connected(page);
  await page.evaluate(() => window.vsculpt.send({ type: 'delete_icon', part: window.vsculpt.state.selectedPart, icon: 987654 }));
  await page.waitForFunction(() => document.querySelector('#toasts .toast'), null, { timeout: 10000 });
  const toast = await page.textContent('#toasts .toast');
  assert.match(toast, /unknown/i, toast);
  assert.equal(await page.getAttribute('#status', 'class'), 'status connected');
  await page.close();
});

test('the keyboard: Delete deletes the selected icon, Ctrl+Z brings it back, Esc cancels a pick, ? opens the help', async () => {
  const page = await openClient(browser, server.editor);
  await connected(page);
  const before = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.31, v: 0.62 }, { kind: 'load' }));
  await page.waitForFunction((n) => window.vsculpt.state.icons.size === n + 1, before, { timeout: 10000 });
  const id = await page.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  await page.evaluate((i) => window.vsculpt.select(i), id);
  await page.locator('canvas').first().focus().catch(() => {});
  await page.keyboard.press('Delete');
  await page.waitForFunction((i) => !window.vsculpt.state.icons.has(i), id, { timeout: 10000 });
  await page.keyboard.press('Control+z');
  await page.waitForFunction((i) => window.vsculpt.state.icons.has(i), id, { timeout: 10000 });
  await page.evaluate(() => {
    document.getElementById('create').value = 'region';
    document.getElementById('create').dispatchEvent(new Event('change'));
    window.vsculpt.pick(0.2, 0.2);
  });
  assert.match(await page.textContent('#pending'), /opposite corner/);
  await page.keyboard.press('Escape');
  assert.equal(await page.evaluate(() => window.vsculpt.state.pending.length), 0);
  assert.equal(await page.textContent('#pending'), '');
  assert.equal(await page.isVisible('#help'), false);
  await page.keyboard.press('?');
  assert.equal(await page.isVisible('#help'), true);
  assert.match(await page.textContent('#help'), /Ctrl\+Z/);
  await page.keyboard.press('?');
  assert.equal(await page.isVisible('#help'), false);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a viewer is told it is view-only, and its keyboard edits are refused with a message', async () => {
  const page = await openClient(browser, server.viewer);
  await connected(page);
  assert.equal(await page.isVisible('#view-only'), true);
  const n = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.keyboard.press('Control+z');
  await page.waitForFunction(() => window.vsculpt.state.toasts.some((t) => /view only/.test(t.text)), null, { timeout: 5000 });
  assert.equal(await page.evaluate(() => window.vsculpt.state.icons.size), n);
  await page.close();
});

test('while the link is down, editing is disabled and a commit is refused visibly, keeping its message', async () => {
  const page = await openClient(browser, server.editor);
  await connected(page);
  assert.equal(await page.isDisabled('#commit button'), false);
  const port = new URL(server.base).port;
  await stopServer(server);
  try {
    await page.waitForFunction(() => document.getElementById('status').className.includes('reconnecting'), null, { timeout: 10000 });
    for (const sel of ['#commit button', '#commit-message', '#create', '#alpha', '#revert']) assert.equal(await page.isDisabled(sel), true, `${sel} disabled`);
    // A commit attempted anyway (e.g. from a script or a stale form) is refused, and says so.
    await page.evaluate(() => {
      const m = document.getElementById('commit-message');
      m.disabled = false;
      m.value = 'keep me';
      document.getElementById('commit').requestSubmit();
    });
    assert.equal(await page.inputValue('#commit-message'), 'keep me');
    assert.ok(await page.evaluate(() => window.vsculpt.state.toasts.some((t) => /not connected: commit was not sent/.test(t.text))));
    assert.equal(await page.evaluate(() => window.vsculpt.send({ type: 'undo' })), null);
  } finally {
    server = await startServer({ listen: `127.0.0.1:${port}`, dataDir });
  }
  await connected(page);
  assert.equal(await page.isDisabled('#commit button'), false, 'enabled again once connected');
  await page.close();
});

test('a position constraint the surface cannot meet shows its target and the miss; labels are readable; driving is not a choosable state', async () => {
  const page = await openClient(browser, server.editor);
  await connected(page);
  const ids = async () => page.evaluate(() => [...window.vsculpt.state.icons.keys()]);
  const known = new Set(await ids());
  // Two position constraints at one point: dragging one away makes them contradictory.
  for (const role of [{ kind: 'position' }, { kind: 'position' }, { kind: 'derivative', which: 'R' }]) {
    const n = (await ids()).length;
    await page.evaluate((r) => window.vsculpt.createIcon({ kind: 'point', u: 0.37, v: 0.41 }, r), role);
    await page.waitForFunction((k) => window.vsculpt.state.icons.size === k + 1, n, { timeout: 10000 });
  }
  const [a, , d] = (await ids()).filter((i) => !known.has(i)).sort((x, y) => x - y);
  const start = await page.evaluate((i) => window.vsculpt.state.icons.get(i).target, a);
  await page.evaluate(
    ([i, p]) => {
      window.vsculpt.send({ type: 'drag_start', icon: i });
      window.vsculpt.send({ type: 'drag', icon: i, xyz: [p[0], p[1], p[2] + 5] });
      window.vsculpt.send({ type: 'drag_end', icon: i });
    },
    [a, start],
  );
  await page.waitForFunction((i) => window.vsculpt.icons.group.getObjectByName(`miss-${i}`), a, { timeout: 15000 });
  const miss = await page.evaluate((i) => {
    const icon = window.vsculpt.state.icons.get(i);
    const dx = icon.target.map((t, k) => t - icon.xyz[k]);
    return { text: window.vsculpt.icons.group.getObjectByName(`miss-${i}`).userData.text, gap: Math.hypot(...dx) };
  }, a);
  assert.ok(miss.gap > 0.5, `the two constraints contradict: gap ${miss.gap}`);
  assert.equal(miss.text, `misses by ${miss.gap.toPrecision(3)}`);
  // The derivative label keeps a readable size on screen, light on dark.
  const px = await page.evaluate((i) => {
    const obj = window.vsculpt.icons.objects.get(i);
    const sprite = obj.children.find((c) => c.isSprite);
    return sprite.material.sizeAttenuation === false ? sprite.scale.y * window.vsculpt.view.renderer.domElement.clientHeight : 0;
  }, d);
  assert.ok(px >= 16, `label ${px} px tall`);
  await page.evaluate((i) => window.vsculpt.select(i), a);
  assert.equal(await page.evaluate(() => document.querySelector('#sel-state option[value=driving]').disabled), true);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a bare server address and a bad token each say what to do, and the page stops trying', async () => {
  const bare = await browser.newPage();
  await bare.goto(server.base);
  await bare.waitForFunction(() => /editor.*viewer.*link/s.test(document.getElementById('shell-stage').textContent), null, { timeout: 20000 });
  await bare.close();
  const bad = await browser.newPage();
  const sockets = [];
  bad.on('websocket', (ws) => sockets.push(ws.url()));
  await bad.goto(`${server.base}/?design=1&token=not-a-token`);
  await bad.waitForFunction(() => /not valid for design 1/.test(document.getElementById('shell-stage').textContent), null, { timeout: 20000 });
  assert.match(await bad.textContent('#status'), /ask the designer for a new link/);
  await new Promise((r) => setTimeout(r, 1500));
  assert.equal(sockets.length, 1, 'no reconnect loop after a refusal');
  await bad.close();
});

test('a viewer compares the live shape with a committed version: zero deviation at that version, the pulled amount after a drag', async () => {
  const editor = await openClient(browser, server.editor);
  await connected(editor);
  const n0 = await editor.evaluate(() => window.vsculpt.state.versions.length);
  await editor.evaluate(() => window.vsculpt.send({ type: 'commit', message: 'before the pull' }));
  await editor.waitForFunction((n) => window.vsculpt.state.versions.length === n + 1, n0, { timeout: 30000 });
  const version = await editor.evaluate(() => window.vsculpt.state.versions.at(-1).version);
  const viewer = await openClient(browser, server.viewer);
  await connected(viewer);
  await viewer.click(`button[data-compare="${version}"]`);
  await viewer.waitForFunction(() => window.vsculpt.state.compare && window.vsculpt.state.compare.max !== undefined, null, { timeout: 30000 });
  assert.ok((await viewer.evaluate(() => window.vsculpt.state.compare.max)) < 1e-3, 'the shape equals the version it was committed as');
  assert.ok(await viewer.isVisible('#compare-legend'));
  // The editor pulls a point up by 2 (a position constraint dragged): the viewer's deviation follows live.
  const before = await editor.evaluate(() => window.vsculpt.state.icons.size);
  await editor.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.45, v: 0.55 }, { kind: 'position' }));
  await editor.waitForFunction((k) => window.vsculpt.state.icons.size === k + 1, before, { timeout: 30000 });
  const id = await editor.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  await editor.evaluate((i) => {
    const { send, state } = window.vsculpt;
    const p = state.icons.get(i).target;
    send({ type: 'drag_start', icon: i });
    send({ type: 'drag', icon: i, xyz: [p[0], p[1], p[2] + 2] });
    send({ type: 'drag_end', icon: i });
  }, id);
  await viewer.waitForFunction(() => window.vsculpt.state.compare.max > 1.5, null, { timeout: 30000 });
  // At the sample nearest the pulled point the surface rose by 2 (the constraint's own move): its
  // deviation along the normal is 2·n_z there. (Elsewhere the plate may swing further: the rim is free.)
  const at = await viewer.evaluate(() => {
    const { state, view, partsView } = window.vsculpt;
    const drawing = partsView.drawings.get(state.compare.part);
    const t = drawing.tess;
    let best = 0;
    for (let i = 0; i < t.su * t.sv; i++) {
      const d = (k) => Math.hypot(t.uvs[2 * k] - 0.45, t.uvs[2 * k + 1] - 0.55);
      if (d(i) < d(best)) best = i;
    }
    return {
      dev: state.compare.deviation[best],
      nz: t.normals[3 * best + 2],
      max: state.compare.max,
      colored: drawing.mesh.material === view.colored,
      ghost: !!view.model.getObjectByName('compare-ghost'),
      colour: Array.from(drawing.mesh.geometry.attributes.color.array.slice(3 * best, 3 * best + 3)),
    };
  });
  assert.ok(Math.abs(at.dev - 2 * at.nz) < 0.15, `deviation at the pulled point ${at.dev}, expected 2·n_z = ${2 * at.nz}`);
  assert.ok(at.max >= at.dev - 1e-9);
  assert.ok(at.colored && at.ghost, 'deviation colours and the version drawn as a ghost');
  assert.ok(at.colour[0] === 1 && at.colour[2] < 1, `raised points are red: ${at.colour}`);
  await viewer.click('#compare-stop');
  assert.equal(await viewer.evaluate(() => {
    const { partsView } = window.vsculpt;
    return [...partsView.drawings.values()].every((d) => d.mesh.material === d.shaded);
  }), true);
  assert.equal(await viewer.evaluate(() => !!window.vsculpt.view.model.getObjectByName('compare-ghost')), false);
  assert.deepEqual([...editor.errors, ...viewer.errors], []);
  await editor.close();
  await viewer.close();
});
