// VMC in the Capture tab: when the studio listens for VMC (`--vmc-listen`), a phone tracker
// (iFacialMocap, Waidayo) or another performer drives the character live, and Record makes a
// take of what arrives, with its arrival times, edited and exported like any take. VMC out:
// when the studio sends VMC (`--vmc-send`), what the viewport plays (a take, the sketch, both)
// goes to the marionette frame by frame.

import { api } from './api.js';
import { turnHead } from './head-turn.js';
import { currentView, post, showTakeFrame } from './take.js';
import { applyLayer, characterMeshes, isPlaying, onFrame, pause } from './playback.js';
import * as store from './store.js';
import { showError, showFailure } from './status.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));
const button = (id) => /** @type {HTMLButtonElement} */ (document.getElementById(id));

/** What arrives over VMC while shown live: the character's weights and the head pose. */
export const vmc = {
  running: false,
  /** @type {number[]|null} */ weights: null,
  /** @type {number[]|null} */ head: null,
};

/** Shows the VMC controls when the studio listens. */
export function showControls(view) {
  const listening = !!(view && view.vmc && view.vmc.listening);
  $('vmc-row').hidden = !listening;
  $('vmc-stats').hidden = !listening;
  if (listening && !vmc.running) $('vmc-stats').textContent = `Listening for VMC on ${view.vmc.listening}.`;
}

/** Reads what arrived, over and over (one request at a time) while live. */
async function poll() {
  while (vmc.running) {
    try {
      const state = await api('GET', 'api/capture/vmc');
      if (!vmc.running || !state) break;
      vmc.weights = state.weights;
      vmc.head = state.head;
      if (state.head) turnHead(state.head);
      applyLayer();
      const age = state.last_packet_ms === null ? 'nothing yet' : `last ${state.last_packet_ms.toFixed(0)} ms ago`;
      const dropped = state.malformed + state.oversized;
      $('vmc-stats').textContent = `VMC on ${state.listening}${state.sender ? ` from ${state.sender}` : ''}: ${state.rate.toFixed(0)} packets/s, ${age}; ${state.frames} frames${dropped ? `, ${dropped} bad packets dropped` : ''}${state.unknown ? `, ${state.unknown} unknown messages` : ''}${state.recording !== null ? `; recording ${state.recording}` : ''}.`;
      if (state.recording !== null) $('vmc-record').textContent = `Stop (${state.recording})`;
    } catch (e) { showFailure(e); break; }
    await new Promise((r) => requestAnimationFrame(r));
  }
}

function start() {
  showError('');
  Object.assign(vmc, { running: true, weights: null, head: null });
  pause();
  $('vmc-live').textContent = 'Stop VMC';
  button('vmc-record').disabled = false;
  poll();
}

async function stop() {
  vmc.running = false;
  vmc.weights = null;
  $('vmc-live').textContent = 'VMC (live)';
  $('vmc-record').textContent = 'Record';
  button('vmc-record').disabled = true;
  showTakeFrame();
}

$('vmc-live').onclick = () => (vmc.running ? stop() : start());
$('vmc-record').onclick = async () => {
  const view = currentView();
  const recording = view && view.vmc && view.vmc.recording !== null;
  if (!recording) {
    if (await post('api/capture/vmc/record', { on: true })) $('vmc-record').textContent = 'Stop (0)';
  } else if (await post('api/capture/vmc/record', { on: false })) {
    await stop();
  }
};

// VMC out while playing: each frame the viewport shows, one request at a time (a slow one
// skips frames rather than falling behind).
let sending = false;
/** Whether the studio sends VMC (`--vmc-send`), asked once: the Sketch tab plays to it too. */
let sendsVmc = false;
api('GET', 'api/capture/vmc').then((state) => { sendsVmc = !!(state && state.sending); }).catch(() => {});
onFrame((frame) => {
  const character = store.character();
  const mesh = characterMeshes()[0];
  if (sending || !sendsVmc || !isPlaying() || !character || !mesh || !mesh.morphTargetInfluences) return;
  const view = currentView();
  const take = view && view.take;
  const head = take && take.head.length ? take.head[Math.min(Math.round(frame), take.frames - 1)] : null;
  sending = true;
  api('POST', 'api/capture/vmc/send', { weights: Array.from(mesh.morphTargetInfluences.slice(0, character.blendshapes.length)), head })
    .catch(showFailure)
    .finally(() => { sending = false; });
});
