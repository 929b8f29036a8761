// The toolbar and the keyboard: undo and redo (the strokes' history in the Sketch tab, the
// take's in the Capture tab), delete, new, open, save, reopen, another character, play and
// stepping, help.

import { api } from './api.js';
import * as capture from './capture.js';
import { inCapture, onMode, setMode } from './mode.js';
import { lastFrame, pause, play, playBackwards, setFrame, step } from './playback.js';
import { toggleOverlays } from './overlays.js';
import { fitTimeline } from './timeline.js';
import { frameCamera } from './scene.js';
import { showError, showFailure, showStatus } from './status.js';
import * as store from './store.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));
const button = (id) => /** @type {HTMLButtonElement} */ (document.getElementById(id));

/** Steps back one edit of the tab shown. */
export function undo() { return inCapture() ? capture.undo() : store.run('POST', 'api/undo'); }
/** Steps forward one undone edit of the tab shown. */
export function redo() { return inCapture() ? capture.redo() : store.run('POST', 'api/redo'); }

/** Deletes the selected action. */
function deleteSelected() {
  const selected = store.selection();
  if (selected === null) return;
  store.select(null);
  return store.run('DELETE', `api/strokes/${selected}`);
}

async function save() {
  try { const r = await api('POST', 'api/project/save'); showError(''); showStatus(`Saved ${r.saved}`); }
  catch (e) { showFailure(e); }
}

/** Enables the buttons for what can be done now. */
function refreshButtons() {
  const state = store.state();
  const history = inCapture() ? capture.history() : { canUndo: !!(state && state.can_undo), canRedo: !!(state && state.can_redo) };
  button('undo').disabled = !history.canUndo;
  button('redo').disabled = !history.canRedo;
  button('delete').disabled = store.selection() === null;
}
store.onState((state) => {
  refreshButtons();
  showStatus(`${state.actions.length} action(s); ${state.rejected.length} stroke(s) ignored; project: ${state.project_path}`);
});
store.onSelection(refreshButtons);
onMode(refreshButtons);
capture.onChange(refreshButtons);

$('undo').onclick = undo;
$('redo').onclick = redo;
$('delete').onclick = deleteSelected;
$('save').onclick = save;
$('reopen').onclick = () => store.run('POST', 'api/project/reopen');
$('new').onclick = () => store.run('POST', 'api/project/new');
$('play').onclick = play;
$('open').onclick = () => $('project-file').click();
$('project-file').addEventListener('change', async (e) => {
  const file = /** @type {HTMLInputElement} */ (e.target).files?.[0];
  if (!file) return;
  try { store.setState(await api('PUT', 'api/project', await file.arrayBuffer()), true); showError(''); }
  catch (err) { showError(`${file.name}: ${err.message || err}`); }
});

// Each character read (the first, another opened, one given blendshapes): its name in the
// toolbar, the camera on its head, and the sketch's VRM Animation download where it is a VRM.
store.onCharacter((character) => {
  $('character-name').textContent = character.name;
  frameCamera(character.head);
  $('export-vrma').hidden = !character.vrm;
});

/** Opens another character (a .glb or self-contained .gltf); the project starts empty. */
async function uploadCharacter(file) {
  showError('');
  showStatus(`Opening ${file.name}…`);
  try {
    const result = await api('POST', 'api/character/upload', await file.arrayBuffer(), { 'x-filename': encodeURIComponent(file.name) });
    await store.loadCharacter();
    store.setState(result.state, true);
    if (result.warnings.length) showError(result.warnings.join('\n'));
  } catch (err) { showFailure(err); showStatus(`Could not open ${file.name}; still on ${store.character().name}.`); }
}
$('open-character').onclick = () => $('character-file').click();
$('character-file').addEventListener('change', (e) => { const f = /** @type {HTMLInputElement} */ (e.target).files?.[0]; if (f) uploadCharacter(f); });
const viewport = $('viewport');
viewport.addEventListener('dragover', (e) => { e.preventDefault(); viewport.classList.add('dragover'); });
viewport.addEventListener('dragleave', () => viewport.classList.remove('dragover'));
// A character opens as the character; speech (lip sync, with its transcript when dropped
// with it), video and photos open as the take, as when picked.
viewport.addEventListener('drop', (e) => {
  e.preventDefault();
  viewport.classList.remove('dragover');
  const files = [...(e.dataTransfer?.files || [])];
  if (!files.length) return;
  if (files.length === 1 && /\.(glb|gltf|vrm)$/i.test(files[0].name)) uploadCharacter(files[0]);
  else { setMode('capture'); capture.openInput(files); }
});
$('help-button').onclick = () => { $('help').hidden = !$('help').hidden; };
$('help-close').onclick = () => { $('help').hidden = true; };
$('step-back').onclick = () => step(-1);
$('step-forward').onclick = () => step(1);
$('play-back').onclick = playBackwards;
// Typing a frame number moves the playhead there (whole frames).
$('current-frame').addEventListener('change', (e) => {
  const typed = Number(/** @type {HTMLInputElement} */ (e.target).value);
  if (Number.isFinite(typed)) { pause(); setFrame(Math.round(typed)); }
});

window.addEventListener('keydown', (e) => {
  if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
  const ctrl = e.ctrlKey || e.metaKey;
  if (ctrl && e.key.toLowerCase() === 'z') { e.preventDefault(); (e.shiftKey ? redo : undo)(); }
  else if (ctrl && e.key.toLowerCase() === 'y') { e.preventDefault(); redo(); }
  else if (ctrl && e.key.toLowerCase() === 's') { e.preventDefault(); save(); }
  else if (e.key === 'Delete' || e.key === 'Backspace') deleteSelected();
  else if (e.key === ' ') { e.preventDefault(); play(); }
  else if (e.key === 'ArrowRight') step(1);
  else if (e.key === 'ArrowLeft') step(-1);
  else if (e.key === 'j') playBackwards();
  else if (e.key === 'k') pause();
  else if (e.key === 'l') { pause(); play(); }
  else if (e.key === 'Home' && e.shiftKey) setFrame(0);
  else if (e.key === 'Home') fitTimeline();
  else if (e.key === 'End') setFrame(lastFrame());
  else if (e.altKey && e.shiftKey && e.key.toLowerCase() === 'z') toggleOverlays();
  else if (e.key === 'f') frameCamera(store.character().head);
  else if (e.key === 'F') frameCamera(store.character().bounds, 0.5, 0.9);
  else if (e.key === '?') $('help').hidden = !$('help').hidden;
  else if (e.key === 'Escape') $('help').hidden = true;
});
