// A protocol client for the link tests and benches (Node, WebSocket): text
// messages and geometry decoded with the web client's own modules (frame.js,
// drag-stream.js, deflated.js), the capabilities of protocol/README.md asked
// for in the URL (drag_stream, deflate, pace), and the bytes and kinds it
// received. Not a test file itself.

import { decodeFrame, PROTOCOL_VERSION } from '../src/frame.js';
import { DragStream } from '../src/drag-stream.js';
import { inflateMessage, isDeflated } from '../src/deflated.js';

/** Resolves after `ms`. */
export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
/** The `p`-th percentile of `xs`. */
export const pct = (xs, p) => {
  const s = [...xs].sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.max(0, Math.ceil((p / 100) * s.length) - 1))];
};

/**
 * A protocol client: text and decoded frames (through a DragStream when
 * `stream`; deflated messages inflated by the page's deflated.js, in order,
 * when `deflate`).
 */
export function connect(base, design, token, { stream = false, deflate = false, pace = false } = {}) {
  const query = [stream && 'drag_stream=1', deflate && 'deflate=1', pace && 'pace=1'].filter(Boolean).join('&');
  const url = `${base.replace('http', 'ws')}/ws${query ? `?${query}` : ''}`;
  const ws = new WebSocket(url);
  ws.binaryType = 'arraybuffer';
  const c = { ws, texts: [], frames: [], onText: () => {}, onFrame: () => {}, drag: stream ? new DragStream() : null, bytes: 0, deflated: 0, kinds: {} };
  let received = 0;
  const receive = async (data, arrived) => {
    if (typeof data === 'string') {
      const m = JSON.parse(data);
      c.texts.push(m);
      c.onText(m, arrived);
      return;
    }
    c.bytes += data.byteLength;
    const size = data.byteLength;
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
    // pace=1: report the binary bytes taken in, once inflated and decoded (protocol/README.md, "Paced delivery").
    if (pace && ws.readyState === WebSocket.OPEN) {
      received += size;
      ws.send(JSON.stringify({ type: 'received', bytes: received }));
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
export async function until(c, part, rev) {
  const t0 = performance.now();
  while (!c.frames.some((f) => f.part === part && f.revision >= rev)) {
    if (performance.now() - t0 > 20000) throw new Error(`no frame of part ${part} at revision ${rev} within 20 s`);
    await sleep(5);
  }
}
