// The deflated message (kind 7) decoder against messages put together here
// from the README's table ("Deflated message (kind 7)"): the header written
// field by field, the records shuffled by index arithmetic, the DEFLATE data
// made by Node's zlib (not by the server's encoder). A lying length, an
// inflation bomb, nesting and bad headers are refused.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { deflateRawSync } from 'node:zlib';
import { inflateMessage, isDeflated } from '../src/deflated.js';

/** A kind-7 message: header (magic, 7, version 2, record length, 0, inner length, start) + `data`. */
function message(word, innerLen, start, data) {
  const out = new Uint8Array(16 + data.length);
  out.set([0x56, 0x53, 0x47, 0x46, 7, 2, word, 0]);
  const dv = new DataView(out.buffer);
  dv.setUint32(8, innerLen, true);
  dv.setUint32(12, start, true);
  out.set(data, 16);
  return out.buffer;
}

/** Bytes before `start` as they are, plane j = byte j of every record, then the tail. */
function planes(inner, word, start) {
  const records = Math.floor((inner.length - start) / word);
  const out = [...inner.subarray(0, start)];
  for (let j = 0; j < word; j++) for (let i = 0; i < records; i++) out.push(inner[start + word * i + j]);
  out.push(...inner.subarray(start + word * records));
  return Uint8Array.from(out);
}

/** An inner message: the frame magic, kind 5, version 2, then `n` f32 of a smooth field (not a valid basis: the decoder does not care). */
function inner(n) {
  const b = new Uint8Array(48 + 4 * n + 3);
  b.set([0x56, 0x53, 0x47, 0x46, 5, 2]);
  const f = new Float32Array(b.buffer, 48, n);
  for (let k = 0; k < n; k++) f[k] = Math.cos(k * 0.01);
  b.set([1, 2, 3], 48 + 4 * n);
  return b;
}

test('a message shuffled and deflated by hand inflates to its inner message, byte for byte', async () => {
  const src = inner(2000);
  for (const [word, start] of [[4, 48], [12, 8], [1, 0], [3, 17]]) {
    const m = message(word, src.length, start, deflateRawSync(planes(src, word, start)));
    assert.ok(isDeflated(m));
    const out = new Uint8Array(await inflateMessage(m, 2));
    assert.deepEqual(out, src, `record length ${word} from ${start}`);
  }
  // Records shuffled but the header says no shuffle: not the message.
  const m = message(1, src.length, 0, deflateRawSync(planes(src, 4, 48)));
  assert.notDeepEqual(new Uint8Array(await inflateMessage(m, 2)), src);
});

test('a lying length, an inflation bomb, nesting and bad headers are refused', async () => {
  const src = inner(500);
  const data = deflateRawSync(planes(src, 4, 48));
  await assert.rejects(inflateMessage(message(4, src.length + 1, 48, data), 2), /inflates to/);
  await assert.rejects(inflateMessage(message(4, src.length - 1, 48, data), 2), /past its stated/);
  // 64 MiB of zeros (64 KB deflated) claimed to be 4 KiB: refused as soon as it passes 4 KiB.
  const bomb = new Uint8Array(64 << 20);
  bomb.set([0x56, 0x53, 0x47, 0x46, 1, 2]);
  await assert.rejects(inflateMessage(message(1, 4096, 0, deflateRawSync(bomb)), 2), /past its stated 4096/);
  await assert.rejects(inflateMessage(message(1, 65 << 20, 0, data), 2), /stands for/);
  // Truncated DEFLATE data.
  await assert.rejects(inflateMessage(message(4, src.length, 48, data.subarray(0, data.length - 8)), 2));
  // A deflated message inside another.
  const once = new Uint8Array(message(1, src.length, 0, deflateRawSync(src)));
  await assert.rejects(inflateMessage(message(1, once.length, 0, deflateRawSync(once)), 2), /inside another/);
  // No frame magic inside.
  const junk = new Uint8Array(3000).fill(0x55);
  await assert.rejects(inflateMessage(message(1, junk.length, 0, deflateRawSync(junk)), 2), /magic/);
  // Header fields.
  const good = new Uint8Array(message(4, src.length, 48, data));
  for (const [at, v, why] of [[5, 3, /version/], [6, 0, /record length/], [6, 13, /record length/], [7, 1, /zero byte/], [0, 0x57, /magic/]]) {
    const b = good.slice();
    b[at] = v;
    await assert.rejects(inflateMessage(b.buffer, 2), why);
  }
  const past = good.slice();
  new DataView(past.buffer).setUint32(12, src.length + 1, true);
  await assert.rejects(inflateMessage(past.buffer, 2), /past its end/);
  await assert.rejects(inflateMessage(new ArrayBuffer(10), 2), /too short/);
});
