// Time to a customer's first picture over an emulated internet link
// (BENCHMARKS.md, "first picture"): real headless Chromium opens a viewer link
// through tests/wan.mjs at 2, 10 and 100 Mbit/s with 40 ms delay each way,
// once with an empty cache (cold) and once reloaded (warm), for the demo
// design and an 81 × 159 design; reports the time from navigation start to
// the first shaded picture, the bytes that crossed the link by then and the
// server's CPU time for the visit (from /proc).
//
//   node bench/first-picture.mjs [--before-bin PATH --before-rev REV] [--rounds N] [--mbit 2,10,100] [--settle MS]
//
// With --before-bin/--before-rev the same run measures an older server binary
// with the client of an older revision, so BENCHMARKS.md can give before →
// after from one run. The first picture is the first animation frame after
// the client has drawn a surface (its perf counters say so), read in the
// page so that old and new clients are timed alike. The reload waits --settle
// ms (default 2000) after the cold picture, as a person's reload would: the
// cold page has by then received its snapshot (and kept its geometry), and
// its own late work (the contact shadow's shaders) no longer holds up the
// reload's navigation. A warm visit drawn from the geometry cache also says
// when the server's welcome confirmed the kept shape ("confirmed"; "-" when
// the client has no cache or the cache was not used).

import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { cpus, tmpdir } from 'node:os';
import { join } from 'node:path';
import { webDir, serverBin, serverBinProblem, createDesign, clientAt, startServer, stopServer, launchChromium } from '../tests/harness.mjs';
import { startLink } from '../tests/wan.mjs';

const arg = (name, fallback) => {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const rounds = Number(arg('rounds', 1));
const beforeBin = arg('before-bin', null);
const beforeRev = arg('before-rev', null);
const speeds = (arg('mbit', '2,10,100')).split(',').map(Number);
const settleMs = Number(arg('settle', 2000));
const DELAY_MS = 40;

/** Resolves, in the page, at the first animation frame after a surface was drawn: ms since navigation start. */
const firstPicture = () =>
  new Promise((resolve) => {
    const poll = () => {
      const p = window.vsculpt && window.vsculpt.perf;
      if (p && (p.shown > 0 || p.redraws > 0)) requestAnimationFrame(() => resolve(performance.now()));
      else requestAnimationFrame(poll);
    };
    poll();
  });

/** CPU time the process `pid` has used so far, in ms (utime + stime from /proc, Linux). */
function cpuMs(pid) {
  const fields = readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
  return ((Number(fields[11]) + Number(fields[12])) * 1000) / 100; // clock ticks of 1/100 s (USER_HZ)
}

async function visit(page, link, url, reload, serverPid) {
  link.reset();
  const cpu0 = cpuMs(serverPid);
  if (reload) await page.reload({ waitUntil: 'commit' });
  else await page.goto(url, { waitUntil: 'commit' });
  const ms = await page.evaluate(firstPicture);
  const serverCpu = cpuMs(serverPid) - cpu0;
  // When the kept shape was confirmed (the welcome, clients with a geometry cache), else null.
  const confirmed = await page.evaluate(async () => {
    const link = window.vsculpt.link;
    while (link.cacheUse && link.cacheUse.offered && link.cacheUse.confirmed === null) await new Promise((r) => setTimeout(r, 20));
    const welcome = performance.getEntriesByName('vsculpt:welcome')[0];
    return link.cacheUse && link.cacheUse.confirmed && welcome ? welcome.startTime : null;
  });
  return { ms, down: link.bytes.down, up: link.bytes.up, serverCpu, confirmed };
}

async function measure(browser, variant) {
  const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-first-picture-'));
  const server = await startServer({ dataDir, dir: variant.dir, bin: variant.bin });
  const out = [];
  try {
    const big = await createDesign(server, dataDir, { name: 'large', nu: 81, nv: 159 });
    const bigViewer = `${server.base}/?design=${big.id}&token=${big.tokens.viewer}`;
    const target = new URL(server.base).host;
    for (const mbit of speeds) {
      for (const [design, url] of [['demo', server.viewer], ['81x159', bigViewer]]) {
        const link = await startLink({ target, mbit, delayMs: DELAY_MS });
        const context = await browser.newContext({ viewport: { width: 1100, height: 700 } });
        try {
          const page = await context.newPage();
          const cold = await visit(page, link, link.url(url), false, server.child.pid);
          await new Promise((r) => setTimeout(r, settleMs));
          const warm = await visit(page, link, link.url(url), true, server.child.pid);
          out.push({ mbit, design, cold, warm });
          console.log(`${variant.name} ${mbit} Mbit/s ${design}: cold ${cold.ms.toFixed(0)} ms, ${(cold.down / 1024).toFixed(0)} KiB down; warm ${warm.ms.toFixed(0)} ms, ${(warm.down / 1024).toFixed(0)} KiB down${warm.confirmed === null ? '' : `, confirmed ${warm.confirmed.toFixed(0)} ms`}`);
        } finally {
          await context.close();
          await link.close();
        }
      }
    }
  } finally {
    await stopServer(server);
    rmSync(dataDir, { recursive: true, force: true });
  }
  return out;
}

const problem = serverBinProblem();
if (problem) {
  console.error(problem);
  process.exit(2);
}
const variants = [{ name: 'this tree', dir: webDir, bin: serverBin }];
let baseline = null;
if (beforeBin && beforeRev) {
  baseline = clientAt(beforeRev);
  variants.unshift({ name: `before (${beforeRev})`, dir: baseline.dir, bin: beforeBin });
}
const browser = await launchChromium();
const results = new Map(variants.map((v) => [v.name, []]));
try {
  for (let r = 0; r < rounds; r++) for (const v of variants) results.get(v.name).push(...(await measure(browser, v)));
} finally {
  await browser.close();
  if (baseline) baseline.cleanup();
}

const median = (xs) => xs.slice().sort((a, b) => a - b)[Math.floor(xs.length / 2)];
console.log(`\n${cpus().length} cores (${cpus()[0].model}); headless Chromium (SwiftShader); link ${DELAY_MS} ms each way; reload ${settleMs} ms after the cold picture; medians of ${rounds} round(s), [min–max]:`);
console.log('| server + client | link | design | cold: first picture | cold: bytes down | cold: server CPU | warm: first picture | warm: confirmed | warm: bytes down |');
console.log('|---|---|---|---|---|---|---|---|---|');
for (const [name, rs] of results) {
  for (const mbit of speeds) {
    for (const design of ['demo', '81x159']) {
      const xs = rs.filter((x) => x.mbit === mbit && x.design === design);
      const f = (k, part) => median(xs.map((x) => x[part][k]));
      const secs = (part, k = 'ms') => {
        const v = xs.map((x) => x[part][k]);
        if (v.some((t) => t === null)) return '-';
        const spread = v.length > 1 ? ` [${(Math.min(...v) / 1000).toFixed(2)}–${(Math.max(...v) / 1000).toFixed(2)}]` : '';
        return `${(median(v) / 1000).toFixed(2)} s${spread}`;
      };
      console.log(`| ${name} | ${mbit} Mbit/s | ${design} | ${secs('cold')} | ${(f('down', 'cold') / 1024).toFixed(0)} KiB | ${f('serverCpu', 'cold').toFixed(0)} ms | ${secs('warm')} | ${secs('warm', 'confirmed')} | ${(f('down', 'warm') / 1024).toFixed(0)} KiB |`);
    }
  }
}
