// The README's pictures of the two pages, made here: the designer's page
// (the demo design, an icon selected with its gizmo, the panel) and the
// reviewer's page (the same design through the viewer link, following the
// designer's camera), both at 1280 × 720 in real headless Chromium against
// the real server. Every run writes them to test-artifacts/ and checks that
// each shows a drawn design; `VSCULPT_UPDATE_SCREENSHOTS=1 npm test --
// tests/screenshots.test.mjs` also writes them to docs/screenshots/, which
// the README shows. The test checks that the README's pictures exist and are
// pictures of that size, so the README cannot point at nothing.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { copyFileSync, mkdirSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { serverAndBrowser, webDir } from './harness.mjs';

let server;
let browser;
serverAndBrowser('vsculpt-shots-', (s, b) => {
  server = s;
  browser = b;
});

const repo = join(webDir, '..');
const artifacts = join(webDir, 'test-artifacts');
const docs = join(repo, 'docs', 'screenshots');
const SIZE = { width: 1280, height: 720 };

/** Opens `url` at 1280 × 720 and waits for the first picture. */
async function open(url) {
  const page = await browser.newPage({ viewport: SIZE });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.errors = errors;
  await page.goto(url);
  await page.waitForFunction(() => window.vsculpt && window.vsculpt.design.joined && window.vsculpt.partsView.drawings.size && !document.querySelector('#shell:not(.done)'), null, { timeout: 30000 });
  return page;
}

/** Fraction of the 3D view's pixels that are not the background. */
async function drawn(page) {
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
    for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 0x20) + Math.abs(d[i + 1] - 0x24) + Math.abs(d[i + 2] - 0x2b) >= 12) n++;
    return n / (d.length / 4);
  });
}

/** Width and height from a PNG's IHDR chunk (PNG spec §11.2.2: signature, length, "IHDR", width, height, big-endian). */
function pngSize(path) {
  const b = readFileSync(path);
  assert.deepEqual([...b.subarray(0, 8)], [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a], `${path} is not a PNG`);
  assert.equal(b.subarray(12, 16).toString('latin1'), 'IHDR');
  return { width: b.readUInt32BE(16), height: b.readUInt32BE(20) };
}

test('the README shows the designer’s and the reviewer’s pages as these tests make them', async () => {
  mkdirSync(artifacts, { recursive: true });
  const editor = await open(`${server.editor}&name=Ana`);
  // Select the demo's load icon: the gizmo and the icon's properties show.
  await editor.evaluate(() => {
    const { state, select } = window.vsculpt;
    const load = [...state.icons.values()].find((i) => i.role === 'load') || [...state.icons.values()][0];
    select(load.id);
  });
  const viewer = await open(`${server.viewer}&name=Carl`);
  await viewer.waitForFunction(() => !document.querySelector('#follow').hidden, null, { timeout: 20000 });
  await viewer.click('#follow');
  await viewer.waitForFunction(() => document.querySelector('#follow').getAttribute('aria-pressed') === 'true');
  // The glide to the designer's camera has ended.
  await viewer.waitForFunction(() => {
    const { view, state, follow } = window.vsculpt;
    const c = state.presence.find((p) => p.client === follow.following)?.camera;
    return c && view.camera.position.toArray().every((x, i) => Math.abs(x - c.eye[i]) <= 1e-9 * (1 + Math.abs(c.eye[i])));
  }, null, { timeout: 20000 });
  const shots = { 'editor.png': editor, 'viewer.png': viewer };
  for (const [name, page] of Object.entries(shots)) {
    const f = await drawn(page);
    // The demo is the mouse with the spool body beside it (the view frames both: 0.052 of the
    // view measured at 1280 × 720); an empty view covers none.
    assert.ok(f > 0.03, `${name}: the design covers ${f} of the view`);
    await page.screenshot({ path: join(artifacts, name) });
    assert.deepEqual(pngSize(join(artifacts, name)), SIZE);
    if (process.env.VSCULPT_UPDATE_SCREENSHOTS === '1') {
      mkdirSync(docs, { recursive: true });
      copyFileSync(join(artifacts, name), join(docs, name));
    }
  }
  // The README shows both, and what it shows exists at that size.
  const readme = readFileSync(join(repo, 'README.md'), 'utf8');
  for (const name of Object.keys(shots)) {
    assert.ok(readme.includes(`](docs/screenshots/${name})`), `README.md shows docs/screenshots/${name}`);
    assert.deepEqual(pngSize(join(docs, name)), SIZE, name);
  }
  assert.deepEqual(editor.errors, []);
  assert.deepEqual(viewer.errors, []);
  await editor.close();
  await viewer.close();
});
