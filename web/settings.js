// The settings panel (seed figure 11): symmetry, stroke mode, selection, falloff, the
// distances (blank: derived from the character's size, shown as placeholders), sampling, and
// the project's frame rate. Every change is sent whole; the server validates it.

import * as store from './store.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

const numberFields = ['stroke_thickness', 'candidate_radius', 'pen_distance', 'edit_radius', 'hook_radius'];
function fillSettings(state) {
  const s = state.settings;
  /** @type {HTMLInputElement} */ ($('symmetry')).checked = !!s.symmetry;
  /** @type {HTMLSelectElement} */ ($('falloff')).value = s.falloff;
  /** @type {HTMLSelectElement} */ ($('mode')).value = s.mode;
  /** @type {HTMLSelectElement} */ ($('selection')).value = s.selection;
  /** @type {HTMLInputElement} */ ($('subsample')).value = s.subsample;
  for (const f of numberFields) {
    const input = /** @type {HTMLInputElement} */ ($(f));
    if (document.activeElement !== input) { input.value = s[f] === null || s[f] === undefined ? '' : percent(s[f]); input.placeholder = percent(state.resolved[f]); }
  }
  const r = state.resolved;
  $('resolved').textContent = `In use, in % of the character's size: candidate radius ${percent(r.candidate_radius)}, pen ${percent(r.pen_distance)}, editing ${percent(r.edit_radius)}, hook ${percent(r.hook_radius)}`;
}
/** The character's size (its bounding box's diagonal), which distances are shown relative to. */
const size = () => Math.max(1e-9, store.character() ? store.character().diagonal : 1);
/** A distance in the character's units as a percentage of its size, for display. */
const percent = (distance) => String(Number((100 * distance / size()).toPrecision(3)));

function settingsFromPanel() {
  const s = { ...store.state().settings };
  s.symmetry = /** @type {HTMLInputElement} */ ($('symmetry')).checked;
  s.falloff = /** @type {HTMLSelectElement} */ ($('falloff')).value;
  s.mode = /** @type {HTMLSelectElement} */ ($('mode')).value;
  s.selection = /** @type {HTMLSelectElement} */ ($('selection')).value;
  s.subsample = Math.max(1, Math.round(Number(/** @type {HTMLInputElement} */ ($('subsample')).value) || 1));
  for (const f of numberFields) { const v = /** @type {HTMLInputElement} */ ($(f)).value; s[f] = v === '' ? null : Number(v) / 100 * size(); }
  return s;
}
for (const id of ['symmetry', 'falloff', 'mode', 'selection', 'subsample', ...numberFields]) {
  $(id).addEventListener('change', () => store.run('PUT', 'api/settings', settingsFromPanel()));
}
$('fps').addEventListener('change', () => store.run('PUT', 'api/fps', { fps: Number(/** @type {HTMLInputElement} */ ($('fps')).value) }));

store.onState((state) => {
  fillSettings(state);
  if (document.activeElement !== $('fps')) /** @type {HTMLInputElement} */ ($('fps')).value = state.fps;
});
