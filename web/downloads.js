// The page's downloads. A link to one of the API's files (`<a href="api/…" download>`) is
// fetched here before it is saved: when the server refuses (nothing to write, a character that
// is no VRM), its message goes to the error banner instead of a browser's bare "Failed"; when
// it answers, the file is saved under the name the server gives and the exporter's notes (what
// the file carries, what it left out) go to the status line.

import { showError, showStatus } from './status.js';

/** The header the server's notes come in (crates/studio/src/http.rs `NOTES_HEADER`). */
const NOTES_HEADER = 'x-faceanim-notes';

/** The file name a `Content-Disposition` gives: its exact UTF-8 `filename*`, else `filename`. */
function fileName(disposition, fallback) {
  const exact = /filename\*=UTF-8''([^;]+)/i.exec(disposition || '');
  if (exact) {
    try { return decodeURIComponent(exact[1].trim()); } catch { /* not percent-encoding: the plain name */ }
  }
  const plain = /filename="([^"]*)"/i.exec(disposition || '');
  return plain ? plain[1] : fallback;
}

/** The notes a download came with (none when the header is missing or not JSON). */
function notesOf(response) {
  try {
    const notes = JSON.parse(response.headers.get(NOTES_HEADER) || '[]');
    return Array.isArray(notes) ? notes.map(String) : [];
  } catch { return []; }
}

/** Fetches `link`'s file and saves it, or shows why there is none. */
async function download(link) {
  const href = link.getAttribute('href') || '';
  let response;
  try { response = await fetch(link.href); } catch (e) { showError(`${href}: ${e.message || e}`); return; }
  if (!response.ok) {
    const text = await response.text();
    let message = text || response.statusText;
    try { message = JSON.parse(text).error || message; } catch { /* not JSON: the text itself */ }
    showError(message);
    return;
  }
  const name = fileName(response.headers.get('content-disposition'), href.split('/').pop() || 'download');
  const url = URL.createObjectURL(await response.blob());
  const save = document.createElement('a');
  save.href = url;
  save.download = name;
  document.body.appendChild(save);
  save.click();
  save.remove();
  // The browser has the file once the click is handled; the URL is freed a while after.
  setTimeout(() => URL.revokeObjectURL(url), 60_000);
  showError('');
  const notes = notesOf(response);
  showStatus(notes.length ? `Downloaded ${name}: ${notes.join('; ')}` : `Downloaded ${name}.`);
}

// Clicks, taps and a keyboard's Enter on a link all arrive as a click.
document.addEventListener('click', (event) => {
  const target = /** @type {Element | null} */ (event.target instanceof Element ? event.target : null);
  const link = /** @type {HTMLAnchorElement | null} */ (target && target.closest('a[download]'));
  if (!link || !(link.getAttribute('href') || '').startsWith('api/')) return;
  event.preventDefault();
  download(link);
});
