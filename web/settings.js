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
    if (document.activeElement !== input) { input.value = s[f] ?? ''; input.placeholder = state.resolved[f].toPrecision(3); }
  }
  $('resolved').textContent = `In use: candidate radius ${state.resolved.candidate_radius.toPrecision(3)}, pen ${state.resolved.pen_distance.toPrecision(3)}, editing ${state.resolved.edit_radius.toPrecision(3)}, hook ${state.resolved.hook_radius.toPrecision(3)}`;
}
function settingsFromPanel() {
  const s = { ...store.state().settings };
  s.symmetry = /** @type {HTMLInputElement} */ ($('symmetry')).checked;
  s.falloff = /** @type {HTMLSelectElement} */ ($('falloff')).value;
  s.mode = /** @type {HTMLSelectElement} */ ($('mode')).value;
  s.selection = /** @type {HTMLSelectElement} */ ($('selection')).value;
  s.subsample = Math.max(1, Math.round(Number(/** @type {HTMLInputElement} */ ($('subsample')).value) || 1));
  for (const f of numberFields) { const v = /** @type {HTMLInputElement} */ ($(f)).value; s[f] = v === '' ? null : Number(v); }
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
