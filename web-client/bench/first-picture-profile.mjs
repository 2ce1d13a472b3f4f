// Where a warm first picture's time goes, for the issue-18 work: loads the
// demo's viewer page (cold, then three warm reloads, on loopback), lists the
// shader programs compiled by the first picture, then profiles one more warm
// reload with the DevTools CPU profiler and prints the self time per
// function and per script, and the page's resource timings. Each warm reload
// (2 s after the previous picture) prints the page's own marks (vsculpt:*, ms
// since navigation start: module evaluation, hello, welcome, the first frame
// — from the geometry cache on a warm visit —, the first redraw, the picture).
//
//   VSCULPT_SERVER_BIN=../target/release/vsculpt-server node bench/first-picture-profile.mjs
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { webDir, serverBin, startServer, stopServer, launchChromium } from '../tests/harness.mjs';
const firstPicture = () => new Promise((resolve) => { const poll = () => { const p = window.vsculpt && window.vsculpt.perf; if (p && (p.shown > 0 || p.redraws > 0)) requestAnimationFrame(() => resolve(performance.now())); else requestAnimationFrame(poll); }; poll(); });
const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-first-picture-profile-'));
const server = await startServer({ dataDir, dir: webDir, bin: serverBin });
const browser = await launchChromium();
try {
  const context = await browser.newContext({ viewport: { width: 1100, height: 700 } });
  const page = await context.newPage();
  await page.goto(server.viewer, { waitUntil: 'commit' });
  console.log('cold local', await page.evaluate(firstPicture));
  const pageMarks = () => page.evaluate(() => performance.getEntriesByType('mark').filter((m) => m.name.startsWith('vsculpt:')).map((m) => `${m.name.slice(8)}@${Math.round(m.startTime)}`).join(' '));
  for (let i = 0; i < 3; i++) {
    await new Promise((r) => setTimeout(r, 2000));
    await page.reload({ waitUntil: 'commit' });
    console.log('warm local', await page.evaluate(firstPicture), await pageMarks());
  }
  const progs = await page.evaluate(() => window.vsculpt.view.renderer.info.programs.map(p => [p.name, p.cacheKey.slice(0, 120)]));
  console.log('programs', progs.length); for (const p of progs) console.log('  ', p[0], '|', p[1]);
  const cdp = await context.newCDPSession(page);
  await cdp.send('Profiler.enable');
  await cdp.send('Profiler.setSamplingInterval', { interval: 200 });
  await cdp.send('Profiler.start');
  await page.reload({ waitUntil: 'commit' });
  const t = await page.evaluate(firstPicture);
  const marks = await page.evaluate(() => { const n = performance.getEntriesByType('navigation')[0]; return { dcl: n.domContentLoadedEventEnd, load: n.loadEventEnd, res: performance.getEntriesByType('resource').map(r => [r.name.replace(/^.*\/\/[^/]+/, '').slice(0, 50), Math.round(r.startTime), Math.round(r.responseEnd)]) }; });
  const { profile } = await cdp.send('Profiler.stop');
  console.log('warm profiled', t, 'dcl', marks.dcl);
  const dt = profile.timeDeltas; const self = new Map(); const byId = new Map(profile.nodes.map(n => [n.id, n]));
  const counts = new Map(); for (const s of profile.samples) counts.set(s, (counts.get(s) ?? 0) + 1);
  const total = (profile.endTime - profile.startTime) / 1000; const per = total / profile.samples.length;
  for (const [id, c] of counts) { const n = byId.get(id); const f = n.callFrame; const k = `${f.functionName || '(anon)'} ${f.url.replace(/^.*\/\/[^/]+/, '').replace(/\?v=.*/, '')}:${f.lineNumber}`; self.set(k, (self.get(k) ?? 0) + c * per); }
  console.log('profile total ms', total.toFixed(0));
  for (const [k, v] of [...self].sort((a, b) => b[1] - a[1]).slice(0, 30)) console.log(v.toFixed(1).padStart(8), k);
  // by url
  const byUrl = new Map(); for (const [k, v] of self) { const u = k.split(' ').slice(1).join(' ').split(':')[0] || k; byUrl.set(u, (byUrl.get(u) ?? 0) + v); }
  console.log('--- by url'); for (const [k, v] of [...byUrl].sort((a, b) => b[1] - a[1]).slice(0, 15)) console.log(v.toFixed(1).padStart(8), k);
  console.log('--- resources'); for (const r of marks.res) console.log(r.join(' '));
} finally { await browser.close(); await stopServer(server); rmSync(dataDir, { recursive: true, force: true }); }
