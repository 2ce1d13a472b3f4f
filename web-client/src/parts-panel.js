// The parts panel: the list of a design's parts (colour swatch, name, kind,
// shown or hidden, locked or not) where a part is selected, shown or hidden,
// locked, renamed, recoloured and deleted; the joins and bindings between
// parts, each with a button to undo it; the join tool (two edges, G0 or G1)
// the binding tool (a surface's parameter line follows a curve part) and the
// FFD tool (the selected surface, curve or DSM part follows a body). It
// draws from the design model and says what the person asked through
// callbacks; app.js turns those into protocol messages. Every control is a
// real button, input or select, so the keyboard reaches all of them; the
// name being edited takes Enter to rename and Esc to cancel.

/** Edges of a surface part, the parameter held fixed along each (protocol/README.md, relate). */
const EDGES = ['u_min', 'u_max', 'v_min', 'v_max'];

function escape(s) {
  return String(s).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
}

export class PartsPanel {
  /**
   * @param {object} o
   * @param {HTMLElement} o.list the <ul> of parts
   * @param {HTMLElement} o.relations the <ul> of joins and bindings
   * @param {HTMLFormElement} o.joinForm the join tool's form
   * @param {HTMLFormElement} o.bindForm the binding tool's form
   * @param {HTMLFormElement} o.ffdForm the FFD tool's form (bind the selected part to a body)
   * @param {(id: number) => void} o.onSelect
   * @param {(id: number, visible: boolean) => void} o.onVisible
   * @param {(id: number, locked: boolean) => void} o.onLock
   * @param {(id: number, name: string) => void} o.onRename
   * @param {(id: number, colour: string) => void} o.onColour
   * @param {(id: number) => void} o.onDelete
   * @param {(relation: object) => void} o.onJoin
   * @param {(relation: object) => void} o.onBind
   * @param {(relation: object) => void} o.onFfd
   * @param {(id: number) => void} o.onUnrelate
   */
  constructor(o) {
    Object.assign(this, o);
    /** The part whose name is being edited, or null. */
    this.renaming = null;
    this.signature = null;
    this.list.addEventListener('click', (e) => this.click(e));
    this.list.addEventListener('change', (e) => {
      const id = Number(e.target.closest('[data-part]')?.dataset.part);
      if (e.target.matches('input[type=color]')) this.onColour(id, e.target.value);
    });
    this.list.addEventListener('keydown', (e) => {
      if (!e.target.matches('input.rename')) return;
      const id = Number(e.target.closest('[data-part]').dataset.part);
      if (e.key === 'Enter') {
        e.preventDefault();
        const name = e.target.value.trim();
        this.renaming = null;
        if (name) this.onRename(id, name);
        this.render(this.last, true);
      } else if (e.key === 'Escape') {
        e.preventDefault();
        e.stopPropagation();
        this.renaming = null;
        this.render(this.last, true);
      }
    });
    this.list.addEventListener('focusout', (e) => {
      if (e.target.matches('input.rename') && this.renaming !== null) {
        this.renaming = null;
        queueMicrotask(() => this.render(this.last, true));
      }
    });
    this.relations.addEventListener('click', (e) => {
      const r = e.target.dataset.unrelate;
      if (r) this.onUnrelate(Number(r));
    });
    this.joinForm.addEventListener('submit', (e) => {
      e.preventDefault();
      const f = this.joinForm.elements;
      this.onJoin({
        kind: 'join',
        a: { part: Number(f['join-a'].value), edge: f['join-a-edge'].value },
        b: { part: Number(f['join-b'].value), edge: f['join-b-edge'].value },
        continuity: f['join-continuity'].value,
        reversed: f['join-reversed'].checked,
      });
    });
    this.bindForm.addEventListener('submit', (e) => {
      e.preventDefault();
      const f = this.bindForm.elements;
      const at = Number(f['bind-at'].value);
      this.onBind({
        kind: 'binding',
        curve: Number(f['bind-curve'].value),
        surface: Number(f['bind-surface'].value),
        line: f['bind-along'].value === 'u' ? { u: at } : { v: at },
        reversed: f['bind-reversed'].checked,
      });
    });
    this.ffdForm.addEventListener('submit', (e) => {
      e.preventDefault();
      const selected = this.last && this.last.selected;
      const body = Number(this.ffdForm.elements['ffd-body'].value);
      if (selected == null || !body) return;
      this.onFfd({ kind: 'ffd', body, part: selected });
    });
    this.ffdForm.elements['ffd-unbind'].addEventListener('click', () => {
      const r = this.ffdOf(this.last && this.last.selected);
      if (r) this.onUnrelate(r.id);
    });
    for (const name of ['join-a-edge', 'join-b-edge']) {
      this.joinForm.elements[name].innerHTML = EDGES.map((e) => `<option value="${e}">${e.replace('_', ' ')}</option>`).join('');
    }
    this.joinForm.elements['join-b-edge'].value = 'u_min';
    this.joinForm.elements['join-a-edge'].value = 'u_max';
  }

  click(e) {
    const row = e.target.closest('[data-part]');
    if (!row) return;
    const id = Number(row.dataset.part);
    const part = this.last && this.last.design.parts.get(id);
    if (!part) return;
    const b = e.target.closest('button');
    if (!b) return;
    if (b.dataset.act === 'select') this.onSelect(id);
    else if (b.dataset.act === 'visible') this.onVisible(id, !this.shown(part));
    else if (b.dataset.act === 'lock') this.onLock(id, !part.locked);
    else if (b.dataset.act === 'delete') this.onDelete(id);
    else if (b.dataset.act === 'rename') {
      this.renaming = id;
      this.render(this.last, true);
      const input = this.list.querySelector('input.rename');
      if (input) {
        input.focus();
        input.select();
      }
    }
  }

  /** The FFD relation binding part `id` to a body, if any. */
  ffdOf(id) {
    if (id == null || !this.last) return null;
    return [...this.last.design.relations.values()].find((r) => r.kind === 'ffd' && r.part === id) || null;
  }

  /** Whether part `part` is drawn on this page. */
  shown(part) {
    return part.visible && !this.last.hidden.has(part.id);
  }

  /**
   * Draws the panel for `{ design, selected, hidden, editor, online }`;
   * skipped when nothing it shows changed (so a colour picker or a name
   * being typed survives unrelated events), unless `force`.
   */
  render(view, force = false) {
    this.last = view;
    const { design, selected, hidden, editor, online } = view;
    const parts = [...design.parts.values()].filter((p) => !p.provisional);
    const signature = JSON.stringify([
      parts.map((p) => [p.id, p.name, p.kind, p.colour, p.visible, p.locked, hidden.has(p.id)]),
      [...design.relations.values()],
      selected,
      editor,
      online,
      this.renaming,
    ]);
    if (!force && signature === this.signature) return;
    this.signature = signature;
    const off = online ? '' : ' disabled';
    // A re-render keeps the keyboard where it was: the same control of the same part.
    const active = document.activeElement;
    const focus = active && this.list.contains(active) && active.closest('[data-part]')
      ? { part: active.closest('[data-part]').dataset.part, act: active.dataset.act, colour: active.type === 'color' }
      : null;
    this.list.innerHTML = parts
      .map((p) => {
        const shown = p.visible && !hidden.has(p.id);
        const name =
          this.renaming === p.id
            ? `<input class="rename" value="${escape(p.name)}" aria-label="new name of ${escape(p.name)}" maxlength="200">`
            : `<button class="part-name" data-act="select" aria-pressed="${p.id === selected}" title="select ${escape(p.name)}">${escape(p.name)}</button>`;
        return `<li data-part="${p.id}" class="part${p.id === selected ? ' selected' : ''}${shown ? '' : ' hidden-part'}${p.locked ? ' locked' : ''}">
          <input type="color" value="${escape(p.colour)}" aria-label="colour of ${escape(p.name)}"${editor ? off : ' disabled'}>
          ${name} <small class="kind">${p.kind}</small>
          <span class="part-tools">
            <button data-act="visible" aria-pressed="${!shown}" title="${shown ? 'hide' : 'show'} ${escape(p.name)}">${shown ? 'hide' : 'show'}</button>
            <span class="edit">
              <button data-act="lock" aria-pressed="${p.locked}" title="${p.locked ? 'unlock' : 'lock'} ${escape(p.name)}"${off}>${p.locked ? 'unlock' : 'lock'}</button>
              <button data-act="rename" title="rename ${escape(p.name)}"${off}>rename</button>
              <button data-act="delete" title="delete ${escape(p.name)}"${off}>delete</button>
            </span>
          </span>
          ${p.locked ? '<small class="lock-note">locked</small>' : ''}
        </li>`;
      })
      .join('');
    if (focus) {
      const row = this.list.querySelector(`[data-part="${focus.part}"]`);
      const el = row && (focus.colour ? row.querySelector('input[type=color]') : focus.act ? row.querySelector(`[data-act="${focus.act}"]`) : null);
      if (el) el.focus();
    }
    const nameOf = (id) => escape(design.parts.get(id)?.name ?? `part ${id}`);
    this.relations.innerHTML = [...design.relations.values()]
      .map((r) => {
        const what =
          r.kind === 'join'
            ? `join ${nameOf(r.a.part)} ${r.a.edge} ↔ ${nameOf(r.b.part)} ${r.b.edge} (${String(r.continuity).toUpperCase()}${r.reversed ? ', reversed' : ''})`
            : r.kind === 'ffd'
              ? `ffd: ${nameOf(r.part)} follows body ${nameOf(r.body)}`
              : `binding: ${nameOf(r.surface)} along ${r.line ? Object.entries(r.line).map(([k, x]) => `${k} = ${x}`).join('') : 'a line'} follows ${nameOf(r.curve)}${r.reversed ? ' (reversed)' : ''}`;
        const act = r.kind === 'ffd' ? 'unbind' : 'remove';
        return `<li data-relation="${r.id}">${what} <button class="edit" data-unrelate="${r.id}"${off}>${act}</button></li>`;
      })
      .join('');
    // The join tool offers the surface parts; the binding tool surfaces and curves.
    const surfaces = parts.filter((p) => p.kind === 'surface');
    const curves = parts.filter((p) => p.kind === 'curve');
    const choices = [
      [this.joinForm.elements['join-a'], surfaces, 0],
      [this.joinForm.elements['join-b'], surfaces, 1],
      [this.bindForm.elements['bind-surface'], surfaces, 0],
      [this.bindForm.elements['bind-curve'], curves, 0],
    ];
    const bodies = parts.filter((p) => p.kind === 'body');
    choices.push([this.ffdForm.elements['ffd-body'], bodies, 0]);
    for (const [sel, list, name] of choices) {
      const keep = sel.value;
      sel.innerHTML = list.map((p) => `<option value="${p.id}">${escape(p.name)}</option>`).join('');
      if (list.some((p) => String(p.id) === keep)) sel.value = keep;
      else if (list[name]) sel.value = String(list[name].id);
    }
    // The FFD tool acts on the selected part: bind it (a surface, curve or
    // DSM part not bound yet) or unbind it.
    const f = this.ffdForm.elements;
    const chosen = selected != null ? design.parts.get(selected) : null;
    const bound = this.ffdOf(selected);
    const bindable = chosen && ['surface', 'curve', 'dsm'].includes(chosen.kind) && !bound;
    f['ffd-part'].value = chosen ? chosen.name : 'the selected part';
    f['ffd-bind'].disabled = !online || !bindable || !bodies.length;
    f['ffd-unbind'].hidden = !bound;
    f['ffd-unbind'].disabled = !online;
  }
}
