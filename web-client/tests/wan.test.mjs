// The link emulator itself (tests/wan.mjs): what crosses it arrives complete
// and in order, even when the event loop running it stalls — the shape of a
// loaded CI machine, where a reordered chunk once corrupted a WebSocket frame
// and made a browser test reconnect and count its bytes twice.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import net from 'node:net';
import { startLink } from './wan.mjs';

/** A TCP server that sends `count` chunks of `size` bytes, each filled with its index mod 251, then ends. */
function source(count, size) {
  const server = net.createServer((s) => {
    let i = 0;
    const pump = () => {
      while (i < count) {
        const chunk = Buffer.alloc(size, i % 251);
        i++;
        if (!s.write(chunk)) return void s.once('drain', pump);
      }
      s.end();
    };
    pump();
  });
  return new Promise((r) => server.listen(0, '127.0.0.1', () => r(server)));
}

test('bytes cross the link in order and complete while its event loop stalls', async () => {
  const count = 400;
  const size = 4096;
  const upstream = await source(count, size);
  const link = await startLink({ target: `127.0.0.1:${upstream.address().port}`, mbit: 100, delayMs: 20, jitterMs: 0 });
  // Stall the loop for 12 ms every 15 ms: chunks handled right after a stall
  // see a cached loop time 12 ms behind the clock.
  const stall = setInterval(() => {
    const until = performance.now() + 12;
    while (performance.now() < until);
  }, 15);
  try {
    const received = await new Promise((resolve, reject) => {
      const parts = [];
      const c = net.connect({ port: link.port, host: '127.0.0.1' });
      c.on('data', (d) => parts.push(d));
      c.on('end', () => resolve(Buffer.concat(parts)));
      c.on('error', reject);
    });
    assert.equal(received.length, count * size);
    for (let i = 0; i < count; i++) {
      const want = i % 251;
      const start = i * size;
      const bad = received.subarray(start, start + size).findIndex((b) => b !== want);
      assert.equal(bad, -1, `chunk ${i} holds bytes of another chunk at offset ${start + bad}`);
    }
    assert.equal(link.bytes.down, count * size);
  } finally {
    clearInterval(stall);
    await link.close();
    await new Promise((r) => upstream.close(() => r()));
  }
});
