// The DSM panel (paper 001): for the selected DSM part, its primitives group
// by group — type, centre and the parameters of its kind (radius, half
// extents, density D and reducing factor a, a net's heights) — each with
// inputs to move it and change its parameters, a button to remove it, and a
// tool to add a primitive. It says what the person asked as `dsm_edit`
// edits through a callback; app.js sends them. Every control is a real
// input or button, so the keyboard reaches all of them.

function escape(s) {
  return String(s).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
}

/** The editable parameters of each primitive type (a net's heights are dragged node by node). */
const PARAMS = {
  box: ['half'],
  cylinder: ['radius', 'half_height'],
  sphere: ['radius'],
  density_sphere: ['density', 'reducing'],
  density_pipe: ['length', 'density', 'reducing'],
  net: [],
};

/** A new primitive of `type` with id `id` at `at`. */
export function newPrimitive(type, id, at) {
  const shapes = {
    sphere: { type: 'sphere', radius: 0.5 },
    box: { type: 'box', half: [0.5, 0.5, 0.5] },
    density_sphere: { type: 'density_sphere', density: 3.0, reducing: 2.0 },
    cylinder: { type: 'cylinder', radius: 0.3, half_height: 0.5 },
  };
  return { id, at, shape: shapes[type] };
}

const num = (x) => Number(x).toPrecision(6).replace(/\.?0+$/, '');

export class DsmPanel {
  /**
   * @param {object} o
   * @param {HTMLElement} o.section the panel's <section> (hidden unless a DSM part is selected)
   * @param {(part: number, edit: object) => void} o.onEdit
   */
  constructor(o) {
    Object.assign(this, o);
    this.part = null;
    this.signature = null;
    this.section.addEventListener('click', (e) => this.click(e));
  }

  /** Draws the panel for `part` (the selected part, any kind); `editor` enables the controls. */
  render(part, editor) {
    const dsm = part && part.kind === 'dsm' ? part.dsm : null;
    this.section.hidden = !dsm;
    if (!dsm) {
      this.part = null;
      this.signature = null;
      return;
    }
    const sig = JSON.stringify([part.id, dsm, editor]);
    if (sig === this.signature) return;
    this.signature = sig;
    this.part = part;
    const dis = editor ? '' : ' disabled';
    const input = (name, value) => `<input name="${name}" type="number" step="any" value="${num(value)}" aria-label="${name}"${dis}>`;
    const rows = [];
    dsm.groups.forEach((g, k) => {
      rows.push(`<li class="dsm-group"><b>group ${k}</b> <small>${escape(g.op)}${g.incorporated && g.incorporated.length ? ` · incorporates ${g.incorporated.join(', ')}` : ''}</small></li>`);
      for (const p of g.primitives) {
        const s = p.shape;
        const params = PARAMS[s.type]
          .map((key) => (Array.isArray(s[key]) ? s[key].map((x, i) => input(`${key}.${i}`, x)).join('') : input(key, s[key])))
          .join(' ');
        rows.push(`<li class="dsm-prim" data-id="${p.id}" data-type="${s.type}">
          <span>#${p.id} ${escape(s.type)}${s.negative ? ' (−)' : ''}</span>
          <span>at ${p.at.map((x, i) => input(`at.${i}`, x)).join('')}</span>
          <span>${params}</span>
          <button data-apply="${p.id}"${dis}>apply</button> <button data-remove="${p.id}"${dis}>remove</button></li>`);
      }
    });
    // What the person has typed and not yet applied survives a redraw
    // caused by someone else's edit: an input whose value differs from the
    // value it was drawn with keeps it, if its primitive is still there.
    const typed = [...this.section.querySelectorAll('input, select')]
      .filter((i) => (i.tagName === 'SELECT' ? i.selectedIndex > 0 : i.value !== i.defaultValue))
      .map((i) => [i.closest('li')?.dataset.id ?? null, i.name, i.value]);
    this.section.innerHTML = `<h2>DSM primitives <small>D_e ${num(dsm.de)} · ${dsm.cells} cells</small></h2>
      <ul class="dsm-list">${rows.join('')}</ul>
      <div class="dsm-add">add <select name="add-type"${dis}><option value="density_sphere">density sphere</option><option value="sphere">sphere</option><option value="box">box</option><option value="cylinder">cylinder</option></select>
      to group <input name="add-group" type="number" min="0" step="1" value="0"${dis}>
      at ${[0, 0, 0].map((x, i) => input(`add-at.${i}`, x)).join('')}
      <button data-add="1"${dis}>add</button></div>`;
    for (const [id, name, value] of typed) {
      const scope = id === null ? this.section.querySelector('.dsm-add') : this.section.querySelector(`li[data-id="${id}"]`);
      const el = scope && scope.querySelector(`[name="${name}"]`);
      if (el) el.value = value;
    }
  }

  /** The value of input `name` inside `el`. */
  value(el, name) {
    const i = el.querySelector(`input[name="${name}"]`);
    return i ? Number(i.value) : NaN;
  }

  /**
   * The value of parameter input `name` inside `el`: `exact` (the stored
   * value) unless the person changed what the input was drawn with — the
   * input shows six significant digits, and reading those back would be an
   * edit nobody asked for.
   */
  edited(el, name, exact) {
    const i = el.querySelector(`input[name="${name}"]`);
    return i && i.value !== i.defaultValue ? Number(i.value) : exact;
  }

  click(e) {
    const b = e.target.closest('button');
    if (!b || !this.part) return;
    const dsm = this.part.dsm;
    const prims = dsm.groups.flatMap((g) => g.primitives);
    if (b.dataset.remove) {
      this.onEdit(this.part.id, { op: 'remove_primitive', id: Number(b.dataset.remove) });
    } else if (b.dataset.apply) {
      const id = Number(b.dataset.apply);
      const li = b.closest('li');
      const p = prims.find((q) => q.id === id);
      if (!p) return;
      const at = [0, 1, 2].map((i) => this.edited(li, `at.${i}`, p.at[i]));
      if (at.some((x, i) => x !== p.at[i])) this.onEdit(this.part.id, { op: 'move_primitive', id, at });
      const s = p.shape;
      const shape = { ...s };
      let changed = false;
      for (const key of PARAMS[s.type]) {
        if (Array.isArray(s[key])) shape[key] = s[key].map((x, i) => this.edited(li, `${key}.${i}`, x));
        else shape[key] = this.edited(li, key, s[key]);
        if (JSON.stringify(shape[key]) !== JSON.stringify(s[key])) changed = true;
      }
      if (!changed) return;
      if (s.type === 'density_sphere') this.onEdit(this.part.id, { op: 'set_density', id, density: shape.density, reducing: shape.reducing });
      else this.onEdit(this.part.id, { op: 'resize_primitive', id, shape });
    } else if (b.dataset.add) {
      const el = this.section;
      const type = el.querySelector('select[name="add-type"]').value;
      const group = Number(el.querySelector('input[name="add-group"]').value);
      const at = [0, 1, 2].map((i) => this.value(el, `add-at.${i}`));
      const id = prims.reduce((m, q) => Math.max(m, q.id), 0) + 1;
      this.onEdit(this.part.id, { op: 'add_primitive', group, primitive: newPrimitive(type, id, at) });
    }
  }
}
