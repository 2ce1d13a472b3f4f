// Benchmark: the cutting plane of a Coons body (src/body-section.js) — sampling
// the volume on its parameter grid (once per body frame) and cutting it
// (once per move of the offset slider) — for a tricubic 5 × 5 × 7 lattice,
// the size of the spool (paper 002, figure 7), warped so det J varies.
// Run with `node bench/body-section.mjs`; prints the mean time of each step
// over timed rounds after warm-up (wall and CPU time), and its share of a
// 60 Hz frame (16.7 ms).

import { BSplineVolume } from '../src/body-volume.js';
import { SectionGrid } from '../src/body-section.js';

const clamped = (p, n) => {
  const k = [];
  for (let i = 0; i <= p; i++) k.push(0);
  for (let i = 1; i < n - p; i++) k.push(i / (n - p));
  for (let i = 0; i <= p; i++) k.push(1);
  return k;
};
const counts = [5, 5, 7];
const knots = counts.map((n) => clamped(3, n));
const points = [];
for (let i = 0; i < counts[0]; i++) {
  for (let j = 0; j < counts[1]; j++) {
    for (let k = 0; k < counts[2]; k++) {
      const [u, v, w] = [i / 4, j / 4, k / 6];
      const r = 1 - 0.5 * Math.sin(Math.PI * w);
      points.push(30 * r * (2 * u - 1), 30 * r * (2 * v - 1), 60 * w - 30);
    }
  }
}
const vol = new BSplineVolume({ degrees: [3, 3, 3], knots, counts, points });

/** Mean wall time and mean CPU time of this process (user + system: less sensitive to other processes on a shared machine) per round. */
function time(label, f, rounds) {
  for (let r = 0; r < 5; r++) f(r);
  const t0 = process.hrtime.bigint();
  const c0 = process.cpuUsage();
  for (let r = 0; r < rounds; r++) f(r);
  const c = process.cpuUsage(c0);
  const ms = Number(process.hrtime.bigint() - t0) / 1e6 / rounds;
  const cpu = (c.user + c.system) / 1000 / rounds;
  console.log(`${label}: wall ${ms.toFixed(2)} ms, CPU ${cpu.toFixed(2)} ms (${((100 * cpu) / (1000 / 60)).toFixed(0)} % of a 60 Hz frame)`);
}

let grid = null;
time('sample the volume (SectionGrid)', () => {
  grid = new SectionGrid(vol);
}, 40);
console.log(`  grid ${grid.n.join(' × ')} cells`);
let sec = null;
time('cut by x = offset', (r) => {
  sec = grid.cut(0, -20 + (40 * (r % 10)) / 10);
}, 200);
console.log(`  last section: ${sec.triangles.length / 3} triangles, det J ${sec.detMin.toPrecision(3)} … ${sec.detMax.toPrecision(3)}`);
