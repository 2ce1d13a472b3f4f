// The page's model of a design (src/design.js) driven by the README's own
// messages: the snapshot of a product of parts, the compact join (frames of
// each part before a snapshot without points), frames applied per part
// (newest revision wins, one part never touches another), part, relation,
// icon and material events with `part`, and icon messages addressed to
// their part.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { Design, domainOf, PROVISIONAL_COLOUR } from '../src/design.js';

const SURFACE = (points) => ({ kind: 'surface', surface: { u: { degree: 1, knots: [0, 0, 1, 1] }, v: { degree: 1, knots: [0, 0, 1, 1] }, nu: 2, nv: 2, points } });
const PLATE = [[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]];
const SIDE = [[1, 0, 0], [1, 1, 0], [2, 0, -0.5], [2, 1, -0.5]];
const MAT = { alpha11: 0.1, alpha12: 0.0, alpha22: 0.1, beta11: 1.0, beta12: 1.0, beta22: 1.0 };

/** The README's snapshot example (three parts, one join), with or without control points. */
function snapshot({ points = true, revision = 12 } = {}) {
  const p = (pts) => (points ? pts : []);
  return {
    type: 'snapshot',
    design: { id: 1, name: 'demo', versions: 1 },
    revision,
    parts: [
      { id: 1, name: 'top shell', visible: true, locked: false, colour: '#c8ccd4', material: MAT,
        icons: [{ id: 3, anchor: { kind: 'point', u: 0.5, v: 0.5 }, role: { kind: 'load' }, state: 'driving', xyz: [0.5, 0.5, 0.0], target: [0.5, 0.5, 0.2], sensors: ['right-hand'], holder: 4 }],
        shape: SURFACE(p(PLATE)) },
      { id: 2, name: 'side', visible: true, locked: true, colour: '#9aa4b8', material: MAT, icons: [], shape: SURFACE(p(SIDE)) },
      { id: 3, name: 'feature line', visible: true, locked: false, colour: '#ff8800', material: { alpha: 0.01, beta: 1.0 },
        icons: [{ id: 7, anchor: { kind: 'param', t: 0.5 }, role: { kind: 'position' }, state: 'passive', xyz: [0.5, 0.5, 0.1], target: [0.5, 0.5, 0.1], sensors: [] }],
        shape: { kind: 'curve', curve: { knots: { degree: 1, knots: [0, 0, 1, 1] }, points: p([[0, 0.5, 0.1], [1, 0.5, 0.1]]) } } },
    ],
    relations: [{ id: 5, kind: 'join', a: { part: 1, edge: 'u_max' }, b: { part: 2, edge: 'u_min' }, continuity: 'g0', reversed: false }],
    versions: [],
    presence: [],
    can_undo: true,
    can_redo: false,
  };
}

/** A decoded frame (the shape frame.js returns) of a bilinear surface part or a linear curve part. */
function surfaceFrame(part, revision, points, { flags = 0, icons = [] } = {}) {
  return { kind: 'surface', part, design: 1, revision, flags, nu: 2, nv: 2, degreeU: 1, degreeV: 1, knotsU: new Float64Array([0, 0, 1, 1]), knotsV: new Float64Array([0, 0, 1, 1]), points: Float32Array.from(points.flat()), icons };
}
function curveFrame(part, revision, points, { flags = 0, icons = [] } = {}) {
  return { kind: 'curve', part, design: 1, revision, flags, n: points.length, degree: 1, knots: new Float64Array([0, 0, 1, 1]), points: Float32Array.from(points.flat()), icons };
}

test('a snapshot with points: every part with its kind, look, material, icons and shape; the join', () => {
  const d = new Design();
  d.applySnapshot(snapshot());
  assert.deepEqual([...d.parts.keys()], [1, 2, 3]);
  const [top, side, line] = [1, 2, 3].map((id) => d.parts.get(id));
  assert.deepEqual([top.kind, side.kind, line.kind], ['surface', 'surface', 'curve']);
  assert.equal(side.locked, true);
  assert.equal(line.colour, '#ff8800');
  assert.deepEqual(line.material, { alpha: 0.01, beta: 1.0 });
  assert.deepEqual(Array.from(side.geometry.points), SIDE.flat());
  assert.deepEqual([line.geometry.degree, line.geometry.n], [1, 2]);
  assert.deepEqual(domainOf(line.geometry), [[0, 1]]);
  assert.equal(d.icons.get(7).part, 3);
  assert.equal(d.partOfIcon(3).name, 'top shell');
  assert.deepEqual([...d.iconsOf(3).keys()], [7]);
  assert.equal(d.relations.get(5).continuity, 'g0');
});

test('the compact join: frames before the snapshot are drawn at once, the snapshot without points names them', () => {
  const d = new Design();
  assert.equal(d.applyFrame(surfaceFrame(1, 12, PLATE, { flags: 2 })), true);
  assert.equal(d.applyFrame(surfaceFrame(2, 12, SIDE, { flags: 2 })), true);
  assert.equal(d.applyFrame(curveFrame(3, 12, [[0, 0.5, 0.1], [1, 0.5, 0.1]], { flags: 2 })), true);
  // Before the snapshot: provisional parts, drawable.
  assert.equal(d.parts.get(2).provisional, true);
  assert.equal(d.parts.get(2).colour, PROVISIONAL_COLOUR);
  assert.deepEqual(Array.from(d.parts.get(2).geometry.points), SIDE.flat());
  d.applySnapshot(snapshot({ points: false }));
  const side = d.parts.get(2);
  assert.equal(side.provisional, false);
  assert.equal(side.name, 'side');
  assert.deepEqual(Array.from(side.geometry.points), SIDE.flat(), 'the frame keeps the shape');
  assert.equal(d.parts.get(3).geometry.kind, 'curve');
  assert.equal(d.icons.get(3).part, 1);
});

test('a snapshot drops parts it does not name; a provisional part it does not name goes too', () => {
  const d = new Design();
  d.applyFrame(surfaceFrame(9, 3, PLATE, { flags: 2 }));
  d.applySnapshot(snapshot());
  assert.equal(d.parts.has(9), false);
  const s = snapshot();
  s.parts = s.parts.filter((p) => p.id !== 3);
  d.applySnapshot(s);
  assert.deepEqual([...d.parts.keys()], [1, 2]);
  assert.equal(d.icons.has(7), false, 'the dropped part took its icon along');
});

test('frames per part: newest revision wins, a frame of one part never changes another, icons move on their own part only', () => {
  const d = new Design();
  d.applySnapshot(snapshot());
  const raised = PLATE.map(([x, y, z]) => [x, y, z + 1]);
  assert.equal(d.applyFrame(surfaceFrame(1, 14, raised, { flags: 1, icons: [{ id: 3, xyz: [0.5, 0.5, 1] }] })), true);
  assert.deepEqual(Array.from(d.parts.get(1).geometry.points), raised.flat());
  assert.deepEqual(Array.from(d.parts.get(2).geometry.points), SIDE.flat(), 'part 2 untouched');
  assert.deepEqual(d.icons.get(3).xyz, [0.5, 0.5, 1]);
  // An older frame of part 1 (it was overtaken) is ignored; part 2's own older revision still applies once.
  assert.equal(d.applyFrame(surfaceFrame(1, 13, PLATE)), false);
  assert.deepEqual(Array.from(d.parts.get(1).geometry.points), raised.flat());
  assert.equal(d.applyFrame(surfaceFrame(2, 13, SIDE.map(([x, y, z]) => [x, y, z - 1]))), true);
  assert.equal(d.parts.get(2).revision, 13);
  // A frame naming part 1's icon on part 2 moves nothing; a frame of the wrong kind is refused.
  d.applyFrame(surfaceFrame(2, 15, SIDE, { icons: [{ id: 3, xyz: [9, 9, 9] }] }));
  assert.deepEqual(d.icons.get(3).xyz, [0.5, 0.5, 1]);
  assert.equal(d.applyFrame(curveFrame(1, 16, [[0, 0, 0], [1, 1, 1]])), false);
  assert.equal(d.parts.get(1).geometry.kind, 'surface');
  // After the snapshot, a frame of an unknown part is not drawn (it may be a late frame of a deleted part)…
  assert.equal(d.applyFrame(surfaceFrame(44, 20, PLATE)), false);
  assert.equal(d.parts.has(44), false);
  // …but a part that then arrives without points (a restore, a snapshot without points) takes its shape.
  d.applyEvent({ type: 'part_created', part: { id: 44, name: 'lid', visible: true, locked: false, colour: '#88aa66', material: MAT, icons: [], shape: SURFACE([]) } });
  assert.deepEqual(Array.from(d.parts.get(44).geometry.points), PLATE.flat());
  assert.equal(d.parts.get(44).revision, 20);
});

test('part events: created, changed (every field), deleted with its icons and relations', () => {
  const d = new Design();
  d.applySnapshot(snapshot());
  d.applyEvent({ type: 'part_created', part: { id: 4, name: 'lid', visible: true, locked: false, colour: '#88aa66', material: MAT, icons: [], shape: SURFACE(PLATE) } });
  assert.equal(d.parts.get(4).name, 'lid');
  assert.equal(d.parts.get(4).geometry.nu, 2);
  assert.deepEqual(d.applyEvent({ type: 'part_changed', part: 2, name: 'left side', visible: false, locked: true, colour: '#3366cc' }), [2]);
  const side = d.parts.get(2);
  assert.deepEqual([side.name, side.visible, side.locked, side.colour], ['left side', false, true, '#3366cc']);
  assert.deepEqual(d.applyEvent({ type: 'part_deleted', part: 1 }), [1]);
  assert.equal(d.parts.has(1), false);
  assert.equal(d.icons.has(3), false);
  assert.equal(d.relations.has(5), false, 'the join named the deleted part');
  assert.deepEqual(d.applyEvent({ type: 'part_deleted', part: 1 }), [], 'twice changes nothing');
});

test('relation events: a join and a binding come and go', () => {
  const d = new Design();
  d.applySnapshot(snapshot());
  d.applyEvent({ type: 'relation_created', relation: { id: 6, kind: 'binding', curve: 3, surface: 1, line: { u: 0.25 }, reversed: true } });
  assert.deepEqual(d.applyEvent({ type: 'relation_deleted', relation: 5 }), [1, 2]);
  assert.deepEqual([...d.relations.keys()], [6]);
});

test('icon and material events act on the part they name', () => {
  const d = new Design();
  d.applySnapshot(snapshot());
  const icon = { id: 8, anchor: { kind: 'span', t0: 0.2, t1: 0.4 }, role: { kind: 'load' }, state: 'passive', xyz: [0.3, 0.5, 0.1], target: [0.3, 0.5, 0.1], sensors: [] };
  assert.deepEqual(d.applyEvent({ type: 'icon_created', part: 3, icon }), [3]);
  assert.deepEqual([...d.parts.get(3).icons].sort(), [7, 8]);
  assert.equal(d.icons.get(8).part, 3);
  d.applyEvent({ type: 'icon_updated', part: 3, icon: { ...icon, state: 'sleeping' } });
  assert.equal(d.icons.get(8).state, 'sleeping');
  assert.deepEqual(d.applyEvent({ type: 'icon_deleted', part: 3, icon: 7 }), [3]);
  assert.deepEqual([...d.parts.get(3).icons], [8]);
  assert.deepEqual(d.applyEvent({ type: 'icon_created', part: 99, icon: { ...icon, id: 30 } }), [], 'an unknown part');
  assert.equal(d.icons.has(30), false);
  d.applyEvent({ type: 'material_changed', part: 3, material: { alpha: 0.01, beta: 2.0 } });
  assert.deepEqual(d.parts.get(3).material, { alpha: 0.01, beta: 2.0 });
  assert.deepEqual(d.parts.get(1).material, MAT);
});

test('icon messages are addressed to the icon\'s part; others and explicit parts are left alone', () => {
  const d = new Design();
  d.applySnapshot(snapshot());
  assert.deepEqual(d.addressed({ type: 'drag', icon: 7, xyz: [1, 2, 3] }), { type: 'drag', icon: 7, xyz: [1, 2, 3], part: 3 });
  for (const type of ['drag_start', 'drag_end', 'set_role', 'set_state', 'delete_icon', 'bind_sensor', 'edit_icon', 'move_icon', 'unbind_sensor']) {
    assert.equal(d.addressed({ type, icon: 3 }).part, 1, type);
  }
  assert.equal(d.addressed({ type: 'drag', icon: 3, part: 2 }).part, 2, 'an explicit part stays (the server judges it)');
  assert.deepEqual(d.addressed({ type: 'undo' }), { type: 'undo' });
  assert.equal(d.addressed({ type: 'delete_icon', icon: 999 }).part, undefined, 'an unknown icon: the server answers unknown_icon');
});
