// Review comments, the customer's feedback loop, in real headless Chromium
// against the real server binary: on the reviewer's (viewer's) page the
// comment tool is switched on and a real mouse click on the demo's shell
// places a pin; the comment is typed with the keyboard and posted. The
// designer's (editor's) page shows it live, with its pin at the surface
// point of the click — checked against this file's own Cox–de Boor
// evaluation of the shell's control net, not bspline.js — drawn over the
// model; the designer resolves it with a real click and the reviewer's page
// shows it resolved; clicking its entry frames its pin. After the server is
// restarted on the same data directory, both pages reconnect and still show
// it (resolved, at the same point), and so does a page opened afresh.
// Editing: the reviewer edits its comment's text with real clicks and the
// designer's page shows the new text; the edit is offered on the designer's
// reply only to the designer; the version history marks the version the
// comment was written on, and the mark frames its pin.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { serverAndBrowser, openClient, startServer, stopServer } from './harness.mjs';

let server;
let browser;
const dataDir = serverAndBrowser('vsculpt-comments-', (s, b) => {
  server = s;
  browser = b;
});

/** N_{i,p}(t) by the Cox–de Boor recursion (0/0 = 0; the last span closed at its right end). */
function basis(knots, i, p, t) {
  if (p === 0) {
    const last = knots[knots.length - 1];
    if (t === last) return knots[i] < t && knots[i + 1] === last ? 1 : 0;
    return knots[i] <= t && t < knots[i + 1] ? 1 : 0;
  }
  const a = knots[i + p] - knots[i];
  const b = knots[i + p + 1] - knots[i + 1];
  return (a > 0 ? ((t - knots[i]) / a) * basis(knots, i, p - 1, t) : 0) + (b > 0 ? ((knots[i + p + 1] - t) / b) * basis(knots, i + 1, p - 1, t) : 0);
}

/** The surface point at (u, v). */
function point(s, u, v) {
  const out = [0, 0, 0];
  for (let i = 0; i < s.nu; i++) {
    const bu = basis(s.knotsU, i, s.degreeU, u);
    if (bu === 0) continue;
    for (let j = 0; j < s.nv; j++) {
      const w = bu * basis(s.knotsV, j, s.degreeV, v);
      for (let x = 0; x < 3; x++) out[x] += w * s.points[3 * (i * s.nv + j) + x];
    }
  }
  return out;
}

/** Screen position (page pixels) of the tessellation vertex of part `part` nearest (u, v), as the page projects it. */
function screenAt(page, part, u, v) {
  return page.evaluate(
    ([id, uu, vv]) => {
      const { view, partsView } = window.vsculpt;
      const t = partsView.drawings.get(id).tess;
      let best = 0;
      for (let i = 0; i < t.su * t.sv; i++) {
        const d = (k) => Math.hypot(t.uvs[2 * k] - uu, t.uvs[2 * k + 1] - vv);
        if (d(i) < d(best)) best = i;
      }
      const p = view.camera.position.clone().set(t.positions[3 * best], t.positions[3 * best + 1], t.positions[3 * best + 2]);
      view.model.localToWorld(p);
      p.project(view.camera);
      const r = view.renderer.domElement.getBoundingClientRect();
      return { x: r.left + ((p.x + 1) / 2) * r.width, y: r.top + ((1 - p.y) / 2) * r.height };
    },
    [part, u, v],
  );
}

/** What `page` shows of comment `id`: the comment, its pin (point, head, on screen, drawn over the model), its list entry, and the part's surface. */
function shown(page, id) {
  return page.evaluate((cid) => {
    const { comments, design, view } = window.vsculpt;
    const c = comments.comments.get(cid);
    const pin = comments.pins.get(cid);
    if (!c || !pin) return null;
    const g = design.parts.get(c.part).geometry;
    const head = pin.children[1].getWorldPosition(pin.position.clone());
    const foot = pin.getWorldPosition(pin.position.clone());
    const q = head.clone().project(view.camera);
    const li = document.querySelector(`#comments li[data-comment="${cid}"]`);
    let overModel = true;
    pin.traverse((m) => {
      if (m.material && (m.material.depthTest || m.renderOrder < 10)) overModel = false;
    });
    return {
      comment: c,
      point: pin.userData.point,
      foot: foot.toArray(),
      head: head.toArray(),
      onScreen: Math.abs(q.x) < 1 && Math.abs(q.y) < 1 && q.z < 1,
      overModel,
      visible: pin.visible && comments.group.visible,
      entry: li ? { text: li.textContent.replace(/\s+/g, ' '), cls: li.className } : null,
      surface: { ...g, knotsU: [...g.knotsU], knotsV: [...g.knotsV], points: [...g.points] },
    };
  }, id);
}

/** The largest extent of a flat control net. */
function sizeOf(s) {
  return Math.hypot(...[0, 1, 2].map((x) => Math.max(...s.points.filter((_, k) => k % 3 === x)) - Math.min(...s.points.filter((_, k) => k % 3 === x))));
}

/** Checks that the pin of `got` stands at S(u, v) of its part, by this file's own evaluation. */
function assertPinOnSurface(got, label) {
  const s = got.surface;
  const size = sizeOf(s);
  const { u, v } = got.comment.anchor;
  const want = point(s, u, v);
  const off = (a) => Math.max(...a.map((x, k) => Math.abs(x - want[k])));
  assert.ok(off(got.point) <= 1e-9 * size, `${label}: pin point ${got.point} is not S(${u}, ${v}) = ${want}`);
  // The page's frame points are f32; the server's xyz was evaluated on its f64 net.
  assert.ok(off(got.comment.anchor.xyz) <= 1e-5 * size, `${label}: stored xyz ${got.comment.anchor.xyz} vs ${want}`);
  assert.ok(off(got.foot) <= 1e-9 * size, `${label}: the pin's foot ${got.foot} is not at S(u, v)`);
  const stem = Math.hypot(...got.head.map((x, k) => x - got.foot[k]));
  assert.ok(stem > 0.01 * size, `${label}: the pin's head stands off the surface (stem ${stem})`);
  assert.ok(got.onScreen && got.visible && got.overModel, `${label}: the pin is drawn, on screen, over the model`);
}

// Runs before the restart test below, and leaves no comment behind.
test('a reviewer edits its comment with the mouse and the designer sees it live; only the author side or an editor is offered the edit; the history marks the version commented on', async () => {
  const editor = await openClient(browser, `${server.editor}&name=Ana`);
  const viewer = await openClient(browser, `${server.viewer}&name=Ben`);
  try {
    const shell = await viewer.evaluate(() => [...window.vsculpt.design.parts.values()].find((p) => p.kind === 'surface').id);
    // A version for the review.
    const before = await editor.evaluate(() => window.vsculpt.state.versions.length);
    await editor.evaluate(() => window.vsculpt.send({ type: 'commit', message: 'for review' }));
    await viewer.waitForFunction((n) => window.vsculpt.state.versions.length > n, before, { timeout: 20000 });
    const version = await viewer.evaluate(() => Math.max(...window.vsculpt.state.versions.map((v) => v.version)));
    assert.equal(await editor.locator('#history button[data-commented]').count(), 0);
    await viewer.evaluate((part) => window.vsculpt.send({ type: 'add_comment', part, anchor: { u: 0.5, v: 0.5 }, text: 'First thought' }), shell);
    await editor.waitForFunction(() => window.vsculpt.comments.comments.size === 1, null, { timeout: 20000 });
    const id = await editor.evaluate(() => [...window.vsculpt.comments.comments.keys()][0]);

    // The history marks the version it was written on, on both pages.
    for (const page of [editor, viewer]) {
      const mark = page.locator(`#history li:has(b:text-is("v${version}")) button[data-commented]`);
      await mark.waitFor({ timeout: 20000 });
      assert.equal((await mark.textContent()).trim(), '💬 1');
    }

    // The reviewer edits it: edit, new text, save; until then nothing says "edited".
    for (const page of [editor, viewer]) assert.equal(await page.locator(`#comments [data-edited="${id}"]`).count(), 0);
    await viewer.waitForSelector(`#comments li[data-comment="${id}"] button[data-edit="${id}"]`);
    await viewer.click(`#comments li[data-comment="${id}"] button[data-edit="${id}"]`);
    const box = viewer.locator(`#comments form[data-edit-form="${id}"] textarea`);
    assert.equal(await box.inputValue(), 'First thought');
    await box.fill('Second thought: softer <edge> & lower');
    await viewer.click(`#comments form[data-edit-form="${id}"] button:text-is("save")`);
    await editor.waitForFunction((cid) => window.vsculpt.comments.comments.get(cid)?.text === 'Second thought: softer <edge> & lower', id, { timeout: 20000 });
    const entry = (page) => page.locator(`#comments li[data-comment="${id}"] > p`).textContent();
    assert.equal(await entry(editor), 'Second thought: softer <edge> & lower');
    await viewer.waitForFunction((cid) => !document.querySelector(`form[data-edit-form="${cid}"]`) && window.vsculpt.comments.comments.get(cid)?.text === 'Second thought: softer <edge> & lower', id, { timeout: 20000 });
    assert.equal(await entry(viewer), 'Second thought: softer <edge> & lower');
    // Both pages mark it edited, with the server's time of the edit on hover.
    for (const page of [editor, viewer]) {
      const mark = page.locator(`#comments li[data-comment="${id}"] [data-edited="${id}"]`);
      await mark.waitFor({ timeout: 20000 });
      assert.equal((await mark.textContent()).trim(), 'edited');
      const [title, expected] = await page.evaluate((cid) => {
        const c = window.vsculpt.comments.comments.get(cid);
        return [document.querySelector(`[data-edited="${cid}"]`).title, `edited ${new Date(c.edited_ms).toLocaleString()}`];
      }, id);
      assert.equal(title, expected);
      assert.ok(await page.evaluate((cid) => window.vsculpt.comments.comments.get(cid).edited_ms >= window.vsculpt.comments.comments.get(cid).time_ms, id));
    }

    // The designer's reply: the designer may edit it, the reviewer is not offered to.
    await editor.evaluate((cid) => window.vsculpt.send({ type: 'reply_comment', comment: cid, text: 'ok' }), id);
    await viewer.waitForFunction((cid) => window.vsculpt.comments.comments.get(cid)?.replies.length === 1, id, { timeout: 20000 });
    const reply = await viewer.evaluate((cid) => window.vsculpt.comments.comments.get(cid).replies[0].id, id);
    await editor.waitForSelector(`#comments button[data-edit="${reply}"]`);
    assert.equal(await viewer.locator(`#comments button[data-edit="${reply}"]`).count(), 0);
    await editor.click(`#comments button[data-edit="${reply}"]`);
    await editor.locator(`#comments form[data-edit-form="${reply}"] textarea`).fill('done in the next version');
    await editor.click(`#comments form[data-edit-form="${reply}"] button:text-is("save")`);
    await viewer.waitForFunction((cid) => window.vsculpt.comments.comments.get(cid)?.replies[0].text === 'done in the next version', id, { timeout: 20000 });

    // The history's mark frames the comment's pin.
    await editor.click(`#history button[data-commented="${id}"]`);
    const target = await editor.evaluate(() => window.vsculpt.view.controls.target.toArray());
    const foot = await editor.evaluate((cid) => window.vsculpt.comments.pins.get(cid).getWorldPosition(window.vsculpt.comments.pins.get(cid).position.clone()).toArray(), id);
    assert.ok(Math.max(...target.map((x, k) => Math.abs(x - foot[k]))) <= 1e-6 * (1 + Math.max(...foot.map(Math.abs))), `framed at ${target}, pin at ${foot}`);

    // Deleted: the mark goes with it.
    await editor.click(`#comments li[data-comment="${id}"] > button[data-delete="${id}"]`);
    for (const page of [editor, viewer]) {
      await page.waitForFunction(() => window.vsculpt.comments.comments.size === 0 && !document.querySelector('#history button[data-commented]'), null, { timeout: 20000 });
    }
    for (const page of [editor, viewer]) assert.deepEqual(page.errors, []);
  } finally {
    await editor.close();
    await viewer.close();
  }
});

test('a reviewer pins a comment with the mouse; the designer sees it live at the surface point and resolves it; it survives a restart', async () => {
  const editor = await openClient(browser, `${server.editor}&name=Ana`);
  const viewer = await openClient(browser, `${server.viewer}&name=Ben`);
  const shell = await viewer.evaluate(() => [...window.vsculpt.design.parts.values()].find((p) => p.kind === 'surface').id);
  const version = await viewer.evaluate(() => Math.max(0, ...window.vsculpt.state.versions.map((v) => v.version)));

  // The reviewer switches the comment tool on and clicks the shell.
  await viewer.click('#comment-tool');
  assert.equal(await viewer.getAttribute('#comment-tool', 'aria-pressed'), 'true');
  assert.ok(await viewer.isHidden('#comment-draft'));
  const at = await screenAt(viewer, shell, 0.4, 0.6);
  await viewer.mouse.click(at.x, at.y);
  await viewer.waitForSelector('#comment-draft:not([hidden])');
  const draft = await viewer.evaluate(() => window.vsculpt.comments.pending);
  assert.equal(draft.part, shell);
  assert.ok(Math.abs(draft.u - 0.4) < 0.05 && Math.abs(draft.v - 0.6) < 0.05, `the click landed at (${draft.u}, ${draft.v})`);
  const text = 'The edge feels too sharp here.\nCould it be softer?';
  await viewer.click('#comment-text');
  await viewer.keyboard.type('The edge feels too sharp here.');
  await viewer.keyboard.press('Shift+Enter');
  await viewer.keyboard.type('Could it be softer?');
  await viewer.click('#comment-post');

  // The designer's page has it live, pinned where the reviewer clicked.
  await editor.waitForFunction(() => window.vsculpt.comments.comments.size === 1, null, { timeout: 20000 });
  const id = await editor.evaluate(() => [...window.vsculpt.comments.comments.keys()][0]);
  const got = await shown(editor, id);
  assert.equal(got.comment.text, text);
  assert.equal(got.comment.part, shell);
  assert.equal(got.comment.author, 'Ben');
  assert.equal(got.comment.access, 'viewer');
  assert.equal(got.comment.version, version);
  assert.equal(got.comment.resolved, false);
  // The pin is at the (u, v) of the click, not somewhere near it.
  assert.equal(got.comment.anchor.u, draft.u);
  assert.equal(got.comment.anchor.v, draft.v);
  assertPinOnSurface(got, 'editor');
  assert.match(got.entry.text, /Ben reviewer · .* · on v\d+ open The edge feels too sharp here\. Could it be softer\?/);
  assert.match(got.entry.cls, /\bopen\b/);
  // The reviewer's own page shows it too; its draft is gone.
  await viewer.waitForFunction((cid) => window.vsculpt.comments.pins.has(cid), id);
  assert.ok(await viewer.isHidden('#comment-draft'));
  assert.ok(!(await viewer.evaluate(() => window.vsculpt.comments.pins.has(-1))));

  // The designer resolves it with a click; the reviewer sees that.
  await editor.click(`#comments li[data-comment="${id}"] button[data-resolve]`);
  await viewer.waitForFunction((cid) => window.vsculpt.comments.comments.get(cid)?.resolved === true, id, { timeout: 20000 });
  const resolved = await shown(viewer, id);
  assert.equal(resolved.comment.resolved_by, 'Ana');
  assert.match(resolved.entry.cls, /\bresolved\b/);
  assert.match(resolved.entry.text, /resolved by Ana/);
  assertPinOnSurface(resolved, 'viewer');

  // Clicking the entry frames its pin on the reviewer's page.
  await viewer.keyboard.press('Escape');
  assert.equal(await viewer.getAttribute('#comment-tool', 'aria-pressed'), 'false');
  await viewer.click(`#comments li[data-comment="${id}"] p`);
  const target = await viewer.evaluate(() => window.vsculpt.view.controls.target.toArray());
  const foot = (await shown(viewer, id)).foot;
  assert.ok(Math.max(...target.map((x, k) => Math.abs(x - foot[k]))) <= 1e-9 * sizeOf(resolved.surface), `framed at ${target}, pin at ${foot}`);

  // Restart the server on the same data directory and address: the pages
  // reconnect and still show the comment, resolved, at the same point.
  const address = new URL(server.base).host;
  // The pages forget the comments: only the restarted server can bring them back.
  for (const page of [editor, viewer]) await page.evaluate(() => window.vsculpt.comments.setAll([]));
  await stopServer(server);
  await editor.waitForFunction(() => !window.vsculpt.state.online, null, { timeout: 20000 });
  const again = await startServer({ dataDir, listen: address });
  try {
    for (const page of [editor, viewer]) {
      await page.waitForFunction(
        (cid) => window.vsculpt.state.online && window.vsculpt.comments.comments.get(cid)?.resolved === true && window.vsculpt.comments.pins.has(cid),
        id,
        { timeout: 30000 },
      );
    }
    for (const page of [editor, viewer]) assert.deepEqual(page.errors, []);
    // Two pages drawing continuously load a small machine: the new page joins alone.
    await editor.close();
    await viewer.close();
    const fresh = await openClient(browser, `${again.editor}&name=Ana`, async (page) => page.setDefaultNavigationTimeout(120000));
    await fresh.waitForFunction((cid) => window.vsculpt.comments.pins.has(cid), id);
    const back = await shown(fresh, id);
    assert.equal(back.comment.text, text);
    assert.equal(back.comment.resolved, true);
    assert.deepEqual(back.comment.anchor, got.comment.anchor);
    assertPinOnSurface(back, 'after the restart');
    assert.deepEqual(fresh.errors, []);
    await fresh.close();
  } finally {
    if (!editor.isClosed()) await editor.close();
    if (!viewer.isClosed()) await viewer.close();
    await stopServer(again);
  }
});
