// Curvature of a drawn triangle mesh (a network part's patches as its mesh
// frame gives them: points and unit normals of the patch, triangles): per
// vertex, the shape operator S fitted by least squares to its 1-ring,
// dn ≈ S dp in the vertex's tangent plane (the frame's normals — area
// averages inside, the patch's own on its boundary — are quantised far
// finer than its points, so no second differences of points are taken).
// Sign as in the kernel's fairing: curvature > 0 where the surface bends
// away from its normal (a sphere with outward normals: H = 1/r). From S:
// mean H, Gaussian K, principal k1 ≥ k2; and the variation of any of
// them, |∇f|, by a least-squares gradient over the 1-ring.

/** The measures a colour map shows: name → what it is. */
export const MEASURES = {
  mean: 'mean curvature H',
  gauss: 'Gaussian curvature K',
  kmax: 'larger principal curvature k1',
  kmin: 'smaller principal curvature k2',
  mean_var: 'variation of H, |∇H|',
  gauss_var: 'variation of K, |∇K|',
  kmax_var: 'variation of k1, |∇k1|',
  kmin_var: 'variation of k2, |∇k2|',
};

/** Whether `mode` is one of the measures. */
export function isMeasure(mode) {
  return Object.hasOwn(MEASURES, mode);
}

/** Whether measure `mode` is signed (a curvature) rather than ≥ 0 (a variation). */
export function isSigned(mode) {
  return !mode.endsWith('_var');
}

/** Each vertex's neighbours (sorted, no repeats) from the triangle list. */
function rings(nv, indices) {
  const sets = Array.from({ length: nv }, () => new Set());
  for (let t = 0; t + 2 < indices.length; t += 3) {
    const [a, b, c] = [indices[t], indices[t + 1], indices[t + 2]];
    sets[a].add(b).add(c);
    sets[b].add(a).add(c);
    sets[c].add(a).add(b);
  }
  return sets.map((s) => Int32Array.from(s));
}

/** A unit tangent basis (e1, e2) of unit normal n. */
function tangents(n) {
  const [x, y, z] = n;
  // The axis least parallel to n, crossed with n.
  const a = Math.abs(x) <= Math.abs(y) && Math.abs(x) <= Math.abs(z) ? [1, 0, 0] : Math.abs(y) <= Math.abs(z) ? [0, 1, 0] : [0, 0, 1];
  let e1 = [a[1] * z - a[2] * y, a[2] * x - a[0] * z, a[0] * y - a[1] * x];
  const l = Math.hypot(...e1);
  e1 = e1.map((v) => v / l);
  const e2 = [y * e1[2] - z * e1[1], z * e1[0] - x * e1[2], x * e1[1] - y * e1[0]];
  return [e1, e2];
}

/** The solution of the 3 × 3 system m x = r (m row-major), or null when singular. */
function solve3(m, r) {
  const det = (a) => a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
  const d = det(m);
  const scale = Math.abs(m[0]) + Math.abs(m[4]) + Math.abs(m[8]);
  if (!(Math.abs(d) > 1e-14 * scale * scale * scale)) return null;
  const out = [0, 0, 0];
  for (let k = 0; k < 3; k++) {
    const c = m.slice();
    for (let row = 0; row < 3; row++) c[3 * row + k] = r[row];
    out[k] = det(c) / d;
  }
  return out;
}

/**
 * The curvature of mesh (`positions`, `normals`: Float32Array xyz per
 * vertex; `indices`: triangles) at every vertex: { mean, gauss, kmax, kmin }
 * (Float64Array each; NaN where a vertex has too few neighbours to fit)
 * and `frames` (each vertex's tangent basis and ring, for variations).
 */
export function meshCurvature(positions, normals, indices) {
  const nv = positions.length / 3;
  const ring = rings(nv, indices);
  const mean = new Float64Array(nv);
  const gauss = new Float64Array(nv);
  const kmax = new Float64Array(nv);
  const kmin = new Float64Array(nv);
  const basis = new Array(nv);
  for (let i = 0; i < nv; i++) {
    let n = [normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]];
    const ln = Math.hypot(...n);
    n = n.map((v) => v / ln);
    const [e1, e2] = tangents(n);
    basis[i] = [e1, e2];
    // Normal equations of dn·e = S (dp·e), S = [[s11, s12], [s12, s22]],
    // each neighbour weighted by 1/|dp|² (a difference quotient each).
    const m = [0, 0, 0, 0, 0, 0, 0, 0, 0];
    const r = [0, 0, 0];
    for (const j of ring[i]) {
      const dp = [0, 1, 2].map((k) => positions[3 * j + k] - positions[3 * i + k]);
      const dn = [0, 1, 2].map((k) => normals[3 * j + k] - normals[3 * i + k]);
      const a1 = dp[0] * e1[0] + dp[1] * e1[1] + dp[2] * e1[2];
      const a2 = dp[0] * e2[0] + dp[1] * e2[1] + dp[2] * e2[2];
      const b1 = dn[0] * e1[0] + dn[1] * e1[1] + dn[2] * e1[2];
      const b2 = dn[0] * e2[0] + dn[1] * e2[1] + dn[2] * e2[2];
      const w2 = a1 * a1 + a2 * a2;
      if (!(w2 > 0)) continue;
      const w = 1 / w2;
      // Rows (a1, a2, 0) · x = b1 and (0, a1, a2) · x = b2.
      m[0] += w * a1 * a1;
      m[1] += w * a1 * a2;
      m[4] += w * (a2 * a2 + a1 * a1);
      m[5] += w * a1 * a2;
      m[8] += w * a2 * a2;
      r[0] += w * a1 * b1;
      r[1] += w * (a2 * b1 + a1 * b2);
      r[2] += w * a2 * b2;
    }
    m[3] = m[1];
    m[7] = m[5];
    const s = solve3(m, r);
    if (!s) {
      mean[i] = gauss[i] = kmax[i] = kmin[i] = NaN;
      continue;
    }
    const [s11, s12, s22] = s;
    const h = (s11 + s22) / 2;
    const k = s11 * s22 - s12 * s12;
    const disc = Math.sqrt(Math.max(0, ((s11 - s22) / 2) ** 2 + s12 * s12));
    mean[i] = h;
    gauss[i] = k;
    kmax[i] = h + disc;
    kmin[i] = h - disc;
  }
  return { mean, gauss, kmax, kmin, frames: { basis, ring, positions } };
}

/**
 * The variation |∇f| of per-vertex values `f` over the mesh of `frames`
 * (from meshCurvature): at each vertex the least-squares tangent gradient
 * g of f_j − f_i ≈ g · (p_j − p_i) over its 1-ring (neighbours with a NaN
 * value left out); NaN where it cannot be fitted.
 */
export function variation(f, frames) {
  const { basis, ring, positions } = frames;
  const out = new Float64Array(f.length);
  for (let i = 0; i < f.length; i++) {
    const [e1, e2] = basis[i];
    let [m11, m12, m22, r1, r2] = [0, 0, 0, 0, 0];
    for (const j of ring[i]) {
      const df = f[j] - f[i];
      if (!Number.isFinite(df)) continue;
      const dp = [0, 1, 2].map((k) => positions[3 * j + k] - positions[3 * i + k]);
      const a1 = dp[0] * e1[0] + dp[1] * e1[1] + dp[2] * e1[2];
      const a2 = dp[0] * e2[0] + dp[1] * e2[1] + dp[2] * e2[2];
      const w2 = a1 * a1 + a2 * a2;
      if (!(w2 > 0)) continue;
      const w = 1 / w2;
      m11 += w * a1 * a1;
      m12 += w * a1 * a2;
      m22 += w * a2 * a2;
      r1 += w * a1 * df;
      r2 += w * a2 * df;
    }
    const det = m11 * m22 - m12 * m12;
    if (!(Math.abs(det) > 1e-14 * (m11 + m22) ** 2)) {
      out[i] = NaN;
      continue;
    }
    out[i] = Math.hypot((m22 * r1 - m12 * r2) / det, (m11 * r2 - m12 * r1) / det);
  }
  return out;
}

/** Measure `mode` of curvature `c` (from meshCurvature), variations computed once and kept in `c`. */
export function measureOf(c, mode) {
  if (!isSigned(mode)) {
    const base = mode.slice(0, -4);
    c[mode] ||= variation(c[base], c.frames);
  }
  return c[mode];
}
