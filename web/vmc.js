// Live links in the Capture tab: when the studio listens to a phone tracker in its own protocol
// (`--phone`: Live Link Face, iFacialMocap, VTube Studio) or for VMC (`--vmc-listen`: Waidayo,
// another performer), what arrives drives the character live, Neutral takes the phone's relaxed
// face away from every frame (kept for later runs), and Record makes a take of what arrives,
// with its arrival times, edited and exported like any take. VMC out: when the studio sends VMC
// (`--vmc-send`), what the viewport plays (a take, the sketch, both) goes to the marionette frame
// by frame; a phone's frames go on as they arrive.

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

/** What is listened to, in words: the app, the port and where the phone should send. */
function describe(state) {
  const port = state.listening.split(':').pop();
  const here = state.this_machine.length ? ` (this machine: ${state.this_machine.map((a) => `${a}:${port}`).join(', ')})` : '';
  const asking = state.phone ? `, asking ${state.phone}` : '';
  return `${state.source} on ${state.listening}${here}${asking}`;
}

/** Names that moved but reach nothing on the character, in words (the first few). */
function unmatched(names) {
  if (!names.length) return '';
  const shown = names.slice(0, 5).join(', ');
  const more = names.length > 5 ? ` and ${names.length - 5} more` : '';
  return `; nothing on this character takes ${shown}${more}`;
}

/** Shows the live-link controls when the studio listens. */
export function showControls(view) {
  const listening = !!(view && view.vmc && view.vmc.listening);
  $('vmc-row').hidden = !listening;
  $('vmc-stats').hidden = !listening;
  if (!listening) return;
  const phone = view.vmc.source !== 'VMC';
  $('vmc-live').textContent = vmc.running ? `Stop ${view.vmc.source}` : `${view.vmc.source} (live)`;
  $('vmc-neutral').hidden = !phone;
  $('vmc-neutral').textContent = view.vmc.neutral ? 'Neutral ✓' : 'Neutral';
  if (!vmc.running) $('vmc-stats').textContent = `Listening for ${describe(view.vmc)}.`;
}

/** Reads what arrived, over and over (one request at a time) while live. */
async function poll() {
  while (vmc.running) {
    try {
      const state = await api('GET', 'api/capture/vmc');
      if (!vmc.running || !state) break;
      vmc.weights = state.weights;
      vmc.head = state.head;
      if (state.head || state.bones) turnHead(state.head, state.bones);
      applyLayer();
      const age = state.last_packet_ms === null ? 'nothing yet' : `last ${state.last_packet_ms.toFixed(0)} ms ago`;
      const dropped = state.malformed + state.oversized + state.foreign;
      const lost = state.faces_lost ? `, face lost ${state.faces_lost}×` : '';
      const out = state.forwarded ? `; out over VMC ${state.forwarded.frames} (median ${state.forwarded.median_ms.toFixed(1)} ms, 95% ${state.forwarded.p95_ms.toFixed(1)} ms)` : '';
      $('vmc-stats').textContent = `${describe(state)}${state.sender ? ` from ${state.sender}` : ''}: ${state.rate.toFixed(0)} packets/s, ${age}; ${state.frames} frames${lost}${dropped ? `, ${dropped} bad or foreign packets dropped` : ''}${state.unknown ? `, ${state.unknown} unknown messages` : ''}${unmatched(state.unmatched_names)}${out}${state.recording !== null ? `; recording ${state.recording}` : ''}.`;
      if (state.recording !== null) $('vmc-record').textContent = `Stop (${state.recording})`;
    } catch (e) { showFailure(e); break; }
    await new Promise((r) => requestAnimationFrame(r));
  }
}

function start() {
  showError('');
  Object.assign(vmc, { running: true, weights: null, head: null });
  pause();
  $('vmc-live').textContent = 'Stop';
  button('vmc-record').disabled = false;
  poll();
}

async function stop() {
  vmc.running = false;
  vmc.weights = null;
  showControls(currentView());
  $('vmc-record').textContent = 'Record';
  button('vmc-record').disabled = true;
  showTakeFrame();
}

$('vmc-live').onclick = () => (vmc.running ? stop() : start());
$('vmc-neutral').onclick = async () => {
  try {
    const state = await api('POST', 'api/capture/vmc/neutral', {});
    if (state) $('vmc-neutral').textContent = state.neutral ? 'Neutral ✓' : 'Neutral';
  } catch (e) { showFailure(e); }
};
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
/** Where frames go out, and how many this page sent and the network refused. */
const out = { to: '', sent: 0, refused: 0 };

/** The transport bar's word on VMC out, so that whoever plays sees that it goes out. */
function showOut() {
  const label = $('vmc-out');
  label.hidden = !out.to;
  const counts = out.sent || out.refused ? `: ${out.sent} frames sent${out.refused ? `, ${out.refused} refused` : ''}` : '';
  label.textContent = `VMC out → ${out.to}${counts}`;
}

api('GET', 'api/capture/vmc').then((state) => {
  sendsVmc = !!(state && state.sending);
  if (sendsVmc) Object.assign(out, { to: state.sending.to });
  showOut();
}).catch(() => {});
// A take's frame goes with its id and number: the studio adds the take's own gaze, jaw and
// ARKit values (a body with no shapes has nothing else to send).
onFrame((frame) => {
  const character = store.character();
  const mesh = characterMeshes()[0];
  const shapes = character ? character.blendshapes.length : 0;
  if (sending || !sendsVmc || !isPlaying() || !character || !mesh || (shapes && !mesh.morphTargetInfluences)) return;
  const view = currentView();
  const take = view && view.take;
  const f = take ? Math.min(Math.round(frame), take.frames - 1) : 0;
  const head = take && take.head.length ? take.head[Math.min(f, take.head.length - 1)] : null;
  const weights = shapes ? Array.from(mesh.morphTargetInfluences.slice(0, shapes)) : [];
  sending = true;
  api('POST', 'api/capture/vmc/send', { weights, head, take: take ? { id: take.id, frame: f } : null })
    .then((answer) => {
      if (answer && answer.sent) out.sent += 1;
      else if (answer) out.refused += 1;
      showOut();
    })
    .catch(showFailure)
    .finally(() => { sending = false; });
});
