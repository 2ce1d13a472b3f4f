// Tensor-product B-spline volumes in the page (paper 002): the body a body
// frame (kind 4) carries — its lattice, degrees and clamped knots — evaluated
// with its first derivatives, so the page can look inside it without asking
// the server: the Jacobian determinant det J = x_u · (x_v × x_w), the
// interior distribution the cutting plane shows (body-section.js).
//
//   x(u, v, w) = Σ_i Σ_j Σ_k N_i(u) M_j(v) L_k(w) P_ijk,  P stored k fastest:
//   points[(i·nv + j)·nw + k].
//
// The 1-D basis and its derivative are the triangular Cox–de Boor scheme
// (The NURBS Book, A2.2/A2.3). No DOM, no three.js:
// tests/body-section.test.mjs checks it against an evaluator written
// independently in the test.

/** The knot span index s with knots[s] ≤ t < knots[s + 1] (the last non-empty span at the domain's end), p ≤ s < n. */
export function findSpan(knots, p, n, t) {
  if (t >= knots[n]) {
    let s = n - 1;
    while (s > p && knots[s] === knots[s + 1]) s--;
    return s;
  }
  if (t <= knots[p]) {
    let s = p;
    while (s < n - 1 && knots[s] === knots[s + 1]) s++;
    return s;
  }
  let lo = p;
  let hi = n;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (t < knots[mid]) hi = mid;
    else lo = mid;
  }
  return lo;
}

/**
 * The p + 1 non-zero basis functions at `t` in span `s` and their first
 * derivatives, written into `N` and `dN` (length ≥ p + 1). `work` holds
 * scratch of length ≥ 3·(p + 1) + (p + 1)².
 */
export function basisWithDerivative(knots, p, s, t, N, dN, work) {
  // work: left[0..p], right[0..p], then ndu[j][r] (as the book's table, row-major, w = p + 1 wide):
  // basis values of degree j in the upper triangle, knot differences in the lower.
  const w = p + 1;
  const L = 0;
  const R = w;
  const U = 2 * w;
  work[U] = 1;
  for (let j = 1; j <= p; j++) {
    work[L + j] = t - knots[s + 1 - j];
    work[R + j] = knots[s + j] - t;
    let saved = 0;
    for (let r = 0; r < j; r++) {
      const diff = work[R + r + 1] + work[L + j - r];
      work[U + j * w + r] = diff;
      const tmp = work[U + r * w + (j - 1)] / diff;
      work[U + r * w + j] = saved + work[R + r + 1] * tmp;
      saved = work[L + j - r] * tmp;
    }
    work[U + j * w + j] = saved;
  }
  for (let j = 0; j <= p; j++) N[j] = work[U + j * w + p];
  // First derivative: p · (N_{r,p−1} / (t_{r+p} − t_r) − N_{r+1,p−1} / (t_{r+p+1} − t_{r+1})).
  for (let r = 0; r <= p; r++) {
    let d = 0;
    if (r >= 1) d += work[U + (r - 1) * w + (p - 1)] / work[U + p * w + (r - 1)];
    if (r <= p - 1) d -= work[U + r * w + (p - 1)] / work[U + p * w + r];
    dN[r] = p * d;
  }
}

/** A B-spline volume: degrees [p, q, r], knots [ku, kv, kw], counts [nu, nv, nw], points (flat x, y, z, k fastest). */
export class BSplineVolume {
  constructor({ degrees, knots, counts, points }) {
    if (!Array.isArray(degrees) || degrees.length !== 3 || knots.length !== 3 || counts.length !== 3) throw new Error('a volume needs three degrees, knot vectors and counts');
    for (let d = 0; d < 3; d++) {
      const [p, n, k] = [degrees[d], counts[d], knots[d]];
      if (!Number.isInteger(p) || p < 1) throw new Error(`degree ${p} along direction ${d}`);
      if (!Number.isInteger(n) || n < p + 1) throw new Error(`${n} points along direction ${d} for degree ${p}`);
      if (k.length !== n + p + 1) throw new Error(`${k.length} knots along direction ${d}; ${n} points of degree ${p} need ${n + p + 1}`);
      for (let i = 1; i < k.length; i++) if (!(k[i] >= k[i - 1])) throw new Error(`knots along direction ${d} decrease`);
      if (!(k[n] > k[p])) throw new Error(`empty domain along direction ${d}`);
    }
    if (points.length !== 3 * counts[0] * counts[1] * counts[2]) throw new Error('the lattice does not match its counts');
    this.degrees = degrees.slice();
    this.knots = knots.map((k) => Float64Array.from(k));
    this.counts = counts.slice();
    this.points = Float64Array.from(points);
    this.dom = [0, 1, 2].map((d) => [this.knots[d][this.degrees[d]], this.knots[d][this.counts[d]]]);
    this.spanAt = new Int32Array(3);
    const m = Math.max(...degrees) + 1;
    this.b = [0, 1, 2].map(() => ({ N: new Float64Array(m), dN: new Float64Array(m) }));
    this.work = new Float64Array(3 * m + m * m);
  }

  /** The volume a decoded body frame (body-frame.js) carries. */
  static fromFrame(f) {
    return new BSplineVolume({ degrees: f.degrees, knots: f.knots, counts: f.counts, points: f.lattice });
  }

  /** The parameter domain [[u0, u1], [v0, v1], [w0, w1]]. */
  domain() {
    return this.dom.map((r) => r.slice());
  }

  /** Knot spans (non-empty) per direction. */
  spans() {
    return [0, 1, 2].map((d) => {
      const k = this.knots[d];
      let c = 0;
      for (let i = this.degrees[d]; i < this.counts[d]; i++) if (k[i + 1] > k[i]) c++;
      return c;
    });
  }

  /**
   * The point and first derivatives at (u, v, w) (clamped into the domain):
   * { p, du, dv, dw: [x, y, z], det } with det = det J = x_u · (x_v × x_w).
   */
  eval(u, v, w) {
    const dom = this.dom;
    const spans = this.spanAt;
    for (let d = 0; d < 3; d++) {
      const x = Math.min(dom[d][1], Math.max(dom[d][0], d === 0 ? u : d === 1 ? v : w));
      const p = this.degrees[d];
      spans[d] = findSpan(this.knots[d], p, this.counts[d], x);
      basisWithDerivative(this.knots[d], p, spans[d], x, this.b[d].N, this.b[d].dN, this.work);
    }
    const [p, q, r] = this.degrees;
    const [, nv, nw] = this.counts;
    const [bu, bv, bw] = this.b;
    const P = [0, 0, 0];
    const Du = [0, 0, 0];
    const Dv = [0, 0, 0];
    const Dw = [0, 0, 0];
    for (let a = 0; a <= p; a++) {
      const i = spans[0] - p + a;
      for (let b = 0; b <= q; b++) {
        const j = spans[1] - q + b;
        const nm = bu.N[a] * bv.N[b];
        const dnm = bu.dN[a] * bv.N[b];
        const ndm = bu.N[a] * bv.dN[b];
        const pts = this.points;
        for (let c = 0; c <= r; c++) {
          const k = spans[2] - r + c;
          const o = 3 * ((i * nv + j) * nw + k);
          const L = bw.N[c];
          const wP = nm * L;
          const wu = dnm * L;
          const wv = ndm * L;
          const ww = nm * bw.dN[c];
          const x = pts[o];
          const y = pts[o + 1];
          const z = pts[o + 2];
          P[0] += wP * x;
          P[1] += wP * y;
          P[2] += wP * z;
          Du[0] += wu * x;
          Du[1] += wu * y;
          Du[2] += wu * z;
          Dv[0] += wv * x;
          Dv[1] += wv * y;
          Dv[2] += wv * z;
          Dw[0] += ww * x;
          Dw[1] += ww * y;
          Dw[2] += ww * z;
        }
      }
    }
    return { p: P, du: Du, dv: Dv, dw: Dw, det: det3(Du, Dv, Dw) };
  }
}

/** det [a b c] = a · (b × c). */
export function det3(a, b, c) {
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}
