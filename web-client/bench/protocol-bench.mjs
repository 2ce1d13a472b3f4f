// An outside client of the vsculpt WebSocket protocol, written from
// protocol/README.md (messages, binary frame layout) and server/README.md
// (the start banner, POST /api/designs) alone: it shares no code with the
// server or the web client. It starts the real server binary over a fresh
// data directory and measures, on loopback:
//
//   join   hello sent → snapshot received, over sequential joins (p50/p99);
//          also over a bare TCP socket with no WebSocket library and no
//          JSON parsing (rawJoin): the server's own share
//   own    drag sent → the dragging editor's own geometry frame (p50/p99),
//          one drag every 1/60 s
//   fanout 50 viewers while the editor drags at 60 Hz on 81 × 159: drag sent
//          → each viewer's frame of that drag (matched by the revision in
//          the editor's icon_feedback), p50/p99, and frames/s per viewer
//   stream the same fanout with every viewer opening /ws?drag_stream=1 (README,
//          "Drag stream (kinds 5 and 6)"): a drag basis once, then per frame
//          d only; each viewer rebuilds the net R + ρ·d itself (time per
//          frame reported) and bytes per viewer are counted
//   soak   300 designs; rounds of 500 clients joining (10 at a time) a random
//          design and leaving; per round the server's RSS and join p50/p99
//   commits the dragging editor's own frame (as in own) while a second editor
//          of the same 81 × 159 design commits over and over (commit, wait
//          for its ack, pause BENCH_COMMIT_PAUSE_MS, again); also commit →
//          ack p50/p99
//
// Node's WebSocket (undici) acks like a browser: no early ACKs, Nagle on.
//
// Run (Node ≥ 20):
//   cargo build --release -p vsculpt-server
//   node --experimental-websocket web-client/bench/protocol-bench.mjs target/release/vsculpt-server
// Optional: BENCH_SOAK_ROUNDS (default 6), BENCH_JOINS (200), BENCH_DRAGS (300),
// BENCH_VIEWERS (50), BENCH_FANOUT_SECONDS (5), BENCH_COMMIT_PAUSE_MS (50),
// BENCH_ONLY (a comma list of join, own, fanout, soak, commits; default all),
// BENCH_VIEWER_THREADS (5: the fanout's viewers are spread over this many
// worker threads, so that one viewer's work does not delay another's arrival
// stamp; 1 puts them all on the main thread, as each browser would not be).
//
// The join is measured twice: a plain hello (the snapshot carries the net as
// JSON numbers) and the compact join the web client uses (README, "The
// compact join": `geometry_first`, the shape as a binary frame first, then a
// snapshot without points); for the latter the time to the first frame is
// reported too.

import { spawn } from 'node:child_process';
import { randomBytes } from 'node:crypto';
import { connect as tcpConnect } from 'node:net';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { performance } from 'node:perf_hooks';
import { Worker, isMainThread, parentPort, workerData } from 'node:worker_threads';

const bin = (isMainThread ? process.argv[2] : null) ?? 'target/release/vsculpt-server';
const env = (k, d) => Number(process.env[k] ?? d);
const JOINS = env('BENCH_JOINS', 200);
const DRAGS = env('BENCH_DRAGS', 300);
const VIEWERS = env('BENCH_VIEWERS', 50);
const FANOUT_SECONDS = env('BENCH_FANOUT_SECONDS', 5);
const SOAK_ROUNDS = env('BENCH_SOAK_ROUNDS', 6);
const COMMIT_PAUSE_MS = env('BENCH_COMMIT_PAUSE_MS', 50);
const VIEWER_THREADS = Math.max(1, env('BENCH_VIEWER_THREADS', 5));
const ONLY = (process.env.BENCH_ONLY ?? 'join,own,fanout,soak,commits').split(',');
const runs = (name) => ONLY.includes(name);
const SOAK_DESIGNS = 300;
const SOAK_CLIENTS = 500;
const PROTOCOL = 2;

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const pct = (xs, p) => {
  const s = [...xs].sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.ceil((p / 100) * s.length) - 1)];
};
const fmt = (x) => x.toFixed(2);
/** A clock shared by the main thread and the workers (ms since the epoch). */
const clock = () => performance.timeOrigin + performance.now();

// ---- the server ----------------------------------------------------------

async function startServer() {
  const data = mkdtempSync(join(tmpdir(), 'vsculpt-node-bench-'));
  const child = spawn(bin, ['--listen', '127.0.0.1:0', '--data', data, '--no-demo'], {
    stdio: ['ignore', 'pipe', 'inherit'],
  });
  let out = '';
  const addr = await new Promise((resolve, reject) => {
    child.on('exit', (c) => reject(new Error(`server exited ${c}`)));
    child.stdout.on('data', (b) => {
      out += b;
      const m = out.match(/listening on http:\/\/(\S+)/);
      if (m) resolve(m[1]);
    });
  });
  const admin = readFileSync(join(data, 'admin-token'), 'utf8').trim();
  return { child, addr, admin, data };
}

function rssMiB(pid) {
  const s = readFileSync(`/proc/${pid}/status`, 'utf8');
  return Number(s.match(/VmRSS:\s+(\d+)/)[1]) / 1024;
}

async function createDesign(srv, name, nu, nv) {
  const body = nu ? { name, nu, nv } : { name };
  const r = await fetch(`http://${srv.addr}/api/designs`, {
    method: 'POST',
    headers: { authorization: `Bearer ${srv.admin}`, 'content-type': 'application/json' },
    body: JSON.stringify(body),
  });
  if (r.status !== 201) throw new Error(`create design: ${r.status} ${await r.text()}`);
  return r.json();
}

// ---- a protocol client -----------------------------------------------------

/** The header fields of a binary geometry frame (README, "Binary geometry frame"). */
function frameHeader(buf) {
  const dv = new DataView(buf);
  const magic = String.fromCharCode(...new Uint8Array(buf, 0, 4));
  if (magic !== 'VSGF') throw new Error('not a frame');
  return {
    kind: dv.getUint8(4),
    version: dv.getUint8(5),
    flags: dv.getUint16(6, true),
    design: Number(dv.getBigUint64(8, true)),
    part: Number(dv.getBigUint64(16, true)),
    revision: Number(dv.getBigUint64(24, true)),
    nu: dv.getUint32(32, true),
    nv: dv.getUint32(36, true),
  };
}

/**
 * The drag stream as README "Drag stream (kinds 5 and 6)" describes it: per
 * part the net of the last full frame (kind 1) and the last basis (kind 5);
 * a drag frame (kind 5) gives R[k] + ρ[k]·d. Returns the header to report,
 * or null for a basis.
 */
class StreamState {
  constructor() {
    this.full = new Map(); // part → { revision, points: Float32Array }
    this.basis = new Map(); // part → { basis, reference, rho: Float32Array }
    this.applyMs = [];
    this.net = new Map(); // part → the net shown (Float32Array)
  }
  take(buf) {
    const dv = new DataView(buf);
    const kind = dv.getUint8(4);
    const part = Number(dv.getBigUint64(16, true));
    if (kind === 5) {
      const n = dv.getUint32(40, true);
      this.basis.set(part, { basis: Number(dv.getBigUint64(24, true)), reference: Number(dv.getBigUint64(32, true)), rho: new Float32Array(buf, 48, n) });
      return null;
    }
    if (kind === 6) {
      const t0 = performance.now();
      const revision = Number(dv.getBigUint64(24, true));
      const b = this.basis.get(part);
      const ref = this.full.get(part);
      if (!b || !ref || b.basis !== Number(dv.getBigUint64(32, true)) || b.reference !== ref.revision) throw new Error('a drag frame that cannot be applied');
      const dx = dv.getFloat64(40, true);
      const dy = dv.getFloat64(48, true);
      const dz = dv.getFloat64(56, true);
      const r = ref.points;
      const rho = b.rho;
      // The net shown is rebuilt in place, as a renderer's vertex buffer
      // would be: no allocation (and no garbage to collect) per frame.
      let out = this.net.get(part);
      if (!out || out === ref.points || out.length !== r.length) out = new Float32Array(r.length);
      for (let k = 0, i = 0; k < rho.length; k++, i += 3) {
        out[i] = r[i] + rho[k] * dx;
        out[i + 1] = r[i + 1] + rho[k] * dy;
        out[i + 2] = r[i + 2] + rho[k] * dz;
      }
      this.net.set(part, out);
      this.applyMs.push(performance.now() - t0);
      return { kind, part, revision, flags: dv.getUint16(6, true) };
    }
    const h = frameHeader(buf);
    if (h.kind === 1) {
      // Points at P = 48 + 8·(nu+pu+1) + 8·(nv+pv+1).
      const pu = dv.getUint8(40);
      const pv = dv.getUint8(41);
      const at = 48 + 8 * (h.nu + pu + 1) + 8 * (h.nv + pv + 1);
      const points = new Float32Array(buf, at, 3 * h.nu * h.nv);
      this.full.set(part, { revision: h.revision, points });
      this.basis.delete(part);
      this.net.set(part, points);
    }
    return h;
  }
}

class Client {
  constructor(addr, stream = false) {
    this.ws = new WebSocket(`ws://${addr}/ws${stream ? '?drag_stream=1' : ''}`);
    this.ws.binaryType = 'arraybuffer';
    this.onText = () => {};
    this.onFrame = () => {};
    this.closed = false;
    this.bytes = 0;
    this.stream = stream ? new StreamState() : null;
    // A message is stamped when it arrives and handled after every socket
    // that became readable in the same turn of the event loop was stamped
    // (setImmediate runs after the poll phase), so one viewer's decoding
    // does not delay another viewer's arrival stamp on the same thread.
    this.ws.onmessage = (ev) => {
      const now = clock();
      setImmediate(() => {
        if (typeof ev.data === 'string') this.onText(JSON.parse(ev.data), now);
        else {
          this.bytes += ev.data.byteLength;
          const h = this.stream ? this.stream.take(ev.data) : frameHeader(ev.data);
          if (h) this.onFrame(h, now);
        }
      });
    };
    this.ws.onclose = () => {
      this.closed = true;
    };
  }
  open() {
    return new Promise((resolve, reject) => {
      this.ws.onopen = resolve;
      this.ws.onerror = (e) => reject(new Error(`websocket error ${e.message ?? ''}`));
    });
  }
  send(msg) {
    this.ws.send(JSON.stringify(msg));
  }
  /** Waits for the first text message satisfying `pred`. */
  waitText(pred) {
    return new Promise((resolve) => {
      const prev = this.onText;
      this.onText = (m, t) => {
        prev(m, t);
        if (pred(m)) {
          this.onText = prev;
          resolve([m, t]);
        }
      };
    });
  }
  /**
   * Opens, says hello, resolves at the snapshot with [snapshot, ms from hello,
   * ms from hello to the first binary frame or null]. `geometryFirst` asks
   * for the compact join.
   */
  async join(design, token, name, geometryFirst = false) {
    await this.open();
    const got = this.waitText((m) => m.type === 'snapshot' || m.type === 'error');
    let firstFrame = null;
    const onFrame = this.onFrame;
    this.onFrame = (h, t) => {
      if (firstFrame === null) firstFrame = t;
      onFrame(h, t);
    };
    const t0 = clock();
    const hello = { type: 'hello', protocol: PROTOCOL, token, design, client_name: name, client_kind: 'tool' };
    if (geometryFirst) hello.geometry_first = true;
    this.send(hello);
    const [m, t1] = await got;
    this.onFrame = onFrame;
    if (m.type === 'error') throw new Error(`join refused: ${m.code} ${m.message}`);
    return [m, t1 - t0, firstFrame === null ? null : firstFrame - t0];
  }
  close() {
    this.ws.close();
  }
}

/**
 * A join over a bare TCP socket (RFC 6455 by hand: the upgrade, one masked
 * text frame out, unmasked frames in), timing the server alone: hello sent →
 * the first and the last byte of the snapshot's frame received, with no
 * WebSocket library and no JSON parsing on the client's side (a message is
 * known for the snapshot by its first bytes, `{"type":"snapshot"`, as the
 * server writes it). Resolves [ms to the first byte, ms to the last byte].
 */
function rawJoin(addr, design, token, name, geometryFirst) {
  const [host, port] = [addr.slice(0, addr.lastIndexOf(':')), Number(addr.slice(addr.lastIndexOf(':') + 1))];
  return new Promise((resolve, reject) => {
    const sock = tcpConnect({ host, port });
    let upgraded = false;
    let buf = Buffer.alloc(0);
    // Chunks of a frame still incomplete, joined once it is whole (joining
    // each chunk to what came before copied the 0.8 MB snapshot quadratically).
    let waiting = [];
    let waitingLen = 0;
    let need = 0;
    let t0 = 0;
    let first = null;
    const fail = (e) => {
      sock.destroy();
      reject(e);
    };
    sock.on('error', fail);
    sock.on('connect', () => {
      sock.write(`GET /ws HTTP/1.1\r\nHost: ${addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: ${randomBytes(16).toString('base64')}\r\nSec-WebSocket-Version: 13\r\n\r\n`);
    });
    sock.on('data', (chunk) => {
      const now = clock();
      if (buf.length + waitingLen + chunk.length < need) {
        waiting.push(chunk);
        waitingLen += chunk.length;
        return;
      }
      buf = Buffer.concat([buf, ...waiting, chunk]);
      waiting = [];
      waitingLen = 0;
      need = 0;
      if (!upgraded) {
        const end = buf.indexOf('\r\n\r\n');
        if (end < 0) return;
        if (!buf.subarray(0, 12).toString().includes('101')) return fail(new Error(`no upgrade: ${buf.subarray(0, end)}`));
        upgraded = true;
        buf = buf.subarray(end + 4);
        const hello = { type: 'hello', protocol: PROTOCOL, token, design, client_name: name, client_kind: 'tool' };
        if (geometryFirst) hello.geometry_first = true;
        const payload = Buffer.from(JSON.stringify(hello));
        const mask = randomBytes(4);
        const head = payload.length < 126 ? Buffer.from([0x81, 0x80 | payload.length]) : Buffer.from([0x81, 0x80 | 126, payload.length >> 8, payload.length & 255]);
        const masked = Buffer.from(payload.map((b, i) => b ^ mask[i & 3]));
        t0 = clock();
        sock.write(Buffer.concat([head, mask, masked]));
      }
      // Frames in: the server's are unmasked.
      while (buf.length >= 2) {
        const op = buf[0] & 15;
        let len = buf[1] & 127;
        let at = 2;
        if (len === 126) {
          if (buf.length < 4) return;
          len = buf.readUInt16BE(2);
          at = 4;
        } else if (len === 127) {
          if (buf.length < 10) return;
          len = Number(buf.readBigUInt64BE(2));
          at = 10;
        }
        const isSnapshot = op === 1 && buf.length >= at + 18 && buf.subarray(at, at + 18).toString() === '{"type":"snapshot"';
        if (isSnapshot && first === null) first = now;
        if (buf.length < at + len) {
          need = at + len;
          return;
        }
        if (isSnapshot) {
          sock.destroy();
          return resolve([first - t0, now - t0]);
        }
        if (op === 1 && buf.subarray(at, at + 15).toString() === '{"type":"error"') return fail(new Error(buf.subarray(at, at + len).toString()));
        buf = buf.subarray(at + len);
      }
    });
  });
}

// ---- the benches -------------------------------------------------------------

/** JOINS sequential joins over a bare socket (rawJoin): the server's own share of a join. */
async function benchJoinRaw(srv, design, viewer, geometryFirst = false) {
  const firstByte = [];
  const lastByte = [];
  for (let k = 0; k < JOINS; k++) {
    const [a, b] = await rawJoin(srv.addr, design.id, viewer, `raw-joiner-${k}`, geometryFirst);
    firstByte.push(a);
    lastByte.push(b);
  }
  return { firstByte, lastByte };
}

/** JOINS sequential joins: hello → snapshot, and hello → first frame. */
async function benchJoin(srv, design, viewer, geometryFirst = false) {
  const times = [];
  const firstFrames = [];
  for (let k = 0; k < JOINS; k++) {
    const c = new Client(srv.addr);
    const [, ms, frame] = await c.join(design.id, viewer, `joiner-${k}`, geometryFirst);
    times.push(ms);
    if (frame !== null) firstFrames.push(frame);
    c.close();
  }
  return { times, firstFrames };
}

/** An editor holding a load icon at (0.5, 0.5) of part 1. */
async function editorWithIcon(srv, design) {
  const ed = new Client(srv.addr);
  const [snap] = await ed.join(design.id, design.tokens.editor, 'bench-editor');
  const part = snap.parts[0].id;
  const ack = ed.waitText((m) => m.req === 1);
  ed.send({ type: 'create_icon', part, req: 1, spec: { anchor: { kind: 'point', u: 0.5, v: 0.5 }, role: { kind: 'load' } } });
  const [a] = await ack;
  if (a.type !== 'ack') throw new Error(`create_icon: ${JSON.stringify(a)}`);
  const grabbed = ed.waitText((m) => m.req === 2);
  ed.send({ type: 'drag_start', part, icon: a.icon, req: 2 });
  await grabbed;
  return { ed, part, icon: a.icon };
}

async function benchOwnFrame(srv, design) {
  const { ed, part, icon } = await editorWithIcon(srv, design);
  const times = await ownFrames(ed, part, icon);
  ed.close();
  return times;
}

/** DRAGS drags at 60 Hz by `ed`, each timed to its own geometry frame. */
async function ownFrames(ed, part, icon) {
  let last = 0;
  const times = [];
  for (let k = 0; k < DRAGS; k++) {
    const frame = new Promise((resolve) => {
      ed.onFrame = (h, t) => {
        if (h.part === part && h.revision > last && (h.flags & 1)) {
          last = h.revision;
          ed.onFrame = () => {};
          resolve(t);
        }
      };
    });
    const t0 = clock();
    ed.send({ type: 'drag', part, icon, xyz: [0.5, 0.5, 0.1 + 0.001 * (k % 100)] });
    times.push((await frame) - t0);
    await sleep(1000 / 60);
  }
  return times;
}

/**
 * The editor's own frame while a second editor commits over and over: a
 * commit, its ack, a pause of COMMIT_PAUSE_MS, the next commit, until the
 * drags are done. Returns the drag times and commit → ack times.
 */
async function benchOwnFrameWhileCommitting(srv, design) {
  const { ed, part, icon } = await editorWithIcon(srv, design);
  const committer = new Client(srv.addr);
  await committer.join(design.id, design.tokens.editor, 'bench-committer');
  let done = false;
  const commits = [];
  let req = 1;
  const committing = (async () => {
    while (!done) {
      const r = req++;
      const ack = committer.waitText((m) => m.req === r);
      const t0 = clock();
      committer.send({ type: 'commit', req: r, message: `bench ${r}` });
      const [m, t1] = await ack;
      if (m.type !== 'ack' || typeof m.version !== 'number') throw new Error(`commit: ${JSON.stringify(m)}`);
      commits.push(t1 - t0);
      await sleep(COMMIT_PAUSE_MS);
    }
  })();
  await sleep(200); // the first commit is under way
  const drags = await ownFrames(ed, part, icon);
  done = true;
  await committing;
  committer.close();
  ed.close();
  return { drags, commits };
}

/**
 * `count` viewers of one design: they join, then from `start()` to `stop()`
 * stamp each geometry frame's arrival with the shared clock.
 */
class ViewerGroup {
  constructor({ addr, design, token, stream, count, offset }) {
    Object.assign(this, { addr, design, token, stream, count, offset });
    this.viewers = [];
    this.arrivals = [];
    this.measuring = false;
  }
  async join() {
    for (let k = 0; k < this.count; k++) {
      const c = new Client(this.addr, this.stream);
      await c.join(this.design, this.token, `viewer-${this.offset + k}`);
      const arrivals = [];
      c.onFrame = (h, t) => {
        if (this.measuring) arrivals.push([h.part, h.revision, t]);
      };
      this.viewers.push(c);
      this.arrivals.push(arrivals);
    }
  }
  start() {
    this.bytes0 = this.viewers.map((c) => c.bytes);
    this.measuring = true;
  }
  stop() {
    this.measuring = false;
    const out = {
      arrivals: this.arrivals,
      bytes: this.viewers.map((c, i) => c.bytes - this.bytes0[i]),
      applyMs: this.stream ? this.viewers.flatMap((c) => c.stream.applyMs) : [],
    };
    this.viewers.forEach((c) => c.close());
    return out;
  }
}

/** A ViewerGroup on its own worker thread, driven by messages. */
class ThreadedViewerGroup {
  constructor(spec) {
    this.worker = new Worker(new URL(import.meta.url), { workerData: spec });
    // Messages are queued from the start: one may come before it is awaited.
    const queue = [];
    const waiting = [];
    this.worker.on('message', (m) => (waiting.length ? waiting.shift().resolve(m) : queue.push(m)));
    this.worker.on('error', (e) => {
      while (waiting.length) waiting.shift().reject(e);
      queue.push(e);
    });
    this.next = () =>
      queue.length
        ? queue[0] instanceof Error
          ? Promise.reject(queue[0])
          : Promise.resolve(queue.shift())
        : new Promise((resolve, reject) => waiting.push({ resolve, reject }));
  }
  async join() {
    const m = await this.next();
    if (m !== 'ready') throw new Error(`viewer thread: ${JSON.stringify(m)}`);
  }
  start() {
    this.worker.postMessage('start');
  }
  async stop() {
    const got = this.next();
    this.worker.postMessage('stop');
    const out = await got;
    await this.worker.terminate();
    return out;
  }
}

async function benchFanout(srv, design, stream = false) {
  const { ed, part, icon } = await editorWithIcon(srv, design);
  const groups = [];
  const threads = Math.min(VIEWER_THREADS, VIEWERS);
  for (let g = 0, offset = 0; g < threads; g++) {
    const count = Math.floor(VIEWERS / threads) + (g < VIEWERS % threads ? 1 : 0);
    const spec = { addr: srv.addr, design: design.id, token: design.tokens.viewer, stream, count, offset };
    groups.push(threads === 1 ? new ViewerGroup(spec) : new ThreadedViewerGroup(spec));
    offset += count;
  }
  for (const g of groups) await g.join();
  // Drag k asks for z = zk; icon_feedback names the revision that solved it.
  const sentAt = new Map(); // requested z (string) → send time
  const revisionSent = new Map(); // revision → send time
  ed.onText = (m) => {
    if (m.type === 'icon_feedback' && m.icon === icon) {
      const t = sentAt.get(m.requested[2].toFixed(6));
      if (t !== undefined) revisionSent.set(m.revision, t);
    }
  };
  groups.forEach((g) => g.start());
  await sleep(50); // every thread has seen its start
  const start = performance.now();
  const n = Math.round(FANOUT_SECONDS * 60);
  for (let k = 0; k < n; k++) {
    const z = 0.1 + 0.0001 * k;
    sentAt.set(z.toFixed(6), clock());
    ed.send({ type: 'drag', part, icon, xyz: [0.5, 0.5, z] });
    const next = start + ((k + 1) * 1000) / 60;
    await sleep(Math.max(0, next - performance.now()));
  }
  await sleep(300);
  const seconds = (performance.now() - start - 300) / 1000;
  const results = await Promise.all(groups.map((g) => g.stop()));
  const arrivals = results.flatMap((r) => r.arrivals);
  const lat = [];
  const fps = [];
  for (const a of arrivals) {
    const mine = a.filter(([p]) => p === part);
    fps.push(mine.length / seconds);
    for (const [, rev, t] of mine) {
      const t0 = revisionSent.get(rev);
      if (t0 !== undefined) lat.push(t - t0);
    }
  }
  const bytes = results.flatMap((r) => r.bytes).map((b) => b / seconds);
  const frames = arrivals.reduce((m, a) => m + a.length, 0);
  const applyMs = results.flatMap((r) => r.applyMs);
  ed.close();
  return { lat, fps, drags: n, threads, bytesPerFrame: bytes.reduce((a, b) => a + b, 0) * seconds / Math.max(1, frames), bytesPerSecond: pct(bytes, 50), applyMs };
}

async function benchSoak(srv) {
  const designs = [];
  for (let k = 0; k < SOAK_DESIGNS; k++) designs.push(await createDesign(srv, `soak-${k}`));
  const rounds = [];
  let seed = 12345;
  const rand = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648);
  for (let r = 0; r < SOAK_ROUNDS; r++) {
    const joins = [];
    const t0 = performance.now();
    for (let k = 0; k < SOAK_CLIENTS; k += 10) {
      await Promise.all(
        Array.from({ length: 10 }, async (_, j) => {
          const d = designs[Math.floor(rand() * designs.length)];
          const token = (k + j) % 5 === 0 ? d.tokens.editor : d.tokens.viewer;
          const c = new Client(srv.addr);
          const [, ms] = await c.join(d.id, token, `soak-${r}-${k + j}`);
          joins.push(ms);
          // One request each, then leave.
          const pong = c.waitText((m) => m.type === 'pong');
          c.send({ type: 'ping', req: 1 });
          await pong;
          c.close();
        }),
      );
    }
    await sleep(500); // let the server drop the closed connections
    rounds.push({
      round: r + 1,
      rss: rssMiB(srv.child.pid),
      p50: pct(joins, 50),
      p99: pct(joins, 99),
      seconds: (performance.now() - t0) / 1000,
    });
  }
  return rounds;
}

// ---- main ----------------------------------------------------------------------

if (!isMainThread) {
  // A viewer thread of the fanout: join, then answer 'start' and 'stop'.
  const group = new ViewerGroup(workerData);
  await group.join();
  parentPort.on('message', (m) => {
    if (m === 'start') group.start();
    if (m === 'stop') parentPort.postMessage(group.stop());
  });
  parentPort.postMessage('ready');
} else {
  const srv = await startServer();
  try {
    console.log(`server ${bin} on ${srv.addr}, pid ${srv.child.pid}`);
    const big = await createDesign(srv, 'bench 81x159', 81, 159);
    if (runs('join')) {
      const plain = await benchJoin(srv, big, big.tokens.viewer);
      console.log(`join 81x159 (hello → snapshot), ${plain.times.length} joins: p50 ${fmt(pct(plain.times, 50))} ms, p99 ${fmt(pct(plain.times, 99))} ms`);
      const compact = await benchJoin(srv, big, big.tokens.viewer, true);
      console.log(
        `compact join 81x159 (geometry_first), ${compact.times.length} joins: hello → first frame p50 ${fmt(pct(compact.firstFrames, 50))} ms, ` +
          `p99 ${fmt(pct(compact.firstFrames, 99))} ms; hello → snapshot p50 ${fmt(pct(compact.times, 50))} ms, p99 ${fmt(pct(compact.times, 99))} ms`,
      );
      for (const [label, gf] of [['plain', false], ['compact', true]]) {
        const raw = await benchJoinRaw(srv, big, big.tokens.viewer, gf);
        console.log(
          `${label} join 81x159 over a bare socket, ${raw.lastByte.length} joins: hello → the snapshot's first byte p50 ${fmt(pct(raw.firstByte, 50))} ms, ` +
            `p99 ${fmt(pct(raw.firstByte, 99))} ms; → its last byte p50 ${fmt(pct(raw.lastByte, 50))} ms, p99 ${fmt(pct(raw.lastByte, 99))} ms`,
        );
      }
    }
    if (runs('own')) {
      const own = await benchOwnFrame(srv, big);
      console.log(`editor's own drag frame 81x159, ${own.length} drags at 60 Hz: p50 ${fmt(pct(own, 50))} ms, p99 ${fmt(pct(own, 99))} ms, max ${fmt(Math.max(...own))} ms`);
    }
    if (runs('commits')) {
      const fresh = await createDesign(srv, 'bench 81x159 commits', 81, 159);
      const { drags, commits } = await benchOwnFrameWhileCommitting(srv, fresh);
      console.log(
        `editor's own drag frame 81x159 while another editor commits (pause ${COMMIT_PAUSE_MS} ms), ${drags.length} drags at 60 Hz: ` +
          `p50 ${fmt(pct(drags, 50))} ms, p99 ${fmt(pct(drags, 99))} ms, max ${fmt(Math.max(...drags))} ms; ` +
          `${commits.length} commits, commit → ack p50 ${fmt(pct(commits, 50))} ms, p99 ${fmt(pct(commits, 99))} ms`,
      );
    }
    for (const stream of runs('fanout') ? [false, true] : []) {
      // Each fanout on a fresh 81 × 159 design: the same starting point.
      const fresh = await createDesign(srv, `bench 81x159 ${stream ? 'stream' : 'full'}`, 81, 159);
      const f = await benchFanout(srv, fresh, stream);
      console.log(
        `${VIEWERS} viewers on ${f.threads} thread(s) at 60 Hz on 81x159 (${f.drags} drags), ${stream ? 'drag stream' : 'full frames'}: drag → viewer frame p50 ${fmt(pct(f.lat, 50))} ms, ` +
          `p99 ${fmt(pct(f.lat, 99))} ms over ${f.lat.length} frames; frames/s per viewer min ${fmt(Math.min(...f.fps))}, median ${fmt(pct(f.fps, 50))}; ` +
          `bytes per frame ${Math.round(f.bytesPerFrame)}, per viewer ${fmt(f.bytesPerSecond / 1e6)} MB/s` +
          (stream ? `; client R + ρ·d per frame p50 ${fmt(pct(f.applyMs, 50))} ms, p99 ${fmt(pct(f.applyMs, 99))} ms` : ''),
      );
    }
    if (runs('soak') && SOAK_ROUNDS > 0) {
      const rss0 = rssMiB(srv.child.pid);
      const rounds = await benchSoak(srv);
      console.log(`soak: ${SOAK_DESIGNS} designs, ${SOAK_CLIENTS} clients joining and leaving per round; RSS before ${fmt(rss0)} MiB`);
      for (const r of rounds) {
        console.log(`  round ${r.round}: RSS ${fmt(r.rss)} MiB, join p50 ${fmt(r.p50)} ms, p99 ${fmt(r.p99)} ms, ${fmt(r.seconds)} s`);
      }
    }
  } finally {
    srv.child.kill('SIGTERM');
    await new Promise((r) => srv.child.on('exit', r));
    rmSync(srv.data, { recursive: true, force: true });
  }
}
