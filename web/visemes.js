// Lip sync's viseme table, edited in the Capture tab: how each of the 15 visemes moves an
// ARKit rig's mouth (channel → value), as JSON the server checks field by field and keeps
// beside the project (the same file `faceanim lipsync --viseme-table` reads). Speech opened
// afterwards and the live microphone use it.

import { api } from './api.js';
import { showError } from './status.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));
const text = /** @type {HTMLTextAreaElement} */ ($('visemes-table'));

/** The last table the server gave (`window.studio.capture.visemes`). */
export const visemes = { /** @type {any} */ view: null };

const ROUTE_TEXT = {
  visemes: 'This character has its own viseme shapes: the table is not used.',
  arkit: 'This character lip-syncs through its ARKit mouth shapes, by this table.',
  adapter: 'This character has no mouth names: its adapter reads the built-in head making each viseme by this table.',
  retarget: 'This character has no mouth names: its retarget map puts each viseme of this table on its own shapes.',
  jaw_bone: 'This character has no blendshapes: its jaw bone opens by each viseme\'s jawOpen in this table.',
};

function show(/** @type {any} */ view) {
  visemes.view = view;
  text.value = JSON.stringify(view.visemes, null, 1);
  $('visemes-note').textContent = `${view.route ? ROUTE_TEXT[view.route] : view.no_mouth}${view.default ? ' (The built-in table.)' : ''}`;
}

async function send(/** @type {string} */ body) {
  try {
    showError('');
    show(await api('PUT', 'api/capture/visemes', new Blob([body])));
  } catch (e) { showError(String(e.message || e)); }
}

// Loaded when the section is first opened.
$('visemes').addEventListener('toggle', async () => {
  if (!/** @type {HTMLDetailsElement} */ ($('visemes')).open || visemes.view) return;
  try { show(await api('GET', 'api/capture/visemes')); } catch (e) { showError(String(e.message || e)); }
});
$('visemes-apply').onclick = () => send(text.value);
$('visemes-reset').onclick = () => send('{}');
