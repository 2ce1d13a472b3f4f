// B-spline surface and curve evaluation and surface tessellation in the
// browser, from the control nets and knots the server sends (the kernel's evaluation is the
// reference; tests/bspline.test.mjs checks the identities). Curvature sign
// convention as in the kernel: n = w_u × w_v normalised, a curvature is
// positive where the surface bends toward n.

/** Index of the knot span holding t (clamped into the domain). */
export function findSpan(knots, degree, t) {
  const n = knots.length - degree - 1;
  const a = knots[degree];
  const b = knots[n];
  if (!(t >= a)) t = a;
  if (t >= b) {
    let s = n - 1;
    while (s > degree && knots[s] === knots[s + 1]) s--;
    return s;
  }
  let lo = degree;
  let hi = n;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (knots[mid] <= t) lo = mid;
    else hi = mid;
  }
  return lo;
}

/**
 * Values and derivatives up to order 2 of the degree+1 non-zero basis
 * functions at t: returns { first, d: [N, N', N''] } (Piegl & Tiller A2.3).
 */
export function basisDerivs(knots, degree, t) {
  const p = degree;
  const span = findSpan(knots, p, t);
  const a0 = knots[p];
  const b0 = knots[knots.length - p - 1];
  t = Math.min(Math.max(t, a0), b0);
  const ndu = Array.from({ length: p + 1 }, () => new Float64Array(p + 1));
  const left = new Float64Array(p + 1);
  const right = new Float64Array(p + 1);
  ndu[0][0] = 1;
  for (let j = 1; j <= p; j++) {
    left[j] = t - knots[span + 1 - j];
    right[j] = knots[span + j] - t;
    let saved = 0;
    for (let r = 0; r < j; r++) {
      ndu[j][r] = right[r + 1] + left[j - r];
      const temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  const d = [new Float64Array(p + 1), new Float64Array(p + 1), new Float64Array(p + 1)];
  for (let j = 0; j <= p; j++) d[0][j] = ndu[j][p];
  const nd = Math.min(2, p);
  for (let r = 0; r <= p; r++) {
    let s1 = 0;
    let s2 = 1;
    const a = [new Float64Array(p + 1), new Float64Array(p + 1)];
    a[0][0] = 1;
    for (let k = 1; k <= nd; k++) {
      let dk = 0;
      const rk = r - k;
      const pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
        dk = a[s2][0] * ndu[rk][pk];
      }
      const j1 = rk >= -1 ? 1 : -rk;
      const j2 = r - 1 <= pk ? k - 1 : p - r;
      for (let j = j1; j <= j2; j++) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
        dk += a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
        dk += a[s2][k] * ndu[r][pk];
      }
      d[k][r] = dk;
      const tmp = s1;
      s1 = s2;
      s2 = tmp;
    }
  }
  let f = p;
  for (let k = 1; k <= nd; k++) {
    for (let j = 0; j <= p; j++) d[k][j] *= f;
    f *= p - k;
  }
  return { first: span - p, d };
}

/**
 * A surface as the frame carries it: { degreeU, degreeV, knotsU, knotsV,
 * nu, nv, points } with points a flat array of nu·nv·3 (row-major i·nv + j).
 * Returns w and its derivatives at (u, v) as arrays [x, y, z].
 */
export function surfaceDerivs(s, u, v) {
  const bu = basisDerivs(s.knotsU, s.degreeU, u);
  const bv = basisDerivs(s.knotsV, s.degreeV, v);
  const out = { p: [0, 0, 0], u: [0, 0, 0], v: [0, 0, 0], uu: [0, 0, 0], uv: [0, 0, 0], vv: [0, 0, 0] };
  for (let a = 0; a <= s.degreeU; a++) {
    const row = (bu.first + a) * s.nv + bv.first;
    const c = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
    for (let b = 0; b <= s.degreeV; b++) {
      const k = (row + b) * 3;
      for (let dv = 0; dv < 3; dv++) {
        const w = bv.d[dv][b];
        c[dv][0] += w * s.points[k];
        c[dv][1] += w * s.points[k + 1];
        c[dv][2] += w * s.points[k + 2];
      }
    }
    for (let x = 0; x < 3; x++) {
      out.p[x] += bu.d[0][a] * c[0][x];
      out.u[x] += bu.d[1][a] * c[0][x];
      out.v[x] += bu.d[0][a] * c[1][x];
      out.uu[x] += bu.d[2][a] * c[0][x];
      out.uv[x] += bu.d[1][a] * c[1][x];
      out.vv[x] += bu.d[0][a] * c[2][x];
    }
  }
  return out;
}

/**
 * A curve as the frame carries it: { degree, knots, n, points } with points
 * a flat array of n·3. Returns c(t), c'(t) and c''(t) as arrays [x, y, z].
 */
export function curveDerivs(c, t) {
  const b = basisDerivs(c.knots, c.degree, t);
  const out = { p: [0, 0, 0], d1: [0, 0, 0], d2: [0, 0, 0] };
  for (let a = 0; a <= c.degree; a++) {
    const k = (b.first + a) * 3;
    for (let x = 0; x < 3; x++) {
      out.p[x] += b.d[0][a] * c.points[k + x];
      out.d1[x] += b.d[1][a] * c.points[k + x];
      out.d2[x] += b.d[2][a] * c.points[k + x];
    }
  }
  return out;
}

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

/** Unit normal, mean and Gaussian curvature from derivatives (null if degenerate). */
export function curvature(d) {
  const E = dot(d.u, d.u);
  const F = dot(d.u, d.v);
  const G = dot(d.v, d.v);
  const det = E * G - F * F;
  if (!(det > 1e-24 * Math.max(E * G, 1e-300))) return null;
  const c = cross(d.u, d.v);
  const len = Math.hypot(c[0], c[1], c[2]);
  const n = [c[0] / len, c[1] / len, c[2] / len];
  const L = dot(d.uu, n);
  const M = dot(d.uv, n);
  const N = dot(d.vv, n);
  return { normal: n, gauss: (L * N - M * M) / det, mean: (E * N - 2 * F * M + G * L) / (2 * det) };
}

function uniform(a, b, n) {
  const out = new Float64Array(n);
  for (let k = 0; k < n; k++) out[k] = a + ((b - a) * k) / (n - 1);
  return out;
}

/**
 * Basis table of one direction: for sample k, the index of its first
 * non-zero basis function (`first`, integers so the hot loops index with
 * integer arithmetic) and N, N', N'' of the degree+1 non-zero functions at
 * w[(3k + d)(p + 1) + j].
 */
function basisTable(knots, p, ts) {
  const q = p + 1;
  const first = new Int32Array(ts.length);
  const w = new Float64Array(ts.length * 3 * q);
  ts.forEach((t, k) => {
    const b = basisDerivs(knots, p, t);
    first[k] = b.first;
    for (let d = 0; d < 3; d++) w.set(b.d[d], (3 * k + d) * q);
  });
  return { first, w };
}

const sameKnots = (a, b) => a.length === b.length && a.every((x, i) => x === b[i]);

/**
 * The fast path of the client's per-frame work: basis tables precomputed
 * for one knot layout and sample density; `fill` refills its typed arrays
 * in place (positions, normals, mean, gauss), so a geometry frame costs two
 * separable passes and no allocation:
 *
 * 1. contract the control net with the v-basis (value, d/dv, d²/dv²) for
 *    every control row and v sample: nu·sv·(pv+1)·9 multiply-adds;
 * 2. contract those rows with the u-basis for every vertex, giving w, w_u,
 *    w_v, w_uu, w_uv, w_vv, then the unit normal and the mean and Gaussian
 *    curvature: su·sv·(pu+1)·18 multiply-adds.
 *
 * Outputs are Float32Array (GPU attributes) unless `{ float64: true }`,
 * which the tests use to compare with `surfaceDerivs` to 1e-12.
 */
export class Tessellator {
  constructor(s, samplesU, samplesV, { float64 = false } = {}) {
    this.degreeU = s.degreeU;
    this.degreeV = s.degreeV;
    this.knotsU = Float64Array.from(s.knotsU);
    this.knotsV = Float64Array.from(s.knotsV);
    this.nu = s.nu;
    this.nv = s.nv;
    this.su = samplesU;
    this.sv = samplesV;
    this.us = uniform(s.knotsU[s.degreeU], s.knotsU[s.knotsU.length - s.degreeU - 1], samplesU);
    this.vs = uniform(s.knotsV[s.degreeV], s.knotsV[s.knotsV.length - s.degreeV - 1], samplesV);
    this.tableU = basisTable(s.knotsU, s.degreeU, this.us);
    this.tableV = basisTable(s.knotsV, s.degreeV, this.vs);
    const n = samplesU * samplesV;
    const Out = float64 ? Float64Array : Float32Array;
    this.positions = new Out(n * 3);
    this.normals = new Out(n * 3);
    this.mean = new Out(n);
    this.gauss = new Out(n);
    /** Per vertex (u, v): fixed for the layout, so written once here. */
    this.uvs = new Float32Array(n * 2);
    for (let a = 0; a < samplesU; a++) {
      for (let b = 0; b < samplesV; b++) {
        this.uvs[(a * samplesV + b) * 2] = this.us[a];
        this.uvs[(a * samplesV + b) * 2 + 1] = this.vs[b];
      }
    }
    /** Axis-aligned bounds of the last fill: min x, y, z, max x, y, z. */
    this.box = new Float64Array(6);
    this.rows = new Float64Array(s.nu * samplesV * 9);
    const idx = n > 65535 ? new Uint32Array((samplesU - 1) * (samplesV - 1) * 6) : new Uint16Array((samplesU - 1) * (samplesV - 1) * 6);
    let o = 0;
    for (let a = 0; a < samplesU - 1; a++) {
      for (let b = 0; b < samplesV - 1; b++) {
        const i0 = a * samplesV + b;
        const i1 = (a + 1) * samplesV + b;
        idx[o++] = i0; idx[o++] = i1; idx[o++] = i1 + 1;
        idx[o++] = i0; idx[o++] = i1 + 1; idx[o++] = i0 + 1;
      }
    }
    this.indices = idx;
  }

  /** Whether surface `s` has this tessellator's degrees, knots and net size. */
  fits(s) {
    return s.degreeU === this.degreeU && s.degreeV === this.degreeV && s.nu === this.nu && s.nv === this.nv &&
      sameKnots(s.knotsU, this.knotsU) && sameKnots(s.knotsV, this.knotsV);
  }

  fill(s) {
    const { su, sv, rows } = this;
    const P = s.points;
    const nv = s.nv;
    const qu = s.degreeU + 1;
    const qv = s.degreeV + 1;
    const fu = this.tableU.first, wu = this.tableU.w;
    const fv = this.tableV.first, wv = this.tableV.w;
    // Pass 1: for every control row i and v sample b, the v-direction sums
    // (value, d/dv, d²/dv²) of the row's points.
    for (let i = 0; i < s.nu; i++) {
      for (let b = 0; b < sv; b++) {
        const o0 = (i * nv + fv[b]) * 3;
        const t = 3 * b * qv;
        let x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0, x2 = 0, y2 = 0, z2 = 0;
        for (let k = 0; k < qv; k++) {
          const o = o0 + 3 * k;
          const px = P[o], py = P[o + 1], pz = P[o + 2];
          const w0 = wv[t + k], w1 = wv[t + qv + k], w2 = wv[t + 2 * qv + k];
          x0 += w0 * px; y0 += w0 * py; z0 += w0 * pz;
          x1 += w1 * px; y1 += w1 * py; z1 += w1 * pz;
          x2 += w2 * px; y2 += w2 * py; z2 += w2 * pz;
        }
        const r = (i * sv + b) * 9;
        rows[r] = x0; rows[r + 1] = y0; rows[r + 2] = z0;
        rows[r + 3] = x1; rows[r + 4] = y1; rows[r + 5] = z1;
        rows[r + 6] = x2; rows[r + 7] = y2; rows[r + 8] = z2;
      }
    }
    // Pass 2: combine along u; derivatives, normal and curvature per vertex.
    const pos = this.positions, nor = this.normals, mean = this.mean, gauss = this.gauss;
    let minX = Infinity, minY = Infinity, minZ = Infinity, maxX = -Infinity, maxY = -Infinity, maxZ = -Infinity;
    const rowStride = sv * 9;
    for (let a = 0; a < su; a++) {
      const t = 3 * a * qu;
      const r0 = fu[a] * rowStride;
      for (let b = 0; b < sv; b++) {
        let px = 0, py = 0, pz = 0, ux = 0, uy = 0, uz = 0, vx = 0, vy = 0, vz = 0;
        let uux = 0, uuy = 0, uuz = 0, uvx = 0, uvy = 0, uvz = 0, vvx = 0, vvy = 0, vvz = 0;
        let r = r0 + b * 9;
        for (let k = 0; k < qu; k++, r += rowStride) {
          const n0 = wu[t + k], n1 = wu[t + qu + k], n2 = wu[t + 2 * qu + k];
          const c0x = rows[r], c0y = rows[r + 1], c0z = rows[r + 2];
          const c1x = rows[r + 3], c1y = rows[r + 4], c1z = rows[r + 5];
          const c2x = rows[r + 6], c2y = rows[r + 7], c2z = rows[r + 8];
          px += n0 * c0x; py += n0 * c0y; pz += n0 * c0z;
          ux += n1 * c0x; uy += n1 * c0y; uz += n1 * c0z;
          vx += n0 * c1x; vy += n0 * c1y; vz += n0 * c1z;
          uux += n2 * c0x; uuy += n2 * c0y; uuz += n2 * c0z;
          uvx += n1 * c1x; uvy += n1 * c1y; uvz += n1 * c1z;
          vvx += n0 * c2x; vvy += n0 * c2y; vvz += n0 * c2z;
        }
        const idx = a * sv + b;
        const i3 = idx * 3;
        pos[i3] = px; pos[i3 + 1] = py; pos[i3 + 2] = pz;
        if (px < minX) minX = px;
        if (px > maxX) maxX = px;
        if (py < minY) minY = py;
        if (py > maxY) maxY = py;
        if (pz < minZ) minZ = pz;
        if (pz > maxZ) maxZ = pz;
        const E = ux * ux + uy * uy + uz * uz;
        const F = ux * vx + uy * vy + uz * vz;
        const G = vx * vx + vy * vy + vz * vz;
        const det = E * G - F * F;
        if (det > 1e-24 * Math.max(E * G, 1e-300)) {
          let nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
          const len = Math.sqrt(nx * nx + ny * ny + nz * nz);
          nx /= len; ny /= len; nz /= len;
          const L = uux * nx + uuy * ny + uuz * nz;
          const M = uvx * nx + uvy * ny + uvz * nz;
          const N = vvx * nx + vvy * ny + vvz * nz;
          nor[i3] = nx; nor[i3 + 1] = ny; nor[i3 + 2] = nz;
          mean[idx] = (E * N - 2 * F * M + G * L) / (2 * det);
          gauss[idx] = (L * N - M * M) / det;
        } else {
          nor[i3] = 0; nor[i3 + 1] = 0; nor[i3 + 2] = 1;
          mean[idx] = 0;
          gauss[idx] = 0;
        }
      }
    }
    const box = this.box;
    box[0] = minX; box[1] = minY; box[2] = minZ; box[3] = maxX; box[4] = maxY; box[5] = maxZ;
  }
}
