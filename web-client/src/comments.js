// Review comments, for viewers and editors alike (the customer's feedback
// loop): the comment tool places a pin where a click meets a part — at the
// click's (u, v) on a surface part, at the hit point on any other — and a
// text box takes the comment; every client of the design sees the pin and
// the thread at once. Pins on a surface part stand at S(u, v) of the shape
// shown (bspline.js), so they stay on the surface as it changes; on other
// parts at the point stored. A pin is a short stem along the surface
// normal with a head, drawn over the model (never hidden inside it). The
// comments panel lists each comment with its author, time, the version it
// was written on, its text, its resolved state and its replies; clicking an
// entry frames its pin; resolve, reopen, edit, delete and reply are offered
// where this page's link may (an editor: every comment; a viewer: those
// written through a viewer link). `byVersion` tells the history which
// versions were commented on.

import * as THREE from 'three';
import { surfaceDerivs } from './bspline.js';

/** Longest comment text, in bytes of UTF-8 (the protocol's limit). */
export const MAX_COMMENT_BYTES = 4096;

const OPEN = 0xff7043;
const RESOLVED = 0x66bb6a;
const DRAFT = 0x4fc3f7;

/**
 * Where comment `c`'s pin stands: { p, n } with the point `p` and a unit
 * direction `n` for its stem — on a surface part with (u, v), S(u, v) and
 * the surface normal of geometry `g` there; else the stored point and +z.
 */
export function pinPoint(c, g) {
  const a = c.anchor;
  if (a.u !== undefined && a.v !== undefined && g && g.knotsU && g.knotsV && g.points && g.points.length) {
    const d = surfaceDerivs(g, a.u, a.v);
    const n = cross(d.u, d.v);
    const len = Math.hypot(...n);
    return { p: d.p, n: len > 0 ? n.map((x) => x / len) : [0, 0, 1] };
  }
  return { p: a.xyz, n: [0, 0, 1] };
}

function cross(a, b) {
  return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
}

const escape = (s) => String(s).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);

export class Comments {
  /**
   * @param {object} o
   * @param {import('./view.js').View} o.view
   * @param {HTMLButtonElement} o.button toggles the comment tool
   * @param {HTMLFormElement} o.draft the form with the new comment's text
   * @param {HTMLTextAreaElement} o.text its text box
   * @param {HTMLElement} o.where says where the new pin is
   * @param {HTMLElement} o.list the comments list
   * @param {HTMLElement} o.count the count of open comments
   * @param {(msg: object) => (number|null)} o.send sends a message (null: not connected)
   * @param {() => (string|null)} o.access this page's access (`editor`, `viewer`, …)
   * @param {(part: number) => object|null} o.geometryOf a part's geometry
   * @param {(part: number) => string} o.partName a part's name
   * @param {(on: boolean) => void} o.onActive called when the tool is switched
   */
  constructor(o) {
    Object.assign(this, o);
    this.active = false;
    /** Every comment of the design by id, as the server sent it. */
    this.comments = new Map();
    /** The pin being written: { part, u, v } or { part, xyz }, or null. */
    this.pending = null;
    /** The comment whose entry was clicked last. */
    this.focused = null;
    /** The comment or reply whose text is being edited, or null. */
    this.editing = null;
    this.group = new THREE.Group();
    this.group.name = 'comments';
    this.view.model.add(this.group);
    /** Pin objects by comment id (the draft under -1). */
    this.pins = new Map();
    this.button.addEventListener('click', () => this.setActive(!this.active));
    this.draft.addEventListener('submit', (e) => {
      e.preventDefault();
      this.post();
    });
    this.draft.querySelector('[data-cancel]').addEventListener('click', () => this.cancelDraft());
    // In the text box Ctrl+Enter (⌘+Enter) posts and Esc drops the draft.
    this.text.addEventListener('keydown', (e) => {
      if (e.key === 'Enter' && (e.ctrlKey || e.metaKey)) {
        e.preventDefault();
        this.post();
      } else if (e.key === 'Escape') {
        e.preventDefault();
        this.cancelDraft();
      }
    });
    this.list.addEventListener('click', (e) => this.clicked(e));
    this.list.addEventListener('submit', (e) => {
      e.preventDefault();
      const edit = e.target.closest('form[data-edit-form]');
      if (edit) {
        this.saveEdit(Number(edit.dataset.editForm), edit.querySelector('textarea').value);
        return;
      }
      const form = e.target.closest('form[data-reply]');
      const input = form && form.querySelector('input');
      if (!input || !input.value.trim()) return;
      if (this.send({ type: 'reply_comment', comment: Number(form.dataset.reply), text: input.value }) !== null) input.value = '';
    });
  }

  /** Whether this page may comment. */
  canComment() {
    const a = this.access();
    return a === 'editor' || a === 'viewer';
  }

  /** Whether this page may resolve, reopen or delete what was written through a `written` link. */
  canModerate(written) {
    const a = this.access();
    return a === 'editor' || (a === 'viewer' && written === 'viewer');
  }

  setActive(on) {
    this.active = on && this.canComment();
    this.button.setAttribute('aria-pressed', String(this.active));
    this.button.textContent = this.active ? 'commenting: click the model' : 'comment';
    if (!this.active) this.cancelDraft();
    if (this.onActive) this.onActive(this.active);
  }

  /** The comments of a snapshot (all of them). */
  setAll(list) {
    this.comments = new Map((list || []).map((c) => [c.id, c]));
    this.update();
  }

  /** A comment event: `comment_added`, `comment_changed` or `comment_deleted`. */
  apply(msg) {
    if (msg.type === 'comment_deleted') {
      this.comments.delete(msg.comment);
      if (this.focused === msg.comment) this.focused = null;
    } else this.comments.set(msg.comment.id, msg.comment);
    this.update();
  }

  /** A click of the tool on the model: `at` is { part, u, v } on a surface part or { part, xyz } elsewhere. */
  place(at) {
    if (!this.active) return;
    this.pending = at;
    this.draft.hidden = false;
    this.where.textContent = at.u !== undefined
      ? `on ${this.partName(at.part)} at (u, v) = (${at.u.toFixed(3)}, ${at.v.toFixed(3)})`
      : `on ${this.partName(at.part)}`;
    this.update();
    this.text.focus();
  }

  cancelDraft() {
    this.pending = null;
    if (document.activeElement === this.text) this.text.blur();
    this.draft.hidden = true;
    this.text.value = '';
    this.update();
  }

  /** Sends the draft; the pin appears for everyone when the server has stored it. */
  post() {
    const at = this.pending;
    const text = this.text.value;
    if (!at || !text.trim()) return;
    if (new TextEncoder().encode(text).length > MAX_COMMENT_BYTES) {
      this.where.textContent = `too long: at most ${MAX_COMMENT_BYTES} bytes`;
      return;
    }
    const anchor = at.u !== undefined ? { u: at.u, v: at.v } : { xyz: at.xyz };
    if (this.send({ type: 'add_comment', part: at.part, anchor, text }) === null) return;
    this.cancelDraft();
  }

  /** Sends comment or reply `id`'s new text; the list shows it when the server has stored it. */
  saveEdit(id, text) {
    if (!text.trim() || new TextEncoder().encode(text).length > MAX_COMMENT_BYTES) return;
    if (this.send({ type: 'edit_comment', comment: id, text }) === null) return;
    this.editing = null;
    this.render();
  }

  /**
   * The versions comments were written on: version → the ids of the
   * comments written on it or holding a reply written on it.
   */
  byVersion() {
    const out = new Map();
    const mark = (version, id) => {
      if (!out.has(version)) out.set(version, []);
      if (!out.get(version).includes(id)) out.get(version).push(id);
    };
    for (const c of this.comments.values()) {
      mark(c.version, c.id);
      for (const r of c.replies) mark(r.version, c.id);
    }
    return out;
  }

  /** Clicks in the list: resolve, reopen, edit, delete, or an entry (frames its pin). */
  clicked(e) {
    const b = e.target.closest('button');
    if (b && b.dataset.edit) {
      this.editing = Number(b.dataset.edit);
      this.render();
      const box = this.list.querySelector('form[data-edit-form] textarea');
      if (box) box.focus();
      return;
    }
    if (b && b.dataset.editCancel !== undefined) {
      this.editing = null;
      this.render();
      return;
    }
    if (b && b.dataset.resolve) {
      this.send({ type: 'resolve_comment', comment: Number(b.dataset.resolve), resolved: b.dataset.to === 'true' });
      return;
    }
    if (b && b.dataset.delete) {
      this.send({ type: 'delete_comment', comment: Number(b.dataset.delete) });
      return;
    }
    if (e.target.closest('form')) return;
    const li = e.target.closest('li[data-comment]');
    if (li) this.frame(Number(li.dataset.comment));
  }

  /** Centres the view on comment `id`'s pin, close enough to see where it is. */
  frame(id) {
    const c = this.comments.get(id);
    if (!c) return;
    this.focused = id;
    const { p } = pinPoint(c, this.geometryOf(c.part));
    const at = this.view.model.localToWorld(new THREE.Vector3(...p));
    const controls = this.view.controls;
    const offset = this.view.camera.position.clone().sub(controls.target);
    const sphere = this.view.boundingSphere();
    const r = sphere ? sphere.radius : offset.length();
    controls.target.copy(at);
    this.view.camera.position.copy(at).add(offset.setLength(r * 0.8));
    controls.update();
    this.update();
  }

  /** Rebuilds the pins (at the shapes shown now) and the list. */
  update() {
    for (const o of this.group.children) {
      o.traverse((m) => {
        if (m.geometry) m.geometry.dispose();
        if (m.material) m.material.dispose();
      });
    }
    this.group.clear();
    this.pins.clear();
    const sphere = this.view.boundingSphere();
    const size = sphere ? sphere.radius : 1;
    const pin = (id, c, colour) => {
      const { p, n } = pinPoint(c, this.geometryOf(c.part));
      if (!p || !p.every(Number.isFinite)) return;
      const g = new THREE.Group();
      g.position.set(...p);
      const len = size * 0.08;
      const tip = new THREE.Vector3(...n).multiplyScalar(len);
      const stem = new THREE.Line(
        new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), tip]),
        new THREE.LineBasicMaterial({ color: colour, depthTest: false }),
      );
      const head = new THREE.Mesh(
        new THREE.SphereGeometry(size * (id === this.focused ? 0.022 : 0.016), 14, 10),
        new THREE.MeshBasicMaterial({ color: colour, depthTest: false }),
      );
      head.position.copy(tip);
      const foot = new THREE.Mesh(new THREE.SphereGeometry(size * 0.005, 8, 6), new THREE.MeshBasicMaterial({ color: colour, depthTest: false }));
      for (const m of [stem, head, foot]) m.renderOrder = 11;
      g.add(stem, head, foot);
      g.userData = { commentId: id, point: p };
      this.group.add(g);
      this.pins.set(id, g);
    };
    for (const c of this.comments.values()) pin(c.id, c, c.resolved ? RESOLVED : OPEN);
    if (this.pending) pin(-1, { part: this.pending.part, anchor: this.pending.xyz ? { xyz: this.pending.xyz } : this.pending }, DRAFT);
    this.render();
  }

  render() {
    const all = [...this.comments.values()];
    const open = all.filter((c) => !c.resolved).length;
    this.count.textContent = all.length ? `${open} open · ${all.length - open} resolved` : 'none yet';
    // Replies being typed survive the list being redrawn.
    const typing = new Map([...this.list.querySelectorAll('form[data-reply] input')].filter((i) => i.value).map((i) => [i.closest('form').dataset.reply, i.value]));
    const focus = document.activeElement && this.list.contains(document.activeElement) ? document.activeElement.closest('form[data-reply]')?.dataset.reply : null;
    // So does an edit being typed.
    const editBox = this.list.querySelector('form[data-edit-form] textarea');
    const editTyped = editBox ? editBox.value : null;
    const when = (ms) => new Date(ms).toLocaleString();
    const text = (x) =>
      x.id === this.editing
        ? `<form data-edit-form="${x.id}"><textarea rows="3" maxlength="${MAX_COMMENT_BYTES}" aria-label="edit comment ${x.id}">${escape(x.text)}</textarea><button>save</button> <button type="button" data-edit-cancel>cancel</button></form>`
        : `<p>${escape(x.text)}</p>`;
    const editButton = (x) => `<button data-edit="${x.id}" title="change its text">edit</button>`;
    // A changed text says so (and when, on hover): a reader must not take it for what was first written.
    const edited = (x) => (x.edited_ms ? ` · <span class="edited" data-edited="${x.id}" title="edited ${when(x.edited_ms)}">edited</span>` : '');
    const who = (x) => `<b>${escape(x.author)}</b> <small>${x.access === 'viewer' ? 'reviewer' : x.access} · ${when(x.time_ms)} · on v${x.version}${edited(x)}</small>`;
    this.list.innerHTML = all
      .map((c) => {
        const mod = this.canModerate(c.access);
        const replies = c.replies
          .map((r) => `<li class="reply">${who(r)}${text(r)}${this.canModerate(r.access) ? `${editButton(r)} <button data-delete="${r.id}" title="delete this reply">delete</button>` : ''}</li>`)
          .join('');
        return `<li data-comment="${c.id}" class="${c.resolved ? 'resolved' : 'open'}${c.id === this.focused ? ' focused' : ''}" title="click to show its pin">
          ${who(c)} <span class="state">${c.resolved ? `resolved${c.resolved_by ? ` by ${escape(c.resolved_by)}` : ''}` : 'open'}</span>
          ${text(c)}
          ${mod ? `<button data-resolve="${c.id}" data-to="${!c.resolved}">${c.resolved ? 'reopen' : 'resolve'}</button> ${editButton(c)} <button data-delete="${c.id}">delete</button>` : ''}
          ${replies ? `<ul class="replies">${replies}</ul>` : ''}
          ${this.canComment() ? `<form data-reply="${c.id}"><input placeholder="reply" aria-label="reply to comment ${c.id}" maxlength="${MAX_COMMENT_BYTES}"> <button>reply</button></form>` : ''}
        </li>`;
      })
      .join('');
    const box = this.list.querySelector('form[data-edit-form] textarea');
    if (box && editTyped !== null) box.value = editTyped;
    for (const form of this.list.querySelectorAll('form[data-reply]')) {
      const input = form.querySelector('input');
      if (typing.has(form.dataset.reply)) input.value = typing.get(form.dataset.reply);
      if (focus === form.dataset.reply) input.focus();
    }
  }
}
