// Benchmark: re-tessellating the paper's largest surface (81×159 control
// points, bicubic) at the client's vertex budget, as every geometry frame
// does. Run with `npm run bench`; prints the mean time per fill of this
// working tree's Tessellator and, in the same run (interleaved rounds), of
// the Tessellator at a baseline git revision (default: the last commit
// before the fast path; `npm run bench -- <rev>` picks another, `-- none`
// skips it), and their ratio.

import { execFileSync } from 'node:child_process';
import { mkdtempSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { Tessellator } from '../src/bspline.js';

/** The last commit before the separable fast path (issue 5). */
export const BASELINE_REV = 'f6db443';

/** Imports web-client/src/bspline.js as it was at git revision `rev`, or null when git cannot show it. */
export async function baselineModule(rev) {
  if (!rev || rev === 'none') return null;
  const here = dirname(fileURLToPath(import.meta.url));
  let source;
  try {
    source = execFileSync('git', ['show', `${rev}:web-client/src/bspline.js`], { cwd: here, encoding: 'utf8', stdio: ['ignore', 'pipe', 'ignore'] });
  } catch {
    console.warn(`(no baseline: git cannot show ${rev}:web-client/src/bspline.js)`);
    return null;
  }
  const dir = mkdtempSync(join(tmpdir(), 'vsculpt-baseline-'));
  const file = join(dir, 'bspline.mjs');
  writeFileSync(file, source);
  try {
    return await import(pathToFileURL(file).href);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
}

/** The bench surface: 81×159 bicubic, clamped uniform knots, a wavy sheet. */
export function benchSurface(nu = 81, nv = 159, p = 3) {
  const knots = (n) => {
    const k = Array(p + 1).fill(0);
    for (let i = 1; i < n - p; i++) k.push(i / (n - p));
    k.push(...Array(p + 1).fill(1));
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
  return { degreeU: p, degreeV: p, knotsU: knots(nu), knotsV: knots(nv), nu, nv, points };
}

if (import.meta.url === pathToFileURL(process.argv[1]).href) {
  const surface = benchSurface();
  const { nu, nv, points } = surface;
  // The density app.js picks for this net under its 50 000-vertex budget.
  const [su, sv] = [2 * nu, 2 * nv];
  const variants = [['this tree', new Tessellator(surface, su, sv)]];
  const rev = process.argv[2] || BASELINE_REV;
  const old = await baselineModule(rev);
  if (old) variants.push([`baseline ${rev}`, new old.Tessellator(surface, su, sv)]);
  const total = new Map(variants.map(([name]) => [name, 0]));
  const rounds = 5;
  const runs = 20;
  for (const [, t] of variants) for (let i = 0; i < 10; i++) t.fill(surface);
  for (let r = 0; r < rounds; r++) {
    for (const [name, t] of variants) {
      const t0 = performance.now();
      for (let i = 0; i < runs; i++) {
        points[(40 * nv + 80) * 3 + 2] += 0.01;
        t.fill(surface);
      }
      total.set(name, total.get(name) + performance.now() - t0);
    }
  }
  const ms = new Map([...total].map(([name, t]) => [name, t / (rounds * runs)]));
  for (const [name, t] of ms) console.log(`tessellate 81x159 -> ${su}x${sv} vertices (${name}): ${t.toFixed(2)} ms per frame`);
  if (old) console.log(`speed-up: ${(ms.get(`baseline ${rev}`) / ms.get('this tree')).toFixed(2)}x`);
}
