// Web Worker: tessellates geometry frames of surface parts off the main
// thread. Each request names its part and carries the surface (its control
// points as a transferred copy) and the output buffers to fill (transferred
// to the worker and back, so nothing is allocated per frame); the answer
// returns them filled, with the bounds. One tessellator is kept per part, so
// parts of different layouts do not rebuild each other's tables.

import { Tessellator } from './bspline.js';

const tessellators = new Map();

self.onmessage = (e) => {
  if (e.data.forget !== undefined) {
    tessellators.delete(e.data.forget);
    return;
  }
  const { key, seq, surface, su, sv, out } = e.data;
  let tess = tessellators.get(key);
  if (!tess || tess.su !== su || tess.sv !== sv || !tess.fits(surface)) {
    tess = new Tessellator(surface, su, sv);
    tessellators.set(key, tess);
  }
  tess.positions = new Float32Array(out.positions);
  tess.normals = new Float32Array(out.normals);
  tess.mean = new Float32Array(out.mean);
  tess.gauss = new Float32Array(out.gauss);
  tess.fill(surface);
  const box = Array.from(tess.box);
  self.postMessage({ key, seq, out, box }, [out.positions, out.normals, out.mean, out.gauss]);
};
