// What a viewer gets of a 60 Hz drag over a real internet link (issue 16's
// bench): bytes per frame and frames per second delivered at 2, 10 and 100
// Mbit/s (40 ms one way, tests/wan.mjs) for the five surfaces of paper 003's
// Table 2, through the real server, in one run, for three kinds of viewer:
//
// - "full" (before): every drag frame a full geometry frame, as every client
//   got before issue 16 and as a client that asks for nothing still gets;
// - "full, deflated, paced" (`deflate=1&pace=1`): full frames, compressed,
//   at the rate the link carries (what a part off the drag stream's fast
//   path reaches a page with);
// - "page" (after, `drag_stream=1&deflate=1&pace=1`): the web client's
//   connection.
//
// Each surface carries the paper's set-up (four point position constraints,
// one curve position constraint, one dragged point load). Each run is one
// grab: the viewer joins through a fresh link, the editor (connected
// directly, full frames) grabs the load and drags it at 60 Hz for `seconds`,
// then releases. Frames/s is the drag frames that reached the viewer within
// the drag and 0.5 s after it, over the drag's length (so a viewer that sees
// every frame the server solved shows the server's rate); "seen" is the
// share of the solved frames that reached it; bytes/frame is the binary bytes that
// reached the viewer in that time (bases and reference frames included) over
// those frames; the added delay is arrival − the drag message's send − the
// link's 40 ms; "exact" says whether the viewer held the editor's frame at
// rest, the same f32 bits, within 5 s of the release.
//
//   cd web-client && node --experimental-websocket bench/link-frames.mjs [--seconds 3] [--mbit 2,10,100]
//     [--surfaces 81x159,...] [--modes 0,1,2,3]
//
// VSCULPT_SERVER_BIN names the server binary (else cargo's target dir).

import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir, loadavg } from 'node:os';
import { join } from 'node:path';
import { serverBin, serverBinProblem, createDesign, startServer, stopServer } from '../tests/harness.mjs';
import { startLink } from '../tests/wan.mjs';
import { connect, until, sleep, pct } from '../tests/ws-client.mjs';

const arg = (name, fallback) => {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const SECONDS = Number(arg('seconds', 3));
const SPEEDS = arg('mbit', '2,10,100').split(',').map(Number);
const DELAY_MS = 40;
/** Paper 003, Table 2 (`--surfaces 81x159,20x15` picks some). */
const SURFACES = [
  [20, 15],
  [38, 32],
  [42, 40],
  [91, 54],
  [81, 159],
].filter(([nu, nv]) => arg('surfaces', null) === null || arg('surfaces').split(',').includes(`${nu}x${nv}`));
const MODES = [
  { name: 'full (before)', opts: {} },
  { name: 'full, deflated, paced', opts: { deflate: true, pace: true } },
  { name: 'page: stream, deflated, paced (after)', opts: { stream: true, deflate: true, pace: true } },
  // Not in the default run (`--modes` picks by index): the page's connection without pacing.
  { name: 'stream, deflated, unpaced', opts: { stream: true, deflate: true } },
].filter((_, i) => (arg('modes', null) === null ? i < 3 : arg('modes').split(',').map(Number).includes(i)));

if (typeof WebSocket === 'undefined') {
  console.error('run with node --experimental-websocket (Node 20)');
  process.exit(2);
}
const problem = serverBinProblem();
if (problem) {
  console.error(problem);
  process.exit(2);
}

let nextReq = 1000;
/** Sends `msg` with a fresh req and resolves with the reply carrying it; throws on an error reply. */
async function request(c, msg) {
  const req = nextReq++;
  const reply = c.waitText((m) => m.req === req);
  c.send({ ...msg, req });
  const r = await reply;
  if (r.type === 'error') throw new Error(`${JSON.stringify(msg)}: ${r.code} ${r.message}`);
  return r;
}

/** The paper's set-up on `part`: four point position constraints, a curve position constraint, a point load; resolves to the load's id. */
async function paperSetUp(ed, part) {
  for (const [u, v] of [
    [0.2, 0.2],
    [0.8, 0.2],
    [0.2, 0.8],
    [0.8, 0.8],
  ]) {
    await request(ed, { type: 'create_icon', part, spec: { anchor: { kind: 'point', u, v }, role: { kind: 'position' } } });
  }
  const curve = { knots: { degree: 1, knots: [0, 0, 1, 1] }, points: [[0.1, 0.1], [0.9, 0.1]] };
  await request(ed, { type: 'create_icon', part, spec: { anchor: { kind: 'curve', curve }, role: { kind: 'position' } } });
  const load = await request(ed, { type: 'create_icon', part, spec: { anchor: { kind: 'point', u: 0.5, v: 0.55 }, role: { kind: 'load' } } });
  return load.icon;
}

const latest = (c, part) => Math.max(0, ...c.frames.filter((f) => f.part === part).map((f) => f.revision));

/** One grab seen by one viewer through a fresh link. */
async function run(server, design, ed, part, icon, mbit, mode, z0) {
  const link = await startLink({ target: new URL(server.base).host, mbit, delayMs: DELAY_MS });
  const viewer = connect(link.url(server.base).replace(/\/$/, ''), design.id, design.tokens.viewer, mode.opts);
  try {
    await viewer.ready;
    await viewer.waitText((m) => m.type === 'snapshot');
    await until(viewer, part, latest(ed, part));
    await request(ed, { type: 'drag_start', part, icon });
    const before = latest(ed, part);
    const sentAt = new Map();
    const revisionSent = new Map();
    ed.onText = (m) => {
      if (m.type === 'icon_feedback' && m.icon === icon) {
        const at = sentAt.get(m.requested[2].toFixed(6));
        if (at !== undefined) revisionSent.set(m.revision, at);
      }
    };
    const arrivals = [];
    viewer.onFrame = (f, at) => {
      if (f.part === part && f.flags & 1) arrivals.push({ revision: f.revision, at });
    };
    const bytes0 = viewer.bytes;
    link.reset();
    const start = performance.now();
    const n = Math.round(SECONDS * 60);
    for (let k = 0; k < n; k++) {
      const z = z0 + 0.001 * k;
      sentAt.set(z.toFixed(6), performance.now());
      ed.send({ type: 'drag', part, icon, xyz: [0.5, 0.55, z] });
      await sleep(Math.max(0, start + ((k + 1) * 1000) / 60 - performance.now()));
    }
    await sleep(500);
    const window = SECONDS + 0.5;
    const delivered = arrivals.filter((a) => a.at <= start + window * 1000);
    const bytes = viewer.bytes - bytes0;
    const wrote = link.bytes.down;
    const delays = delivered.filter((a) => revisionSent.has(a.revision)).map((a) => a.at - revisionSent.get(a.revision) - DELAY_MS);
    const solvedRevisions = ed.frames.filter((f) => f.part === part && f.flags & 1 && f.revision > before).map((f) => f.revision);
    const solved = solvedRevisions.length;
    const got = new Set(delivered.map((a) => a.revision));
    // Which of the solved frames did not reach the viewer, by their place in the drag (0 = first).
    const missed = solvedRevisions.map((r, i) => (got.has(r) ? -1 : i)).filter((i) => i >= 0);
    await request(ed, { type: 'drag_end', part, icon });
    let rest;
    const t0 = performance.now();
    while (!(rest = ed.frames.filter((f) => f.part === part && !(f.flags & 1) && f.revision > before).pop())) {
      if (performance.now() - t0 > 10000) throw new Error('no frame at rest for the editor');
      await sleep(5);
    }
    let exact = false;
    const t1 = performance.now();
    while (performance.now() - t1 < 5000) {
      const shown = viewer.frames.filter((f) => f.part === part).pop();
      if (shown && shown.revision >= rest.revision) {
        exact = shown.revision === rest.revision && shown.points.length === rest.points.length && shown.points.every((x, i) => Object.is(x, rest.points[i]));
        break;
      }
      await sleep(10);
    }
    return {
      fps: delivered.length / SECONDS,
      seen: solved ? delivered.filter((a) => a.revision > before).length / solved : NaN,
      missed,
      solvedFps: solved / SECONDS,
      bytesPerFrame: delivered.length ? bytes / delivered.length : NaN,
      wroteMBs: wrote / window / 1e6,
      p50: delays.length ? pct(delays, 50) : NaN,
      p90: delays.length ? pct(delays, 90) : NaN,
      exact,
    };
  } finally {
    ed.onText = () => {};
    // Only the latest frame is needed from here on (81 × 159 frames are 157 KB each).
    ed.frames.splice(0, ed.frames.length - 1);
    viewer.ws.close();
    await link.close();
  }
}

const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-link-frames-'));
const server = await startServer({ dataDir, args: ['--no-demo'] });
const rows = [];
try {
  console.log(`server ${serverBin}; node ${process.version}; load average ${loadavg().map((x) => x.toFixed(1)).join(' ')}; ${SECONDS} s drags at 60 Hz, ${DELAY_MS} ms one way`);
  for (const [nu, nv] of SURFACES) {
    const design = await createDesign(server, dataDir, { name: `paper ${nu}x${nv}`, nu, nv });
    const ed = connect(server.base, design.id, design.tokens.editor);
    await ed.ready;
    const snap = await ed.waitText((m) => m.type === 'snapshot');
    const part = snap.parts[0].id;
    const icon = await paperSetUp(ed, part);
    let z0 = 0.05;
    for (const mbit of SPEEDS) {
      for (const mode of MODES) {
        const r = await run(server, design, ed, part, icon, mbit, mode, z0);
        z0 = z0 > 0.3 ? 0.05 : z0 + 0.05;
        const row = { surface: `${nu} × ${nv}`, mbit, mode: mode.name, ...r };
        rows.push(row);
        console.log(
          `${row.surface}\t${mbit} Mbit/s\t${mode.name}\t${r.fps.toFixed(1)} frames/s (server solved ${r.solvedFps.toFixed(1)}/s, seen ${(100 * r.seen).toFixed(0)} %)\t${Math.round(r.bytesPerFrame)} B/frame\tdelay p50 ${r.p50.toFixed(0)} p90 ${r.p90.toFixed(0)} ms\tserver wrote ${r.wroteMBs.toFixed(2)} MB/s\texact at rest: ${r.exact ? 'yes' : 'NO'}${r.missed.length && r.missed.length < 10 ? `\tmissed frames #${r.missed.join(', #')}` : ''}`,
        );
      }
    }
    ed.ws.close();
  }
} finally {
  await stopServer(server);
  rmSync(dataDir, { recursive: true, force: true });
}

console.log('\n| surface | link | viewer | frames/s (server solved) | bytes/frame | added delay p50 / p90 | exact at rest |');
console.log('|---|---|---|---|---|---|---|');
for (const r of rows) {
  console.log(`| ${r.surface} | ${r.mbit} Mbit/s | ${r.mode} | ${r.fps.toFixed(1)} (${r.solvedFps.toFixed(1)}) | ${Math.round(r.bytesPerFrame).toLocaleString('en')} | ${r.p50.toFixed(0)} / ${r.p90.toFixed(0)} ms | ${r.exact ? 'yes' : 'no'} |`);
}
