// The page's model of a design (protocol version 2): a product of parts —
// each with its id, name, kind (surface or curve), colour, visibility, lock,
// material, icons and shape — and the relations between them (joins,
// bindings). It applies the server's snapshot, events and per-part geometry
// frames (newest revision per part; a frame of one part never touches
// another) and knows which part an icon lives on. No DOM and no three.js:
// tests/design.test.mjs drives it with messages written from the README.

import { FLAG_SNAPSHOT } from './frame.js';

/** The messages that act on an icon and so name its part (README, "Client → server"). */
const ICON_MESSAGES = new Set(['edit_icon', 'move_icon', 'delete_icon', 'set_role', 'set_state', 'bind_sensor', 'unbind_sensor', 'drag_start', 'drag', 'drag_end']);

/**
 * A part's shape as the page draws it, from the JSON `shape` of a snapshot or
 * event: a surface { kind, degreeU, degreeV, knotsU, knotsV, nu, nv, points }
 * or a curve { kind, degree, knots, n, points } (points a flat Float32Array
 * of x, y, z); `points` is null when the JSON carried none (the compact join:
 * frames carry them).
 */
export function geometryFromShape(shape) {
  const flat = (pts) => (pts.length ? Float32Array.from(pts.flat()) : null);
  if (shape.kind === 'surface') {
    const s = shape.surface;
    return {
      kind: 'surface',
      degreeU: s.u.degree,
      degreeV: s.v.degree,
      knotsU: Float64Array.from(s.u.knots),
      knotsV: Float64Array.from(s.v.knots),
      nu: s.nu,
      nv: s.nv,
      points: flat(s.points),
    };
  }
  if (shape.kind === 'curve') {
    const c = shape.curve;
    return {
      kind: 'curve',
      degree: c.knots.degree,
      knots: Float64Array.from(c.knots.knots),
      n: c.knots.knots.length - c.knots.degree - 1,
      points: flat(c.points),
    };
  }
  // A network's curves and patches are drawn by network-view.js (part.network).
  if (shape.kind === 'network') return { kind: 'network', points: null };
  // A DSM part: no control points; the server sends its mesh (dsm-view.js).
  if (shape.kind === 'dsm') return { kind: 'dsm' };
  // A body part (paper 002) is drawn from its body frames by body-view.js.
  if (shape.kind === 'body') return { kind: 'body', points: null };
  throw new Error(`unknown part kind ${shape.kind}`);
}

/** The geometry a decoded frame (frame.js) carries. */
export function geometryFromFrame(f) {
  if (f.kind === 'curve') return { kind: 'curve', degree: f.degree, knots: f.knots, n: f.n, points: f.points };
  return { kind: 'surface', degreeU: f.degreeU, degreeV: f.degreeV, knotsU: f.knotsU, knotsV: f.knotsV, nu: f.nu, nv: f.nv, points: f.points };
}

/** The parameter interval of a curve geometry, or of a surface along u and v: [[a, b], …]. */
export function domainOf(g) {
  if (g.kind === 'curve') return [[g.knots[g.degree], g.knots[g.n]]];
  return [[g.knotsU[g.degreeU], g.knotsU[g.nu]], [g.knotsV[g.degreeV], g.knotsV[g.nv]]];
}

/** How many unknown parts' frames are held after joining. */
const HELD = 64;

/** The colour of a part drawn from its frame before the snapshot names it. */
export const PROVISIONAL_COLOUR = '#b8c4d6';

export class Design {
  constructor() {
    /** Parts by id: { id, name, kind, visible, locked, colour, material, icons: Set of icon ids, geometry, revision }. */
    this.parts = new Map();
    /** Relations by id, as the server sends them ({ id, kind: 'join' | 'binding', … }). */
    this.relations = new Map();
    /** Every icon of the design by id (ids are unique across parts), each with `part`: the part it lives on. */
    this.icons = new Map();
    /** The design's newest revision seen (snapshot or frame). */
    this.revision = 0;
    /** Whether a snapshot arrived (frames of unknown parts after that are held, not drawn, unless they announce a snapshot). */
    this.joined = false;
    /** After joining, the newest frame of each part not known (yet): a part that then arrives without points takes its shape from here. */
    this.held = new Map();
  }

  /** The part of icon `id`, or undefined. */
  partOfIcon(id) {
    const icon = this.icons.get(id);
    return icon ? this.parts.get(icon.part) : undefined;
  }

  /** The icons of part `id`, as a Map id → icon. */
  iconsOf(id) {
    const part = this.parts.get(id);
    const out = new Map();
    if (part) for (const i of part.icons) out.set(i, this.icons.get(i));
    return out;
  }

  /**
   * `msg` with `part` filled in when it acts on an icon and names none (every
   * icon message of version 2 names its part); other messages unchanged.
   */
  addressed(msg) {
    if (!ICON_MESSAGES.has(msg.type) || msg.part !== undefined || msg.icon === undefined) return msg;
    const icon = this.icons.get(msg.icon);
    return icon ? { ...msg, part: icon.part } : msg;
  }

  /** Adds or replaces part `p` (snapshot or part_created JSON); keeps its geometry's points when the JSON has none. */
  putPart(p, revision) {
    const old = this.parts.get(p.id);
    if (old) for (const i of old.icons) this.icons.delete(i);
    const geometry = geometryFromShape(p.shape);
    let rev = revision;
    const held = this.held.get(p.id);
    this.held.delete(p.id);
    const kept = old && old.geometry ? { geometry: old.geometry, revision: old.revision } : held;
    if (!geometry.points && kept && kept.geometry.kind === geometry.kind) {
      Object.assign(geometry, kept.geometry);
      rev = Math.max(kept.revision, revision);
    }
    const part = {
      id: p.id,
      name: p.name,
      kind: p.shape.kind,
      visible: p.visible,
      locked: p.locked,
      colour: p.colour,
      material: p.material,
      dsm: p.shape.kind === 'dsm' ? p.shape.dsm : undefined,
      icons: new Set(),
      geometry: geometry.points ? geometry : null,
      revision: rev,
      provisional: false,
      network: p.shape.kind === 'network' ? p.shape.network : undefined,
    };
    for (const icon of p.icons) {
      part.icons.add(icon.id);
      this.icons.set(icon.id, { ...icon, part: p.id });
    }
    this.parts.set(p.id, part);
    return part;
  }

  /** Drops part `id`, its icons and every relation naming it. */
  dropPart(id) {
    const part = this.parts.get(id);
    if (!part) return false;
    for (const i of part.icons) this.icons.delete(i);
    this.parts.delete(id);
    for (const [rid, r] of this.relations) if (relationParts(r).includes(id)) this.relations.delete(rid);
    return true;
  }

  /** Applies a `snapshot`: the parts and relations become exactly those it names. */
  applySnapshot(msg) {
    this.revision = msg.revision;
    const keep = new Set(msg.parts.map((p) => p.id));
    for (const id of [...this.parts.keys()]) if (!keep.has(id)) this.dropPart(id);
    for (const p of msg.parts) this.putPart(p, msg.revision);
    this.relations = new Map(msg.relations.map((r) => [r.id, r]));
    this.joined = true;
  }

  /**
   * Applies an event (part_*, relation_*, icon_*, material_changed);
   * returns the ids of the parts it changed (empty when it was not one of
   * these or named nothing this page knows).
   */
  applyEvent(msg) {
    switch (msg.type) {
      case 'part_created':
        this.putPart(msg.part, this.revision);
        return [msg.part.id];
      case 'part_deleted':
        return this.dropPart(msg.part) ? [msg.part] : [];
      case 'part_changed': {
        const part = this.parts.get(msg.part);
        if (!part) return [];
        for (const k of ['name', 'visible', 'locked', 'colour']) if (msg[k] !== undefined) part[k] = msg[k];
        return [part.id];
      }
      case 'dsm_changed': {
        const part = this.parts.get(msg.part);
        if (!part || part.kind !== 'dsm') return [];
        part.dsm = msg.dsm;
        return [part.id];
      }
      case 'relation_created':
        this.relations.set(msg.relation.id, msg.relation);
        return relationParts(msg.relation);
      case 'relation_deleted': {
        const r = this.relations.get(msg.relation);
        this.relations.delete(msg.relation);
        return r ? relationParts(r) : [];
      }
      case 'icon_created':
      case 'icon_updated': {
        const part = this.parts.get(msg.part);
        if (!part) return [];
        const old = this.icons.get(msg.icon.id);
        if (old && old.part !== msg.part) {
          const from = this.parts.get(old.part);
          if (from) from.icons.delete(old.id);
        }
        this.icons.set(msg.icon.id, { ...msg.icon, part: msg.part });
        part.icons.add(msg.icon.id);
        return [msg.part];
      }
      case 'icon_deleted': {
        const part = this.parts.get(msg.part);
        const icon = this.icons.get(msg.icon);
        if (!icon) return [];
        this.icons.delete(msg.icon);
        const owner = this.parts.get(icon.part) || part;
        if (owner) owner.icons.delete(msg.icon);
        return [icon.part];
      }
      case 'material_changed': {
        const part = this.parts.get(msg.part);
        if (!part) return [];
        part.material = msg.material;
        return [part.id];
      }
      default:
        return [];
    }
  }

  /**
   * Applies a decoded geometry frame to its part: kept only when it is not
   * older than what the part shows (newest revision per part). A frame of a
   * part not known yet that comes before a snapshot (the compact join: the
   * picture before the snapshot) makes a provisional part — drawn in a
   * neutral colour, no name, no icons — that the snapshot then names or
   * drops. Any other frame of an unknown part is held (newest per part,
   * at most HELD parts) in case the part arrives without points; it is not
   * drawn, since it may be a late frame of a deleted part.
   * Returns true when the part's geometry changed.
   */
  applyFrame(f) {
    this.revision = Math.max(this.revision, f.revision);
    const geometry = geometryFromFrame(f);
    let part = this.parts.get(f.part);
    if (!part) {
      if (this.joined && !(f.flags & FLAG_SNAPSHOT)) {
        const held = this.held.get(f.part);
        if (!held || held.revision <= f.revision) {
          this.held.delete(f.part);
          this.held.set(f.part, { geometry, revision: f.revision });
          if (this.held.size > HELD) this.held.delete(this.held.keys().next().value);
        }
        return false;
      }
      part = { id: f.part, name: `part ${f.part}`, kind: geometry.kind, visible: true, locked: false, colour: PROVISIONAL_COLOUR, material: null, icons: new Set(), geometry: null, revision: 0, provisional: true };
      this.parts.set(f.part, part);
    }
    if (part.kind !== geometry.kind) return false;
    if (part.geometry && f.revision < part.revision && !(f.flags & FLAG_SNAPSHOT)) return false;
    part.geometry = geometry;
    part.revision = f.revision;
    for (const fi of f.icons) {
      const icon = this.icons.get(fi.id);
      if (icon && icon.part === part.id) icon.xyz = fi.xyz;
    }
    return true;
  }
}

/** The part ids a relation names. */
export function relationParts(r) {
  if (r.kind === 'join') return [r.a.part, r.b.part];
  if (r.kind === 'binding') return [r.curve, r.surface];
  if (r.kind === 'ffd') return [r.body, r.part];
  return [];
}
