// The page against a scripted server, in real headless Chromium: the page's
// files come from this folder and its WebSocket is answered by this test
// with the README's own messages and geometry frames put together byte by
// byte at the README's offsets (no server code, no encoder of ours). It
// checks the client side of protocol version 2 on its own: the hello, the
// compact join of a product of parts (two surfaces joined, one of them
// locked, and a curve), the parts panel, tubes, seams, hiding, locking,
// selecting, and `part` on every icon message.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { mkdirSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { launchChromium, webDir } from './harness.mjs';
import { fileFor } from '../tools/module-graph.mjs';

const ORIGIN = 'http://vsculpt.test';
let browser;

before(async () => {
  browser = await launchChromium();
});

after(async () => {
  if (browser) await browser.close();
});

/**
 * A geometry frame per protocol/README.md ("Binary geometry frame"):
 * `shape` { kind: 'surface', nu, nv, pu, pv, ku, kv, points } or
 * { kind: 'curve', n, p, knots, points }, icons [[id, [x, y, z]], …].
 */
function frame({ design = 1, part, revision, flags = 0, shape, icons = [] }) {
  const curve = shape.kind === 'curve';
  const [nu, nv, pu, pv] = curve ? [shape.n, 1, shape.p, 0] : [shape.nu, shape.nv, shape.pu, shape.pv];
  const ku = curve ? shape.knots : shape.ku;
  const kv = curve ? [] : shape.kv;
  const P = 48 + 8 * ku.length + 8 * kv.length;
  const I = Math.ceil((P + 12 * nu * nv) / 8) * 8;
  const buf = Buffer.alloc(I + 24 * icons.length);
  buf.write('VSGF', 0, 'latin1');
  buf.writeUInt8(curve ? 2 : 1, 4);
  buf.writeUInt8(2, 5);
  buf.writeUInt16LE(flags, 6);
  buf.writeBigUInt64LE(BigInt(design), 8);
  buf.writeBigUInt64LE(BigInt(part), 16);
  buf.writeBigUInt64LE(BigInt(revision), 24);
  buf.writeUInt32LE(nu, 32);
  buf.writeUInt32LE(nv, 36);
  buf.writeUInt8(pu, 40);
  buf.writeUInt8(pv, 41);
  buf.writeUInt32LE(icons.length, 44);
  [...ku, ...kv].forEach((k, i) => buf.writeDoubleLE(k, 48 + 8 * i));
  shape.points.flat().forEach((x, i) => buf.writeFloatLE(x, P + 4 * i));
  icons.forEach(([id, xyz], k) => {
    buf.writeBigUInt64LE(BigInt(id), I + 24 * k);
    xyz.forEach((x, i) => buf.writeFloatLE(x, I + 24 * k + 8 + 4 * i));
  });
  return buf;
}

const MAT = { alpha11: 0.1, alpha12: 0.0, alpha22: 0.1, beta11: 1.0, beta12: 1.0, beta22: 1.0 };
const TOP = [[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]];
const SIDE = [[1, 0, 0], [1, 1, 0], [2, 0, -0.5], [2, 1, -0.5]];
const LINE = [[0, 0.5, 0.3], [0.5, 0.8, 0.6], [1, 0.5, 0.3]];
const bilinear = (points) => ({ kind: 'surface', nu: 2, nv: 2, pu: 1, pv: 1, ku: [0, 0, 1, 1], kv: [0, 0, 1, 1], points });
const surfaceJson = (points) => ({ kind: 'surface', surface: { u: { degree: 1, knots: [0, 0, 1, 1] }, v: { degree: 1, knots: [0, 0, 1, 1] }, nu: 2, nv: 2, points } });

/** The README's snapshot of a product: top shell (a load icon), side (locked), joined to it along u; a feature line (a param icon). */
function snapshotWithoutPoints() {
  return {
    type: 'snapshot',
    design: { id: 1, name: 'mouse', versions: 1 },
    revision: 12,
    parts: [
      { id: 1, name: 'top shell', visible: true, locked: false, colour: '#c8ccd4', material: MAT,
        icons: [{ id: 3, anchor: { kind: 'point', u: 0.5, v: 0.5 }, role: { kind: 'load' }, state: 'passive', xyz: [0.5, 0.5, 0], target: [0.5, 0.5, 0], sensors: [] }],
        shape: surfaceJson([]) },
      { id: 2, name: 'side', visible: true, locked: true, colour: '#9aa4b8', material: MAT,
        icons: [{ id: 4, anchor: { kind: 'point', u: 0.5, v: 0.5 }, role: { kind: 'load' }, state: 'passive', xyz: [1.5, 0.5, -0.25], target: [1.5, 0.5, -0.25], sensors: [] }],
        shape: surfaceJson([]) },
      { id: 3, name: 'feature line', visible: true, locked: false, colour: '#ff8800', material: { alpha: 0.01, beta: 1.0 },
        icons: [{ id: 7, anchor: { kind: 'param', t: 0.5 }, role: { kind: 'position' }, state: 'passive', xyz: [0.5, 0.65, 0.45], target: [0.5, 0.65, 0.45], sensors: [] }],
        shape: { kind: 'curve', curve: { knots: { degree: 2, knots: [0, 0, 0, 1, 1, 1] }, points: [] } } },
    ],
    relations: [{ id: 5, kind: 'join', a: { part: 1, edge: 'u_max' }, b: { part: 2, edge: 'u_min' }, continuity: 'g1', reversed: false }],
    versions: [{ version: 1, time_ms: 1700000000000, author: 'Ana', message: 'first' }],
    presence: [{ client: 4, name: 'Ana', access: 'editor' }],
    can_undo: false,
    can_redo: false,
  };
}

/**
 * Opens the page with its files served from this folder and its socket
 * answered by a script that keeps the parts' state for part_changed and
 * answers icon creation; resolves { page, sent (every JSON message the
 * page sent), server (to push more) }.
 */
/** Serves the page's files from this folder under ORIGIN. */
function serveFiles(page) {
  return page.route(`${ORIGIN}/**`, (route) => {
    const url = new URL(route.request().url());
    const path = url.pathname === '/' ? '/index.html' : url.pathname;
    let body;
    try {
      body = readFileSync(fileFor(path));
    } catch {
      return route.fulfill({ status: 404, body: 'not here' });
    }
    const type = path.endsWith('.html') ? 'text/html' : path.endsWith('.css') ? 'text/css' : path.endsWith('.json') ? 'application/json' : 'text/javascript';
    return route.fulfill({ status: 200, body, headers: { 'content-type': type } });
  });
}

async function openScripted(access = 'editor', pageOptions = { viewport: { width: 1100, height: 700 } }) {
  const page = await browser.newPage(pageOptions);
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.errors = errors;
  await serveFiles(page);
  const sent = [];
  const snap = snapshotWithoutPoints();
  const server = { ws: null, snapshot: snap };
  // The page may add query parameters (`?drag_stream=1`).
  await page.routeWebSocket(/^ws:\/\/vsculpt\.test\/ws(\?.*)?$/, (ws) => {
    server.ws = ws;
    ws.onMessage((text) => {
      const msg = JSON.parse(text);
      sent.push(msg);
      if (msg.type === 'hello') {
        ws.send(JSON.stringify({ type: 'welcome', client_id: 4, access, design: 1, protocol: 2 }));
        // The compact join: one frame per part (flag 2), then the snapshot without points.
        ws.send(frame({ part: 1, revision: 12, flags: 2, shape: bilinear(TOP), icons: [[3, [0.5, 0.5, 0]]] }));
        ws.send(frame({ part: 2, revision: 12, flags: 2, shape: bilinear(SIDE), icons: [[4, [1.5, 0.5, -0.25]]] }));
        ws.send(frame({ part: 3, revision: 12, flags: 2, shape: { kind: 'curve', n: 3, p: 2, knots: [0, 0, 0, 1, 1, 1], points: LINE }, icons: [[7, [0.5, 0.65, 0.45]]] }));
        ws.send(JSON.stringify(snap));
      } else if (msg.type === 'set_part') {
        const part = snap.parts.find((p) => p.id === msg.part);
        for (const k of ['name', 'visible', 'locked', 'colour']) if (msg[k] !== undefined) part[k] = msg[k];
        ws.send(JSON.stringify({ type: 'ack', req: msg.req }));
        ws.send(JSON.stringify({ type: 'part_changed', part: part.id, name: part.name, visible: part.visible, locked: part.locked, colour: part.colour }));
      } else if (msg.type === 'relate') {
        ws.send(JSON.stringify({ type: 'ack', req: msg.req, relation: 6 }));
        ws.send(JSON.stringify({ type: 'relation_created', relation: { id: 6, ...msg.relation } }));
      } else if (msg.req !== undefined) {
        ws.send(JSON.stringify({ type: 'ack', req: msg.req }));
      }
    });
  });
  await page.goto(`${ORIGIN}/?design=1&token=scripted`);
  await page.waitForFunction(() => window.vsculpt && window.vsculpt.perf.firstPicture !== null && window.vsculpt.design.joined && window.vsculpt.state.access, null, { timeout: 30000 });
  return { page, sent, server };
}

test('hello says protocol 2 and asks for the compact join; the product of parts is drawn and listed', async () => {
  const { page, sent } = await openScripted();
  const hello = sent.find((m) => m.type === 'hello');
  assert.equal(hello.protocol, 2);
  assert.equal(hello.geometry_first, true);
  const rows = await page.$$eval('#parts li', (lis) => lis.map((li) => ({ name: li.querySelector('.part-name').textContent, kind: li.querySelector('.kind').textContent, colour: li.querySelector('input[type=color]').value })));
  assert.deepEqual(rows, [
    { name: 'top shell', kind: 'surface', colour: '#c8ccd4' },
    { name: 'side', kind: 'surface', colour: '#9aa4b8' },
    { name: 'feature line', kind: 'curve', colour: '#ff8800' },
  ]);
  const scene = await page.evaluate(() => {
    const { partsView } = window.vsculpt;
    const d = (id) => partsView.drawings.get(id);
    const seam = partsView.seams.getObjectByName('seam-5');
    return {
      kinds: [1, 2, 3].map((id) => d(id).kind),
      colours: [1, 2, 3].map((id) => '#' + d(id).shaded.color.getHexString()),
      tubeVertices: d(3).mesh.geometry.attributes.position.count,
      tubeType: d(3).mesh.geometry.type,
      comb: d(3).comb.children[0].geometry.attributes.position.count,
      seamBox: seam && (seam.geometry.computeBoundingBox(), [seam.geometry.boundingBox.min.toArray(), seam.geometry.boundingBox.max.toArray()]),
      lock: [1, 2].map((id) => !!d(id).group.getObjectByName(`lock-${id}`)),
      points: Array.from(window.vsculpt.design.parts.get(2).geometry.points),
    };
  });
  assert.deepEqual(scene.kinds, ['surface', 'surface', 'curve']);
  assert.deepEqual(scene.colours, ['#c8ccd4', '#9aa4b8', '#ff8800']);
  assert.equal(scene.tubeType, 'TubeGeometry');
  assert.ok(scene.tubeVertices > 100, `a tube: ${scene.tubeVertices} vertices`);
  assert.equal(scene.comb, 128, 'a comb of 64 teeth along the curve');
  // The seam lies along the top shell's u_max edge: x = 1, y from 0 to 1, z = 0 (a tube of small radius around it).
  const [min, max] = scene.seamBox;
  assert.ok(Math.abs(min[0] - 1) < 0.05 && Math.abs(max[0] - 1) < 0.05 && min[1] < 0.01 && max[1] > 0.99 && Math.abs(min[2]) < 0.05, JSON.stringify(scene.seamBox));
  assert.deepEqual(scene.lock, [false, true], 'the locked part is labelled');
  assert.deepEqual(scene.points, SIDE.flat(), 'the frame drew the side');
  assert.match(await page.textContent('#parts li[data-part="2"]'), /locked/);
  mkdirSync(join(webDir, 'test-artifacts'), { recursive: true });
  await page.screenshot({ path: join(webDir, 'test-artifacts', 'parts-scripted.png') });
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('selecting a part makes the icon tools act on it; every icon message names its part; a locked part gets no gizmo', async () => {
  const { page, sent } = await openScripted();
  await page.click('#parts li[data-part="3"] .part-name');
  assert.equal(await page.evaluate(() => window.vsculpt.state.selectedPart), 3);
  assert.match(await page.textContent('#target-part'), /feature line \(curve\)/);
  // In "point" mode a pick on the curve is a param icon at t.
  await page.selectOption('#create', 'point');
  await page.selectOption('#create-role', 'load');
  await page.evaluate(() => window.vsculpt.pick(0.25));
  const create = sent.filter((m) => m.type === 'create_icon').at(-1);
  assert.deepEqual(create, { type: 'create_icon', part: 3, spec: { anchor: { kind: 'param', t: 0.25 }, role: { kind: 'load' }, state: 'passive' }, req: create.req });
  // A normal constraint is not a curve's role: refused here, nothing sent.
  const n = sent.length;
  await page.evaluate(() => window.vsculpt.createIcon({ kind: 'param', t: 0.5 }, { kind: 'normal' }));
  assert.equal(sent.length, n);
  // Clicking a part in the view selects it: the top shell's middle.
  const at = await page.evaluate(() => {
    const { view } = window.vsculpt;
    const p = new view.camera.position.constructor(0.3, 0.3, 0).project(view.camera);
    const r = view.renderer.domElement.getBoundingClientRect();
    return { x: r.left + ((p.x + 1) / 2) * r.width, y: r.top + ((1 - p.y) / 2) * r.height };
  });
  await page.selectOption('#create', 'none');
  await page.mouse.click(at.x, at.y);
  await page.waitForFunction(() => window.vsculpt.state.selectedPart === 1, null, { timeout: 5000 });
  // The icon on the unlocked top shell gets a gizmo; a drag names the part; the one on the locked side does not.
  await page.evaluate(() => window.vsculpt.select(3));
  assert.equal(await page.evaluate(() => window.vsculpt.state.selectedPart), 1);
  await page.evaluate(() => {
    window.vsculpt.send({ type: 'drag_start', icon: 3 });
    window.vsculpt.send({ type: 'set_state', icon: 3, state: 'sleeping' });
  });
  for (const type of ['drag_start', 'set_state']) assert.equal(sent.filter((m) => m.type === type).at(-1).part, 1, type);
  const attached = (id) => page.evaluate((i) => {
    window.vsculpt.select(i);
    return window.vsculpt.state.selectedPart;
  }, id);
  assert.equal(await attached(4), 2, 'selecting the side\'s icon selects the side');
  assert.equal(await page.evaluate(() => window.vsculpt.gizmoAttached()), false, 'no gizmo on a locked part');
  await attached(3);
  assert.equal(await page.evaluate(() => window.vsculpt.gizmoAttached()), true, 'a gizmo on an unlocked part');
  // The join tool in the view: an edge of one surface, then an edge of another, with the form's continuity.
  await page.selectOption('#create', 'join');
  await page.click('#join-tool summary');
  await page.selectOption('select[name="join-continuity"]', 'g1');
  await page.evaluate(() => {
    window.vsculpt.selectPart(1);
    window.vsculpt.pick(0.93, 0.4);
    window.vsculpt.selectPart(2);
    window.vsculpt.pick(0.1, 0.55);
  });
  const relate = sent.filter((m) => m.type === 'relate').at(-1);
  assert.deepEqual(relate.relation, { kind: 'join', a: { part: 1, edge: 'u_max' }, b: { part: 2, edge: 'u_min' }, continuity: 'g1', reversed: false });
  await page.selectOption('#create', 'none');
  // Material of a curve part: alpha and beta.
  await page.click('#parts li[data-part="3"] .part-name');
  await page.fill('#alpha', '0.02');
  await page.fill('#beta', '3');
  await page.click('#material button');
  assert.deepEqual(sent.filter((m) => m.type === 'set_material').at(-1).material, { alpha: 0.02, beta: 3 });
  assert.equal(sent.filter((m) => m.type === 'set_material').at(-1).part, 3);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('hide, lock, rename and colour from the panel go out as set_part; the answers change the picture', async () => {
  const { page, sent, server } = await openScripted();
  const pickable = () => page.evaluate(() => window.vsculpt.partsView.pickables().map((m) => m.userData.partId).sort());
  assert.deepEqual(await pickable(), [1, 2, 3]);
  await page.click('#parts li[data-part="1"] button[data-act="visible"]');
  assert.deepEqual(sent.filter((m) => m.type === 'set_part').at(-1), { type: 'set_part', part: 1, visible: false, req: sent.at(-1).req });
  await page.waitForFunction(() => !window.vsculpt.partsView.drawings.get(1).group.visible, null, { timeout: 5000 });
  assert.deepEqual(await pickable(), [2, 3], 'a hidden part cannot be picked');
  assert.equal(await page.evaluate(() => window.vsculpt.icons.objects.has(3)), false, 'its icons are not drawn');
  assert.equal(await page.evaluate(() => window.vsculpt.partsView.seams.children.length), 1, 'the seam stays while the side is drawn');
  // A frame of the hidden part is kept, not drawn; shown again, the part is drawn in its newest shape.
  const uploads = () => page.evaluate(() => window.vsculpt.partsView.drawings.get(1).mesh.geometry.attributes.position.version);
  const before = await uploads();
  server.ws.send(frame({ part: 1, revision: 20, shape: bilinear(TOP.map(([x, y, z]) => [x, y, z + 0.7])) }));
  await page.waitForFunction(() => window.vsculpt.design.parts.get(1).revision === 20, null, { timeout: 5000 });
  await page.evaluate(() => new Promise((r) => setTimeout(r, 400)));
  assert.equal(await uploads(), before, 'the hidden part\'s mesh is not filled');
  await page.click('#parts li[data-part="1"] button[data-act="visible"]');
  await page.waitForFunction(() => window.vsculpt.partsView.drawings.get(1).group.visible && window.vsculpt.partsView.drawings.get(1).mesh.geometry.attributes.position.array[2] > 0.6, null, { timeout: 5000 });
  await page.click('#parts li[data-part="1"] button[data-act="visible"]');
  await page.waitForFunction(() => !window.vsculpt.partsView.drawings.get(1).group.visible, null, { timeout: 5000 });
  // Lock the curve, rename it, recolour it.
  await page.click('#parts li[data-part="3"] button[data-act="lock"]');
  await page.waitForFunction(() => window.vsculpt.design.parts.get(3).locked, null, { timeout: 5000 });
  await page.click('#parts li[data-part="3"] button[data-act="rename"]');
  await page.fill('#parts input.rename', 'spine');
  await page.press('#parts input.rename', 'Enter');
  await page.waitForFunction(() => window.vsculpt.design.parts.get(3).name === 'spine', null, { timeout: 5000 });
  assert.equal(await page.textContent('#parts li[data-part="3"] .part-name'), 'spine');
  await page.$eval('#parts li[data-part="3"] input[type=color]', (el) => {
    el.value = '#3366cc';
    el.dispatchEvent(new Event('change', { bubbles: true }));
  });
  await page.waitForFunction(() => window.vsculpt.partsView.drawings.get(3).shaded.color.getHexString() === '3366cc', null, { timeout: 5000 });
  const parts = sent.filter((m) => m.type === 'set_part').map(({ req, ...m }) => m);
  assert.deepEqual(parts.slice(3), [{ type: 'set_part', part: 3, locked: true }, { type: 'set_part', part: 3, name: 'spine' }, { type: 'set_part', part: 3, colour: '#3366cc' }]);
  // The keyboard: ] selects the next part, H hides it.
  await page.evaluate(() => window.vsculpt.selectPart(2));
  await page.locator('body').press(']');
  assert.equal(await page.evaluate(() => window.vsculpt.state.selectedPart), 3);
  await page.locator('body').press('h');
  assert.deepEqual(sent.filter((m) => m.type === 'set_part').at(-1).visible, false);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a viewer hides a part on its own page only; it has no editing tools', async () => {
  const { page, sent } = await openScripted('viewer');
  assert.equal(await page.isVisible('#parts li[data-part="1"] button[data-act="lock"]'), false);
  await page.click('#parts li[data-part="2"] button[data-act="visible"]');
  assert.equal(sent.filter((m) => m.type === 'set_part').length, 0);
  assert.deepEqual(await page.evaluate(() => window.vsculpt.partsView.pickables().map((m) => m.userData.partId).sort()), [1, 3]);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('frames of one part leave the others alone; part events add and remove drawings', async () => {
  const { page, server } = await openScripted();
  const positions = (id) => page.evaluate((i) => Array.from(window.vsculpt.partsView.drawings.get(i).mesh.geometry.attributes.position.array.slice(0, 30)), id);
  const side = await positions(2);
  const raised = TOP.map(([x, y, z]) => [x, y, z + 0.5]);
  server.ws.send(frame({ part: 1, revision: 13, flags: 1, shape: bilinear(raised), icons: [[3, [0.5, 0.5, 0.5]]] }));
  await page.waitForFunction(() => window.vsculpt.partsView.drawings.get(1).mesh.geometry.attributes.position.array[2] > 0.4, null, { timeout: 5000 });
  assert.deepEqual(await positions(2), side, 'the side did not move');
  // An older frame of the top shell is ignored.
  server.ws.send(frame({ part: 1, revision: 12, shape: bilinear(TOP) }));
  await page.evaluate(() => new Promise((r) => setTimeout(r, 300)));
  assert.ok((await positions(1))[2] > 0.4);
  // An icon event redraws the icons, not the parts' meshes; a new part (inside the design's bounds) is the one shape filled.
  const fills = await page.evaluate(() => window.vsculpt.partsView.fills);
  server.ws.send(JSON.stringify({ type: 'icon_created', part: 3, icon: { id: 8, anchor: { kind: 'span', t0: 0.2, t1: 0.4 }, role: { kind: 'load' }, state: 'passive', xyz: [0.3, 0.6, 0.4], target: [0.3, 0.6, 0.4], sensors: [] } }));
  await page.waitForFunction(() => window.vsculpt.icons.objects.has(8) && window.vsculpt.icons.group.getObjectByName('span-8'), null, { timeout: 5000 });
  assert.equal(await page.evaluate(() => window.vsculpt.partsView.fills), fills, 'no part refilled for an icon event');
  server.ws.send(JSON.stringify({ type: 'part_created', part: { id: 9, name: 'lid', visible: true, locked: false, colour: '#88aa66', material: MAT, icons: [], shape: surfaceJson([[0, 0, 0.5], [0, 1, 0.5], [1, 0, 0.5], [1, 1, 0.5]]) } }));
  await page.waitForFunction(() => window.vsculpt.partsView.drawings.has(9) && document.querySelector('#parts li[data-part="9"]'), null, { timeout: 5000 });
  assert.equal(await page.evaluate(() => window.vsculpt.partsView.fills), fills + 1, 'only the new part was filled');
  server.ws.send(JSON.stringify({ type: 'relation_deleted', relation: 5 }));
  server.ws.send(JSON.stringify({ type: 'part_deleted', part: 2 }));
  await page.waitForFunction(() => !window.vsculpt.partsView.drawings.has(2) && !document.querySelector('#parts li[data-part="2"]'), null, { timeout: 5000 });
  assert.equal(await page.evaluate(() => window.vsculpt.partsView.seams.children.length), 0);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the keyboard reaches the parts: Tab to a part\'s name and Enter selects it; on a phone the panel is a bottom sheet with finger-sized part buttons', async () => {
  const { page } = await openScripted('editor', { viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true });
  await page.focus('#parts li[data-part="3"] .part-name');
  await page.keyboard.press('Enter');
  assert.equal(await page.evaluate(() => window.vsculpt.state.selectedPart), 3);
  await page.keyboard.press('Tab');
  assert.equal(await page.evaluate(() => document.activeElement.dataset.act), 'visible', 'Tab goes on to the part\'s tools');
  await page.click('#panel-toggle');
  await page.waitForFunction(() => document.getElementById('panel').getBoundingClientRect().top < innerHeight / 2 + 20);
  const button = await page.evaluate(() => {
    const r = document.querySelector('#parts li[data-part="1"] button[data-act="visible"]').getBoundingClientRect();
    const panel = document.getElementById('panel').getBoundingClientRect();
    return { height: r.height, inside: r.top >= panel.top && r.bottom <= panel.bottom, top: document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2)?.dataset.act };
  });
  assert.ok(button.height >= 36, `hide button ${button.height} px tall`);
  assert.equal(button.inside, true, 'in the sheet');
  assert.equal(button.top, 'visible', 'not covered');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the binding tool: a surface line bound to a curve goes out as relate and is drawn along that line', async () => {
  const { page, sent } = await openScripted();
  await page.click('#bind-tool summary');
  await page.selectOption('select[name="bind-surface"]', '1');
  await page.selectOption('select[name="bind-along"]', 'v');
  await page.fill('input[name="bind-at"]', '0.25');
  await page.selectOption('select[name="bind-curve"]', '3');
  await page.check('input[name="bind-reversed"]');
  await page.click('#bind button');
  const relate = sent.filter((m) => m.type === 'relate').at(-1);
  assert.deepEqual(relate.relation, { kind: 'binding', curve: 3, surface: 1, line: { v: 0.25 }, reversed: true });
  await page.waitForFunction(() => window.vsculpt.partsView.seams.getObjectByName('binding-6'), null, { timeout: 5000 });
  // On the top shell (x = u, y = v, z = 0) the line v = 0.25 runs along x from 0 to 1 at y = 0.25.
  const box = await page.evaluate(() => {
    const g = window.vsculpt.partsView.seams.getObjectByName('binding-6').geometry;
    g.computeBoundingBox();
    return [g.boundingBox.min.toArray(), g.boundingBox.max.toArray()];
  });
  assert.ok(box[0][0] < 0.01 && box[1][0] > 0.99 && Math.abs(box[0][1] - 0.25) < 0.05 && Math.abs(box[1][1] - 0.25) < 0.05, JSON.stringify(box));
  assert.match(await page.textContent('#relations'), /binding: top shell along v = 0.25 follows feature line \(reversed\)/);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a server of another protocol version: the page says so and stops trying', async () => {
  const page = await browser.newPage();
  await serveFiles(page);
  let hellos = 0;
  await page.routeWebSocket(/^ws:\/\/vsculpt\.test\/ws(\?.*)?$/, (ws) => {
    ws.onMessage((text) => {
      if (JSON.parse(text).type !== 'hello') return;
      hellos++;
      ws.send(JSON.stringify({ type: 'error', code: 'bad_version', message: 'this server speaks protocol 3' }));
      ws.close({ code: 1008 });
    });
  });
  await page.goto(`${ORIGIN}/?design=1&token=scripted`);
  await page.waitForFunction(() => /different protocol versions/.test(document.getElementById('status').textContent), null, { timeout: 20000 });
  await new Promise((r) => setTimeout(r, 1500));
  assert.equal(hellos, 1, 'no reconnect loop');
  await page.close();
});
