// Benchmark: re-tessellating the paper's largest surface (81×159 control
// points, bicubic) at the client's vertex budget, as every drag frame does.
// Run with `npm run bench`; prints the mean time per fill.

import { Tessellator } from '../src/bspline.js';

const nu = 81;
const nv = 159;
const p = 3;
const knots = (n) => {
  const k = [0, 0, 0, 0];
  for (let i = 1; i < n - p; i++) k.push(i / (n - p));
  k.push(1, 1, 1, 1);
  return Float64Array.from(k);
};
const points = new Float32Array(nu * nv * 3);
for (let i = 0; i < nu; i++) {
  for (let j = 0; j < nv; j++) {
    const o = (i * nv + j) * 3;
    points[o] = i;
    points[o + 1] = j;
    points[o + 2] = Math.sin(i / 9) * Math.cos(j / 13) * 5;
  }
}
const surface = { degreeU: p, degreeV: p, knotsU: knots(nu), knotsV: knots(nv), nu, nv, points };
// The density app.js picks for this net under its 50 000-vertex budget.
const tess = new Tessellator(surface, 2 * nu, 2 * nv);
for (let i = 0; i < 10; i++) tess.fill(surface);
const runs = 50;
const t0 = performance.now();
for (let i = 0; i < runs; i++) {
  points[(40 * nv + 80) * 3 + 2] += 0.01;
  tess.fill(surface);
}
const ms = (performance.now() - t0) / runs;
console.log(`tessellate 81x159 -> ${2 * nu}x${2 * nv} vertices: ${ms.toFixed(2)} ms per frame`);
