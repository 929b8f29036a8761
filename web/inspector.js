// The Action inspector: the selected action's target, weight, exaggeration, ease (with its
// timing curve as the engine plays it), start, duration and mirror, shown and typed. Every
// edit is one PATCH of the stroke, so it undoes like a handle drag.

import { api } from './api.js';
import * as store from './store.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));
const field = (id) => /** @type {HTMLInputElement} */ (document.getElementById(id));

/** The selected action, or null. */
function selectedAction() {
  const state = store.state();
  const stroke = store.selection();
  return state && stroke !== null ? state.actions.find((a) => a.stroke === stroke) || null : null;
}

/** Sets an input's value unless the user is typing in it. */
function show(id, value) {
  const input = field(id);
  if (document.activeElement !== input) input.value = value;
}

/** The candidates (`name`, `position`) the stroke's start reaches, for the target list. */
let reachable = { stroke: -1, start: '', names: /** @type {any[]} */ ([]) };

async function fillTargets(action) {
  const side = action.sides[0];
  const key = JSON.stringify([side.start, action.start_frame]);
  const select = /** @type {HTMLSelectElement} */ ($('inspect-target'));
  if (reachable.stroke !== action.stroke || reachable.start !== key) {
    reachable = { stroke: action.stroke, start: key, names: [] };
    try {
      const found = await api('POST', 'api/candidates', { point: side.start, frame: action.start_frame });
      reachable.names = found ? found.candidates.filter((c) => c.name) : [];
    } catch { reachable.names = []; }
  }
  const names = reachable.names.map((c) => c.name);
  if (side.target && !names.includes(side.target)) names.unshift(side.target);
  select.innerHTML = '';
  for (const name of names) {
    const option = document.createElement('option');
    option.value = name; option.textContent = name;
    select.appendChild(option);
  }
  if (!side.target) {
    const option = document.createElement('option');
    option.value = ''; option.textContent = side.goal;
    select.prepend(option);
  }
  select.value = side.target || '';
}

function drawCurve(progress) {
  const canvas = /** @type {HTMLCanvasElement} */ ($('inspect-curve'));
  const g = canvas.getContext('2d');
  if (!g) return;
  const { width: w, height: h } = canvas;
  g.clearRect(0, 0, w, h);
  g.strokeStyle = '#555b66'; g.strokeRect(0.5, 0.5, w - 1, h - 1);
  g.strokeStyle = '#f0d020'; g.lineWidth = 2; g.beginPath();
  progress.forEach((p, k) => { const x = 2 + (w - 4) * k / (progress.length - 1), y = h - 2 - (h - 4) * p; if (k) g.lineTo(x, y); else g.moveTo(x, y); });
  g.stroke();
}

/** The runners-up of a stroke just drawn: `{stroke, candidates}`. */
let alternatives = { stroke: -1, candidates: /** @type {any[]} */ ([]) };

/** Offers `candidates` (the targets nearest the stroke's end after the one chosen) as one-click
 * re-targets of stroke `stroke`. */
export function offerAlternatives(stroke, candidates) {
  alternatives = { stroke, candidates };
  refresh();
}

function showAlternatives(action) {
  const box = $('inspect-alternatives');
  const offered = alternatives.stroke === action.stroke ? alternatives.candidates.filter((c) => c.name !== action.sides[0].target) : [];
  box.hidden = offered.length === 0;
  box.innerHTML = '';
  if (!offered.length) return;
  box.append('Or instead: ');
  for (const c of offered) {
    const choice = document.createElement('button');
    choice.textContent = c.name;
    choice.title = `Re-target this action to ${c.name} at full weight`;
    choice.onclick = () => { alternatives = { stroke: -1, candidates: [] }; edit(() => ({ end: c.position })); };
    box.appendChild(choice);
  }
}

function refresh() {
  const action = selectedAction();
  $('inspector-empty').hidden = !!action;
  $('inspector-fields').hidden = !action;
  if (!action) return;
  const side = action.sides[0];
  show('inspect-weight', side.weight.toFixed(2));
  field('inspect-weight').disabled = side.goal !== 'blendshape';
  // In the character's size, as the settings speak: a distance of 1e-8 is rounding, not a pose.
  const percent = 100 * side.exaggeration / Math.max(1e-9, store.character().diagonal);
  $('inspect-exaggeration').textContent = percent >= 0.05 ? `${percent.toFixed(1)} % of the character's size` : 'none';
  show('inspect-ease', action.ease.toFixed(2));
  show('inspect-start', String(Math.round(action.start_frame)));
  show('inspect-duration', String(Math.round(action.end_frame - action.start_frame)));
  field('inspect-mirrored').checked = action.symmetric;
  $('inspect-unmirrored').hidden = !action.unmirrored;
  $('inspect-unmirrored').textContent = action.unmirrored || '';
  drawCurve(action.progress);
  fillTargets(action);
  showAlternatives(action);
}
store.onState(refresh);
store.onSelection(refresh);

/** Sends `edit` for the selected action (one undoable step). */
function edit(change) {
  const action = selectedAction();
  if (action) store.run('PATCH', `api/strokes/${action.stroke}`, change(action));
}

const number = (id) => Number(field(id).value);
field('inspect-weight').addEventListener('change', () => edit((action) => {
  // The end moves along the way from the stroke's start to the target at full weight.
  const side = action.sides[0];
  const w = Math.min(1, Math.max(0, number('inspect-weight')));
  return { end: side.start.map((a, i) => a + w * (side.target_position[i] - a)) };
}));
$('inspect-target').addEventListener('change', () => edit(() => {
  const name = /** @type {HTMLSelectElement} */ ($('inspect-target')).value;
  const candidate = reachable.names.find((c) => c.name === name);
  return candidate ? { end: candidate.position } : {};
}));
field('inspect-ease').addEventListener('change', () => edit(() => ({ ease: number('inspect-ease') })));
field('inspect-start').addEventListener('change', () => edit(() => ({ start_frame: number('inspect-start') })));
field('inspect-duration').addEventListener('change', () => edit(() => ({ duration: number('inspect-duration') })));
field('inspect-mirrored').addEventListener('change', () => edit(() => ({ symmetry: field('inspect-mirrored').checked })));
