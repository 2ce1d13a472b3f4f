// Curvature comb of a space curve: a curve icon's c(t) = w(u(t), v(t)) that
// its (u, v) B-spline traces on the surface (curvature along t from the
// chain rule), or a curve part's own B-spline c(t); and the comb's teeth
// (drawn against the curvature vector, length proportional to the
// curvature), as designers read it.

import { curveDerivs, surfaceDerivs } from './bspline.js';

/** The (u, v) curve of a curve anchor as a one-row "surface" so surfaceDerivs evaluates it and its t-derivatives. */
function uvCurve(curve) {
  const { knots, points } = curve;
  return {
    degreeU: knots.degree,
    knotsU: knots.knots,
    nu: points.length,
    degreeV: 1,
    knotsV: [0, 0, 1, 1],
    nv: 2,
    points: points.flatMap((p) => [p[0], p[1], 0, p[0], p[1], 0]),
  };
}

const add = (a, b, s = 1) => [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

/**
 * Samples the curve icon on the surface: for n parameters t, the point,
 * the curvature κ ≥ 0 and the curvature vector (toward the centre of
 * curvature, length κ). `surface` is the client surface record
 * ({degreeU, knotsU, nu, degreeV, knotsV, nv, points}), `curve` the anchor's
 * {knots: {degree, knots}, points: [[u, v, 0], …]}.
 */
export function curvatureSamples(surface, curve, n = 48) {
  const c = uvCurve(curve);
  const k = curve.knots.knots;
  const [a, b] = [k[0], k[k.length - 1]];
  const out = [];
  for (let i = 0; i < n; i++) {
    const t = a + ((b - a) * i) / (n - 1);
    const cd = surfaceDerivs(c, t, 0);
    const [u, v] = cd.p;
    const [u1, v1] = cd.u;
    const [u2, v2] = cd.uu;
    const w = surfaceDerivs(surface, u, v);
    const d1 = add(w.u.map((x) => x * u1), w.v, v1);
    let d2 = add(w.uu.map((x) => x * u1 * u1), w.uv, 2 * u1 * v1);
    d2 = add(add(add(d2, w.vv, v1 * v1), w.u, u2), w.v, v2);
    out.push(sample(w.p, d1, d2));
  }
  return out;
}

/** Point, curvature and curvature vector (c'' − (c''·c̄')c̄') / |c'|² from the first two derivatives. */
function sample(point, d1, d2) {
  const s2 = dot(d1, d1);
  if (!(s2 > 1e-300)) return { point, kappa: 0, vector: [0, 0, 0] };
  const vector = add(d2, d1, -dot(d2, d1) / s2).map((x) => x / s2);
  return { point, kappa: Math.sqrt(dot(vector, vector)), vector };
}

/**
 * Samples a curve part ({ degree, knots, n, points }, frame layout) at n
 * parameters spread over its domain: the point, κ ≥ 0 and the curvature
 * vector, as curvatureSamples does for a curve icon.
 */
export function curvePartSamples(curve, n = 64) {
  const a = curve.knots[curve.degree];
  const b = curve.knots[curve.n];
  const out = [];
  for (let i = 0; i < n; i++) {
    const d = curveDerivs(curve, a + ((b - a) * i) / (n - 1));
    out.push(sample(d.p, d.d1, d.d2));
  }
  return out;
}

/**
 * Line-segment pairs of the comb: from each curve point against its
 * curvature vector, the longest tooth `length` long; plus the comb's
 * outline through the teeth's ends. Returns flat [x, y, z, …] arrays.
 */
export function combSegments(samples, length) {
  const max = Math.max(...samples.map((s) => s.kappa));
  const scale = max > 0 ? length / max : 0;
  const teeth = [];
  const outline = [];
  for (const s of samples) {
    const end = add(s.point, s.vector, -scale);
    teeth.push(...s.point, ...end);
    outline.push(...end);
  }
  return { teeth, outline };
}
