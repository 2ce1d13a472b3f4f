// A link emulator for the tests and benches: a TCP proxy on loopback that
// gives every connection through it the bandwidth and one-way delay of a
// real internet link, in each direction, without loss or reordering (a slow
// link stalls, it does not drop). Bytes are serialised at `mbit` megabits
// per second per direction, shared by all connections of the proxy as on one
// access link, then delivered `delayMs` later; `jitterMs` adds a random extra
// delay to each chunk while keeping the order. The proxy counts the bytes it
// carried each way and the path of every HTTP request that crossed it. Not a
// test file itself.

import net from 'node:net';

/**
 * Starts a shaping proxy in front of `target` ("host:port").
 * Resolves to { port, url(base), bytes: { down, up }, requests, reset(), close() }:
 * `requests` lists "METHOD /path" of each HTTP request line sent upstream.
 */
export function startLink({ target, mbit, delayMs, jitterMs = 0 }) {
  const [host, port] = target.split(':');
  const bytesPerMs = (mbit * 1e6) / 8 / 1000;
  // One serialiser per direction, shared by every connection (one access link).
  const lanes = { down: { free: 0 }, up: { free: 0 } };
  const counters = { down: 0, up: 0 };
  const requests = [];
  const sockets = new Set();

  /**
   * Sends `chunk` to `to` as the link would: after its serialisation time and
   * the delay. Each socket direction is one FIFO drained by a single timer, so
   * chunks leave in the order they came even when timers fire late or out of
   * order (Node schedules a timer from its cached loop time, which lags on a
   * loaded machine: one timer per chunk reordered the bytes of a large frame).
   */
  function shape(lane, dir, chunk, to, state) {
    counters[dir] += chunk.length;
    const now = performance.now();
    const start = Math.max(now, lane.free);
    lane.free = start + chunk.length / bytesPerMs;
    const at = Math.max(lane.free + delayMs + (jitterMs ? Math.random() * jitterMs : 0), state.last);
    state.last = at;
    state.queue.push({ at, chunk });
    drain(to, state);
  }

  /** Writes every queued chunk that is due, in order, and re-arms for the next one. */
  function drain(to, state) {
    if (state.timer) return;
    const now = performance.now();
    while (state.queue.length && state.queue[0].at <= now) {
      const { chunk } = state.queue.shift();
      if (!to.destroyed) to.write(chunk);
    }
    if (state.queue.length) {
      state.timer = setTimeout(() => {
        state.timer = null;
        drain(to, state);
      }, Math.max(1, state.queue[0].at - now));
    } else if (state.ended && !to.destroyed) {
      to.end();
    }
  }

  const server = net.createServer((client) => {
    client.setNoDelay(true);
    const upstream = net.connect({ host, port: Number(port) });
    upstream.setNoDelay(true);
    sockets.add(client);
    sockets.add(upstream);
    const downState = { last: 0, queue: [], timer: null, ended: false };
    const upState = { last: 0, queue: [], timer: null, ended: false };
    client.on('data', (c) => {
      for (const m of c.toString('latin1').matchAll(/(?:^|\r\n)(GET|HEAD|POST) (\S+) HTTP\/1\.1\r\n/g)) requests.push(`${m[1]} ${m[2]}`);
      shape(lanes.up, 'up', c, upstream, upState);
    });
    upstream.on('data', (c) => shape(lanes.down, 'down', c, client, downState));
    const finish = (state, to) => {
      state.ended = true;
      if (state.queue.length === 0 && !state.timer && !to.destroyed) to.end();
    };
    client.on('end', () => finish(upState, upstream));
    upstream.on('end', () => finish(downState, client));
    const destroy = () => {
      client.destroy();
      upstream.destroy();
      sockets.delete(client);
      sockets.delete(upstream);
    };
    client.on('error', destroy);
    upstream.on('error', destroy);
    client.on('close', () => sockets.delete(client));
    upstream.on('close', () => sockets.delete(upstream));
  });

  return new Promise((resolve, reject) => {
    server.once('error', reject);
    server.listen(0, '127.0.0.1', () => {
      const { port: own } = server.address();
      resolve({
        port: own,
        /** `url` (on the target) rewritten to go through this link. */
        url: (u) => {
          const x = new URL(u);
          x.host = `127.0.0.1:${own}`;
          return x.toString();
        },
        bytes: counters,
        requests,
        reset() {
          counters.down = 0;
          counters.up = 0;
          requests.length = 0;
        },
        close() {
          for (const s of sockets) s.destroy();
          return new Promise((r) => server.close(() => r()));
        },
      });
    });
  });
}
