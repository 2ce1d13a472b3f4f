// Comparing a surface part with a committed version of it: the part's
// control net in the version's document (the REST API's design document),
// whether the two share a parameter domain, and the deviation at each
// tessellation vertex — how far the live surface lies from the version's
// along the live normal, both evaluated at the same (u, v).

/**
 * A surface part's control net in a version as the REST API returns it
 * (`design.parts[].body.surface`, the store's document), in the page's
 * layout ({ degreeU, degreeV, knotsU, knotsV, nu, nv, points }); null when
 * that version has no surface part `partId`.
 */
export function versionSurface(doc, partId) {
  const part = (doc.parts || []).find((p) => p.id === partId);
  const body = part && part.body;
  const s = body && body.kind === 'surface' ? body.surface : null;
  if (!s) return null;
  return {
    degreeU: s.u_degree,
    degreeV: s.v_degree,
    knotsU: Float64Array.from(s.u_knots),
    knotsV: Float64Array.from(s.v_knots),
    nu: s.nu,
    nv: s.nv,
    points: Float64Array.from(s.points.flat()),
  };
}

/** Whether surface `other` has the parameter domain that tessellation `t` samples (to 1e-12 relative). */
export function sameDomain(t, other) {
  const same = (a, b) => Math.abs(a - b) <= 1e-12 * Math.max(1, Math.abs(a));
  const o = other;
  const domain = [o.knotsU[o.degreeU], o.knotsU[o.nu], o.knotsV[o.degreeV], o.knotsV[o.nv]];
  const shown = [t.us[0], t.us[t.su - 1], t.vs[0], t.vs[t.sv - 1]];
  return domain.every((x, i) => same(x, shown[i]));
}

/**
 * The signed deviation of tessellation `t` (the live surface) from `ref`
 * (the version's, same layout) at each vertex, along `t`'s normal, written
 * into `out` (a Float32Array of su·sv, reused when given); returns
 * { deviation, max } with max the largest |deviation|.
 */
export function deviation(t, ref, out) {
  const n = t.su * t.sv;
  const dev = out && out.length === n ? out : new Float32Array(n);
  let max = 0;
  for (let i = 0; i < n; i++) {
    const o = 3 * i;
    const x =
      (t.positions[o] - ref.positions[o]) * t.normals[o] +
      (t.positions[o + 1] - ref.positions[o + 1]) * t.normals[o + 1] +
      (t.positions[o + 2] - ref.positions[o + 2]) * t.normals[o + 2];
    dev[i] = x;
    max = Math.max(max, Math.abs(x));
  }
  return { deviation: dev, max };
}
