// The section of a Coons body by an axis-aligned cutting plane (x, y or z =
// offset), coloured by the interior distribution det J (paper 002: the
// lattice shapes the interior; det J of the body map is its measure).
//
// How: the body map x(u, v, w) is sampled once on a grid of its parameter
// cube; the plane's section is the level set g = x_axis(u, v, w) − offset = 0
// there. Each grid cell is split into six tetrahedra around its main
// diagonal (a split neighbouring cells agree on, so the section has no
// cracks) and cut by marching tetrahedra; every vertex where an edge of
// the grid crosses the level set is found by a root search along that edge
// in parameter space, so it lies on the plane to rounding and is a true
// point of the body, with det J evaluated there exactly. The outline is
// where the section meets the boundary of the parameter cube: its vertices
// have a parameter at its start or end, so they lie on the body's boundary.
// No DOM, no three.js: tests/body-section.test.mjs checks it.

/** Grid cells per knot span and direction (at least MIN_CELLS, at most MAX_CELLS per direction). */
const CELLS_PER_SPAN = 6;
const MIN_CELLS = 12;
const MAX_CELLS = 48;
/** Root search along an edge: iterations and tolerance (relative to the body's size). */
const ROOT_ITERATIONS = 60;
const ROOT_TOLERANCE = 1e-13;

// The six tetrahedra of a cell, as corners (bit 0: +u, bit 1: +v, bit 2: +w), all through corners 0 and 7.
const TETS = [
  [0, 1, 3, 7],
  [0, 1, 5, 7],
  [0, 2, 3, 7],
  [0, 2, 6, 7],
  [0, 4, 5, 7],
  [0, 4, 6, 7],
];
// A tetrahedron's faces (vertex indices into the tet).
const FACES = [
  [0, 1, 2],
  [0, 1, 3],
  [0, 2, 3],
  [1, 2, 3],
];

/** The body `volume` (body-volume.js) sampled for cutting. */
export class SectionGrid {
  /** `cells`: cells per direction (default from the knot spans). */
  constructor(volume, cells = null) {
    this.volume = volume;
    this.dom = volume.domain();
    const spans = volume.spans();
    this.n = cells || spans.map((s) => Math.min(MAX_CELLS, Math.max(MIN_CELLS, CELLS_PER_SPAN * s)));
    const [a, b, c] = this.n;
    const count = (a + 1) * (b + 1) * (c + 1);
    this.pos = new Float64Array(3 * count);
    this.min = [Infinity, Infinity, Infinity];
    this.max = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i <= a; i++) {
      for (let j = 0; j <= b; j++) {
        for (let k = 0; k <= c; k++) {
          const t = this.param(i, j, k);
          const { p } = volume.eval(t[0], t[1], t[2]);
          const o = 3 * this.node(i, j, k);
          for (let e = 0; e < 3; e++) {
            this.pos[o + e] = p[e];
            this.min[e] = Math.min(this.min[e], p[e]);
            this.max[e] = Math.max(this.max[e], p[e]);
          }
        }
      }
    }
    this.size = Math.hypot(...[0, 1, 2].map((e) => this.max[e] - this.min[e])) || 1;
  }

  node(i, j, k) {
    return (i * (this.n[1] + 1) + j) * (this.n[2] + 1) + k;
  }

  /** The parameters of grid node (i, j, k): the domain's ends exactly at the ends. */
  param(i, j, k) {
    return [i, j, k].map((x, d) => {
      const [lo, hi] = this.dom[d];
      return x === this.n[d] ? hi : lo + ((hi - lo) * x) / this.n[d];
    });
  }

  /** The range of world coordinate `axis` (0 x, 1 y, 2 z) over the sampled body: [min, max]. */
  range(axis) {
    return [this.min[axis], this.max[axis]];
  }

  /**
   * The section by the plane x_axis = offset: { positions (Float32Array x,
   * y, z), params (Float64Array u, v, w), det (Float64Array det J per
   * vertex), triangles (Uint32Array), outline (Uint32Array, pairs of vertex
   * indices: segments on the body's boundary), detMin, detMax }. Empty
   * arrays when the plane misses the body.
   */
  cut(axis, offset) {
    const [A, B, C] = this.n;
    const pos = [];
    const par = [];
    const det = [];
    const tris = [];
    const outline = [];
    const edges = new Map();
    const nodes = (A + 1) * (B + 1) * (C + 1);
    const g = (id) => this.pos[3 * id + axis] - offset;
    const corner = [0, 0, 0, 0, 0, 0, 0, 0];
    const cijk = [];
    for (let q = 0; q < 8; q++) cijk.push([0, 0, 0]);
    const tv = [0, 0, 0, 0];
    const tijk = [null, null, null, null];
    const vertexOn = (a, b) => {
      const key = a < b ? a * nodes + b : b * nodes + a;
      let v = edges.get(key);
      if (v === undefined) {
        v = g(a) < 0 ? this.crossing(a, b, axis, offset, pos, par, det) : this.crossing(b, a, axis, offset, pos, par, det);
        edges.set(key, v);
      }
      return v;
    };
    for (let i = 0; i < A; i++) {
      for (let j = 0; j < B; j++) {
        for (let k = 0; k < C; k++) {
          let lo = Infinity;
          let hi = -Infinity;
          for (let q = 0; q < 8; q++) {
            const ci = i + (q & 1);
            const cj = j + ((q >> 1) & 1);
            const ck = k + ((q >> 2) & 1);
            corner[q] = this.node(ci, cj, ck);
            cijk[q][0] = ci;
            cijk[q][1] = cj;
            cijk[q][2] = ck;
            const x = g(corner[q]);
            lo = Math.min(lo, x);
            hi = Math.max(hi, x);
          }
          if (!(lo < 0 && hi >= 0)) continue;
          const edge = i === 0 || j === 0 || k === 0 || i === A - 1 || j === B - 1 || k === C - 1;
          for (const tet of TETS) {
            for (let q = 0; q < 4; q++) {
              tv[q] = corner[tet[q]];
              tijk[q] = cijk[tet[q]];
            }
            this.cutTet(tv, edge ? tijk : null, g, vertexOn, tris, outline);
          }
        }
      }
    }
    let detMin = Infinity;
    let detMax = -Infinity;
    for (const x of det) {
      detMin = Math.min(detMin, x);
      detMax = Math.max(detMax, x);
    }
    return {
      positions: Float32Array.from(pos),
      params: Float64Array.from(par),
      det: Float64Array.from(det),
      triangles: Uint32Array.from(tris),
      outline: Uint32Array.from(outline),
      detMin: det.length ? detMin : 0,
      detMax: det.length ? detMax : 0,
    };
  }

  /**
   * Marching tetrahedra on one tetrahedron (node ids `v`); with its nodes'
   * grid indices `ijk` (a cell at the grid's boundary), a tet face on the
   * parameter cube's boundary adds its outline segment.
   */
  cutTet(v, ijk, g, vertexOn, tris, outline) {
    const inside = [g(v[0]) < 0, g(v[1]) < 0, g(v[2]) < 0, g(v[3]) < 0];
    const nIn = inside[0] + inside[1] + inside[2] + inside[3];
    if (nIn === 0 || nIn === 4) return;
    // The crossed edges, in an order that walks around the section polygon.
    const ins = [0, 1, 2, 3].filter((x) => inside[x]);
    const outs = [0, 1, 2, 3].filter((x) => !inside[x]);
    if (nIn === 1 || nIn === 3) {
      const [one, rest] = nIn === 1 ? [ins[0], outs] : [outs[0], ins];
      tris.push(...rest.map((x) => vertexOn(v[one], v[x])));
    } else {
      const [a, b] = ins;
      const [c, d] = outs;
      const q = [vertexOn(v[a], v[c]), vertexOn(v[a], v[d]), vertexOn(v[b], v[d]), vertexOn(v[b], v[c])];
      tris.push(q[0], q[1], q[2], q[0], q[2], q[3]);
    }
    if (!ijk) return;
    for (const f of FACES) {
      if (!this.onBoundary(f.map((x) => ijk[x]))) continue;
      const fi = f.filter((x) => inside[x]);
      if (fi.length === 0 || fi.length === 3) continue;
      const fo = f.filter((x) => !inside[x]);
      const [one, rest] = fi.length === 1 ? [fi[0], fo] : [fo[0], fi];
      outline.push(vertexOn(v[one], v[rest[0]]), vertexOn(v[one], v[rest[1]]));
    }
  }

  /** Whether three grid nodes lie on one face of the parameter cube. */
  onBoundary(nodes) {
    for (let d = 0; d < 3; d++) {
      for (const end of [0, this.n[d]]) if (nodes.every((p) => p[d] === end)) return true;
    }
    return false;
  }

  /** The vertex where the grid edge from node `a` (g < 0) to node `b` (g ≥ 0) crosses the plane: a bracketed root search (Illinois) in parameter space. */
  crossing(a, b, axis, offset, pos, par, det) {
    const pa = this.paramOf(a);
    const pb = this.paramOf(b);
    const at = (s) => pa.map((x, d) => (s === 1 ? pb[d] : x + s * (pb[d] - x)));
    let s0 = 0;
    let s1 = 1;
    let g0 = this.pos[3 * a + axis] - offset;
    let g1 = this.pos[3 * b + axis] - offset;
    let s = g0 / (g0 - g1);
    let e = null;
    const tol = ROOT_TOLERANCE * this.size;
    let side = 0;
    for (let it = 0; it < ROOT_ITERATIONS; it++) {
      const t = at(s);
      e = this.volume.eval(t[0], t[1], t[2]);
      const gs = e.p[axis] - offset;
      if (Math.abs(gs) <= tol || s1 - s0 <= 1e-16) break;
      e = null;
      if (gs < 0) {
        s0 = s;
        g0 = gs;
        if (side === -1) g1 /= 2;
        side = -1;
      } else {
        s1 = s;
        g1 = gs;
        if (side === 1) g0 /= 2;
        side = 1;
      }
      s = (s0 * g1 - s1 * g0) / (g1 - g0);
      if (!(s > s0 && s < s1)) s = (s0 + s1) / 2;
    }
    const t = at(s);
    if (!e) e = this.volume.eval(t[0], t[1], t[2]);
    const index = det.length;
    pos.push(e.p[0], e.p[1], e.p[2]);
    par.push(t[0], t[1], t[2]);
    det.push(e.det);
    return index;
  }

  /** The parameters of node id `id`. */
  paramOf(id) {
    const c = this.n[2] + 1;
    const b = this.n[1] + 1;
    return this.param(Math.floor(id / (b * c)), Math.floor(id / c) % b, id % c);
  }
}
