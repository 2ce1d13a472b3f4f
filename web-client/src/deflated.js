// The deflated message (protocol/README.md, "Deflated message (kind 7)"):
// any other binary message, its records byte-shuffled and compressed with
// DEFLATE, sent to a page that opened its socket with `deflate=1`. The
// browser inflates it natively (DecompressionStream 'deflate-raw'); the
// inflation stops as soon as it passes the stated length, so a message that
// inflates without end costs nothing. The result is the inner message, byte
// for byte, decoded as usual (frame.js).

const MAGIC = [0x56, 0x53, 0x47, 0x46]; // "VSGF"
export const KIND_DEFLATED = 7;
const HEADER = 16;
/** Largest inner message, as protocol/src/deflated.rs. */
const MAX_INFLATED = 64 * 1024 * 1024;

/** Whether `buf` (an ArrayBuffer) is a deflated message. */
export function isDeflated(buf) {
  return buf instanceof ArrayBuffer && buf.byteLength >= HEADER && new Uint8Array(buf, 4, 1)[0] === KIND_DEFLATED;
}

/**
 * The inner message of a deflated message, as an ArrayBuffer; rejects on
 * any malformed input (header, stated length, DEFLATE data, nesting).
 */
export async function inflateMessage(buf, version) {
  if (!(buf instanceof ArrayBuffer) || buf.byteLength < HEADER) throw new Error('deflated message too short');
  const dv = new DataView(buf);
  for (let i = 0; i < 4; i++) if (dv.getUint8(i) !== MAGIC[i]) throw new Error('bad magic');
  if (dv.getUint8(4) !== KIND_DEFLATED) throw new Error('not a deflated message');
  if (dv.getUint8(5) !== version) throw new Error(`frame version ${dv.getUint8(5)}, this page speaks ${version}`);
  const word = dv.getUint8(6);
  if (word < 1 || word > 12) throw new Error(`deflated message: record length ${word}`);
  if (dv.getUint8(7) !== 0) throw new Error('deflated message zero byte is not zero');
  const len = dv.getUint32(8, true);
  const start = dv.getUint32(12, true);
  if (len > MAX_INFLATED) throw new Error(`deflated message stands for ${len} bytes`);
  if (start > len) throw new Error('deflated message records start past its end');

  const shuffled = new Uint8Array(len);
  let at = 0;
  const stream = new Blob([new Uint8Array(buf, HEADER)]).stream().pipeThrough(new DecompressionStream('deflate-raw'));
  const reader = stream.getReader();
  try {
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      if (at + value.length > len) throw new Error(`deflated message inflates past its stated ${len} bytes`);
      shuffled.set(value, at);
      at += value.length;
    }
  } finally {
    reader.cancel().catch(() => {});
  }
  if (at !== len) throw new Error(`deflated message inflates to ${at} bytes, its header says ${len}`);

  // Un-shuffle: plane j holds byte j of every record from `start` on.
  const inner = new Uint8Array(len);
  inner.set(shuffled.subarray(0, start));
  const records = Math.floor((len - start) / word);
  for (let j = 0; j < word; j++) {
    const plane = start + j * records;
    for (let i = 0; i < records; i++) inner[start + i * word + j] = shuffled[plane + i];
  }
  const tail = start + records * word;
  inner.set(shuffled.subarray(tail), tail);
  if (len < 8 || MAGIC.some((m, i) => inner[i] !== m)) throw new Error("deflated message's inner message has no frame magic");
  if (inner[4] === KIND_DEFLATED) throw new Error('a deflated message inside another');
  return inner.buffer;
}
