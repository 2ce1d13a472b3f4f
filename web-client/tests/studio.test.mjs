// The product's shading, in real headless Chromium against the real server
// (the demo design): the surface's normals are the B-spline's own (smooth,
// no facets along the rim), the studio's environment light brightens the
// shaded parts and leaves the analysis views' colours alone, and the
// reviewer's page shows a contact shadow on the ground under the model in
// the shaded view only (the designer's page has none).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { serverAndBrowser, openClient } from './harness.mjs';

let server;
let browser;
serverAndBrowser('vsculpt-studio-', (s, b) => {
  server = s;
  browser = b;
});

/** Background colour of the view (view.js: 0x20242b). */
const BG = [0x20, 0x24, 0x2b];

/**
 * Renders the page's view once after `before()` (a function source run in
 * the page with `v` the view) and returns its pixels (RGBA, bottom row
 * first), then runs `after()`. All in one task: no frame of the page's own
 * loop comes between.
 */
function picture(page, before = '', after = '') {
  return page.evaluate(
    ([b, a]) => {
      const v = window.vsculpt.view;
      new Function('v', b)(v);
      v.render();
      const gl = v.renderer.getContext();
      const w = gl.drawingBufferWidth;
      const h = gl.drawingBufferHeight;
      const px = new Uint8Array(w * h * 4);
      gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
      new Function('v', a)(v);
      return { w, h, px: Array.from(px) };
    },
    [before, after],
  );
}

const isBg = (p, i) => Math.abs(p[i] - BG[0]) + Math.abs(p[i + 1] - BG[1]) + Math.abs(p[i + 2] - BG[2]) <= 3;

test('the demo surface’s normals are its own: smooth along the rim (no facets), equal to the normal of its tessellation', async () => {
  const page = await openClient(browser, server.editor);
  const r = await page.evaluate(() => {
    const { design, partsView } = window.vsculpt;
    const part = [...design.parts.values()].find((p) => p.name === 'top shell');
    const d = partsView.drawings.get(part.id);
    const { su, sv } = d.tess;
    const P = d.mesh.geometry.attributes.position.array;
    const N = d.mesh.geometry.attributes.normal.array;
    const at = (A, a, b) => [A[3 * (a * sv + b)], A[3 * (a * sv + b) + 1], A[3 * (a * sv + b) + 2]];
    const sub = (x, y) => x.map((c, k) => c - y[k]);
    const cross = (x, y) => [x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]];
    const unit = (x) => x.map((c) => c / Math.hypot(...x));
    const angle = (x, y) => (Math.acos(Math.min(1, Math.abs(x[0] * y[0] + x[1] * y[1] + x[2] * y[2]))) * 180) / Math.PI;
    let worstStep = 0;
    let worstFacet = 0;
    let worstLength = 0;
    // The rim: the first and last rows and columns of the grid.
    const rim = [];
    for (let a = 0; a < su; a++) rim.push([a, 0], [a, sv - 1]);
    for (let b = 0; b < sv; b++) rim.push([0, b], [su - 1, b]);
    for (const [a, b] of rim) {
      const n = at(N, a, b);
      worstLength = Math.max(worstLength, Math.abs(Math.hypot(...n) - 1));
      // The normal of the mesh around the vertex, from its neighbours (one-sided at the border).
      const du = sub(at(P, Math.min(a + 1, su - 1), b), at(P, Math.max(a - 1, 0), b));
      const dv = sub(at(P, a, Math.min(b + 1, sv - 1)), at(P, a, Math.max(b - 1, 0)));
      worstFacet = Math.max(worstFacet, angle(unit(n), unit(cross(du, dv))));
      // Neighbouring rim normals turn a little (a facet would turn them at once).
      if (b === 0 || b === sv - 1) if (a + 1 < su) worstStep = Math.max(worstStep, angle(n, at(N, a + 1, b)));
      if (a === 0 || a === su - 1) if (b + 1 < sv) worstStep = Math.max(worstStep, angle(n, at(N, a, b + 1)));
    }
    return { su, sv, worstStep, worstFacet, worstLength };
  });
  assert.ok(r.su * r.sv > 1000, `a fine tessellation: ${r.su} × ${r.sv}`);
  assert.ok(r.worstLength < 1e-4, `unit normals: ${r.worstLength}`);
  assert.ok(r.worstFacet < 3, `vertex normals agree with the mesh around them: worst ${r.worstFacet}°`);
  assert.ok(r.worstStep < 4, `neighbouring rim normals differ by at most ${r.worstStep}°`);
  await page.close();
});

test('the studio light brightens the shaded parts and leaves the curvature view’s colours alone; the designer’s page has no ground shadow', async () => {
  const page = await openClient(browser, server.editor);
  const off = 'v.studio.uniforms.studioIntensity.value = 0;';
  const on = 'v.studio.uniforms.studioIntensity.value = 0.5;';
  const compare = async () => {
    const dark = await picture(page, off, on);
    const lit = await picture(page);
    let drawn = 0;
    let brighter = 0;
    let changed = 0;
    for (let i = 0; i < lit.px.length; i += 4) {
      if (isBg(lit.px, i)) continue;
      drawn++;
      const d = lit.px[i] + lit.px[i + 1] + lit.px[i + 2] - (dark.px[i] + dark.px[i + 1] + dark.px[i + 2]);
      if (d > 6) brighter++;
      if (d !== 0) changed++;
    }
    return { drawn, brighter, changed };
  };
  const shaded = await compare();
  assert.ok(shaded.drawn > 20000, `the design is drawn: ${shaded.drawn} px`);
  assert.ok(shaded.brighter > 0.5 * shaded.drawn, `the studio lights most of the shaded picture: ${JSON.stringify(shaded)}`);
  await page.selectOption('#mode', 'mean');
  await page.waitForFunction(() => window.vsculpt.view.mode === 'mean');
  // The demo's body (the spool), which the curvature views do not colour and the studio lights, is set aside here.
  await page.evaluate(() => window.vsculpt.bodyView.bodies.forEach((b) => (b.group.visible = false)));
  const mean = await compare();
  await page.evaluate(() => window.vsculpt.bodyView.bodies.forEach((b) => (b.group.visible = true)));
  assert.ok(mean.drawn > 20000);
  // The surfaces' curvature colours do not take the studio (the thin feature-line tube, still shaded, does).
  assert.ok(mean.changed < 0.1 * mean.drawn, `the curvature colours do not take the studio: ${JSON.stringify(mean)}`);
  await page.selectOption('#mode', 'shaded');
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  assert.equal(await page.evaluate(() => window.vsculpt.view.shadow.ground.visible), false, 'no ground shadow on the designer’s page');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the reviewer’s page: a contact shadow darkens the ground under the model in the shaded view, none in the curvature and zebra views', async () => {
  const page = await openClient(browser, server.viewer);
  await page.waitForFunction(() => window.vsculpt.view.shadow.draws > 0, null, { timeout: 20000 });
  // The same picture with the shadow and without it: the pixels it darkens.
  const without = await picture(page, 'v.shadow.ground.material.visible = false;', 'v.shadow.ground.material.visible = true;');
  const withShadow = await picture(page);
  const shadowPx = [];
  let onModel = 0;
  let model = { x0: Infinity, x1: -Infinity, y0: Infinity, y1: -Infinity };
  let shadowBox = { x0: Infinity, x1: -Infinity, y0: Infinity, y1: -Infinity };
  const grow = (box, x, y) => ({ x0: Math.min(box.x0, x), x1: Math.max(box.x1, x), y0: Math.min(box.y0, y), y1: Math.max(box.y1, y) });
  for (let i = 0; i < withShadow.px.length; i += 4) {
    const x = (i / 4) % withShadow.w;
    const y = Math.floor(i / 4 / withShadow.w);
    if (!isBg(without.px, i)) model = grow(model, x, y);
    const d = without.px[i] + without.px[i + 1] + without.px[i + 2] - (withShadow.px[i] + withShadow.px[i + 1] + withShadow.px[i + 2]);
    if (d > 6) {
      // The ground darkens, where the picture without the shadow is the background (and a
      // few of the model's antialiased edge pixels where it meets the ground).
      if (isBg(without.px, i)) {
        shadowPx.push(i);
        shadowBox = grow(shadowBox, x, y);
      } else {
        onModel++;
      }
    }
  }
  const n = withShadow.w * withShadow.h;
  assert.ok(onModel < 0.1 * shadowPx.length, `the shadow is on the ground: ${shadowPx.length} px, ${onModel} on the model`);
  assert.ok(shadowPx.length > 0.003 * n, `the shadow darkens ${shadowPx.length} of ${n} pixels`);
  // Under the model: at its feet (the bottom of its picture; y here counts from the bottom), within its width.
  assert.ok(shadowBox.y0 < model.y0 + 0.25 * (model.y1 - model.y0), `the shadow (${JSON.stringify(shadowBox)}) reaches the model's feet (${JSON.stringify(model)})`);
  assert.ok(shadowBox.x0 >= model.x0 - 0.3 * (model.x1 - model.x0) && shadowBox.x1 <= model.x1 + 0.3 * (model.x1 - model.x0), 'and lies under it');
  for (const mode of ['mean', 'zebra']) {
    await page.selectOption('#mode', mode);
    await page.waitForFunction((m) => window.vsculpt.view.mode === m, mode);
    const p = await picture(page);
    const left = shadowPx.filter((i) => !isBg(p.px, i)).length;
    assert.equal(left, 0, `${mode}: the shadow's pixels are background again (${left} are not)`);
  }
  await page.selectOption('#mode', 'shaded');
  await page.waitForFunction(() => window.vsculpt.view.mode === 'shaded');
  const back = await picture(page);
  const shadowAgain = shadowPx.filter((i) => !isBg(back.px, i)).length;
  assert.ok(shadowAgain > 0.9 * shadowPx.length, `back in the shaded view, the shadow is back: ${shadowAgain} of ${shadowPx.length}`);
  assert.deepEqual(page.errors, []);
  await page.close();
});
