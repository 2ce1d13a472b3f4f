// The parts panel end to end (issue 11), in real headless Chromium against
// the real server: the panel lists every part the server holds; parts
// added from the page (a plate, a curve) come back drawn — the curve as a
// tube with its comb; hiding a part takes it out of every page's picture;
// a locked part refuses a drag (no gizmo, and a drag sent anyway is refused
// with `locked`); a rename reaches a second browser; an icon created after
// selecting a part lands on that part; two plates joined draw their seam.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { webDir, createDesign, serverAndBrowser, openClient, documentPoints } from './harness.mjs';

const artifacts = join(webDir, 'test-artifacts');
let server;
let browser;
const dataDir = serverAndBrowser('vsculpt-parts-', (s, b) => {
  server = s;
  browser = b;
});

/** A fresh design (one flat plate) with its editor and viewer links. */
async function freshDesign(name) {
  const d = await createDesign(server, dataDir, { name, nu: 12, nv: 9 });
  return {
    id: d.id,
    tokens: d.tokens,
    editor: `${server.base}/?design=${d.id}&token=${d.tokens.editor}`,
    viewer: `${server.base}/?design=${d.id}&token=${d.tokens.viewer}`,
  };
}

/** The design document the REST API serves. */
async function documentOf(d) {
  const res = await fetch(`${server.base}/api/designs/${d.id}?token=${d.tokens.editor}`);
  assert.equal(res.status, 200);
  return (await res.json()).design;
}

/** Adds a part from the page's panel and waits until it is drawn; its id. */
async function addPart(page, button) {
  const before = await page.evaluate(() => [...window.vsculpt.design.parts.keys()]);
  await page.click(button);
  const id = await page.waitForFunction(
    (known) => {
      const { design, partsView } = window.vsculpt;
      const id = [...design.parts.keys()].find((k) => !known.includes(k));
      return id !== undefined && partsView.drawings.has(id) ? id : null;
    },
    before,
    { timeout: 10000 },
  );
  return id.jsonValue();
}

const listed = (page) => page.$$eval('#parts li', (lis) => lis.map((li) => ({ id: Number(li.dataset.part), name: li.querySelector('.part-name, input.rename').textContent || li.querySelector('input.rename')?.value })));

/** Fraction of canvas pixels that are clearly green (green over red and blue by 60: a lit #00c000 part; nothing else drawn is). */
async function greenPixels(page) {
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  return page.evaluate(() => {
    const src = window.vsculpt.view.renderer.domElement;
    const c = document.createElement('canvas');
    c.width = src.width;
    c.height = src.height;
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i + 1] > d[i] + 60 && d[i + 1] > d[i + 2] + 60) n++;
    return n / (d.length / 4);
  });
}

test('the panel lists every part; an added plate and curve come back drawn, the curve as a tube with its comb', async () => {
  const d = await freshDesign('panel');
  const page = await openClient(browser, d.editor);
  const plate = await addPart(page, '#add-plane');
  const curve = await addPart(page, '#add-curve');
  const doc = await documentOf(d);
  assert.equal(doc.parts.length, 3);
  assert.deepEqual((await listed(page)).map((p) => p.id), doc.parts.map((p) => p.id), 'the panel lists the server\'s parts, in its order');
  assert.deepEqual((await listed(page)).map((p) => p.name), doc.parts.map((p) => p.name));
  assert.deepEqual(doc.parts.map((p) => p.body.kind), ['surface', 'surface', 'curve']);
  const drawn = await page.evaluate(([p, c]) => {
    const { partsView } = window.vsculpt;
    return {
      plate: partsView.drawings.get(p).kind,
      tube: partsView.drawings.get(c).mesh.geometry.type,
      comb: partsView.drawings.get(c).comb.children[0].geometry.attributes.position.count,
    };
  }, [plate, curve]);
  assert.deepEqual(drawn, { plate: 'surface', tube: 'TubeGeometry', comb: 128 });
  // The page holds what the server holds, part by part.
  const rest = documentPoints(doc);
  const shown = await page.evaluate(() => Object.fromEntries([...window.vsculpt.design.parts.values()].map((p) => [p.id, Array.from(p.geometry.points)])));
  for (const [id, pts] of Object.entries(rest)) pts.forEach((x, i) => assert.ok(Math.abs(shown[id][i] - x) <= 1e-5 * (1 + Math.abs(x)), `part ${id} point ${i}`));
  await page.screenshot({ path: join(artifacts, 'parts-panel.png') });
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('selecting a part, then creating an icon, creates it on that part; a param icon on a curve part', async () => {
  const d = await freshDesign('select');
  const page = await openClient(browser, d.editor);
  const plate = await addPart(page, '#add-plane');
  const curve = await addPart(page, '#add-curve');
  await page.click(`#parts li[data-part="${plate}"] .part-name`);
  assert.equal(await page.evaluate(() => window.vsculpt.state.selectedPart), plate);
  const n = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.selectOption('#create', 'point');
  await page.selectOption('#create-role', 'load');
  await page.evaluate(() => window.vsculpt.pick(0.4, 0.6));
  await page.waitForFunction((k) => window.vsculpt.state.icons.size === k + 1, n, { timeout: 10000 });
  await page.click(`#parts li[data-part="${curve}"] .part-name`);
  await page.selectOption('#create-role', 'position');
  await page.evaluate(() => window.vsculpt.pick(0.5));
  await page.waitForFunction((k) => window.vsculpt.state.icons.size === k + 2, n, { timeout: 10000 });
  const doc = await documentOf(d);
  const iconsOf = (id) => doc.parts.find((p) => p.id === id).body.icons;
  assert.deepEqual(iconsOf(plate).map((i) => [i.anchor, i.role.kind]), [[{ kind: 'point', u: 0.4, v: 0.6 }, 'load']]);
  assert.deepEqual(iconsOf(curve).map((i) => [i.anchor, i.role.kind]), [[{ kind: 'param', t: 0.5 }, 'position']]);
  assert.equal(iconsOf(doc.parts[0].id).length, 0, 'nothing on the first part');
  // The page drew both on their parts: the param icon sits on the curve's tube axis at t = 0.5.
  const onCurve = await page.evaluate((c) => {
    const { design } = window.vsculpt;
    const icon = [...design.icons.values()].find((i) => i.part === c);
    return { xyz: icon.xyz, drawn: window.vsculpt.icons.objects.has(icon.id) };
  }, curve);
  assert.equal(onCurve.drawn, true);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('hide takes a part out of every page\'s picture; a viewer sees it hidden and cannot pick it', async () => {
  const d = await freshDesign('hide');
  const editor = await openClient(browser, d.editor);
  const plate = await addPart(editor, '#add-plane');
  const viewer = await openClient(browser, d.viewer);
  // Colour the new plate a colour nothing else has, so its pixels can be counted.
  await editor.$eval(`#parts li[data-part="${plate}"] input[type=color]`, (el) => {
    el.value = '#00c000';
    el.dispatchEvent(new Event('change', { bubbles: true }));
  });
  await viewer.waitForFunction((p) => window.vsculpt.design.parts.get(p).colour === '#00c000', plate, { timeout: 10000 });
  await viewer.evaluate(() => window.vsculpt.view.fit());
  const green = await greenPixels(viewer);
  assert.ok(green > 0.002, `the plate is drawn green: ${green}`);
  await editor.click(`#parts li[data-part="${plate}"] button[data-act="visible"]`);
  await viewer.waitForFunction((p) => !window.vsculpt.partsView.drawings.get(p).group.visible, plate, { timeout: 10000 });
  const after = await greenPixels(viewer);
  assert.ok(after < green / 20, `hidden: ${green} → ${after}`);
  assert.ok(!(await viewer.evaluate(() => window.vsculpt.partsView.pickables().map((m) => m.userData.partId))).includes(plate), 'not pickable');
  assert.match(await viewer.getAttribute(`#parts li[data-part="${plate}"]`, 'class'), /hidden-part/);
  assert.equal((await documentOf(d)).parts.find((p) => p.id === plate).visible, false, 'the server keeps it hidden');
  // Shown again from the panel.
  await editor.click(`#parts li[data-part="${plate}"] button[data-act="visible"]`);
  await viewer.waitForFunction((p) => window.vsculpt.partsView.drawings.get(p).group.visible, plate, { timeout: 10000 });
  assert.deepEqual([...editor.errors, ...viewer.errors], []);
  await editor.close();
  await viewer.close();
});

test('a locked part refuses a drag: no gizmo on its icons, and a drag sent anyway is refused with `locked`', async () => {
  const d = await freshDesign('lock');
  const page = await openClient(browser, d.editor);
  const first = await page.evaluate(() => window.vsculpt.state.selectedPart);
  const n = await page.evaluate(() => window.vsculpt.state.icons.size);
  await page.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.5, v: 0.5 }, { kind: 'position' }));
  await page.waitForFunction((k) => window.vsculpt.state.icons.size === k + 1, n, { timeout: 10000 });
  const icon = await page.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  await page.evaluate((i) => window.vsculpt.select(i), icon);
  assert.equal(await page.evaluate(() => window.vsculpt.gizmoAttached()), true, 'unlocked: a gizmo');
  await page.click(`#parts li[data-part="${first}"] button[data-act="lock"]`);
  await page.waitForFunction((p) => window.vsculpt.design.parts.get(p).locked, first, { timeout: 10000 });
  assert.equal(await page.evaluate(() => window.vsculpt.gizmoAttached()), false, 'locked: no gizmo');
  assert.match(await page.textContent(`#parts li[data-part="${first}"]`), /locked/);
  assert.equal(await page.evaluate((p) => !!window.vsculpt.partsView.drawings.get(p).group.getObjectByName(`lock-${p}`), first), true, 'labelled locked in the view');
  const before = await documentOf(d);
  const target = await page.evaluate((i) => window.vsculpt.state.icons.get(i).target, icon);
  await page.evaluate(([i, p]) => {
    const { send } = window.vsculpt;
    send({ type: 'drag_start', icon: i });
    send({ type: 'drag', icon: i, xyz: [p[0], p[1], p[2] + 5] });
    send({ type: 'drag_end', icon: i });
  }, [icon, target]);
  await page.waitForFunction(() => window.vsculpt.state.toasts.some((t) => t.text.startsWith('locked')), null, { timeout: 10000 });
  await new Promise((r) => setTimeout(r, 300));
  assert.deepEqual(documentPoints(await documentOf(d)), documentPoints(before), 'the shape did not move');
  // Unlocked, the same drag moves it.
  await page.click(`#parts li[data-part="${first}"] button[data-act="lock"]`);
  await page.waitForFunction((p) => !window.vsculpt.design.parts.get(p).locked, first, { timeout: 10000 });
  await page.evaluate(([i, p]) => {
    const { send } = window.vsculpt;
    send({ type: 'drag_start', icon: i });
    send({ type: 'drag', icon: i, xyz: [p[0], p[1], p[2] + 5] });
    send({ type: 'drag_end', icon: i });
  }, [icon, target]);
  await page.waitForFunction(([i, z]) => window.vsculpt.state.icons.get(i).target[2] > z + 4, [icon, target[2]], { timeout: 10000 });
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a rename from one browser reaches a second one', async () => {
  const d = await freshDesign('rename');
  const a = await openClient(browser, d.editor);
  const b = await openClient(browser, d.editor);
  const id = await a.evaluate(() => window.vsculpt.state.selectedPart);
  await a.click(`#parts li[data-part="${id}"] button[data-act="rename"]`);
  await a.fill('#parts input.rename', 'top shell');
  await a.press('#parts input.rename', 'Enter');
  await b.waitForFunction((p) => document.querySelector(`#parts li[data-part="${p}"] .part-name`)?.textContent === 'top shell', id, { timeout: 10000 });
  assert.equal((await documentOf(d)).parts.find((p) => p.id === id).name, 'top shell');
  assert.deepEqual([...a.errors, ...b.errors], []);
  await a.close();
  await b.close();
});

test('two plates joined G1 from the join tool: a second page lists the join and draws its seam along the joined edge', async () => {
  const d = await freshDesign('join');
  const editor = await openClient(browser, d.editor);
  const a = await addPart(editor, '#add-plane');
  const b = await addPart(editor, '#add-plane');
  const viewer = await openClient(browser, d.viewer);
  await editor.click('#join-tool summary');
  await editor.selectOption('select[name="join-a"]', String(a));
  await editor.selectOption('select[name="join-a-edge"]', 'u_max');
  await editor.selectOption('select[name="join-b"]', String(b));
  await editor.selectOption('select[name="join-b-edge"]', 'u_min');
  await editor.selectOption('select[name="join-continuity"]', 'g1');
  await editor.click('#join button');
  await viewer.waitForFunction(() => window.vsculpt.partsView.seams.children.length === 1, null, { timeout: 15000 });
  const relation = await viewer.evaluate(() => [...window.vsculpt.design.relations.values()][0]);
  assert.deepEqual([relation.kind, relation.a, relation.b, relation.continuity], ['join', { part: a, edge: 'u_max' }, { part: b, edge: 'u_min' }, 'g1']);
  assert.match(await viewer.textContent('#relations'), /join .* u_max ↔ .* u_min \(G1\)/);
  // The seam runs along a's u_max edge as the page holds it (whatever the join did to the shapes), and the page holds the server's shapes.
  await new Promise((r) => setTimeout(r, 500));
  const seam = await viewer.evaluate((pa) => {
    const { design, partsView } = window.vsculpt;
    const g = design.parts.get(pa).geometry;
    const last = Array.from(g.points.slice(3 * (g.nu - 1) * g.nv, 3 * g.nu * g.nv));
    const mesh = partsView.seams.children[0];
    mesh.geometry.computeBoundingBox();
    const box = mesh.geometry.boundingBox;
    return { last, min: box.min.toArray(), max: box.max.toArray(), size: partsView.scale };
  }, a);
  const slack = 0.05 * seam.size;
  for (let k = 0; k < 3; k++) {
    const coords = seam.last.filter((_, i) => i % 3 === k);
    assert.ok(seam.min[k] > Math.min(...coords) - slack && seam.max[k] < Math.max(...coords) + slack, `seam within the edge along axis ${k}: ${seam.min}…${seam.max} vs ${coords}`);
    assert.ok(seam.min[k] < Math.min(...coords) + slack && seam.max[k] > Math.max(...coords) - slack, `seam spans the edge along axis ${k}`);
  }
  const rest = documentPoints(await documentOf(d));
  const shown = await viewer.evaluate(() => Object.fromEntries([...window.vsculpt.design.parts.values()].map((p) => [p.id, Array.from(p.geometry.points)])));
  for (const [id, pts] of Object.entries(rest)) pts.forEach((x, i) => assert.ok(Math.abs(shown[id][i] - x) <= 1e-5 * (1 + Math.abs(x)), `part ${id} point ${i}: ${shown[id][i]} vs ${x}`));
  // Joining moved both edges to meet (README, relate): a's last row of control points is b's first, on the page.
  const firstRow = shown[b].slice(0, seam.last.length);
  seam.last.forEach((x, i) => assert.ok(Math.abs(x - firstRow[i]) <= 1e-4 * (1 + Math.abs(x)), `edge point ${i}: ${x} vs ${firstRow[i]}`));
  await viewer.screenshot({ path: join(artifacts, 'parts-seam.png') });
  assert.deepEqual([...editor.errors, ...viewer.errors], []);
  await editor.close();
  await viewer.close();
});

test('dragging a param icon on a curve part: the curve\'s frames (kind 2) reach a second page and its tube follows', async () => {
  const d = await freshDesign('curve-drag');
  const editor = await openClient(browser, d.editor);
  const curve = await addPart(editor, '#add-curve');
  const viewer = await openClient(browser, d.viewer);
  await editor.evaluate((c) => window.vsculpt.selectPart(c), curve);
  const n = await editor.evaluate(() => window.vsculpt.state.icons.size);
  await editor.evaluate(() => window.vsculpt.createIcon({ kind: 'param', t: 0.5 }, { kind: 'position' }));
  await editor.waitForFunction((k) => window.vsculpt.state.icons.size === k + 1, n, { timeout: 10000 });
  const icon = await editor.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  await viewer.waitForFunction((i) => window.vsculpt.icons.objects.has(i), icon, { timeout: 10000 });
  const tubeTop = (page) => page.evaluate((c) => {
    const g = window.vsculpt.partsView.drawings.get(c).mesh.geometry;
    g.computeBoundingBox();
    return g.boundingBox.max.z;
  }, curve);
  const [z0, frames0] = [await tubeTop(viewer), await viewer.evaluate(() => window.vsculpt.state.frames)];
  // Lift the icon by half the design's size, in four drag frames.
  const z = await editor.evaluate((i) => {
    const { send, state, partsView } = window.vsculpt;
    const p = state.icons.get(i).target;
    const h = 0.5 * partsView.scale;
    send({ type: 'drag_start', icon: i });
    for (let k = 1; k <= 4; k++) send({ type: 'drag', icon: i, xyz: [p[0], p[1], p[2] + (h * k) / 4] });
    send({ type: 'drag_end', icon: i });
    return p[2];
  }, icon);
  await viewer.waitForFunction(([i, z0]) => window.vsculpt.state.icons.get(i).target[2] > z0 + 0.9 * 0.5 * window.vsculpt.partsView.scale, [icon, z], { timeout: 15000 });
  await viewer.waitForFunction(([c, z]) => {
    const g = window.vsculpt.partsView.drawings.get(c).mesh.geometry;
    g.computeBoundingBox();
    return g.boundingBox.max.z > z + 0.5 * window.vsculpt.partsView.scale * 0.5;
  }, [curve, z0], { timeout: 15000 });
  assert.ok((await viewer.evaluate(() => window.vsculpt.state.frames)) > frames0, 'frames arrived');
  // The curve the page draws passes through the position constraint: its point at t = 0.5 is the icon's target.
  const at = await viewer.evaluate(async ([i, c]) => {
    const { curveDerivs } = await import('/src/bspline.js');
    const { design, partsView } = window.vsculpt;
    const g = design.parts.get(c).geometry;
    const p = curveDerivs(g, 0.5).p;
    const t = design.icons.get(i).target;
    return { kind: g.kind, miss: Math.hypot(p[0] - t[0], p[1] - t[1], p[2] - t[2]), size: partsView.scale };
  }, [icon, curve]);
  assert.equal(at.kind, 'curve');
  assert.ok(at.miss < 1e-3 * at.size, `the curve meets its constraint: misses by ${at.miss}`);
  const rest = (await documentOf(d)).parts.find((p) => p.id === curve).body.curve;
  const shown = await viewer.evaluate((c) => Array.from(window.vsculpt.design.parts.get(c).geometry.points), curve);
  rest.points.flat().forEach((x, k) => assert.ok(Math.abs(shown[k] - x) <= 1e-5 * (1 + Math.abs(x)), `curve point ${k}: ${shown[k]} vs ${x}`));
  await viewer.screenshot({ path: join(artifacts, 'curve-drag.png') });
  assert.deepEqual([...editor.errors, ...viewer.errors], []);
  await editor.close();
  await viewer.close();
});

test('undo takes an added part away on every page, redo brings it back drawn', async () => {
  const d = await freshDesign('undo');
  const editor = await openClient(browser, d.editor);
  const viewer = await openClient(browser, d.viewer);
  const plate = await addPart(editor, '#add-plane');
  await viewer.waitForFunction((p) => window.vsculpt.partsView.drawings.has(p), plate, { timeout: 10000 });
  const points = await viewer.evaluate((p) => Array.from(window.vsculpt.design.parts.get(p).geometry.points), plate);
  await editor.keyboard.press('Control+z');
  for (const page of [editor, viewer]) {
    await page.waitForFunction((p) => !window.vsculpt.design.parts.has(p) && !window.vsculpt.partsView.drawings.has(p) && !document.querySelector(`#parts li[data-part="${p}"]`), plate, { timeout: 10000 });
  }
  await editor.keyboard.press('Control+Shift+z');
  for (const page of [editor, viewer]) {
    await page.waitForFunction((p) => window.vsculpt.partsView.drawings.has(p) && document.querySelector(`#parts li[data-part="${p}"]`), plate, { timeout: 10000 });
  }
  assert.deepEqual(await viewer.evaluate((p) => Array.from(window.vsculpt.design.parts.get(p).geometry.points), plate), points, 'the same plate, drawn');
  assert.deepEqual([...editor.errors, ...viewer.errors], []);
  await editor.close();
  await viewer.close();
});

test('a plate\'s line bound to a curve from the binding tool: listed on a second page and drawn along the line', async () => {
  const d = await freshDesign('bind');
  const editor = await openClient(browser, d.editor);
  const plate = await addPart(editor, '#add-plane');
  const curve = await addPart(editor, '#add-curve');
  const viewer = await openClient(browser, d.viewer);
  // The added plate (6 × 6 bicubic) and curve (6 points, cubic) share their knots: compatible.
  await editor.click('#bind-tool summary');
  await editor.selectOption('select[name="bind-surface"]', String(plate));
  await editor.selectOption('select[name="bind-along"]', 'v');
  await editor.fill('input[name="bind-at"]', '0.5');
  await editor.selectOption('select[name="bind-curve"]', String(curve));
  await editor.click('#bind button');
  await viewer.waitForFunction(() => [...window.vsculpt.design.relations.values()].some((r) => r.kind === 'binding'), null, { timeout: 15000 });
  const r = await viewer.evaluate(() => [...window.vsculpt.design.relations.values()].find((x) => x.kind === 'binding'));
  assert.deepEqual([r.curve, r.surface, r.line], [curve, plate, { v: 0.5 }]);
  await viewer.waitForFunction((id) => window.vsculpt.partsView.seams.getObjectByName(`binding-${id}`), r.id, { timeout: 10000 });
  assert.match(await viewer.textContent('#relations'), /binding: plane 1 along v = 0.5 follows curve 1/);
  assert.deepEqual([...editor.errors, ...viewer.errors], []);
  await editor.close();
  await viewer.close();
});

test('a drag on one part: a second page gets frames of that part only, and the other part\'s mesh is not touched', async () => {
  const d = await freshDesign('one-part');
  const editor = await openClient(browser, d.editor);
  const plate = await addPart(editor, '#add-plane');
  const first = await editor.evaluate((p) => [...window.vsculpt.design.parts.keys()].find((k) => k !== p), plate);
  const viewer = await openClient(browser, d.viewer);
  // Count the frames the viewer receives, by part, and the uploads of the first part's mesh.
  await viewer.evaluate(() => {
    const link = window.vsculpt.link;
    const onFrame = link.onFrame;
    window.__framesOf = {};
    link.onFrame = (f) => {
      window.__framesOf[f.part] = (window.__framesOf[f.part] || 0) + 1;
      onFrame(f);
    };
  });
  const uploads = (id) => viewer.evaluate((p) => window.vsculpt.partsView.drawings.get(p).mesh.geometry.attributes.position.version, id);
  const firstBefore = await uploads(first);
  await editor.evaluate((p) => window.vsculpt.selectPart(p), plate);
  const n = await editor.evaluate(() => window.vsculpt.state.icons.size);
  await editor.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.5, v: 0.5 }, { kind: 'load' }));
  await editor.waitForFunction((k) => window.vsculpt.state.icons.size === k + 1, n, { timeout: 10000 });
  const icon = await editor.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
  await editor.evaluate((i) => {
    const { send, state, partsView } = window.vsculpt;
    const p = state.icons.get(i).xyz;
    send({ type: 'drag_start', icon: i });
    for (let k = 1; k <= 6; k++) send({ type: 'drag', icon: i, xyz: [p[0], p[1], p[2] + 0.05 * k * partsView.scale] });
    send({ type: 'drag_end', icon: i });
  }, icon);
  await viewer.waitForFunction((p) => (window.__framesOf[p] || 0) >= 1, plate, { timeout: 15000 });
  await new Promise((r) => setTimeout(r, 800));
  const frames = await viewer.evaluate(() => window.__framesOf);
  assert.ok(frames[plate] >= 1, JSON.stringify(frames));
  assert.equal(frames[first] || 0, 0, `no frame of the part not dragged: ${JSON.stringify(frames)}`);
  assert.equal(await uploads(first), firstBefore, 'its mesh was not uploaded again');
  assert.deepEqual([...editor.errors, ...viewer.errors], []);
  await editor.close();
  await viewer.close();
});
