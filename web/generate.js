// "Generate blendshapes": offered when the character has none (a scan, a sculpt, an avatar
// exported without shape keys). The server makes ARKit's 52 on it (as `faceanim
// generate-shapes` does), writes NAME.shapes.glb beside the project (the user's own file is
// never written) and opens it; a character whose file says its shapes were generated says so.

import { api } from './api.js';
import { showError, showFailure, showStatus } from './status.js';
import * as store from './store.js';

const button = /** @type {HTMLButtonElement} */ (document.getElementById('generate-shapes'));
const note = /** @type {HTMLElement} */ (document.getElementById('generated-note'));

store.onCharacter((character) => {
  button.hidden = character.blendshapes.length > 0;
  const generated = character.generated;
  note.hidden = !generated;
  note.textContent = generated ? `${generated.count} generated shapes` : '';
  note.title = generated
    ? `Blendshapes made by faceanim generate-shapes from the template ${generated.template}`
    : '';
});

button.onclick = async () => {
  button.disabled = true;
  showError('');
  showStatus('Generating blendshapes: finding the face, fitting the template, moving its 52 shapes onto this head…');
  try {
    const result = await api('POST', 'api/character/generate-shapes', {});
    await store.loadCharacter();
    store.setState(result.state, true);
    showStatus(`${result.shapes.length} blendshapes made; written to ${result.written}.`);
  } catch (err) {
    showFailure(err);
    showStatus('No blendshapes were made.');
  } finally {
    button.disabled = false;
  }
};
