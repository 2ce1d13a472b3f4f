// A viewer on a real internet link (issue 16): through the link emulator
// (tests/wan.mjs) at 2 Mbit/s and 80 ms round trip, a viewer of an 81 × 159
// surface that uses the web client's own decoding (frame.js, drag-stream.js)
// sees the editor's 60 Hz drag at ≥ 30 frames/s (or, when the loaded
// server solved fewer, ≥ 90 % of the frames the editor saw) with ≤ 150 ms added delay
// (p90, over the link's own 40 ms one way), and at rest holds exactly the
// editor's net; at 100 Mbit/s it sees every drag frame the editor (connected
// directly) saw, but for the 5 % either latest-wins writer may skip on a loaded machine. The editor is connected directly, without the stream (full
// frames: the reference). Paced delivery (`pace=1`): a viewer on a 1 Mbit/s
// link that takes full frames gets complete frames all through a drag with a
// bounded backlog in its link, while a fast viewer gets every frame, and both
// end on the editor's frame at rest. Node 20 has WebSocket behind a flag: without it
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
import { connect, until, sleep, pct } from './ws-client.mjs';

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

  test('paced delivery: a viewer on a 1 Mbit/s link gets complete, recent frames while a fast one gets every frame, and both end exact', async (t) => {
    // Two viewers of one 60 Hz drag: a fast one connected directly (drag
    // stream, deflated, paced, as the page) and a slow one on a 1 Mbit/s
    // link with 40 ms one way that takes full frames (deflated and paced),
    // so the link, not the server, is what limits it: ~14 KB a frame is
    // 0.3–0.8 MB/s at the 20–60 frames a second the server solves, against
    // the link's 0.125 MB/s. Without pacing the server writes every frame
    // into the link, whose backlog (and delay) grows all through the drag;
    // paced, the backlog (what the server wrote into the link and the viewer
    // has not taken in) stays within about a window and a frame. Bytes, not
    // times, are asserted: the delays are reported.
    const mbit = 1;
    const capacity = (mbit * 1e6) / 8; // bytes a second
    const seconds = 4;
    const design = await createDesign(server, dataDir, { name: 'paced', nu: 81, nv: 159 });
    const link = await startLink({ target: new URL(server.base).host, mbit, delayMs: 40 });
    const ed = connect(server.base, design.id, design.tokens.editor);
    const fast = connect(server.base, design.id, design.tokens.viewer, { stream: true, deflate: true, pace: true });
    const slow = connect(link.url('http://x').replace(/\/$/, ''), design.id, design.tokens.viewer, { deflate: true, pace: true });
    try {
      await Promise.all([ed.ready, fast.ready, slow.ready]);
      const [snap] = await Promise.all([ed.waitText((m) => m.type === 'snapshot'), fast.waitText((m) => m.type === 'snapshot'), slow.waitText((m) => m.type === 'snapshot')]);
      const part = snap.parts[0].id;
      const created = ed.waitText((m) => m.req === 1);
      ed.send({ type: 'create_icon', part, req: 1, spec: { anchor: { kind: 'point', u: 0.5, v: 0.5 }, role: { kind: 'load' } } });
      const icon = (await created).icon;
      const grabbed = ed.waitText((m) => m.req === 2);
      ed.send({ type: 'drag_start', part, icon, req: 2 });
      await grabbed;
      const restRev = Math.max(...ed.frames.filter((f) => f.part === part).map((f) => f.revision));
      await until(fast, part, restRev);
      await until(slow, part, restRev);

      const sentAt = new Map();
      const revisionSent = new Map();
      ed.onText = (m) => {
        if (m.type === 'icon_feedback' && m.icon === icon) {
          const at = sentAt.get(m.requested[2].toFixed(6));
          if (at !== undefined) revisionSent.set(m.revision, at);
        }
      };
      const arrivals = { fast: [], slow: [] };
      fast.onFrame = (f, at) => f.part === part && f.flags & 1 && arrivals.fast.push({ revision: f.revision, at });
      slow.onFrame = (f, at) => f.part === part && f.flags & 1 && arrivals.slow.push({ revision: f.revision, at, bytes: slow.bytes });
      link.reset();
      const slowBytes0 = slow.bytes;
      const start = performance.now();
      const n = seconds * 60;
      let backlog = 0;
      for (let k = 0; k < n; k++) {
        const z = 0.1 + 0.002 * k;
        sentAt.set(z.toFixed(6), performance.now());
        ed.send({ type: 'drag', part, icon, xyz: [0.5, 0.5, z] });
        backlog = Math.max(backlog, link.bytes.down - (slow.bytes - slowBytes0));
        await sleep(Math.max(0, start + ((k + 1) * 1000) / 60 - performance.now()));
      }
      await sleep(500);
      const slowBytesDuring = slow.bytes - slowBytes0;
      const released = ed.waitText((m) => m.req === 3);
      ed.send({ type: 'drag_end', part, icon, req: 3 });
      await released;
      let rest;
      while (!(rest = ed.frames.filter((f) => f.part === part && !(f.flags & 1) && f.revision > restRev).pop())) await sleep(5);
      await until(fast, part, rest.revision);
      await until(slow, part, rest.revision);
      const elapsed = (performance.now() - start) / 1000;
      const wrote = link.bytes.down;

      const editorFrames = ed.frames.filter((f) => f.part === part && f.flags & 1 && f.revision > restRev).map((f) => f.revision);
      const seenFast = new Set(arrivals.fast.map((a) => a.revision));
      const missed = editorFrames.filter((r) => !seenFast.has(r));
      const delay = (a) => a.at - revisionSent.get(a.revision);
      const slowDelays = arrivals.slow.filter((a) => revisionSent.has(a.revision)).map((a) => delay(a) - 40);
      const fastDelays = arrivals.fast.filter((a) => revisionSent.has(a.revision)).map(delay);
      t.diagnostic(`editor: ${editorFrames.length} drag frames (${(editorFrames.length / (seconds + 0.5)).toFixed(1)}/s); fast viewer: ${arrivals.fast.length} frames, missed ${missed.length}, delay p50 ${pct(fastDelays, 50).toFixed(1)} ms p90 ${pct(fastDelays, 90).toFixed(1)} ms; slow viewer: ${arrivals.slow.length} frames (${(arrivals.slow.length / (seconds + 0.5)).toFixed(1)}/s), ${slowBytesDuring} bytes during the drag (${((100 * slowBytesDuring) / (capacity * (seconds + 0.5))).toFixed(0)} % of the link), added delay p50 ${pct(slowDelays, 50).toFixed(1)} ms p90 ${pct(slowDelays, 90).toFixed(1)} ms max ${Math.max(...slowDelays).toFixed(1)} ms; the server wrote ${wrote} bytes into the slow link in ${elapsed.toFixed(2)} s, backlog at most ${backlog} bytes`);

      // The fast viewer: every frame the editor saw (but for the 5 % either latest-wins writer may skip on a loaded machine).
      assert.ok(missed.length <= 0.05 * editorFrames.length, `the fast viewer missed ${missed.length} of ${editorFrames.length} drag frames`);
      // The slow viewer: complete frames all through the drag …
      assert.ok(arrivals.slow.length >= seconds, `the slow viewer got ${arrivals.slow.length} drag frames in ${seconds} s`);
      // … each recent: what waits for it in the link stays within a window
      // and a frame (unpaced, it grows by hundreds of KB a second) …
      assert.ok(backlog <= 256 * 1024, `${backlog} bytes were waiting in the slow viewer's link`);
      // … and the server wrote into its link about what the link carried.
      assert.ok(wrote <= capacity * elapsed + 256 * 1024, `the server wrote ${wrote} bytes into a link that carried at most ${Math.round(capacity * elapsed)} in ${elapsed.toFixed(2)} s`);
      // Both end on the editor's frame at rest, exactly.
      for (const [name, v] of [['fast', fast], ['slow', slow]]) {
        const shown = v.frames.filter((f) => f.part === part).pop();
        assert.equal(shown.revision, rest.revision, name);
        assert.deepEqual(shown.points, rest.points, `the ${name} viewer's shape at rest is not the editor's`);
      }
    } finally {
      for (const c of [ed, fast, slow]) c.ws.close();
      await link.close();
    }
  });
}
