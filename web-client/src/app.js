// The vsculpt web client: joins the design named in the page URL
// (?design=ID&token=TOKEN; the token is then moved out of the address bar),
// draws its parts live, and — for an editor link — lets a person select a
// part (in the parts panel or the view), create, drag and switch icons on
// it, show, hide, lock, rename, recolour, add, delete and join parts, set a
// part's material, undo, commit, revert and restore versions. A viewer link
// shows the same, read-only (it may hide parts on its own page), with
// presence. Exposed as `window.vsculpt` for scripting and tests.

import * as THREE from 'three';
import { TransformControls } from 'three/addons/controls/TransformControls.js';
import { Tessellator } from './bspline.js';
import { TessellationWorker } from './tessellate.js';
import { View } from './view.js';
import { IconLayer } from './icons.js';
import { Link } from './net.js';
import { KIND_SURFACE } from './frame.js';
import { GeometryCache } from './geometry-cache.js';
import { XRSculpt } from './xr.js';
import { Design, domainOf, relationParts } from './design.js';
import { PartsView } from './parts-view.js';
import { NetworkView } from './network-view.js';
import { PartsPanel } from './parts-panel.js';
import { BodyView } from './body-view.js';
import { deviation, sameDomain, versionSurface } from './compare.js';
import { DsmView } from './dsm-view.js';
import { DsmPanel } from './dsm-panel.js';
import { Follow } from './follow.js';
import { Measure } from './measure.js';
import { Comments } from './comments.js';
import { MEASURES, isMeasure, isSigned } from './mesh-curvature.js';

/** A named moment of the page's load (performance marks `vsculpt:NAME`, once each), read by bench/first-picture-profile.mjs. */
const marked = new Set();
const mark = (name) => {
  if (marked.has(name)) return;
  marked.add(name);
  performance.mark(`vsculpt:${name}`);
};
mark('app-evaluating');

const params = new URLSearchParams(location.search);
const designId = Number(params.get('design') || 1);
// The token arrives in the link (?token= or #token=) and leaves the address
// bar at once: kept for this tab only (sessionStorage, so a reload still
// works), never in history, bookmarks or a referrer.
const fragment = new URLSearchParams(location.hash.slice(1));
const tokenKey = `vsculpt-token-${designId}`;
const token = params.get('token') || fragment.get('token') || sessionStorage.getItem(tokenKey) || '';
if (token) sessionStorage.setItem(tokenKey, token);
if (params.has('token') || fragment.has('token')) {
  params.delete('token');
  history.replaceState(null, '', `${location.pathname}?${params}`);
}
const $ = (id) => document.getElementById(id);

const state = {
  access: null,
  /** The design: parts, relations, icons (design.js). */
  design: new Design(),
  versions: [],
  presence: [],
  /** The selected icon's id, or null. */
  selected: null,
  /** The selected part's id (the icon tools act on it), or null. */
  selectedPart: null,
  /** Parts hidden on this page only (a viewer's show/hide; an editor's goes to everyone). */
  hidden: new Set(),
  create: 'none',
  pending: [],
  revision: 0,
  frames: 0,
  lastError: null,
  lastWarning: null,
  toasts: [],
  online: null,
  canUndo: false,
  canRedo: false,
  /** The version being compared with: { version, part, other (its surface), tess, deviation, max } or null. */
  compare: null,
  /** Every icon of the design by id (each with `part`). */
  get icons() {
    return this.design.icons;
  },
};
const design = state.design;

const view = new View($('viewport'));
const partsView = new PartsView(view);
// Body parts (paper 002): drawn from body frames, lattice handles, morph slider.
const bodyView = new BodyView(view, {
  send: (msg) => send(msg),
  canEdit: () => state.access === 'editor',
  panel: $('viewport').parentElement,
  partNames: () => new Set([...design.parts.values()].map((p) => p.name)),
});
const icons = new IconLayer(view.model);
const networkView = new NetworkView(view, { send: (m) => send(m), canEdit: () => state.access === 'editor' && state.online });
const dsmView = new DsmView(view.model);
{
  // The view's bounds: the surface and curve drawings' and the DSM meshes'.
  const partsBounds = view.bounds;
  view.bounds = () => {
    const a = partsBounds();
    const b = dsmView.bounds();
    return a && b ? a.clone().union(b) : a || b;
  };
}

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
  renderPanels();
}

/** Whether part `id` is drawn here (visible for everyone and not hidden on this page). */
function partShownHere(id) {
  const p = design.parts.get(id);
  return !!p && p.visible && !state.hidden.has(id);
}

// The first framing waits until every part drawn here is drawn: a surface's
// or curve's drawing filled, a body's frame, a network's curves, a DSM
// part's mesh. (It used to frame whatever was drawn first: a body frame is
// drawn as it arrives, before the surfaces' tessellation, so the first-start
// demo was framed on its spool alone with the mouse off to the side.)
view.ready = () => design.joined && [...design.parts.values()].every((p) => {
  if (!partShownHere(p.id)) return true;
  if (p.kind === 'body') return !!bodyView.bodies.get(p.id)?.frame;
  if (p.kind === 'network') return networkView.parts.has(p.id);
  if (p.kind === 'dsm') return dsmView.drawings.has(p.id);
  return !!partsView.drawings.get(p.id)?.filled;
});

/** The icons of the parts drawn here. */
function drawnIcons() {
  const out = new Map();
  for (const [id, icon] of design.icons) if (partShownHere(icon.part)) out.set(id, icon);
  return out;
}

const geometryOf = (partId) => design.parts.get(partId)?.geometry || null;

/** Work counted for BENCHMARKS.md (bench/browser-fps.mjs reads it): full redraws, surfaces sent to the worker and shown; when the first picture was drawn (ms since navigation start). */
const perf = { redraws: 0, submitted: 0, shown: 0, workerFailed: null, firstPicture: null, prewarmedAt: null, prewarmPlain: null };

/** Per part: how many shapes arrived (frames, snapshots) and which of them its drawing shows. */
const partSeq = new Map();
const partShownSeq = new Map();
/** Parts with a frame not yet drawn. */
const dirtyParts = new Set();
/** Whether any part has been drawn (the first picture). */
let pictured = false;

/** Full redraw: every part's drawing filled on the main thread, exact bounds, icons rebuilt. */
function redraw() {
  mark('first-redraw');
  perf.redraws++;
  partsView.sync(design, { hidden: state.hidden, selected: state.selectedPart });
  networkView.sync(design, state.hidden);
  dsmView.sync(design, partShownHere);
  bodyView.sync(design, state.hidden);
  for (const id of design.parts.keys()) partShownSeq.set(id, partSeq.get(id) || 0);
  dirtyParts.clear();
  if (partsView.drawings.size || networkView.parts.size) pictured = true;
  const sphere = view.boundingSphere();
  icons.size = sphere ? sphere.radius * 0.025 : 0.05;
  icons.update(drawnIcons(), geometryOf, state.selected);
  attachGizmo();
  updateCompare();
  comments.update();
  mark('first-redrawn');
}

/** The selected part, or undefined. */
const selectedPart = () => design.parts.get(state.selectedPart);

/** Keeps a selection that still exists; else the first part (the icon tools always have a part to act on). */
function keepSelection() {
  if (state.selected != null && !design.icons.has(state.selected)) state.selected = null;
  if (state.selectedPart == null || !design.parts.has(state.selectedPart)) {
    const first = [...design.parts.values()].find((p) => !p.provisional && partShownHere(p.id)) || [...design.parts.values()].find((p) => !p.provisional);
    state.selectedPart = first ? first.id : null;
    state.pending = [];
    $('pending').textContent = '';
  }
}

// The measure tool (distance, curvature at a point), for viewers too.
const measure = new Measure({ view, button: $('measure'), output: $('measure-out') });

// Review comments: pins on the model and the comments panel, for viewers and editors.
const comments = new Comments({
  view,
  button: $('comment-tool'),
  draft: $('comment-draft'),
  text: $('comment-text'),
  where: $('comment-where'),
  list: $('comments'),
  count: $('comment-count'),
  send: (msg) => send(msg),
  access: () => state.access,
  geometryOf: (id) => geometryOf(id),
  partName: (id) => design.parts.get(id)?.name ?? `part ${id}`,
  // The comment and measure tools take clicks on the model in turn.
  onActive: (on) => {
    if (on && measure.active) measure.setActive(false);
  },
});
$('measure').addEventListener('click', () => {
  if (measure.active && comments.active) comments.setActive(false);
});

// Following another person's view; this page's own camera goes out in its presence.
const follow = new Follow({
  view,
  send: (msg) => !!state.online && link.send(msg) !== null,
  button: $('follow'),
  onChange: () => renderPanels(),
});
$('presence').addEventListener('click', (e) => {
  const b = e.target.closest('button[data-follow]');
  if (!b) return;
  const id = Number(b.dataset.follow);
  if (follow.following === id) follow.stop();
  else follow.follow(id);
});
const dsmPanel = new DsmPanel({ section: $('dsm-section'), onEdit: (part, edit) => dsmEdit(part, edit) });
const partsPanel = new PartsPanel({
  list: $('parts'),
  relations: $('relations'),
  joinForm: $('join'),
  bindForm: $('bind'),
  ffdForm: $('ffd'),
  onSelect: (id) => selectPart(id),
  onVisible: (id, visible) => setVisible(id, visible),
  onLock: (id, locked) => send({ type: 'set_part', part: id, locked }),
  onRename: (id, name) => send({ type: 'set_part', part: id, name }),
  onColour: (id, colour) => send({ type: 'set_part', part: id, colour }),
  onDelete: (id) => send({ type: 'delete_part', part: id }),
  onJoin: (relation) => send({ type: 'relate', relation }),
  onBind: (relation) => send({ type: 'relate', relation }),
  onFfd: (relation) => send({ type: 'relate', relation }),
  onUnrelate: (id) => send({ type: 'unrelate', relation: id }),
});

/** Shows or hides part `id`: for everyone from an editor (set_part), on this page only for a viewer. */
function setVisible(id, visible) {
  if (state.access === 'editor') {
    state.hidden.delete(id);
    send({ type: 'set_part', part: id, visible });
    return;
  }
  if (visible) state.hidden.delete(id);
  else state.hidden.add(id);
  if (!visible && state.selected != null && design.icons.get(state.selected)?.part === id) state.selected = null;
  redraw();
  renderPanels();
}

/** The version history, newest first; a version comments were written on is marked (a click frames the first of them). */
function renderHistory() {
  const editor = state.access === 'editor';
  const commented = comments.byVersion();
  $('history').innerHTML = state.versions
    .slice()
    .reverse()
    .map((v) => {
      const ids = commented.get(v.version) || [];
      const mark = ids.length
        ? ` <button class="commented" data-commented="${ids[0]}" title="${ids.length} comment${ids.length > 1 ? 's' : ''} written on v${v.version}: click to show">💬 ${ids.length}</button>`
        : '';
      return `<li${ids.length ? ' class="commented"' : ''}><b>v${v.version}</b>${mark} ${escape(v.message)} <small>${escape(v.author)} · ${new Date(v.time_ms).toLocaleString()}</small>
      <button data-compare="${v.version}">${state.compare && state.compare.version === v.version ? 'comparing' : 'compare'}</button>
      ${editor ? `<button data-restore="${v.version}"${state.online ? '' : ' disabled'}>restore</button>` : ''}</li>`;
    })
    .join('');
}

function renderPanels() {
  const editor = state.access === 'editor';
  document.body.classList.toggle('viewer', !editor);
  $('role').textContent = state.access ? `${state.access} · design ${designId}` : '';
  $('presence').innerHTML = state.presence
    .map((p) => `<li>${escape(p.name)} <small>${p.access}</small>${p.holding ? ` holds icon ${p.holding}` : ''}${
      p.camera && p.client !== state.clientId ? ` <button data-follow="${p.client}" aria-pressed="${follow.following === p.client}">${follow.following === p.client ? 'following' : 'follow'}</button>` : ''
    }</li>`)
    .join('');
  renderHistory();
  partsPanel.render({ design, selected: state.selectedPart, hidden: state.hidden, editor, online: !!state.online });
  comments.render();
  dsmPanel.render(selectedPart(), editor && !!state.online);
  const part = selectedPart();
  $('target-part').textContent = part ? `on ${part.name} (${part.kind})${part.locked ? ' · locked' : ''}` : 'no part selected';
  const curve = part && part.kind === 'curve';
  for (const o of $('create').options) o.disabled = curve && (o.value === 'curve' || o.value === 'join' || o.value === 'edge');
  $('create').querySelector('option[value=point]').textContent = curve ? 'param icon (t)' : 'point icon';
  $('create').querySelector('option[value=region]').textContent = curve ? 'span icon (t0…t1)' : 'region icon';
  for (const sel of [$('create-role'), $('sel-role')]) for (const o of sel.options) o.hidden = curve && !CURVE_ROLES.has(o.value);
  const sel = design.icons.get(state.selected);
  $('selection').hidden = !sel;
  if (sel) {
    const owner = design.parts.get(sel.part);
    $('sel-title').textContent = `icon ${sel.id} · ${sel.anchor.kind} on ${owner ? owner.name : `part ${sel.part}`}`;
    $('sel-role').value = sel.role.kind === 'derivative' ? sel.role.which : sel.role.kind;
    $('sel-state').value = sel.state;
    $('sel-sensors').textContent = sel.sensors.join(', ') || 'none';
  }
  const m = part && part.material;
  $('material-part').textContent = part ? part.name : '';
  if (m && m.alpha11 !== undefined) {
    $('alpha').value = m.alpha11;
    $('beta').value = m.beta11;
  } else if (m && m.alpha !== undefined) {
    $('alpha').value = m.alpha;
    $('beta').value = m.beta;
  }
  for (const fmt of ['igs', 'obj', 'stl', 'gltf']) $(`export-${fmt}`).href = `/api/designs/${designId}/export.${fmt}?token=${encodeURIComponent(token)}`;
}

function escape(s) {
  return String(s).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
}

function onMessage(msg) {
  mark(msg.type);
  if (msg.type === 'ack' || msg.type === 'error') {
    networkView.answered(msg.req, msg.type === 'error');
    bodyView.answered(msg);
  }
  switch (msg.type) {
    case 'network_changed': {
      const p = design.parts.get(msg.part);
      if (p) {
        p.network = msg.network;
        networkView.setNetwork(msg.part, msg.network, p.colour);
      }
      break;
    }
    case 'fairing_progress':
    case 'fairing_ended':
      networkView.fairing(msg);
      if (msg.type === 'fairing_ended' && msg.outcome !== 'applied' && msg.outcome !== 'cancelled') toast(msg.message);
      renderFairing();
      break;
    case 'welcome':
      state.access = msg.access;
      state.clientId = msg.client_id;
      // The reviewer's page is a studio: the product stands on a ground with its contact shadow.
      view.groundShadow = msg.access !== 'editor';
      // The snapshot that follows lists the jobs running now.
      networkView.jobs.clear();
      renderFairing();
      break;
    case 'snapshot':
      shellDesign(msg.design);
      // The compact join (geometry_first): the points came in the frames before
      // this snapshot, and frames keep them current; only a full snapshot carries them.
      for (const p of msg.parts) if (partHasPoints(p)) partSeq.set(p.id, (partSeq.get(p.id) || 0) + 1);
      design.applySnapshot(msg);
      for (const id of [...state.hidden]) if (!design.parts.has(id)) state.hidden.delete(id);
      state.versions = msg.versions;
      state.presence = msg.presence;
      follow.setPresence(state.presence, state.clientId);
      follow.joined();
      state.revision = msg.revision;
      keepSelection();
      setHistory(msg.can_undo, msg.can_redo);
      comments.comments = new Map((msg.comments || []).map((c) => [c.id, c]));
      networkView.setJobs(msg.fairing || []);
      renderFairing();
      redraw();
      break;
    case 'comment_added':
    case 'comment_changed':
    case 'comment_deleted':
      comments.apply(msg);
      renderHistory();
      break;
    case 'part_created':
    case 'part_deleted':
    case 'part_changed':
    case 'relation_created':
    case 'relation_deleted':
    case 'icon_created':
    case 'icon_updated':
    case 'icon_deleted':
    case 'material_changed':
    case 'dsm_changed': {
      if (msg.type === 'part_created' && partHasPoints(msg.part)) partSeq.set(msg.part.id, (partSeq.get(msg.part.id) || 0) + 1);
      design.applyEvent(msg);
      if (msg.type === 'part_deleted') {
        state.hidden.delete(msg.part);
        dsmView.drop(msg.part);
        if (tessWorker) tessWorker.forget(msg.part);
        if (state.compare && state.compare.part === msg.part) stopCompare();
      }
      keepSelection();
      if (msg.type !== 'material_changed') redraw();
      break;
    }
    case 'committed':
      state.versions.push(msg.version);
      break;
    case 'versions':
      state.versions = msg.versions;
      break;
    case 'presence':
      state.presence = msg.clients;
      follow.setPresence(state.presence, state.clientId);
      break;
    case 'presence_changed': {
      const i = state.presence.findIndex((p) => p.client === msg.client.client);
      if (i >= 0) state.presence[i] = msg.client;
      else state.presence.push(msg.client);
      follow.setPresence(state.presence, state.clientId);
      break;
    }
    case 'presence_left':
      state.presence = state.presence.filter((p) => p.client !== msg.client);
      follow.setPresence(state.presence, state.clientId);
      break;
    case 'history':
      setHistory(msg.can_undo, msg.can_redo);
      break;
    case 'error':
      state.lastError = `${msg.code}: ${msg.message}`;
      toast(state.lastError);
      break;
    case 'icon_feedback':
      // The solve could not meet every constraint (they contradict each
      // other): said once per drag, not at the frame rate.
      if (msg.warning && msg.warning !== state.lastWarning) toast(msg.warning, 'error');
      state.lastWarning = msg.warning || null;
      break;
    default:
      break;
  }
  renderPanels();
}

/** Whether a part's JSON carries its control points (a full snapshot or part_created). */
function partHasPoints(p) {
  const s = p.shape;
  if (s.kind !== 'surface' && s.kind !== 'curve') return false;
  return (s.kind === 'surface' ? s.surface.points : s.curve.points).length > 0;
}

function setHistory(canUndo, canRedo) {
  state.canUndo = canUndo;
  state.canRedo = canRedo;
  $('undo').disabled = !canUndo || !state.online;
  $('redo').disabled = !canRedo || !state.online;
}

function onFrame(f) {
  mark('first-frame');
  state.frames++;
  if (f.kind === 'body') {
    bodyView.apply(f, design.parts.get(f.part));
    return;
  }
  // Mesh frames (kind 3): a network part's patches, a DSM part's surface.
  // Before the snapshot (compact join) the part is unknown: both views take
  // the frame and each keeps only its own kind once the parts are known.
  if (f.kind === 'mesh') {
    const part = design.parts.get(f.part);
    if ((!part || part.kind === 'network') && networkView.mesh(f)) {
      pictured = true;
      renderLegendValues();
    }
    if ((!part || part.kind === 'dsm') && dsmView.show(f, part)) {
      dsmView.style(part || { id: f.part }, partShownHere(f.part));
      pictured = true;
    }
    return;
  }
  const known = design.parts.has(f.part);
  if (!design.applyFrame(f)) return;
  state.revision = design.revision;
  partSeq.set(f.part, (partSeq.get(f.part) || 0) + 1);
  if (!known) keepSelection();
  dirtyParts.add(f.part);
  // Coalescing: the render loop tessellates only the newest shape of each part, once per animation frame.
  frameDue = true;
  clearTimeout(settleTimer);
  settleTimer = setTimeout(settle, SETTLE_MS);
}

/** After this long without a frame, a full redraw redraws icons (curves, regions, spans) on the settled shapes. */
const SETTLE_MS = 200;
let settleTimer = null;
let frameDue = false;

function settle() {
  if (dragging) settleTimer = setTimeout(settle, SETTLE_MS);
  else redraw();
}

/** The per-frame path: each changed part's newest shape to the worker (or filled here: curves, or when there is no worker); a new layout or a new part takes a full redraw; hidden parts wait. */
function showNewestFrames() {
  let full = false;
  for (const id of dirtyParts) {
    const part = design.parts.get(id);
    // A hidden part's newest shape waits: showing it again redraws it (its drawing then lags its shape).
    if (!part || !part.geometry || !partShownHere(id)) continue;
    const seq = partSeq.get(id) || 0;
    if (!partsView.drawings.has(id)) {
      full = true;
    } else if (part.kind === 'curve') {
      perf.submitted++;
      partsView.fill(id, part.geometry);
      partShown(id, seq, null);
    } else {
      const tess = partsView.tessFor(id, part.geometry);
      if (!tess) {
        full = true;
        continue;
      }
      perf.submitted++;
      if (!tessWorker || !tessWorker.submit(id, seq, part.geometry, tess)) {
        tess.fill(part.geometry);
        partShown(id, seq, tess, part.geometry);
      }
    }
  }
  dirtyParts.clear();
  if (full) redraw();
}

/** Part `id`'s drawing now shows shape number `seq` (`tess` holds it for a surface: `g`): the mesh, seams and handles in place. */
function partShown(id, seq, tess, g) {
  if (seq <= (partShownSeq.get(id) || 0)) return;
  partShownSeq.set(id, seq);
  perf.shown++;
  mark('first-shown');
  pictured = true;
  const part = design.parts.get(id);
  if (tess && part) partsView.surfaceFilled(id, tess, g);
  if ([...design.relations.values()].some((r) => relationParts(r).includes(id))) partsView.drawSeams(design);
  if (state.compare && state.compare.part === id) updateCompare();
  if (part) icons.move([...part.icons].map((i) => design.icons.get(i)).filter(Boolean).map((i) => ({ id: i.id, xyz: i.xyz })));
  if ([...comments.comments.values()].some((c) => c.part === id)) comments.update();
}

// `?worker=0` keeps the same fill on the main thread (compared in bench/browser-fps.mjs).
const tessWorker = params.get('worker') === '0' ? null : new TessellationWorker({
  onFilled: (id, seq, tess, g) => partShown(id, seq, tess, g),
  onFailure: (reason) => {
    perf.workerFailed = reason;
    for (const id of design.parts.keys()) dirtyParts.add(id);
    frameDue = true;
  },
});

/**
 * Sends `msg` (a message acting on an icon is addressed to the icon's part
 * when it names none); when the link is down says so and returns null
 * (nothing is sent, nothing is queued).
 */
function send(msg) {
  const req = link.send(design.addressed(msg));
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

/** Where the gizmo of icon `icon` sits: a point-like position constraint's target, else the icon on its part. */
function dragPoint(icon) {
  return icon.role.kind === 'position' && (icon.anchor.kind === 'point' || icon.anchor.kind === 'param') ? icon.target : icon.xyz;
}

/** Whether icon `icon` may be dragged from this page: an editor's, on a part drawn here and not locked, not a derivative. */
function draggable(icon) {
  const part = icon && design.parts.get(icon.part);
  return !!part && state.access === 'editor' && !part.locked && partShownHere(part.id) && icon.role.kind !== 'derivative';
}

function attachGizmo() {
  const sel = state.icons.get(state.selected);
  if (!draggable(sel)) {
    gizmo.detach();
    return;
  }
  if (!dragging) {
    proxy.position.set(...dragPoint(sel));
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
  if (comments.active) {
    // Commenting pins a point of a part: (u, v) on a surface, the hit point elsewhere.
    const hit = raycaster.intersectObjects(partsView.pickables(), false)[0];
    const at = hit && partsView.hitParams(hit);
    if (at && at.kind === 'surface') comments.place({ part: at.part, u: at.u, v: at.v });
    else if (at) {
      const p = view.model.worldToLocal(hit.point.clone());
      comments.place({ part: at.part, xyz: [p.x, p.y, p.z] });
    }
    return;
  }
  if (measure.active) {
    // Measuring reads the surface; it selects and creates nothing.
    const hit = raycaster.intersectObjects(partsView.pickables(), false)[0];
    const at = hit && partsView.hitParams(hit);
    if (at && at.kind === 'surface') measure.add(at.part, design.parts.get(at.part).geometry, at.u, at.v);
    return;
  }
  const hitIcon = raycaster.intersectObjects(icons.handles(), false)[0];
  if (hitIcon) {
    select(hitIcon.object.userData.iconId);
    return;
  }
  const hit = raycaster.intersectObjects(partsView.pickables(), false)[0];
  const at = hit && partsView.hitParams(hit);
  if (!at) return;
  if (at.part !== state.selectedPart) selectPart(at.part);
  if (at.kind === 'surface') pick(at.u, at.v);
  else pick(at.t);
});

/** Selects icon `id` (and its part), or nothing. */
function select(id) {
  state.selected = id;
  const icon = design.icons.get(id);
  if (icon && icon.part !== state.selectedPart) {
    state.selectedPart = icon.part;
    state.pending = [];
    $('pending').textContent = '';
  }
  redraw();
  renderPanels();
}

/** Selects part `id`: the icon tools and the material act on it; a selected icon of another part is let go. */
function selectPart(id) {
  if (!design.parts.has(id)) return;
  if (state.selectedPart !== id && state.create !== 'join') {
    state.pending = [];
    $('pending').textContent = '';
  }
  state.selectedPart = id;
  if (state.selected != null && design.icons.get(state.selected)?.part !== id) state.selected = null;
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
/** The roles an icon on a curve part may take (README: load, position, derivative R or R2). */
const CURVE_ROLES = new Set(['position', 'load', 'R', 'R2']);

/**
 * A click on the selected part in the current creation mode: at (u, v) on a
 * surface part (point, curve, region or edge icon — the edge nearest the
 * click, clamped or simply supported as the panel says), at t (the first argument) on
 * a curve part (param or span icon).
 */
function pick(u, v) {
  if (state.access !== 'editor') return;
  const part = selectedPart();
  if (!part) return;
  const mode = state.create;
  const role = ROLES[$('create-role').value] || ROLES.position;
  if (part.kind === 'curve') {
    const t = u;
    if (mode === 'point') {
      createIcon({ kind: 'param', t }, role);
    } else if (mode === 'region') {
      state.pending.push(t);
      $('pending').textContent = 'span start picked: click where it ends (Esc cancels)';
      if (state.pending.length === 2) {
        const [t0, t1] = state.pending.slice().sort((a, b) => a - b);
        state.pending = [];
        $('pending').textContent = '';
        createIcon({ kind: 'span', t0, t1 }, role);
      }
    } else if (mode === 'curve') {
      toast('a curve icon goes on a surface part: pick a surface, or make a param or span icon here', 'info');
    } else if (mode === 'join') {
      toast('a join ties two surface edges: pick an edge of a surface part', 'info');
    } else if (mode === 'edge') {
      toast('an edge clamp holds a surface edge: pick an edge of a surface part', 'info');
    }
    return;
  }
  if (mode === 'join') {
    pickEdge(part, u, v);
  } else if (mode === 'edge') {
    // One click: the nearest edge of the part, held as a position constraint.
    createIcon({ kind: 'edge', edge: nearestEdge(part.geometry, u, v), mode: $('edge-mode').value }, ROLES.position);
  } else if (mode === 'point') {
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

/** The edge of surface geometry `g` nearest to (u, v), measured across the domain (u_min, u_max, v_min, v_max). */
function nearestEdge(g, u, v) {
  const [[u0, u1], [v0, v1]] = domainOf(g);
  const su = (u - u0) / (u1 - u0);
  const sv = (v - v0) / (v1 - v0);
  return [['u_min', su], ['u_max', 1 - su], ['v_min', sv], ['v_max', 1 - sv]].sort((a, b) => a[1] - b[1])[0][0];
}

/**
 * The join tool in the view: a click on a surface picks its nearest edge;
 * the second click (on another part) joins the two with the continuity and
 * direction chosen in the panel's join form.
 */
function pickEdge(part, u, v) {
  const edge = nearestEdge(part.geometry, u, v);
  const f = $('join').elements;
  if (!state.pending.length) {
    state.pending = [{ part: part.id, edge }];
    $('pending').textContent = `${part.name} ${edge.replace('_', ' ')} picked: click the edge to join it to (Esc cancels)`;
    return;
  }
  const [a] = state.pending;
  state.pending = [];
  $('pending').textContent = '';
  if (a.part === part.id && a.edge === edge) return;
  send({ type: 'relate', relation: { kind: 'join', a, b: { part: part.id, edge }, continuity: f['join-continuity'].value, reversed: f['join-reversed'].checked } });
}

/** Creates an icon on part `part` (default: the selected part); refused here when a curve part cannot take the role. */
function createIcon(anchor, role, part = state.selectedPart) {
  const p = design.parts.get(part);
  if (p && p.kind === 'curve') {
    const name = role.kind === 'derivative' ? role.which : role.kind;
    if (!CURVE_ROLES.has(name)) {
      toast(`an icon on a curve is a load, a position or a derivative R or R2, not ${name}`, 'info');
      return null;
    }
  }
  return send({ type: 'create_icon', part, spec: { anchor, role, state: 'passive' } });
}

function finishCurve() {
  const pts = state.pending;
  state.pending = [];
  $('pending').textContent = '';
  if (pts.length < 2 || !Array.isArray(pts[0])) return;
  const degree = Math.min(3, pts.length - 1);
  const n = pts.length;
  const knots = [...Array(degree + 1).fill(0)];
  for (let k = 1; k < n - degree; k++) knots.push(k / (n - degree));
  knots.push(...Array(degree + 1).fill(1));
  createIcon({ kind: 'curve', curve: { knots: { degree, knots }, points: pts } }, ROLES[$('create-role').value] || ROLES.position);
}

// --- parts: add -----------------------------------------------------------------

/** A name not yet used by a part: `base 1`, `base 2`, … */
function freshName(base) {
  const used = new Set([...design.parts.values()].map((p) => p.name));
  for (let k = 1; ; k++) if (!used.has(`${base} ${k}`)) return `${base} ${k}`;
}

/** Where a new part goes: beside what is drawn (x beyond its right side), sized like a third of it. */
function placeNew() {
  const box = view.bounds();
  if (!box || box.isEmpty()) return { x: 0, y: 0, z: 0, size: 1 };
  const size = Math.max(box.max.x - box.min.x, box.max.y - box.min.y, 1e-3) / 3;
  return { x: box.max.x + size * 0.3, y: (box.min.y + box.max.y) / 2 - size / 2, z: (box.min.z + box.max.z) / 2, size };
}

/** Adds a small flat bicubic plate (6 × 6 control points) beside the design. */
function addPlane() {
  const { x, y, z, size } = placeNew();
  const n = 6;
  const knots = [0, 0, 0, 0, 1 / 3, 2 / 3, 1, 1, 1, 1];
  const points = [];
  for (let i = 0; i < n; i++) for (let j = 0; j < n; j++) points.push([x + (size * i) / (n - 1), y + (size * j) / (n - 1), z]);
  return send({ type: 'create_part', spec: { name: freshName('plane'), shape: { kind: 'surface', surface: { u: { degree: 3, knots }, v: { degree: 3, knots }, nu: n, nv: n, points } } } });
}

/** Adds a DSM part beside the design (paper 001): a flat box whose ends two sphere-based density primitives round off, and a bump on top. */
function addDsm() {
  const { x, y, z, size } = placeNew();
  const c = [x + size / 2, y + size / 2, z];
  const a = Math.log(3) / (0.2 * size);
  const prims = [
    { id: 1, at: c, shape: { type: 'box', half: [0.4 * size, 0.2 * size, 0.08 * size] } },
    { id: 2, at: [c[0] + 0.4 * size, c[1], c[2]], shape: { type: 'density_sphere', density: 3, reducing: a } },
    { id: 3, at: [c[0] - 0.4 * size, c[1], c[2]], shape: { type: 'density_sphere', density: 3, reducing: a } },
    { id: 4, at: [c[0], c[1], c[2] + 0.08 * size], shape: { type: 'density_sphere', density: 2, reducing: a } },
  ];
  return send({ type: 'create_part', spec: { name: freshName('concept'), shape: { kind: 'dsm', dsm: { de: 1, cells: 32, groups: [{ op: 'add', primitives: prims }] } } } });
}

/** Sends one `dsm_edit` of DSM part `part`. */
function dsmEdit(part, edit) {
  return send({ type: 'dsm_edit', part, edit });
}

/** Adds a cubic curve (6 control points, a gentle arch) beside the design. */
function addCurve() {
  const { x, y, z, size } = placeNew();
  const n = 6;
  const points = Array.from({ length: n }, (_, i) => [x + (size * i) / (n - 1), y + size / 2, z + size * 0.3 * Math.sin((Math.PI * i) / (n - 1))]);
  return send({ type: 'create_part', spec: { name: freshName('curve'), shape: { kind: 'curve', curve: { knots: { degree: 3, knots: [0, 0, 0, 0, 1 / 3, 2 / 3, 1, 1, 1, 1] }, points } } } });
}

// --- panels -------------------------------------------------------------------

function setRange(r) {
  view.setRange(r);
  $('range').value = r;
  // A variation (≥ 0) runs white → red from 0; a curvature blue → white → red.
  $('legend-min').textContent = isSigned(view.mode) ? (-r).toPrecision(2) : '0';
  $('legend').classList.toggle('unsigned', !isSigned(view.mode));
  $('legend-max').textContent = r.toPrecision(2);
}

/** The values of the view's measure on everything drawn: surfaces (mean, Gaussian) and network patches (every measure). */
function measureValues(mode) {
  const out = networkView.shownValues(mode);
  if (mode === 'mean' || mode === 'gauss') for (const d of partsView.drawings.values()) if (d.visible && d.tess) out.push(mode === 'mean' ? d.tess.mean : d.tess.gauss);
  return out;
}

/** The legend's line of the values drawn: their smallest and largest. */
function renderLegendValues() {
  const mode = view.mode;
  if (!isMeasure(mode)) return;
  let [lo, hi] = [Infinity, -Infinity];
  for (const a of measureValues(mode))
    for (const x of a)
      if (Number.isFinite(x)) {
        if (x < lo) lo = x;
        if (x > hi) hi = x;
      }
  $('legend-values').textContent = lo <= hi ? `${MEASURES[mode]}: ${lo.toPrecision(3)} … ${hi.toPrecision(3)}` : '';
}

$('mode').addEventListener('change', (e) => {
  const mode = e.target.value;
  view.setMode(mode);
  const analysis = isMeasure(mode);
  $('legend').hidden = !analysis;
  $('legend').classList.toggle('unsigned', !isSigned(mode));
  const drawnValues = analysis ? measureValues(mode) : [];
  if (analysis && drawnValues.length) {
    // Start from the 95th percentile of |value| over what is drawn; the slider spans 100× around it.
    const values = drawnValues.flatMap((a) => Array.from(a, Math.abs).filter(Number.isFinite)).sort((a, b) => a - b);
    const p95 = values[Math.floor(values.length * 0.95)] || 1;
    $('range').min = p95 / 10;
    $('range').max = p95 * 10;
    $('range').step = p95 / 100;
    setRange(p95);
  }
  renderLegendValues();
});
$('range').addEventListener('input', (e) => setRange(Number(e.target.value)));
$('net').addEventListener('change', (e) => partsView.setShowNet(e.target.checked));
$('fit').addEventListener('click', () => {
  view.userMoved = true;
  view.fit();
});
$('create').addEventListener('change', (e) => {
  state.create = e.target.value;
  state.pending = [];
  $('pending').textContent = '';
});
$('add-plane').addEventListener('click', addPlane);
$('add-curve').addEventListener('click', addCurve);
/** The network parts the fair button acts on: the selected one, or every one. */
function fairTargets() {
  return [...design.parts.values()].filter((p) => p.kind === 'network' && (state.selectedPart === null || state.selectedPart === undefined || state.selectedPart === p.id)).map((p) => p.id);
}
/**
 * The fair button while fairing jobs run: it shows their progress and
 * cancels them; the progress bar beside it is shown to viewers too.
 */
function renderFairing() {
  const all = networkView.progress();
  const mine = fairTargets().reduce((n, id) => n + networkView.jobsOf(id).length, 0);
  const pct = Math.round(100 * all.fraction);
  const button = $('fair-network');
  button.textContent = mine ? `cancel fairing (${pct} %)` : 'fair network';
  button.classList.toggle('running', mine > 0);
  $('fairing').hidden = all.count === 0;
  $('fair-progress').value = all.fraction;
  $('fair-status').textContent = all.count ? `fairing ${all.count} face${all.count === 1 ? '' : 's'}: ${pct} % (sweep ${all.iteration})` : '';
}
$('fair-network').addEventListener('click', () => {
  const ids = fairTargets();
  const running = ids.filter((id) => networkView.jobsOf(id).length);
  if (running.length) for (const id of running) networkView.cancelJobs(id);
  else for (const id of ids) networkView.fairAll(id, undefined, { measure: $('fair-measure').value });
});
$('ribbon-handles').addEventListener('click', () => {
  const on = !networkView.handles.shown;
  networkView.handles.show(on);
  $('ribbon-handles').setAttribute('aria-pressed', String(on));
});
$('add-dsm').addEventListener('click', addDsm);
$('finish-curve').addEventListener('click', finishCurve);
/** Switches icon `id`'s role to `name` (a key of ROLES): the panel's role list and the VR menu. */
function setRole(id, name) {
  send({ type: 'set_role', icon: id, role: ROLES[name] });
}
/** Switches icon `id`'s state (passive or sleeping): the panel's state list and the VR menu. */
function setIconState(id, iconState) {
  send({ type: 'set_state', icon: id, state: iconState });
}
$('sel-role').addEventListener('change', (e) => setRole(state.selected, e.target.value));
$('sel-state').addEventListener('change', (e) => setIconState(state.selected, e.target.value));
$('sel-delete').addEventListener('click', () => send({ type: 'delete_icon', icon: state.selected }));
$('sel-bind').addEventListener('click', () => {
  const sensor = $('sel-sensor').value.trim();
  if (sensor) send({ type: 'bind_sensor', icon: state.selected, sensor });
});
$('material').addEventListener('submit', (e) => {
  e.preventDefault();
  const part = selectedPart();
  if (!part) return;
  const a = Number($('alpha').value);
  const b = Number($('beta').value);
  // A surface takes six coefficients (isotropic here), a curve alpha and beta.
  const material = part.kind === 'curve' ? { alpha: a, beta: b } : { alpha11: a, alpha12: 0, alpha22: a, beta11: b, beta12: b, beta22: b };
  send({ type: 'set_material', part: part.id, material });
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
  const commented = e.target.closest('[data-commented]');
  if (commented) comments.frame(Number(commented.dataset.commented));
  const c = e.target.dataset.compare;
  if (c) compareWith(Number(c)).catch((err) => toast(`compare with v${c}: ${err.message}`));
});
$('compare-stop').addEventListener('click', () => stopCompare());

// --- version compare ------------------------------------------------------------------

/** The surface part a comparison is about: the selected part when it is a surface, else the first surface part drawn. */
function comparedPart() {
  const sel = selectedPart();
  if (sel && sel.kind === 'surface') return sel.id;
  const first = [...design.parts.values()].find((p) => p.kind === 'surface' && partShownHere(p.id));
  return first ? first.id : null;
}

/**
 * Compares a surface part on screen (the selected one, or the first) with
 * committed version `version`: both are evaluated at the same (u, v)
 * samples, each vertex coloured by how far the current surface lies from
 * the version's along its normal, and the version drawn as a faint
 * wireframe. Follows the live shape until stopped. Needs the same parameter
 * domain (a restore to another structure ends it).
 */
async function compareWith(version) {
  const part = comparedPart();
  if (part == null) throw new Error('no surface part to compare');
  const res = await fetch(`/api/designs/${designId}/versions/${version}`, { headers: { authorization: `Bearer ${token}` } });
  if (!res.ok) throw new Error(`${res.status} ${(await res.json().catch(() => ({}))).message || ''}`);
  const other = versionSurface((await res.json()).design, part);
  if (!other) throw new Error(`v${version} has no surface part ${design.parts.get(part)?.name ?? part}`);
  state.compare = { version, part, other, tess: null };
  partsView.compared = part;
  updateCompare();
  renderPanels();
}

function stopCompare() {
  state.compare = null;
  partsView.compared = null;
  partsView.setGhost(null);
  view.setDeviation(false);
  $('compare-legend').hidden = true;
  renderPanels();
}

/** Recomputes the deviation of the compared part's tessellation from the version. */
function updateCompare() {
  const c = state.compare;
  const d = c && partsView.drawings.get(c.part);
  const t = d && d.tess;
  if (!c || !t) return;
  if (!sameDomain(t, c.other)) {
    toast(`v${c.version} has another parameter domain: it cannot be compared point by point`);
    stopCompare();
    return;
  }
  if (!c.tess || c.tess.su !== t.su || c.tess.sv !== t.sv) {
    c.tess = new Tessellator(c.other, t.su, t.sv);
    c.tess.fill(c.other);
    partsView.setGhost(c.tess);
  }
  const { deviation: dev, max } = deviation(t, c.tess, c.deviation);
  c.deviation = dev;
  c.max = max;
  d.deviation = dev;
  view.setDeviation(true, max || 1);
  $('compare-legend').hidden = false;
  $('compare-text').textContent = `deviation of ${design.parts.get(c.part)?.name ?? 'the part'} from v${c.version}: up to ${max.toPrecision(3)} (blue below, red above)`;
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
  ['Esc', 'end commenting or measuring; else cancel the curve or region being picked, else deselect', false],
  ['F', 'frame the selected icon (or the whole design)', false],
  ['[ and ]', 'select the previous or next part', false],
  ['H', 'hide or show the selected part', false],
  ['L', 'lock or unlock the selected part', true],
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
  if (k === ']') return 'next-part';
  if (k === '[') return 'previous-part';
  if (k === 'h' || k === 'H') return 'hide';
  if (k === 'l' || k === 'L') return 'lock';
  return null;
}

/** Selects the part `step` places after the selected one in the panel's order (wrapping). */
function cyclePart(step) {
  const ids = [...design.parts.values()].filter((p) => !p.provisional).map((p) => p.id);
  if (!ids.length) return;
  const i = ids.indexOf(state.selectedPart);
  selectPart(ids[(i + step + ids.length) % ids.length]);
}

document.addEventListener('keydown', (e) => {
  const t = e.target;
  if (t instanceof HTMLElement && (t.isContentEditable || ['INPUT', 'SELECT', 'TEXTAREA'].includes(t.tagName))) return;
  const action = keyAction(e);
  if (!action) return;
  e.preventDefault();
  const editing = ['undo', 'redo', 'delete', 'lock'].includes(action);
  if (editing && state.access !== 'editor') {
    toast('view only: this link cannot edit', 'info');
    return;
  }
  if (action === 'undo') send({ type: 'undo' });
  else if (action === 'redo') send({ type: 'redo' });
  else if (action === 'delete' && state.selected != null) send({ type: 'delete_icon', icon: state.selected });
  else if (action === 'cancel' && comments.active) comments.setActive(false);
  else if (action === 'cancel' && measure.active) measure.setActive(false);
  else if (action === 'cancel') cancel();
  else if (action === 'frame') frameSelection();
  else if (action === 'help') $('help').hidden = !$('help').hidden;
  else if (action === 'next-part') cyclePart(1);
  else if (action === 'previous-part') cyclePart(-1);
  else if (action === 'hide' && selectedPart()) setVisible(state.selectedPart, !partShownHere(state.selectedPart));
  else if (action === 'lock' && selectedPart()) send({ type: 'set_part', part: state.selectedPart, locked: !selectedPart().locked });
});

/** Centres the view on the selected icon at a close distance, or fits the whole design. */
function frameSelection() {
  const icon = state.icons.get(state.selected);
  view.userMoved = true;
  if (!icon) {
    view.fit();
    return;
  }
  const at = new THREE.Vector3(...icon.xyz);
  const offset = view.camera.position.clone().sub(view.controls.target);
  const sphere = view.boundingSphere();
  const r = sphere ? sphere.radius : offset.length();
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
  // A grab takes icons of the parts drawn that are not locked.
  handles: () => icons.handles().filter((h) => !design.partOfIcon(h.userData.iconId)?.locked),
  iconPosition: (id) => {
    const icon = state.icons.get(id);
    return icon ? dragPoint(icon) : null;
  },
  send,
  pickables: () => partsView.pickables(),
  create: (hit) => {
    const at = partsView.hitParams(hit);
    if (!at) return;
    selectPart(at.part);
    const role = ROLES[$('create-role').value] || ROLES.position;
    createIcon(at.kind === 'surface' ? { kind: 'point', u: at.u, v: at.v } : { kind: 'param', t: at.t }, role, at.part);
  },
  onDragging: (on, id) => {
    dragging = on;
    if (on) select(id);
  },
  canEdit: () => state.access === 'editor',
  menu: {
    // The icon in hand: the one grabbed, else the one selected (a grab selects it).
    target: () => state.icons.get(xr.grab ? xr.grab.id : state.selected) || null,
    rolesFor: (icon) => (design.parts.get(icon.part)?.kind === 'curve' ? CURVE_ROLES : new Set(Object.keys(ROLES))),
    setRole,
    setState: setIconState,
  },
});

$('enter-vr').addEventListener('click', () => {
  xr.enter().catch((e) => status('error', e.message));
});

// --- the link (last: its first status call reaches everything above) ------------

/** The first picture's shader programs compile while the design is on its way (once: they stay cached). */
let prewarmed = false;
function prewarmOnce(options) {
  if (prewarmed) return;
  prewarmed = true;
  perf.prewarmPlain = options.plain;
  perf.prewarm = view.prewarm(options).then(() => {
    perf.prewarmedAt = performance.now();
    mark('prewarmed');
  });
}

// Without a token this page is the bare server address: say what to open instead of failing to join.
const link = token
  ? new Link({
      design: designId,
      token,
      name: params.get('name') || 'browser',
      onMessage,
      onFrame,
      onStatus: status,
      // The first picture's programs compile while the design is on its way; a warm visit, whose
      // kept geometry is drawn before any hello is answered, also the plain ones it draws (lines
      // of curves, bodies and networks: any kept frame but a surface's, kind 1), and draws them
      // once (view.prewarm). A kept picture of surfaces alone draws only the studio program:
      // compiling the plain ones then only delayed it (81 × 159, quiet: 0.1-0.2 s).
      onHello: () => {
        mark('hello');
        prewarmOnce({ plain: link.cacheUse.replayed > 0 && link.cacheUse.kinds.some((k) => k !== KIND_SURFACE) });
      },
      // The last visit's shape, drawn at once (geometry-cache.js); `?geometry_cache=0` joins without it.
      cache: params.get('geometry_cache') === '0' ? null : new GeometryCache(),
    })
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
    showNewestFrames();
  }
  xr.update();
  view.controls.update();
  view.settle();
  view.render();
  // The shell stays until the first picture is framed (view.settle).
  if (!shellDone && pictured && (view.fitted || !view.boundingSphere())) {
    perf.firstPicture = performance.now();
    mark('first-picture');
    dismissShell();
    // Where the browser has a headset, the VR controllers' code comes now, after the picture.
    xr.prefetch();
  }
});

window.vsculpt = { state, design, follow, measure, comments, dsmView, dsmEdit, addDsm, send, view, partsView, networkView, bodyView, icons, pick, select, selectPart, createIcon, finishCurve, addPlane, addCurve, gizmoAttached: () => !!gizmo.object, link, xr, perf, toast, compareWith, stopCompare };
mark('app-evaluated');
