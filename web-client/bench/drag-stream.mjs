// Client JS per drag-stream frame at 81 × 159 (issue 16: ≤ 2 ms in Node):
// decoding a drag frame (frame.js) and rebuilding the net R + ρ·d
// (drag-stream.js), against decoding a full geometry frame of the same net,
// the work per frame before the stream. Messages are built here at the
// offsets of protocol/README.md.
//
// Run: node web-client/bench/drag-stream.mjs

import { performance } from 'node:perf_hooks';
import { decodeFrame } from '../src/frame.js';
import { DragStream } from '../src/drag-stream.js';

const NU = 81;
const NV = 159;
const N = NU * NV;
const ICONS = 6;
const ROUNDS = 2000;

function fullFrame(revision) {
  const nku = NU + 4;
  const nkv = NV + 4;
  const pts = 48 + 8 * (nku + nkv);
  const icons = Math.ceil((pts + 12 * N) / 8) * 8;
  const buf = new ArrayBuffer(icons + 24 * ICONS);
  const dv = new DataView(buf);
  [0x56, 0x53, 0x47, 0x46, 1, 2].forEach((b, i) => dv.setUint8(i, b));
  dv.setBigUint64(8, 1n, true);
  dv.setBigUint64(16, 1n, true);
  dv.setBigUint64(24, BigInt(revision), true);
  dv.setUint32(32, NU, true);
  dv.setUint32(36, NV, true);
  dv.setUint8(40, 3);
  dv.setUint8(41, 3);
  dv.setUint32(44, ICONS, true);
  const knots = (n, at) => {
    for (let k = 0; k < n + 4; k++) dv.setFloat64(at + 8 * k, Math.min(Math.max(k - 3, 0), n - 3) / (n - 3), true);
  };
  knots(NU, 48);
  knots(NV, 48 + 8 * nku);
  const p = new Float32Array(buf, pts, 3 * N);
  for (let i = 0; i < NU; i++) for (let j = 0; j < NV; j++) p.set([i / NU, j / NV, 0], 3 * (i * NV + j));
  for (let k = 0; k < ICONS; k++) dv.setBigUint64(icons + 24 * k, BigInt(k + 1), true);
  return buf;
}

function basis() {
  const buf = new ArrayBuffer(48 + 4 * N);
  const dv = new DataView(buf);
  [0x56, 0x53, 0x47, 0x46, 5, 2].forEach((b, i) => dv.setUint8(i, b));
  dv.setBigUint64(8, 1n, true);
  dv.setBigUint64(16, 1n, true);
  dv.setBigUint64(24, 1n, true);
  dv.setBigUint64(32, 1n, true);
  dv.setUint32(40, N, true);
  const rho = new Float32Array(buf, 48, N);
  for (let k = 0; k < N; k++) rho[k] = Math.exp(-k / N);
  return buf;
}

function dragFrame(revision, z) {
  const buf = new ArrayBuffer(72 + 24 * ICONS);
  const dv = new DataView(buf);
  [0x56, 0x53, 0x47, 0x46, 6, 2, 1].forEach((b, i) => dv.setUint8(i, b));
  dv.setBigUint64(8, 1n, true);
  dv.setBigUint64(16, 1n, true);
  dv.setBigUint64(24, BigInt(revision), true);
  dv.setBigUint64(32, 1n, true);
  dv.setFloat64(56, z, true);
  dv.setUint32(64, ICONS, true);
  for (let k = 0; k < ICONS; k++) dv.setBigUint64(72 + 24 * k, BigInt(k + 1), true);
  return buf;
}

const pct = (xs, p) => [...xs].sort((a, b) => a - b)[Math.min(xs.length - 1, Math.ceil((p / 100) * xs.length) - 1)];

const stream = new DragStream();
stream.take(decodeFrame(fullFrame(1)));
stream.take(decodeFrame(basis()));
const drags = Array.from({ length: ROUNDS }, (_, k) => dragFrame(k + 2, 0.001 * k));
const fulls = Array.from({ length: 200 }, (_, k) => fullFrame(k + 2));
const streamMs = [];
for (const b of drags) {
  const t0 = performance.now();
  const f = stream.take(decodeFrame(b));
  streamMs.push(performance.now() - t0);
  if (!f || f.points.length !== 3 * N) throw new Error('a drag frame was not applied');
}
const fullMs = [];
for (const b of fulls) {
  const t0 = performance.now();
  decodeFrame(b);
  fullMs.push(performance.now() - t0);
}
const fmt = (x) => x.toFixed(3);
console.log(`node ${process.version}, ${NU} x ${NV}, ${ICONS} icons`);
console.log(`drag frame (${72 + 24 * ICONS} B): decode + R + rho*d per frame p50 ${fmt(pct(streamMs, 50))} ms, p99 ${fmt(pct(streamMs, 99))} ms over ${ROUNDS}`);
console.log(`full frame (${fulls[0].byteLength} B): decode (zero-copy views) per frame p50 ${fmt(pct(fullMs, 50))} ms, p99 ${fmt(pct(fullMs, 99))} ms`);
