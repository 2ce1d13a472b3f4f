// The vsculpt web client: joins the design named in the page URL
// (?design=ID&token=TOKEN; the token is then moved out of the address bar),
// draws it live, and — for an editor link — lets a
// person create, drag and switch icons, set the material, undo, commit,
// revert and restore versions. A viewer link shows the same, read-only, with
// presence. Exposed as `window.vsculpt` for scripting and tests.

import * as THREE from 'three';
import { TransformControls } from 'three/addons/controls/TransformControls.js';
import { Tessellator } from './bspline.js';
import { TessellationWorker } from './tessellate.js';
import { View } from './view.js';
import { IconLayer } from './icons.js';
import { Link } from './net.js';
import { XRSculpt } from './xr.js';

const params = new URLSearchParams(location.search);
const design = Number(params.get('design') || 1);
// The token arrives in the link (?token= or #token=) and leaves the address
// bar at once: kept for this tab only (sessionStorage, so a reload still
// works), never in history, bookmarks or a referrer.
const fragment = new URLSearchParams(location.hash.slice(1));
const tokenKey = `vsculpt-token-${design}`;
const token = params.get('token') || fragment.get('token') || sessionStorage.getItem(tokenKey) || '';
if (token) sessionStorage.setItem(tokenKey, token);
if (params.has('token') || fragment.has('token')) {
  params.delete('token');
  history.replaceState(null, '', `${location.pathname}?${params}`);
}
const $ = (id) => document.getElementById(id);

const state = {
  access: null,
  surface: null,
  tess: null,
  icons: new Map(),
  versions: [],
  presence: [],
  selected: null,
  create: 'none',
  pending: [],
  revision: 0,
  frames: 0,
  material: null,
  lastError: null,
  toasts: [],
  online: null,
  canUndo: false,
  canRedo: false,
  /** The version being compared with: { version, other (its surface), tess, deviation, max } or null. */
  compare: null,
};

const view = new View($('viewport'));
const icons = new IconLayer(view.model);

function status(kind, text) {
  const el = $('status');
  el.className = `status ${kind}`;
  el.textContent = text;
  if (kind === 'error') state.lastError = text;
  setOnline(kind === 'connected');
  if (!shellDone) {
    $('shell-stage').textContent = kind === 'connected' ? 'receiving the design…' : text;
    $('shell').classList.toggle('failed', kind === 'error');
  }
}

/** The page shell (index.html) stays until the first shaded picture is on screen. */
let shellDone = false;

function shellDesign(info) {
  if (!shellDone && info && info.name) $('shell-title').textContent = info.name;
}

function dismissShell() {
  shellDone = true;
  $('shell').classList.add('done');
  setTimeout(() => $('shell').remove(), 400);
}

/**
 * A transient message over the view (server errors, refused edits): it
 * leaves the connection badge alone and goes after a few seconds or a click.
 * The newest ones are kept in state.toasts for scripts and tests.
 */
function toast(text, kind = 'error') {
  state.toasts.push({ text, kind });
  if (state.toasts.length > 20) state.toasts.shift();
  const el = document.createElement('div');
  el.className = `toast ${kind}`;
  el.setAttribute('role', 'alert');
  el.textContent = text;
  el.addEventListener('click', () => el.remove());
  $('toasts').append(el);
  while ($('toasts').children.length > 4) $('toasts').firstChild.remove();
  setTimeout(() => el.remove(), 6000);
}

/**
 * While the link is down nothing can be edited: every control of the editing
 * panels is disabled and the gizmo let go, so no edit is made that could not
 * be sent. Undo/redo come back as the server last said.
 */
function setOnline(online) {
  if (state.online === online) return;
  state.online = online;
  document.body.classList.toggle('offline', !online);
  for (const el of document.querySelectorAll('#panel .edit input, #panel .edit select, #panel .edit button, #panel [data-restore]')) {
    el.disabled = !online;
  }
  if (online) {
    $('undo').disabled = !state.canUndo;
    $('redo').disabled = !state.canRedo;
  } else if (dragging) {
    dragging = false;
    pendingDrag = null;
  }
  gizmo.enabled = online;
}

function surfaceFromSnapshot(s) {
  return {
    degreeU: s.u.degree,
    degreeV: s.v.degree,
    knotsU: Float64Array.from(s.u.knots),
    knotsV: Float64Array.from(s.v.knots),
    nu: s.nu,
    nv: s.nv,
    points: Float32Array.from(s.points.flat()),
  };
}

/** Most vertices a tessellation may have. */
const VERTEX_BUDGET = 50000;

function density(s) {
  // About 4 vertices per control point along each direction, within a budget
  // of 50 000 vertices (81×159 gets 162×318; BENCHMARKS.md, web client).
  let su = 4 * s.nu;
  let sv = 4 * s.nv;
  const scale = Math.min(1, Math.sqrt(VERTEX_BUDGET / (su * sv)));
  su = Math.max(2 * s.nu, Math.round(su * scale), 8);
  sv = Math.max(2 * s.nv, Math.round(sv * scale), 8);
  return [su, sv];
}

/** Work counted for BENCHMARKS.md (bench/browser-fps.mjs reads it): full redraws, surfaces sent to the worker and shown; when the first picture was drawn (ms since navigation start). */
const perf = { redraws: 0, submitted: 0, shown: 0, workerFailed: null, firstPicture: null };

/** Counts surface changes (frames, snapshots); what the mesh shows is `shownSeq`. */
let surfaceSeq = 0;
let shownSeq = 0;

/** Full redraw: tessellation on the main thread, exact bounds, icons rebuilt. */
function redraw() {
  const s = state.surface;
  if (!s) return;
  perf.redraws++;
  if (!state.tess || !state.tess.fits(s)) state.tess = new Tessellator(s, ...density(s));
  state.tess.fill(s);
  shownSeq = surfaceSeq;
  view.setTessellation(state.tess);
  view.setNet(s);
  icons.size = view.geometry.boundingSphere ? view.geometry.boundingSphere.radius * 0.025 : 0.05;
  icons.update(state.icons, s, state.selected);
  attachGizmo();
  updateCompare();
}

function renderPanels() {
  const editor = state.access === 'editor';
  document.body.classList.toggle('viewer', !editor);
  $('role').textContent = state.access ? `${state.access} · design ${design}` : '';
  $('presence').innerHTML = state.presence
    .map((p) => `<li>${escape(p.name)} <small>${p.access}</small>${p.holding ? ` holds icon ${p.holding}` : ''}</li>`)
    .join('');
  $('history').innerHTML = state.versions
    .slice()
    .reverse()
    .map((v) => `<li><b>v${v.version}</b> ${escape(v.message)} <small>${escape(v.author)} · ${new Date(v.time_ms).toLocaleString()}</small>
      <button data-compare="${v.version}">${state.compare && state.compare.version === v.version ? 'comparing' : 'compare'}</button>
      ${editor ? `<button data-restore="${v.version}"${state.online ? '' : ' disabled'}>restore</button>` : ''}</li>`)
    .join('');
  const sel = state.icons.get(state.selected);
  $('selection').hidden = !sel;
  if (sel) {
    $('sel-title').textContent = `icon ${sel.id} · ${sel.anchor.kind}`;
    $('sel-role').value = sel.role.kind === 'derivative' ? sel.role.which : sel.role.kind;
    $('sel-state').value = sel.state;
    $('sel-sensors').textContent = sel.sensors.join(', ') || 'none';
  }
  if (state.material) {
    $('alpha').value = state.material.alpha11;
    $('beta').value = state.material.beta11;
  }
  for (const fmt of ['igs', 'obj', 'stl', 'gltf']) $(`export-${fmt}`).href = `/api/designs/${design}/export.${fmt}?token=${encodeURIComponent(token)}`;
}

function escape(s) {
  return String(s).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
}

function onMessage(msg) {
  switch (msg.type) {
    case 'welcome':
      state.access = msg.access;
      break;
    case 'snapshot':
      shellDesign(msg.design);
      // The compact join (geometry_first): the points came in the frame before
      // this snapshot, and frames keep them current; only a full snapshot carries them.
      if (msg.surface.points.length) {
        state.surface = surfaceFromSnapshot(msg.surface);
        surfaceSeq++;
      }
      state.icons = new Map(msg.icons.map((i) => [i.id, i]));
      state.versions = msg.versions;
      state.presence = msg.presence;
      state.material = msg.material;
      state.revision = msg.revision;
      setHistory(msg.can_undo, msg.can_redo);
      redraw();
      break;
    case 'icon_created':
    case 'icon_updated':
      state.icons.set(msg.icon.id, msg.icon);
      redraw();
      break;
    case 'icon_deleted':
      state.icons.delete(msg.icon);
      if (state.selected === msg.icon) state.selected = null;
      redraw();
      break;
    case 'material_changed':
      state.material = msg.material;
      break;
    case 'committed':
      state.versions.push(msg.version);
      break;
    case 'versions':
      state.versions = msg.versions;
      break;
    case 'presence':
      state.presence = msg.clients;
      break;
    case 'presence_changed': {
      const i = state.presence.findIndex((p) => p.client === msg.client.client);
      if (i >= 0) state.presence[i] = msg.client;
      else state.presence.push(msg.client);
      break;
    }
    case 'presence_left':
      state.presence = state.presence.filter((p) => p.client !== msg.client);
      break;
    case 'history':
      setHistory(msg.can_undo, msg.can_redo);
      break;
    case 'error':
      state.lastError = `${msg.code}: ${msg.message}`;
      toast(state.lastError);
      break;
    default:
      break;
  }
  renderPanels();
}

function setHistory(canUndo, canRedo) {
  state.canUndo = canUndo;
  state.canRedo = canRedo;
  $('undo').disabled = !canUndo || !state.online;
  $('redo').disabled = !canRedo || !state.online;
}

function onFrame(f) {
  state.frames++;
  state.revision = f.revision;
  state.surface = { degreeU: f.degreeU, degreeV: f.degreeV, knotsU: f.knotsU, knotsV: f.knotsV, nu: f.nu, nv: f.nv, points: f.points };
  surfaceSeq++;
  for (const fi of f.icons) {
    const icon = state.icons.get(fi.id);
    if (icon) icon.xyz = fi.xyz;
  }
  // Coalescing: the render loop tessellates only the newest surface, once per animation frame.
  frameDue = true;
  clearTimeout(settleTimer);
  settleTimer = setTimeout(settle, SETTLE_MS);
}

/** After this long without a frame, a full redraw redraws icons (curves, regions) on the settled surface. */
const SETTLE_MS = 200;
let settleTimer = null;
let frameDue = false;

function settle() {
  if (dragging) settleTimer = setTimeout(settle, SETTLE_MS);
  else redraw();
}


/** The per-frame path: the newest surface to the worker (or filled here when there is none); same layout only. */
function showNewestFrame() {
  const s = state.surface;
  if (!s) return;
  if (!state.tess || !state.tess.fits(s)) {
    redraw();
    return;
  }
  perf.submitted++;
  if (!tessWorker || !tessWorker.submit(surfaceSeq, s, state.tess)) {
    state.tess.fill(s);
    surfaceShown(surfaceSeq, state.tess);
  }
}

/** `tess` now holds surface number `seq`: update the mesh, the net and the handles in place. */
function surfaceShown(seq, tess) {
  if (seq <= shownSeq || tess !== state.tess) return;
  shownSeq = seq;
  perf.shown++;
  view.updateTessellation(tess);
  view.setNet(state.surface);
  if (state.compare) updateCompare();
  icons.move([...state.icons.values()].map((i) => ({ id: i.id, xyz: i.xyz })));
}

// `?worker=0` keeps the same fill on the main thread (compared in bench/browser-fps.mjs).
const tessWorker = params.get('worker') === '0' ? null : new TessellationWorker({
  onFilled: surfaceShown,
  onFailure: (reason) => {
    perf.workerFailed = reason;
    frameDue = true;
  },
});


/** Sends `msg`; when the link is down says so and returns null (nothing is sent, nothing is queued). */
function send(msg) {
  const req = link.send(msg);
  if (req === null) toast(`not connected: ${msg.type.replace(/_/g, ' ')} was not sent`);
  return req;
}

// --- editing ----------------------------------------------------------------

const gizmo = new TransformControls(view.camera, view.renderer.domElement);
view.scene.add(gizmo.getHelper());
const proxy = new THREE.Object3D();
view.model.add(proxy);
let dragging = false;
let pendingDrag = null;

function attachGizmo() {
  const sel = state.icons.get(state.selected);
  if (!sel || state.access !== 'editor' || sel.role.kind === 'derivative') {
    gizmo.detach();
    return;
  }
  if (!dragging) {
    proxy.position.set(...(sel.role.kind === 'position' && sel.anchor.kind === 'point' ? sel.target : sel.xyz));
    gizmo.attach(proxy);
  }
}

// The pointerdown that starts a gizmo drag must not also start an orbit.
// OrbitControls was created first (view.js), so its pointerdown listener on
// the canvas runs before the gizmo's: it began a rotation (state ROTATE, the
// pointer captured, rotateStart at the press) that 'dragging-changed' then
// only froze by disabling the controls, and the controls came back enabled
// with that rotation still live. So decide first, in the capture phase on
// the container: over a gizmo handle, the orbit controls are off before
// they see the press; a press that started no drag turns them back on.
$('viewport').addEventListener('pointerdown', (e) => {
  if (!gizmo.object || !gizmo.enabled || e.button !== 0 || e.target !== view.renderer.domElement) return;
  const rect = view.renderer.domElement.getBoundingClientRect();
  gizmo.pointerHover({ x: ((e.clientX - rect.left) / rect.width) * 2 - 1, y: -((e.clientY - rect.top) / rect.height) * 2 + 1, button: e.button });
  if (gizmo.axis !== null) view.controls.enabled = false;
}, { capture: true });
$('viewport').addEventListener('pointerup', () => {
  if (!gizmo.dragging && !dragging) view.controls.enabled = true;
}, { capture: true });

gizmo.addEventListener('dragging-changed', (e) => {
  view.controls.enabled = !e.value;
  const id = state.selected;
  if (id == null) return;
  if (e.value) {
    dragging = true;
    send({ type: 'drag_start', icon: id });
  } else {
    if (pendingDrag) sendDrag();
    send({ type: 'drag_end', icon: id });
    dragging = false;
  }
});
gizmo.addEventListener('objectChange', () => {
  if (!dragging) return;
  const first = pendingDrag == null;
  pendingDrag = [proxy.position.x, proxy.position.y, proxy.position.z];
  if (first) requestAnimationFrame(sendDrag);
});
function sendDrag() {
  if (!pendingDrag || state.selected == null) return;
  send({ type: 'drag', icon: state.selected, xyz: pendingDrag });
  pendingDrag = null;
}

const raycaster = new THREE.Raycaster();
const pointer = new THREE.Vector2();
let downAt = null;
view.renderer.domElement.addEventListener('pointerdown', (e) => {
  downAt = [e.clientX, e.clientY];
});
view.renderer.domElement.addEventListener('pointerup', (e) => {
  if (!downAt || Math.hypot(e.clientX - downAt[0], e.clientY - downAt[1]) > 4 || dragging || gizmo.dragging) return;
  const rect = view.renderer.domElement.getBoundingClientRect();
  pointer.set(((e.clientX - rect.left) / rect.width) * 2 - 1, -((e.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(pointer, view.camera);
  const hitIcon = raycaster.intersectObjects(icons.handles(), false)[0];
  if (hitIcon) {
    select(hitIcon.object.userData.iconId);
    return;
  }
  const hit = raycaster.intersectObject(view.mesh, false)[0];
  if (hit && hit.uv) pick(hit.uv.x, hit.uv.y);
});

function select(id) {
  state.selected = id;
  redraw();
  renderPanels();
}

const ROLES = {
  position: { kind: 'position' },
  load: { kind: 'load' },
  normal: { kind: 'normal' },
  R: { kind: 'derivative', which: 'R' },
  V: { kind: 'derivative', which: 'V' },
  R2: { kind: 'derivative', which: 'R2' },
  V2: { kind: 'derivative', which: 'V2' },
  RV: { kind: 'derivative', which: 'RV' },
};

/** A click on the surface at (u, v) in the current creation mode. */
function pick(u, v) {
  if (state.access !== 'editor') return;
  const mode = state.create;
  const role = ROLES[$('create-role').value] || ROLES.position;
  if (mode === 'point') {
    createIcon({ kind: 'point', u, v }, role);
  } else if (mode === 'curve') {
    state.pending.push([u, v]);
    $('pending').textContent = `${state.pending.length} curve points (finish to create, Esc cancels)`;
  } else if (mode === 'region') {
    state.pending.push([u, v]);
    $('pending').textContent = 'first corner picked: click the opposite corner (Esc cancels)';
    if (state.pending.length === 2) {
      const [[u0, v0], [u1, v1]] = state.pending;
      state.pending = [];
      $('pending').textContent = '';
      createIcon({ kind: 'region', u0, v0, u1, v1, inside: $('region-inside').checked }, role);
    }
  }
}

function createIcon(anchor, role) {
  return send({ type: 'create_icon', spec: { anchor, role, state: 'passive' } });
}

function finishCurve() {
  const pts = state.pending;
  state.pending = [];
  $('pending').textContent = '';
  if (pts.length < 2) return;
  const degree = Math.min(3, pts.length - 1);
  const n = pts.length;
  const knots = [...Array(degree + 1).fill(0)];
  for (let k = 1; k < n - degree; k++) knots.push(k / (n - degree));
  knots.push(...Array(degree + 1).fill(1));
  createIcon({ kind: 'curve', curve: { knots: { degree, knots }, points: pts } }, ROLES[$('create-role').value] || ROLES.position);
}

// --- panels -------------------------------------------------------------------

function setRange(r) {
  view.setRange(r);
  $('range').value = r;
  $('legend-min').textContent = (-r).toPrecision(2);
  $('legend-max').textContent = r.toPrecision(2);
}

$('mode').addEventListener('change', (e) => {
  const mode = e.target.value;
  view.setMode(mode);
  const analysis = mode === 'mean' || mode === 'gauss';
  $('legend').hidden = !analysis;
  if (analysis && state.tess) {
    // Start from the 95th percentile of |curvature|; the slider spans 100× around it.
    const values = Array.from(mode === 'mean' ? state.tess.mean : state.tess.gauss, Math.abs).sort((a, b) => a - b);
    const p95 = values[Math.floor(values.length * 0.95)] || 1;
    $('range').min = p95 / 10;
    $('range').max = p95 * 10;
    $('range').step = p95 / 100;
    setRange(p95);
  }
});
$('range').addEventListener('input', (e) => setRange(Number(e.target.value)));
$('net').addEventListener('change', (e) => view.showNet(e.target.checked));
$('fit').addEventListener('click', () => view.fit());
$('create').addEventListener('change', (e) => {
  state.create = e.target.value;
  state.pending = [];
});
$('finish-curve').addEventListener('click', finishCurve);
$('sel-role').addEventListener('change', (e) => send({ type: 'set_role', icon: state.selected, role: ROLES[e.target.value] }));
$('sel-state').addEventListener('change', (e) => send({ type: 'set_state', icon: state.selected, state: e.target.value }));
$('sel-delete').addEventListener('click', () => send({ type: 'delete_icon', icon: state.selected }));
$('sel-bind').addEventListener('click', () => {
  const sensor = $('sel-sensor').value.trim();
  if (sensor) send({ type: 'bind_sensor', icon: state.selected, sensor });
});
$('material').addEventListener('submit', (e) => {
  e.preventDefault();
  const a = Number($('alpha').value);
  const b = Number($('beta').value);
  send({ type: 'set_material', material: { alpha11: a, alpha12: 0, alpha22: a, beta11: b, beta12: b, beta22: b } });
});
$('undo').addEventListener('click', () => send({ type: 'undo' }));
$('redo').addEventListener('click', () => send({ type: 'redo' }));
$('revert').addEventListener('click', () => send({ type: 'revert' }));
$('commit').addEventListener('submit', (e) => {
  e.preventDefault();
  if (send({ type: 'commit', message: $('commit-message').value || 'commit' }) !== null) $('commit-message').value = '';
});
$('history').addEventListener('click', (e) => {
  const v = e.target.dataset.restore;
  if (v) send({ type: 'restore_version', version: Number(v) });
  const c = e.target.dataset.compare;
  if (c) compareWith(Number(c)).catch((err) => toast(`compare with v${c}: ${err.message}`));
});
$('compare-stop').addEventListener('click', () => stopCompare());

// --- version compare ------------------------------------------------------------------

/**
 * Compares the shape on screen with committed version `version`: both are
 * evaluated at the same (u, v) samples, each vertex coloured by how far the
 * current surface lies from the version's along its normal, and the version
 * drawn as a faint wireframe. Follows the live shape until stopped. Needs
 * the same parameter domain (a restore to another structure ends it).
 */
async function compareWith(version) {
  const res = await fetch(`/api/designs/${design}/versions/${version}`, { headers: { authorization: `Bearer ${token}` } });
  if (!res.ok) throw new Error(`${res.status} ${(await res.json().catch(() => ({}))).message || ''}`);
  const s = (await res.json()).design.surface;
  const other = {
    degreeU: s.u_degree,
    degreeV: s.v_degree,
    knotsU: Float64Array.from(s.u_knots),
    knotsV: Float64Array.from(s.v_knots),
    nu: s.nu,
    nv: s.nv,
    points: Float64Array.from(s.points.flat()),
  };
  state.compare = { version, other, tess: null };
  updateCompare();
  renderPanels();
}

function stopCompare() {
  state.compare = null;
  view.setDeviation(null);
  $('compare-legend').hidden = true;
  renderPanels();
}

/** Recomputes the deviation of the current tessellation from the compared version. */
function updateCompare() {
  const c = state.compare;
  const t = state.tess;
  if (!c || !t) return;
  const same = (a, b) => Math.abs(a - b) <= 1e-12 * Math.max(1, Math.abs(a));
  const o = c.other;
  const domain = [o.knotsU[o.degreeU], o.knotsU[o.nu], o.knotsV[o.degreeV], o.knotsV[o.nv]];
  const shown = [t.us[0], t.us[t.su - 1], t.vs[0], t.vs[t.sv - 1]];
  if (!domain.every((x, i) => same(x, shown[i]))) {
    toast(`v${c.version} has another parameter domain: it cannot be compared point by point`);
    stopCompare();
    return;
  }
  if (!c.tess || c.tess.su !== t.su || c.tess.sv !== t.sv) {
    c.tess = new Tessellator(c.other, t.su, t.sv);
    c.tess.fill(c.other);
  }
  const n = t.su * t.sv;
  const d = c.deviation && c.deviation.length === n ? c.deviation : new Float32Array(n);
  let max = 0;
  for (let i = 0; i < n; i++) {
    const o = 3 * i;
    const dev =
      (t.positions[o] - c.tess.positions[o]) * t.normals[o] +
      (t.positions[o + 1] - c.tess.positions[o + 1]) * t.normals[o + 1] +
      (t.positions[o + 2] - c.tess.positions[o + 2]) * t.normals[o + 2];
    d[i] = dev;
    max = Math.max(max, Math.abs(dev));
  }
  c.deviation = d;
  c.max = max;
  view.setDeviation(d, max || 1, c.tess);
  $('compare-legend').hidden = false;
  $('compare-text').textContent = `deviation from v${c.version}: up to ${max.toPrecision(3)} (blue below, red above)`;
}

// --- keyboard -----------------------------------------------------------------------

/** Cancels a curve or region being picked, else lets go of the selection. */
function cancel() {
  if (state.pending.length) {
    state.pending = [];
    $('pending').textContent = '';
  } else if (state.selected != null) {
    select(null);
  }
}

/** The shortcuts, as the help overlay lists them: [keys, what, editor only]. */
const SHORTCUTS = [
  ['Ctrl+Z', 'undo', true],
  ['Ctrl+Shift+Z, Ctrl+Y', 'redo', true],
  ['Delete', 'delete the selected icon', true],
  ['Esc', 'cancel the curve or region being picked, else deselect', false],
  ['F', 'frame the selected icon (or the whole design)', false],
  ['?', 'show or hide this help', false],
];

function keyAction(e) {
  const k = e.key;
  const mod = e.ctrlKey || e.metaKey;
  if (mod && !e.shiftKey && k.toLowerCase() === 'z') return 'undo';
  if (mod && ((e.shiftKey && k.toLowerCase() === 'z') || k.toLowerCase() === 'y')) return 'redo';
  if (mod || e.altKey) return null;
  if (k === 'Delete' || k === 'Backspace') return 'delete';
  if (k === 'Escape') return 'cancel';
  if (k === 'f' || k === 'F') return 'frame';
  if (k === '?') return 'help';
  return null;
}

document.addEventListener('keydown', (e) => {
  const t = e.target;
  if (t instanceof HTMLElement && (t.isContentEditable || ['INPUT', 'SELECT', 'TEXTAREA'].includes(t.tagName))) return;
  const action = keyAction(e);
  if (!action) return;
  e.preventDefault();
  const editing = ['undo', 'redo', 'delete'].includes(action);
  if (editing && state.access !== 'editor') {
    toast('view only: this link cannot edit', 'info');
    return;
  }
  if (action === 'undo') send({ type: 'undo' });
  else if (action === 'redo') send({ type: 'redo' });
  else if (action === 'delete' && state.selected != null) send({ type: 'delete_icon', icon: state.selected });
  else if (action === 'cancel') cancel();
  else if (action === 'frame') frameSelection();
  else if (action === 'help') $('help').hidden = !$('help').hidden;
});

/** Centres the view on the selected icon at a close distance, or fits the whole design. */
function frameSelection() {
  const icon = state.icons.get(state.selected);
  if (!icon) {
    view.fit();
    return;
  }
  const at = new THREE.Vector3(...icon.xyz);
  const offset = view.camera.position.clone().sub(view.controls.target);
  const r = view.geometry.boundingSphere ? view.geometry.boundingSphere.radius : offset.length();
  view.controls.target.copy(at);
  view.camera.position.copy(at).add(offset.setLength(r * 0.8));
  view.controls.update();
}

$('help-list').innerHTML = SHORTCUTS.map(([keys, what, edit]) => `<dt>${keys}</dt><dd>${what}${edit ? ' <small>(editor)</small>' : ''}</dd>`).join('');
$('help-open').addEventListener('click', () => ($('help').hidden = false));
$('help').addEventListener('click', (e) => {
  if (e.target === $('help') || e.target.id === 'help-close') $('help').hidden = true;
});
$('panel-toggle').addEventListener('click', () => document.body.classList.toggle('panel-open'));

// --- VR ---------------------------------------------------------------------------

const xr = new XRSculpt({
  view,
  handles: () => icons.handles(),
  iconPosition: (id) => {
    const icon = state.icons.get(id);
    if (!icon) return null;
    return icon.role.kind === 'position' && icon.anchor.kind === 'point' ? icon.target : icon.xyz;
  },
  send,
  create: (u, v) => createIcon({ kind: 'point', u, v }, ROLES[$('create-role').value] || ROLES.position),
  onDragging: (on, id) => {
    dragging = on;
    if (on) select(id);
  },
  canEdit: () => state.access === 'editor',
});

$('enter-vr').addEventListener('click', () => {
  xr.enter().catch((e) => status('error', e.message));
});

// --- the link (last: its first status call reaches everything above) ------------

// Without a token this page is the bare server address: say what to open instead of failing to join.
const link = token
  ? new Link({ design, token, name: params.get('name') || 'browser', onMessage, onFrame, onStatus: status })
  : { send: () => null, open: false };
if (!token) {
  $('shell-title').textContent = 'vsculpt';
  $('shell-stage').innerHTML =
    'This is the vsculpt server. Open the <b>editor</b> or <b>viewer</b> link it printed for a design ' +
    '(it looks like <code>/?design=1&amp;token=…</code>), or ask the designer for one.';
  $('shell').classList.add('failed');
}

// --- loop ------------------------------------------------------------------------

view.renderer.setAnimationLoop(() => {
  if (frameDue) {
    frameDue = false;
    showNewestFrame();
  }
  xr.update();
  view.controls.update();
  view.render();
  if (!shellDone && shownSeq > 0) {
    perf.firstPicture = performance.now();
    dismissShell();
  }
});

window.vsculpt = { state, send, view, icons, pick, select, createIcon, finishCurve, link, xr, perf, toast, compareWith, stopCompare };
