// Web Worker: tessellates geometry frames off the main thread. Each request
// carries the surface (its control points as a transferred copy) and the
// output buffers to fill (transferred to the worker and back, so nothing is
// allocated per frame); the answer returns them filled, with the bounds.

import { Tessellator } from './bspline.js';

let tess = null;

self.onmessage = (e) => {
  const { seq, surface, su, sv, out } = e.data;
  if (!tess || tess.su !== su || tess.sv !== sv || !tess.fits(surface)) tess = new Tessellator(surface, su, sv);
  tess.positions = new Float32Array(out.positions);
  tess.normals = new Float32Array(out.normals);
  tess.mean = new Float32Array(out.mean);
  tess.gauss = new Float32Array(out.gauss);
  tess.fill(surface);
  const box = Array.from(tess.box);
  self.postMessage({ seq, out, box }, [out.positions, out.normals, out.mean, out.gauss]);
};
