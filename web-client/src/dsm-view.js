// Drawings of DSM parts (paper 001): the server meshes a DSM part's implicit
// surface and sends it as a mesh frame (kind 3, decoded by frame.js); this
// keeps one three.js mesh per DSM part, replaced by each newer frame
// (latest wins), coloured and shown like the part, and remembers the
// newest frame per part (revision, positions, indices) for tools and tests.

import * as THREE from 'three';

export class DsmView {
  /** @param {THREE.Object3D} parent where the drawings hang (the view's model group) */
  constructor(parent) {
    this.group = new THREE.Group();
    this.group.name = 'dsm-parts';
    parent.add(this.group);
    /** By part id: { mesh, frame }. */
    this.drawings = new Map();
  }

  /** Shows mesh frame `f` (from decodeMeshFrame) of `part` unless an equal or newer one is shown. */
  show(f, part) {
    const old = this.drawings.get(f.part);
    if (old && old.frame.revision >= f.revision) return false;
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(f.positions, 3));
    geo.setAttribute('normal', new THREE.BufferAttribute(f.normals, 3));
    geo.setIndex(new THREE.BufferAttribute(f.indices instanceof Uint16Array ? new Uint16Array(f.indices) : new Uint32Array(f.indices), 1));
    geo.computeBoundingBox();
    geo.computeBoundingSphere();
    let mesh = old && old.mesh;
    if (mesh) {
      mesh.geometry.dispose();
      mesh.geometry = geo;
    } else {
      const mat = new THREE.MeshStandardMaterial({ color: 0xc8ccd4, metalness: 0.0, roughness: 0.55, side: THREE.DoubleSide });
      mesh = new THREE.Mesh(geo, mat);
      mesh.name = `dsm-${f.part}`;
      this.group.add(mesh);
    }
    this.drawings.set(f.part, { mesh, frame: f });
    if (part) this.style(part, true);
    return true;
  }

  /** Colour and visibility of part `part`'s drawing. */
  style(part, shown) {
    const d = this.drawings.get(part.id);
    if (!d) return;
    d.mesh.material.color.set(part.colour || '#c8ccd4');
    d.mesh.visible = shown;
  }

  /** Drops drawings of parts `design` no longer has; styles the rest (`shown(id)` says whether a part is drawn here). */
  sync(design, shown) {
    for (const id of [...this.drawings.keys()]) {
      const part = design.parts.get(id);
      if (!part || part.kind !== 'dsm') this.drop(id);
      else this.style(part, shown(id));
    }
  }

  /** Removes part `id`'s drawing. */
  drop(id) {
    const d = this.drawings.get(id);
    if (!d) return;
    this.group.remove(d.mesh);
    d.mesh.geometry.dispose();
    d.mesh.material.dispose();
    this.drawings.delete(id);
  }

  /** The bounds of what is drawn (a THREE.Box3), or null. */
  bounds() {
    let box = null;
    for (const d of this.drawings.values()) {
      if (!d.mesh.visible || !d.mesh.geometry.boundingBox) continue;
      box = box ? box.union(d.mesh.geometry.boundingBox) : d.mesh.geometry.boundingBox.clone();
    }
    return box;
  }

  /** The newest frame of each DSM part: { [part]: { revision, positions: number[], indices: number[] } } (for scripts and tests). */
  frames() {
    const out = {};
    for (const [id, d] of this.drawings) {
      out[id] = { revision: d.frame.revision, positions: Array.from(d.frame.positions), indices: Array.from(d.frame.indices), step: d.frame.step };
    }
    return out;
  }
}
