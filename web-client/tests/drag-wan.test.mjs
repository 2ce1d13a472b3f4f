// A viewer on a real internet link (issue 16): through the link emulator
// (tests/wan.mjs) at 2 Mbit/s and 80 ms round trip, a viewer of an 81 × 159
// surface that uses the web client's own decoding (frame.js, drag-stream.js)
// sees the editor's 60 Hz drag at ≥ 30 frames/s (or, when the loaded
// server solved fewer, ≥ 90 % of the frames the editor saw) with ≤ 150 ms added delay
// (p90, over the link's own 40 ms one way), and at rest holds exactly the
// editor's net; at 100 Mbit/s it sees every drag frame the editor (connected
// directly) saw, but for the 5 % either latest-wins writer may skip on a loaded machine. The editor is connected directly, without the stream (full
// frames: the reference). Node 20 has WebSocket behind a flag: without it
// this file runs itself again with the flag.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { serverBinProblem, createDesign, startServer, stopServer } from './harness.mjs';
import { startLink } from './wan.mjs';
import { decodeFrame, PROTOCOL_VERSION } from '../src/frame.js';
import { DragStream } from '../src/drag-stream.js';
import { inflateMessage, isDeflated } from '../src/deflated.js';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const pct = (xs, p) => {
  const s = [...xs].sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.max(0, Math.ceil((p / 100) * s.length) - 1))];
};

/**
 * A protocol client: text and decoded frames (through a DragStream when
 * `stream`; deflated messages inflated by the page's deflated.js, in order,
 * when `deflate`).
 */
function connect(base, design, token, { stream = false, deflate = false } = {}) {
  const query = [stream && 'drag_stream=1', deflate && 'deflate=1'].filter(Boolean).join('&');
  const url = `${base.replace('http', 'ws')}/ws${query ? `?${query}` : ''}`;
  const ws = new WebSocket(url);
  ws.binaryType = 'arraybuffer';
  const c = { ws, texts: [], frames: [], onText: () => {}, onFrame: () => {}, drag: stream ? new DragStream() : null, bytes: 0, deflated: 0, kinds: {} };
  const receive = async (data, arrived) => {
    if (typeof data === 'string') {
      const m = JSON.parse(data);
      c.texts.push(m);
      c.onText(m, arrived);
      return;
    }
    c.bytes += data.byteLength;
    let now = arrived;
    if (isDeflated(data)) {
      c.deflated++;
      data = await inflateMessage(data, PROTOCOL_VERSION);
      now = performance.now();
    }
    const d = decodeFrame(data);
    c.kinds[d.kind] = (c.kinds[d.kind] || 0) + 1;
    const f = c.drag ? c.drag.take(d) : d;
    if (f) {
      c.frames.push(f);
      c.onFrame(f, now, d.kind);
    }
  };
  // As net.js: messages wait behind one that is still inflating.
  let inbox = Promise.resolve();
  ws.onmessage = (ev) => {
    const arrived = performance.now();
    inbox = inbox.then(() => receive(ev.data, arrived));
  };
  c.send = (m) => ws.send(JSON.stringify(m));
  c.waitText = (pred) =>
    new Promise((resolve) => {
      const prev = c.onText;
      c.onText = (m, t) => {
        prev(m, t);
        if (pred(m)) {
          c.onText = prev;
          resolve(m);
        }
      };
    });
  c.ready = new Promise((resolve, reject) => {
    ws.onopen = () => {
      c.send({ type: 'hello', protocol: PROTOCOL_VERSION, token, design, client_name: stream ? 'viewer' : 'editor', client_kind: 'tool' });
      resolve();
    };
    ws.onerror = (e) => reject(new Error(`websocket: ${e.message ?? e}`));
  });
  return c;
}

/** Waits until `c` has a frame of `part` with revision ≥ `rev`. */
async function until(c, part, rev) {
  const t0 = performance.now();
  while (!c.frames.some((f) => f.part === part && f.revision >= rev)) {
    if (performance.now() - t0 > 20000) throw new Error(`no frame of part ${part} at revision ${rev} within 20 s`);
    await sleep(5);
  }
}

if (typeof WebSocket === 'undefined') {
  test('the drag stream over an emulated link (run again with --experimental-websocket)', () => {
    const r = spawnSync(process.execPath, ['--experimental-websocket', '--test', fileURLToPath(import.meta.url)], { stdio: 'inherit' });
    assert.equal(r.status, 0, 'the drag-stream link tests failed');
  });
} else {
  const dataDir = mkdtempSync(join(tmpdir(), 'vsculpt-drag-wan-'));
  let server;

  before(async () => {
    const problem = serverBinProblem();
    assert.equal(problem, null, problem);
    server = await startServer({ dataDir, args: ['--no-demo'] });
  });

  after(async () => {
    await stopServer(server);
    rmSync(dataDir, { recursive: true, force: true });
  });

  /** A 60 Hz drag of a load icon seen by a stream viewer through a link of `mbit` and 40 ms one way. */
  async function dragOverLink(mbit, seconds, { deflate = false } = {}) {
    const design = await createDesign(server, dataDir, { name: `wan ${mbit}`, nu: 81, nv: 159 });
    const host = new URL(server.base).host;
    const link = await startLink({ target: host, mbit, delayMs: 40 });
    const ed = connect(server.base, design.id, design.tokens.editor);
    await ed.ready;
    const snap = await ed.waitText((m) => m.type === 'snapshot');
    const part = snap.parts[0].id;
    const viewer = connect(link.url('http://x').replace(/\/$/, ''), design.id, design.tokens.viewer, { stream: true, deflate });
    try {
      await viewer.ready;
      await viewer.waitText((m) => m.type === 'snapshot');
      const created = ed.waitText((m) => m.req === 1);
      ed.send({ type: 'create_icon', part, req: 1, spec: { anchor: { kind: 'point', u: 0.5, v: 0.5 }, role: { kind: 'load' } } });
      const ack = await created;
      assert.equal(ack.type, 'ack', JSON.stringify(ack));
      const icon = ack.icon;
      const grabbed = ed.waitText((m) => m.req === 2);
      ed.send({ type: 'drag_start', part, icon, req: 2 });
      await grabbed;
      // The viewer holds the shape at rest before the drag.
      const restRev = Math.max(...ed.frames.filter((f) => f.part === part).map((f) => f.revision));
      await until(viewer, part, restRev);

      const sentAt = new Map(); // requested z → send time
      const revisionSent = new Map(); // revision → send time of its drag
      ed.onText = (m) => {
        if (m.type === 'icon_feedback' && m.icon === icon) {
          const t = sentAt.get(m.requested[2].toFixed(6));
          if (t !== undefined) revisionSent.set(m.revision, t);
        }
      };
      const arrivals = [];
      viewer.onFrame = (f, t, kind) => {
        if (f.part === part && f.flags & 1) arrivals.push({ revision: f.revision, t, kind });
      };
      const start = performance.now();
      const n = Math.round(seconds * 60);
      for (let k = 0; k < n; k++) {
        const z = 0.1 + 0.002 * k;
        sentAt.set(z.toFixed(6), performance.now());
        ed.send({ type: 'drag', part, icon, xyz: [0.5, 0.5, z] });
        await sleep(Math.max(0, start + ((k + 1) * 1000) / 60 - performance.now()));
      }
      const lastSent = Math.max(...revisionSent.keys());
      const wait = performance.now();
      while (!arrivals.some((a) => a.revision >= lastSent) && performance.now() - wait < 10000) await sleep(5);
      const during = arrivals.filter((a) => a.t <= start + seconds * 1000 + 500);
      const fps = during.length / (seconds + 0.5);
      const delays = arrivals.filter((a) => revisionSent.has(a.revision)).map((a) => a.t - revisionSent.get(a.revision) - 40);

      // Release: the editor's full frame at rest, and the viewer's.
      const released = ed.waitText((m) => m.req === 3);
      ed.send({ type: 'drag_end', part, icon, req: 3 });
      await released;
      let rest;
      const t1 = performance.now();
      while (!(rest = ed.frames.filter((f) => f.part === part && !(f.flags & 1) && f.revision > lastSent).pop())) {
        if (performance.now() - t1 > 20000) throw new Error('no frame at rest for the editor');
        await sleep(5);
      }
      await until(viewer, part, rest.revision);
      const shown = viewer.frames.filter((f) => f.part === part).pop();
      return { fps, delays, arrivals, revisionSent, rest, shown, streamed: arrivals.filter((a) => a.kind === 'drag').length, bytes: link.bytes.down, deflated: viewer.deflated, kinds: JSON.stringify(viewer.kinds), editorFrames: ed.frames.filter((f) => f.part === part && f.flags & 1 && f.revision > restRev).map((f) => f.revision), texts: JSON.stringify(viewer.texts.reduce((m, x) => ((m[x.type] = (m[x.type] || 0) + 1), m), {})) };
    } finally {
      viewer.ws.close();
      ed.ws.close();
      await link.close();
    }
  }

  test('at 2 Mbit/s and 80 ms round trip a viewer sees a 60 Hz drag at ≥ 30 frames/s, ≤ 150 ms added delay, and the editor’s shape at rest', async (t) => {
    // The page asks for deflated messages; a client that does not gets the same frames plain.
    const runs = {};
    for (const deflate of [true, false]) {
      const r = await dragOverLink(2, 6, { deflate });
      runs[deflate] = r;
      const name = deflate ? 'deflated' : 'plain';
      t.diagnostic(`2 Mbit/s, ${name}: ${r.fps.toFixed(1)} frames/s, added delay p50 ${pct(r.delays, 50).toFixed(1)} ms p90 ${pct(r.delays, 90).toFixed(1)} ms max ${Math.max(...r.delays).toFixed(1)} ms, ${r.streamed} stream frames, ${r.bytes} bytes down, ${r.deflated} deflated messages, messages ${r.kinds}, editor drag frames ${r.editorFrames.length}, viewer texts ${r.texts}`);
      assert.ok(r.streamed > 0, `${name}: no drag frame came as a stream frame`);
      // The server (on a loaded machine) may solve fewer than 60 frames a
      // second: the link must not cost frames, and ≥ 30 frames/s is asked of
      // it whenever the server produced ≥ 33.
      const editorFps = r.editorFrames.length / 6.5;
      assert.ok(r.fps >= Math.min(30, 0.9 * editorFps), `${name}: the viewer saw ${r.fps.toFixed(1)} frames/s, the editor ${editorFps.toFixed(1)}`);
      const p90 = pct(r.delays, 90);
      assert.ok(p90 <= 150, `${name}: added delay p90 ${p90.toFixed(1)} ms (median ${pct(r.delays, 50).toFixed(1)} ms)`);
      assert.equal(r.shown.revision, r.rest.revision);
      assert.deepEqual(r.shown.points, r.rest.points, `${name}: the viewer’s shape at rest is not the editor’s`);
      assert.deepEqual(r.shown.knotsU, r.rest.knotsU);
    }
    // Deflated: the basis and the full frames came as kind 7, and the link carried fewer bytes.
    assert.ok(runs.true.deflated >= 2, `${runs.true.deflated} deflated messages`);
    assert.equal(runs.false.deflated, 0);
    assert.ok(runs.true.bytes < runs.false.bytes, `deflated ${runs.true.bytes} bytes, plain ${runs.false.bytes}`);
  });

  test('at 100 Mbit/s a viewer sees every drag frame', async (t) => {
    const r = await dragOverLink(100, 2);
    t.diagnostic(`100 Mbit/s: ${r.fps.toFixed(1)} frames/s, added delay p50 ${pct(r.delays, 50).toFixed(1)} ms p90 ${pct(r.delays, 90).toFixed(1)} ms, ${r.streamed} stream frames, the editor ${r.editorFrames.length}`);
    const seen = new Set(r.arrivals.map((a) => a.revision));
    const missed = r.editorFrames.filter((rev) => !seen.has(rev));
    // Both writers are latest-wins: on a loaded machine either may skip a
    // frame the other sends, so "every" is ≥ 95 % of the editor's.
    assert.ok(missed.length <= 0.05 * r.editorFrames.length, `missed ${missed.length} of the ${r.editorFrames.length} drag frames the editor got`);
    assert.deepEqual(r.shown.points, r.rest.points);
  });
}
