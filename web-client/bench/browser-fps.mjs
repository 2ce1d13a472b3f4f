// Browser measurement (not a test): the web client in headless Chromium
// against the real server holding an 81×159 bicubic design with a load icon:
//
//   idle    the editor page with nothing moving: how fast this machine
//           draws the mesh at all (the ceiling for the two below);
//   editor  the page drags the icon with its gizmo (mouse moves ~60 Hz);
//   viewer  the page watches while another client (a page in its own
//           browser context, no rendering) drags at 60 Hz over its WebSocket.
//
// For each it reports animation frames per second (requestAnimationFrame
// callbacks), surface updates shown per second (uploads of the mesh's
// position attribute), geometry frames received per second, and the page's
// main-thread JavaScript cost: every requestAnimationFrame, WebSocket and
// Worker message and pointer-event callback timed with performance.now (an
// init script wraps them), per animation frame and per surface update. Work
// in the tessellation worker runs on another thread and is not counted.
// The same run measures this working tree (tessellation in its Web Worker,
// and with ?worker=0 the same fill on the main thread) and the client at a
// baseline git revision (default: the last commit before the fast path),
// alternating.
//
//   node bench/browser-fps.mjs [--before REV|none] [--seconds 5] [--rounds 2] [--parts N]
//
// With --parts N the run also measures the 81×159 part among N parts (N − 1
// small plates beside it, the drags on the big part).
//
// Frame pacing is Chromium's own: headless on this machine it hands a page
// anywhere from ~3 (idle) to ~30 animation frames per second depending on
// input and network activity, not only on the page's work; so read the
// animation rate against the idle line, and the JS cost per surface update
// as the client's own cost. (--disable-frame-rate-limit was tried: the
// unthrottled page floods the software GPU and the run stalls.)
//
// Needs the server binary (VSCULPT_SERVER_BIN, default the release build in
// cargo's target directory, as `cargo metadata` reports it) and
// /usr/bin/chromium (CHROMIUM). Chromium draws with SwiftShader (software
// GL on the CPU), so the frame rate is that of the CPU, shared with the
// server: a machine with a GPU renders far faster.

import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir, cpus } from 'node:os';
import { join } from 'node:path';
import { webDir, serverBinProblem, createDesign, clientAt, startServer, stopServer, launchChromium, openClient, gizmoZArrow } from '../tests/harness.mjs';
import { BASELINE_REV } from './tessellate.mjs';

const arg = (name, fallback) => {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const seconds = Number(arg('seconds', 5));
const rounds = Number(arg('rounds', 2));
const before = arg('before', BASELINE_REV);
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/**
 * Installed in the page before it loads: times every callback the client's
 * main thread runs for a frame (requestAnimationFrame, WebSocket and Worker
 * messages, pointer events) with performance.now, and counts animation frames.
 */
function instrument() {
  window.__js = 0;
  window.__rafs = 0;
  const timed = (fn) =>
    function timedCallback(...args) {
      const t = performance.now();
      try {
        return fn.apply(this, args);
      } finally {
        window.__js += performance.now() - t;
      }
    };
  const raf = window.requestAnimationFrame.bind(window);
  window.requestAnimationFrame = (cb) => raf(timed(cb));
  for (const Class of [WebSocket, Worker]) {
    const d = Object.getOwnPropertyDescriptor(Class.prototype, 'onmessage');
    Object.defineProperty(Class.prototype, 'onmessage', {
      configurable: true,
      get() {
        return d.get.call(this);
      },
      set(fn) {
        d.set.call(this, fn && timed(fn));
      },
    });
  }
  const add = EventTarget.prototype.addEventListener;
  EventTarget.prototype.addEventListener = function addTimed(type, fn, opts) {
    const wrap = typeof fn === 'function' && /^pointer/.test(type);
    if (wrap) {
      fn.__timed = fn.__timed || timed(fn);
      return add.call(this, type, fn.__timed, opts);
    }
    return add.call(this, type, fn, opts);
  };
  const remove = EventTarget.prototype.removeEventListener;
  EventTarget.prototype.removeEventListener = function removeTimed(type, fn, opts) {
    return remove.call(this, type, (fn && fn.__timed) || fn, opts);
  };
  const tick = () => {
    window.__rafs++;
    raf(tick);
  };
  raf(tick);
}

/** Times three's renderer.render apart (drawing and the buffer uploads it does; with SwiftShader it waits on the software GPU). */
function timeRender(page) {
  return page.evaluate(() => {
    window.__render = 0;
    const r = window.vsculpt.view.renderer;
    const render = r.render.bind(r);
    r.render = (...args) => {
      const t = performance.now();
      render(...args);
      window.__render += performance.now() - t;
    };
  });
}

const sample = (page) =>
  page.evaluate(() => ({
    t: performance.now(),
    js: window.__js,
    render: window.__render,
    rafs: window.__rafs,
    // Uploads of every part's mesh positions (a benchmark run drags one part).
    uploads: window.vsculpt.partsView
      ? [...window.vsculpt.partsView.drawings.values()].reduce((n, d) => n + (d.mesh.geometry.attributes.position?.version || 0), 0)
      : window.vsculpt.view.geometry.attributes.position.version,
    frames: window.vsculpt.state.frames,
    perf: window.vsculpt.perf ? { ...window.vsculpt.perf } : null,
  }));

function figures(a, b) {
  const s = (b.t - a.t) / 1000;
  const rafs = b.rafs - a.rafs;
  if (b.perf) console.log(`  (client counters over ${s.toFixed(1)} s: ${b.perf.redraws - a.perf.redraws} full redraws, ${b.perf.submitted - a.perf.submitted} surfaces submitted (worker or main thread), ${b.perf.shown - a.perf.shown} shown${b.perf.workerFailed ? `; worker failed: ${b.perf.workerFailed}` : ''})`);
  const shown = b.uploads - a.uploads;
  const js = b.js - a.js;
  const render = b.render - a.render;
  return {
    fps: rafs / s,
    shown: shown / s,
    received: (b.frames - a.frames) / s,
    jsPerFrame: js / rafs,
    renderPerFrame: render / rafs,
    clientPerSurface: (js - render) / Math.max(1, shown),
    busy: js / (b.t - a.t),
  };
}

/** The editor page drags the icon's gizmo up and down for `seconds`. */
async function editorScenario(page, icon) {
  await page.evaluate((id) => window.vsculpt.select(id), icon);
  await sleep(300);
  const z = await gizmoZArrow(page);
  await page.mouse.move(z.from.x, z.from.y);
  await page.mouse.down();
  await page.mouse.move(z.from.x, z.from.y - 5);
  const a = await sample(page);
  const t0 = Date.now();
  for (let k = 0; Date.now() - t0 < seconds * 1000; k++) {
    await page.mouse.move(z.from.x, z.from.y - 5 - 60 * Math.abs(Math.sin(k / 30)));
    await sleep(8);
  }
  const b = await sample(page);
  await page.mouse.up();
  return figures(a, b);
}

/** Another client drags the icon at 60 Hz over its own WebSocket while the viewer page watches. */
async function viewerScenario(browser, server, design, viewerPage, icon) {
  const context = await browser.newContext();
  const driver = await context.newPage();
  await driver.goto(`${server.base}/healthz`);
  const start = await viewerPage.evaluate((id) => window.vsculpt.state.icons.get(id).xyz, icon);
  await driver.evaluate(
    ({ design: d, token, id, part, xyz, ms }) =>
      new Promise((resolve, reject) => {
        const ws = new WebSocket(`ws://${location.host}/ws`);
        window.__ws = ws;
        ws.onerror = () => reject(new Error('driver socket failed'));
        ws.onopen = () => {
          ws.send(JSON.stringify({ type: 'hello', protocol: 2, token, design: d, client_name: 'fps-driver', client_kind: 'tool' }));
          ws.send(JSON.stringify({ type: 'drag_start', part, icon: id, req: 1 }));
          let k = 0;
          const timer = setInterval(() => {
            k++;
            ws.send(JSON.stringify({ type: 'drag', part, icon: id, xyz: [xyz[0], xyz[1], xyz[2] + 3 * Math.abs(Math.sin(k / 30))], req: k + 1 }));
          }, 1000 / 60);
          setTimeout(() => {
            clearInterval(timer);
            ws.send(JSON.stringify({ type: 'drag_end', part, icon: id }));
          }, ms);
          resolve();
        };
      }),
    { design: design.id, token: design.tokens.editor, id: icon, part: await viewerPage.evaluate((i) => window.vsculpt.state.icons.get(i).part, icon), xyz: start, ms: (seconds + 2) * 1000 },
  );
  await sleep(700);
  const a = await sample(viewerPage);
  await sleep(seconds * 1000);
  const b = await sample(viewerPage);
  await context.close();
  return figures(a, b);
}

async function measure(browser, variant) {
  const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-fps-'));
  const server = await startServer({ dataDir, dir: variant.dir, args: ['--no-demo'] });
  try {
    const design = await createDesign(server, dataDir, { name: 'fps', nu: 81, nv: 159 });
    const url = (token) => `${server.base}/?design=${design.id}&token=${token}${variant.query || ''}`;
    const editor = await openClient(browser, url(design.tokens.editor), (p) => p.addInitScript(instrument));
    await timeRender(editor);
    // A product: the 81×159 part and (parts − 1) small plates beside it; the drags stay on the big part.
    for (let k = 1; k < (variant.parts || 1); k++) {
      const count = await editor.evaluate(() => window.vsculpt.partsView.drawings.size);
      await editor.evaluate(() => window.vsculpt.addPlane());
      await editor.waitForFunction((c) => window.vsculpt.partsView.drawings.size > c, count, { timeout: 20000 });
    }
    await editor.evaluate(() => window.vsculpt.selectPart([...window.vsculpt.design.parts.keys()][0]));
    const n = await editor.evaluate(() => window.vsculpt.state.icons.size);
    await editor.evaluate(() => window.vsculpt.createIcon({ kind: 'point', u: 0.5, v: 0.5 }, { kind: 'load' }));
    await editor.waitForFunction((k) => window.vsculpt.state.icons.size > k, n, { timeout: 20000 });
    const icon = await editor.evaluate(() => Math.max(...window.vsculpt.state.icons.keys()));
    // Nothing moving: the rate at which this machine draws the 81×159 mesh at all (the ceiling).
    await sleep(500);
    const i0 = await sample(editor);
    await sleep(Math.min(3, seconds) * 1000);
    const idle = figures(i0, await sample(editor));
    const ed = await editorScenario(editor, icon);
    const errors = editor.errors;
    await editor.close();
    const viewerPage = await openClient(browser, url(design.tokens.viewer), (p) => p.addInitScript(instrument));
    await timeRender(viewerPage);
    const vw = await viewerScenario(browser, server, design, viewerPage, icon);
    errors.push(...viewerPage.errors);
    await viewerPage.close();
    if (errors.length) console.warn(`page errors (${variant.name}):`, errors);
    return { idle, editor: ed, viewer: vw };
  } finally {
    await stopServer(server);
    rmSync(dataDir, { recursive: true, force: true });
  }
}

const variants = [
  { name: 'this tree', dir: webDir },
  { name: 'this tree, ?worker=0', dir: webDir, query: '&worker=0' },
];
// --parts N: the same with the 81×159 part among N parts (issue 11: a frame of one part costs what it costs alone).
const parts = Number(arg('parts', 1));
if (parts > 1) variants.push({ name: `this tree, ${parts} parts`, dir: webDir, parts });
let baseline = null;
if (before !== 'none') {
  baseline = clientAt(before);
  variants.unshift({ name: `baseline ${before}`, dir: baseline.dir });
}
const problem = serverBinProblem();
if (problem) {
  console.error(problem);
  process.exit(2);
}
const browser = await launchChromium();
const results = new Map(variants.map((v) => [v.name, []]));
try {
  for (let r = 0; r < rounds; r++) {
    for (const v of variants) {
      const res = await measure(browser, v);
      results.get(v.name).push(res);
      for (const [scenario, f] of Object.entries(res)) {
        console.log(`round ${r + 1} ${v.name} ${scenario}: ${f.fps.toFixed(1)} fps, ${f.shown.toFixed(1)} surface updates/s, ${f.received.toFixed(1)} frames received/s; main-thread JS ${f.jsPerFrame.toFixed(2)} ms per animation frame (renderer.render ${f.renderPerFrame.toFixed(2)} ms), the client's own ${f.clientPerSurface.toFixed(2)} ms per surface update; JS ${(100 * f.busy).toFixed(0)} % of the time`);
      }
    }
  }
} finally {
  await browser.close();
  if (baseline) baseline.cleanup();
}

const mean = (xs) => xs.reduce((a, b) => a + b, 0) / xs.length;
console.log(`\n${cpus().length} cores (${cpus()[0].model}); Chromium headless, SwiftShader software GL, Chromium's own frame pacing; ${seconds} s per scenario, ${rounds} rounds; means:`);
console.log('| client | scenario | animation fps | surface updates/s | frames received/s | main-thread JS / animation frame | of which renderer.render | client JS (all but render) / surface update | main thread in JS |');
console.log('|---|---|---|---|---|---|---|---|---|');
const avg = new Map();
for (const [name, rs] of results) {
  for (const scenario of ['idle', 'editor', 'viewer']) {
    const f = Object.fromEntries(['fps', 'shown', 'received', 'jsPerFrame', 'renderPerFrame', 'clientPerSurface', 'busy'].map((k) => [k, mean(rs.map((x) => x[scenario][k]))]));
    avg.set(`${name}/${scenario}`, f);
    console.log(`| ${name} | ${scenario} | ${f.fps.toFixed(1)} | ${f.shown.toFixed(1)} | ${f.received.toFixed(1)} | ${f.jsPerFrame.toFixed(2)} ms | ${f.renderPerFrame.toFixed(2)} ms | ${f.clientPerSurface.toFixed(2)} ms | ${(100 * f.busy).toFixed(0)} % |`);
  }
}
for (const name of baseline ? ['this tree', 'this tree, ?worker=0'] : []) {
  for (const scenario of ['editor', 'viewer']) {
    const o = avg.get(`baseline ${before}/${scenario}`);
    const n = avg.get(`${name}/${scenario}`);
    console.log(`${name} against the baseline, ${scenario}: animation fps ×${(n.fps / o.fps).toFixed(2)}, surface updates/s ×${(n.shown / o.shown).toFixed(2)}, client JS per surface update ÷${(o.clientPerSurface / n.clientPerSurface).toFixed(2)}, main-thread JS per animation frame ÷${(o.jsPerFrame / n.jsPerFrame).toFixed(2)}`);
  }
}
