// An evaluator of B-spline volumes written for the tests, independently of
// src/body-volume.js: the basis by the recursive Cox–de Boor definition
// (slow and plain), det J by finite differences of the map, lattices with
// control points at the Greville abscissae, a seeded generator.

/** N_{i,p}(t) by the Cox–de Boor recursion; at the domain's end the last non-empty interval is closed. */
export function basis(knots, i, p, t) {
  if (p === 0) {
    const [a, b] = [knots[i], knots[i + 1]];
    const end = knots[knots.length - 1];
    if (a < b && (t >= a && t < b)) return 1;
    if (a < b && t === end && b === end) return 1;
    return 0;
  }
  let s = 0;
  const d1 = knots[i + p] - knots[i];
  const d2 = knots[i + p + 1] - knots[i + 1];
  if (d1 > 0) s += ((t - knots[i]) / d1) * basis(knots, i, p - 1, t);
  if (d2 > 0) s += ((knots[i + p + 1] - t) / d2) * basis(knots, i + 1, p - 1, t);
  return s;
}

/** x(u, v, w) of lattice `L` ({ degrees, knots, counts, points }) by the definition. */
export function point(L, t) {
  const [nu, nv, nw] = L.counts;
  const B = [0, 1, 2].map((d) => Array.from({ length: L.counts[d] }, (_, i) => basis(L.knots[d], i, L.degrees[d], t[d])));
  const x = [0, 0, 0];
  for (let i = 0; i < nu; i++) {
    for (let j = 0; j < nv; j++) {
      for (let k = 0; k < nw; k++) {
        const w = B[0][i] * B[1][j] * B[2][k];
        if (w === 0) continue;
        for (let e = 0; e < 3; e++) x[e] += w * L.points[3 * ((i * nv + j) * nw + k) + e];
      }
    }
  }
  return x;
}

export function domainOf(L) {
  return [0, 1, 2].map((d) => [L.knots[d][L.degrees[d]], L.knots[d][L.counts[d]]]);
}

/** det J by finite differences of `point` (central inside, second-order one-sided at the domain's ends). */
export function fdDet(L, t, h = 1e-6) {
  const dom = domainOf(L);
  const cols = [0, 1, 2].map((d) => {
    const at = (s) => point(L, t.map((x, e) => (e === d ? x + s : x)));
    if (t[d] - h >= dom[d][0] && t[d] + h <= dom[d][1]) {
      const [a, b] = [at(h), at(-h)];
      return a.map((x, e) => (x - b[e]) / (2 * h));
    }
    const sg = t[d] + 2 * h <= dom[d][1] ? 1 : -1;
    const [f0, f1, f2] = [at(0), at(sg * h), at(2 * sg * h)];
    return f0.map((x, e) => (sg * (-3 * x + 4 * f1[e] - f2[e])) / (2 * h));
  });
  const [a, b, c] = cols;
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/** The Greville abscissae of a knot vector of degree p. */
export function greville(knots, p) {
  const n = knots.length - p - 1;
  return Array.from({ length: n }, (_, i) => {
    let s = 0;
    for (let r = 1; r <= p; r++) s += knots[i + r];
    return s / p;
  });
}

/** A lattice with control point f(g_u, g_v, g_w) at the Greville abscissae (plus `jitter(i, j, k)` if given). */
export function lattice(degrees, knots, f, jitter = null) {
  const g = [0, 1, 2].map((d) => greville(knots[d], degrees[d]));
  const counts = g.map((x) => x.length);
  const points = [];
  for (let i = 0; i < counts[0]; i++) {
    for (let j = 0; j < counts[1]; j++) {
      for (let k = 0; k < counts[2]; k++) {
        const p = f([g[0][i], g[1][j], g[2][k]]);
        const e = jitter ? jitter(i, j, k, counts) : [0, 0, 0];
        points.push(p[0] + e[0], p[1] + e[1], p[2] + e[2]);
      }
    }
  }
  return { degrees, knots, counts, points };
}

/** A small seeded generator (numbers in [0, 1)). */
export function lcg(seed) {
  let s = seed >>> 0;
  return () => {
    s = (Math.imul(s, 1664525) + 1013904223) >>> 0;
    return s / 2 ** 32;
  };
}

