// Page load and frame cost of the reviewer's page in headless Chromium
// (SwiftShader) against the real server: for each web-client directory
// given (e.g. this one and an export of an older commit, to compare in one
// run), the viewer page is opened ROUNDS times and the time from navigation
// to the first picture (perf.firstPicture) recorded, then the cost of one
// frame (view.render() followed by a 1-pixel readPixels, which waits for the
// GPU) averaged over FRAMES frames, in the shaded and zebra views, and of
// one redraw of the contact shadow (done only when the shape changes).
//
//   VSCULPT_SERVER_BIN=../target/debug/vsculpt-server node bench/shading.mjs [web-client dir …]

import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { startServer, stopServer, launchChromium, webDir } from '../tests/harness.mjs';

const ROUNDS = Number(process.env.ROUNDS || 5);
const FRAMES = Number(process.env.FRAMES || 60);
const dirs = process.argv.slice(2).length ? process.argv.slice(2) : [webDir];
const median = (a) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];

const browser = await launchChromium();
const results = [];
for (const dir of dirs) {
  const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-shading-'));
  const server = await startServer({ dataDir, dir });
  const load = [];
  const shadow = [];
  const frame = { shaded: [], zebra: [] };
  for (let k = 0; k < ROUNDS; k++) {
    const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
    await page.goto(server.viewer);
    await page.waitForFunction(() => window.vsculpt && window.vsculpt.perf.firstPicture, null, { timeout: 120000 });
    load.push(await page.evaluate(() => window.vsculpt.perf.firstPicture));
    for (const mode of ['shaded', 'zebra']) {
      await page.selectOption('#mode', mode);
      frame[mode].push(
        await page.evaluate(async (n) => {
          const v = window.vsculpt.view;
          const gl = v.renderer.getContext();
          const px = new Uint8Array(4);
          v.renderer.setAnimationLoop(null);
          for (let i = 0; i < 5; i++) v.render();
          gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
          const t0 = performance.now();
          for (let i = 0; i < n; i++) {
            v.render();
            gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
          }
          return (performance.now() - t0) / n;
        }, FRAMES),
      );
    }
    // One redraw of the contact shadow (when the shape changes), where there is one.
    shadow.push(
      await page.evaluate((n) => {
        const v = window.vsculpt.view;
        if (!v.shadow) return null;
        const gl = v.renderer.getContext();
        const px = new Uint8Array(4);
        v.shadow.box.copy(v.bounds());
        v.shadow.draw();
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
        const t0 = performance.now();
        for (let i = 0; i < n; i++) {
          v.shadow.draw();
          gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
        }
        return (performance.now() - t0) / n;
      }, FRAMES),
    );
    await page.close();
  }
  await stopServer(server);
  rmSync(dataDir, { recursive: true, force: true });
  results.push({ dir, loadMs: median(load), shadedFrameMs: median(frame.shaded), zebraFrameMs: median(frame.zebra), shadowDrawMs: median(shadow), load, frame });
}
await browser.close();
for (const r of results) console.log(JSON.stringify(r));
