// The two tabs: Sketch (strokes on the face) and Capture (a video, photos or the webcam drive
// the character, strokes layered on top). This module owns which one is shown.

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

/** @type {'sketch'|'capture'} */
let mode = 'sketch';
/** @type {((mode: 'sketch'|'capture') => void)[]} */
const listeners = [];

/** The tab shown. */
export const currentMode = () => mode;
/** Whether the Capture tab is shown. */
export const inCapture = () => mode === 'capture';
/** Calls `listener(mode)` after every switch. */
export function onMode(listener) { listeners.push(listener); }

/** Shows the tab `next`. */
export function setMode(next) {
  mode = next;
  const on = next === 'capture';
  document.body.classList.toggle('capture', on);
  $('tab-sketch').setAttribute('aria-selected', String(!on));
  $('tab-capture').setAttribute('aria-selected', String(on));
  $('capture-input').hidden = !on;
  $('capture-panel').hidden = !on;
  $('settings').hidden = on;
  for (const listener of listeners) listener(next);
  window.dispatchEvent(new Event('resize'));
}

$('tab-sketch').onclick = () => setMode('sketch');
$('tab-capture').onclick = () => setMode('capture');
