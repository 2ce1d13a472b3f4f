// Metamorphosis frames to a viewer (issue 13's bench: "metamorphosis frames
// at ≥ 60 Hz to a viewer"), through the real server: the first-start demo's
// body (paper 002's cube whose morph target is the spool, figures 7 and 10).
// An editor plays the morph as the page's play button does — one
// `body_morph` per display frame, t stepping from 0 to 1 — at each rate
// asked for, for `seconds`; a viewer (a second connection with the viewer
// token, full frames, no deflate) counts the body frames (kind 4) of that
// part it receives within the play and 0.5 s after it, and the delay from
// each `body_morph` sent to the viewer's frame carrying its t.
//
// Frames/s is those frames over the play's length; "distinct" counts
// distinct t (the server publishes the latest state, so a server slower
// than the editor skips times rather than queueing them).
//
//   cd web-client && node --experimental-websocket bench/morph-frames.mjs [--seconds 3] [--rates 60,120]
//
// VSCULPT_SERVER_BIN names the server binary (else cargo's target dir).

import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir, loadavg } from 'node:os';
import { join } from 'node:path';
import { serverBinProblem, startServer, stopServer } from '../tests/harness.mjs';
import { connect, sleep, pct } from '../tests/ws-client.mjs';

const arg = (name, fallback) => {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const SECONDS = Number(arg('seconds', 3));
const RATES = arg('rates', '60,120').split(',').map(Number);

if (typeof WebSocket === 'undefined') {
  console.error('run with node --experimental-websocket (Node 20)');
  process.exit(2);
}
const problem = serverBinProblem();
if (problem) {
  console.error(problem);
  process.exit(2);
}

/** design id and token of a link the server printed (`…/?design=1&token=…`). */
const linkOf = (url) => {
  const q = new URL(url).searchParams;
  return { design: Number(q.get('design')), token: q.get('token') };
};

/** t as the frame carries it (f32), as a key. */
const key = (t) => Math.fround(t).toFixed(7);

/** One play at `rate` body_morph messages per second; the viewer's count. */
async function play(ed, viewer, part, rate) {
  const sentAt = new Map();
  const arrivals = [];
  viewer.onFrame = (f, at) => {
    if (f.kind === 'body' && f.part === part) arrivals.push({ t: f.t, at });
  };
  const errors = [];
  ed.onText = (m) => {
    if (m.type === 'error') errors.push(m);
  };
  const bytes0 = viewer.bytes;
  const n = Math.round(SECONDS * rate);
  const start = performance.now();
  for (let k = 1; k <= n; k++) {
    const t = k / n;
    sentAt.set(key(t), performance.now());
    ed.send({ type: 'body_morph', part, t });
    await sleep(Math.max(0, start + (k * 1000) / rate - performance.now()));
  }
  await sleep(500);
  const inPlay = arrivals.filter((a) => a.at <= start + (SECONDS + 0.5) * 1000);
  const delays = inPlay.filter((a) => sentAt.has(key(a.t))).map((a) => a.at - sentAt.get(key(a.t)));
  const distinct = new Set(inPlay.map((a) => key(a.t))).size;
  const last = inPlay.length ? inPlay[inPlay.length - 1].t : NaN;
  // Back to t = 0 for the next play.
  ed.send({ type: 'body_morph', part, t: 0 });
  await sleep(300);
  if (errors.length) throw new Error(`body_morph refused: ${JSON.stringify(errors[0])}`);
  return {
    rate,
    sent: n,
    frames: inPlay.length,
    perSecond: inPlay.length / SECONDS,
    distinct,
    last,
    p50: pct(delays, 50),
    p99: pct(delays, 99),
    bytes: inPlay.length ? (viewer.bytes - bytes0) / inPlay.length : 0,
  };
}

const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-morph-bench-'));
const server = await startServer({ dataDir });
try {
  const e = linkOf(server.editor);
  const v = linkOf(server.viewer);
  const ed = connect(server.base, e.design, e.token);
  const viewer = connect(server.base, v.design, v.token);
  await Promise.all([ed.ready, viewer.ready]);
  // The demo's body part: the first body frame the viewer gets.
  const t0 = performance.now();
  let body;
  while (!(body = viewer.frames.find((f) => f.kind === 'body'))) {
    if (performance.now() - t0 > 20000) throw new Error('no body frame within 20 s');
    await sleep(10);
  }
  const part = body.part;
  console.log(`demo body: part ${part}, lattice ${body.counts.join(' × ')}, ${body.positions.length / 3} boundary vertices`);
  console.log(`load before: ${loadavg().map((x) => x.toFixed(1)).join(' ')}`);
  const rows = [];
  for (const rate of RATES) rows.push(await play(ed, viewer, part, rate));
  console.log(`load after: ${loadavg().map((x) => x.toFixed(1)).join(' ')}`);
  console.log('| body_morph sent/s | viewer body frames/s | distinct t | last t | sent → viewer p50 / p99 | bytes/frame |');
  console.log('|---|---|---|---|---|---|');
  for (const r of rows) {
    console.log(
      `| ${r.rate} | ${r.perSecond.toFixed(1)} (${r.frames} of ${r.sent}) | ${r.distinct} | ${r.last.toFixed(4)} | ${r.p50?.toFixed(1)} / ${r.p99?.toFixed(1)} ms | ${Math.round(r.bytes)} |`,
    );
  }
  ed.ws.close();
  viewer.ws.close();
} finally {
  await stopServer(server);
  rmSync(dataDir, { recursive: true, force: true });
}
