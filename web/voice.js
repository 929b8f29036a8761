// Live microphone: the voice drives the mouth in real time. The microphone's samples go to
// the server 20 ms at a time at 16 kHz — none dropped: chunks that wait for an answer go
// together with the next — and the mouth that comes back goes on the character (the server
// sends it out over VMC too). Calibrate shows a passage to read for 20 seconds, in the language
// the speech field names (or asks for free speech where the server has no passage in it);
// Record makes a take with its sound. Measures voice-to-mouth latency.

import { api } from './api.js';
import { apply, post, showTakeFrame } from './take.js';
import { pushMedian } from './medians.js';
import { applyLayer, pause } from './playback.js';
import { onRender } from './scene.js';
import { showError } from './status.js';
import { turnHead } from './head-turn.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));
const RATE = 16000;
/** The newest mouth describes the window centred this long before the newest sample at
 * most: half a 25 ms window, plus up to one 10 ms hop not yet complete. */
const WINDOW_MS = 22.5;

/** Live microphone measurements; scripts read them as `window.studio.capture.voice`. */
export const voice = {
  running: false,
  /** Chunks answered. */
  chunks: 0,
  /** @type {number[]|null} the character's weights now */ weights: null,
  open: 0, level_db: -100, server_ms: 0,
  /** Median voice-to-screen latency, ms: from the newest sample's arrival in the page to the
   * character drawn with the mouth it gave, plus the analysis window and the microphone's own
   * input latency as the browser reports it. */
  latency_ms: 0,
  /** Where it goes (ms, last answer). */
  stages: { input_ms: 0, window_ms: WINDOW_MS, round_trip_ms: 0, draw_ms: 0 },
  /** Median mouth-to-voice lag, ms, at the voice's onsets: from a chunk where the voice
   * starts after a pause to the first drawn frame with the mouth open — the whole chain,
   * smoothing included, measured on the signal itself (null before the first onset). */
  onset_lag_ms: /** @type {number|null} */ (null),
  onset_lags: /** @type {number[]} */ ([]),
  /** Onsets the mouth did not open for within MISS_MS (a cough or a knock may be one). */
  onset_misses: 0,
  /** @type {any} the server's view of the microphone */ view: null,
  latencies: /** @type {number[]} */ ([]),
};

let context = /** @type {AudioContext|null} */ (null);
let stream = /** @type {MediaStream|null} */ (null);
/** Chunks not yet sent, and when the newest arrived. */
let pending = /** @type {Int16Array[]} */ ([]);
let newest = 0;
let inFlight = false;
/** The answer whose mouth is on the character but not yet drawn. */
let shown = /** @type {{newest: number, sent: number, received: number, open: number}|null} */ (null);
/** Recent loudness per chunk: [page time of the chunk's centre, dB]. */
const levels = /** @type {[number, number][]} */ ([]);
const KEEP_CHUNKS = 50;
/** A voice onset: a chunk louder than -60 dBFS and ONSET_DB louder than each of the
 * PAUSE_CHUNKS before it; it began at the first of the last RISE_CHUNKS that rose ONSET_DB
 * above the pause's quietest. The mouth counts as open from OPEN. */
const ONSET_DB = 20, PAUSE_CHUNKS = 15, RISE_CHUNKS = 4, OPEN = 0.2, MISS_MS = 500;
/** The page time of the onset the mouth has not opened for yet. */
let onset = /** @type {number|null} */ (null);

/** The language the user speaks: the speech field's (capture.js owns it; read here only). */
const spokenLanguage = () => /** @type {HTMLInputElement} */ ($('speech-language')).value.trim();

async function startVoice() {
  showError('');
  try {
    stream = await navigator.mediaDevices.getUserMedia({
      audio: { echoCancellation: false, noiseSuppression: false, autoGainControl: false, channelCount: 1 }, video: false,
    });
  } catch (e) { showError(`The microphone could not be opened: ${e.message || e}`); return; }
  const delay_ms = Number(/** @type {HTMLInputElement} */ ($('voice-delay')).value) || 0;
  try { apply(await api('PUT', 'api/capture/voice', { on: true, delay_ms, language: spokenLanguage() })); }
  catch (e) { showError(String(e.message || e)); stopTracks(); return; }
  try {
    // At 16 kHz where the browser can open the microphone so; else at its own rate, which the
    // worklet brings down to 16 kHz.
    let source;
    try {
      context = new AudioContext({ sampleRate: RATE });
      source = context.createMediaStreamSource(stream);
    } catch {
      if (context) await context.close().catch(() => {});
      context = new AudioContext();
      source = context.createMediaStreamSource(stream);
    }
    await context.audioWorklet.addModule('voice-worklet.js');
    const chunker = new AudioWorkletNode(context, 'faceanim-chunker');
    chunker.port.onmessage = (event) => onChunk(new Int16Array(event.data));
    // The worklet runs while its output reaches the speakers; silenced, it makes no sound.
    const mute = context.createGain();
    mute.gain.value = 0;
    source.connect(chunker).connect(mute).connect(context.destination);
  } catch (e) {
    showError(`The microphone's sound could not be read: ${e.message || e}`);
    await stopVoice();
    return;
  }
  const settings = /** @type {any} */ (stream.getAudioTracks()[0].getSettings());
  voice.stages.input_ms = typeof settings.latency === 'number' ? settings.latency * 1000 : 0;
  Object.assign(voice, { running: true, chunks: 0, weights: null, latencies: [], onset_lag_ms: null, onset_lags: [], onset_misses: 0 });
  pending = []; levels.length = 0; onset = null;
  $('voice-live').textContent = 'Stop microphone';
  for (const id of ['voice-record', 'voice-calibrate']) /** @type {HTMLButtonElement} */ ($(id)).disabled = false;
  pause();
}

function stopTracks() {
  if (stream) for (const t of stream.getTracks()) t.stop();
  stream = null;
}

function onChunk(/** @type {Int16Array} */ samples) {
  if (!voice.running) return;
  const now = performance.now();
  let sum = 0;
  for (const s of samples) sum += s * s;
  const db = 10 * Math.log10(sum / samples.length / (32768 * 32768) + 1e-10);
  if (onset !== null && now - onset > MISS_MS) { voice.onset_misses++; onset = null; }
  const centre = now - (samples.length / RATE) * 500;
  levels.push([centre, db]);
  if (levels.length > KEEP_CHUNKS) levels.shift();
  const before = levels.slice(-PAUSE_CHUNKS - 1, -1);
  if (onset === null && before.length === PAUSE_CHUNKS && db > -60 && before.every(([, l]) => l < db - ONSET_DB)) {
    const quietest = Math.min(...before.map(([, l]) => l));
    const rise = levels.slice(-RISE_CHUNKS).find(([, l]) => l >= quietest + ONSET_DB);
    onset = rise ? rise[0] : centre;
  }
  pending.push(samples);
  newest = now;
  if (!inFlight) sendPending();
}

async function sendPending() {
  if (!pending.length || !voice.running) return;
  const length = pending.reduce((n, c) => n + c.length, 0);
  const body = new Int16Array(length);
  let at = 0;
  for (const c of pending) { body.set(c, at); at += c.length; }
  pending = [];
  const arrived = newest, sent = performance.now();
  inFlight = true;
  try {
    const response = await fetch('api/capture/voice/chunk', { method: 'POST', headers: { 'x-sample-rate': String(RATE) }, body: new Blob([body.buffer]) });
    const result = await response.json();
    if (!response.ok) throw new Error(result.error || response.statusText);
    if (!voice.running || !result.live) return;
    voice.chunks++;
    Object.assign(voice, { open: result.open, level_db: result.level_db, server_ms: result.server_ms, view: result.voice });
    if (result.weights) {
      voice.weights = result.weights;
      shown = { newest: arrived, sent, received: performance.now(), open: result.open };
      applyLayer();
      // A character with a skeleton opens its jaw bone too (a body with no shapes only so).
      if (result.bones) turnHead(null, result.bones);
    }
    showVoice();
  } catch (e) {
    if (voice.running) showError(String(e.message || e));
  } finally {
    inFlight = false;
    if (pending.length) sendPending();
  }
}

onRender(() => {
  if (shown === null) return;
  const drawn = performance.now();
  voice.stages.round_trip_ms = shown.received - shown.sent;
  voice.stages.draw_ms = drawn - shown.received;
  const latency = drawn - shown.newest + WINDOW_MS + voice.stages.input_ms;
  if (onset !== null && shown.open > OPEN && shown.newest >= onset) {
    voice.onset_lag_ms = pushMedian(voice.onset_lags, drawn - onset + voice.stages.input_ms, 50);
    onset = null;
  }
  shown = null;
  voice.latency_ms = pushMedian(voice.latencies, latency, 200);
});

const CALIBRATION_TEXT = {
  none: () => 'Voice: not calibrated (the mouth follows loudness until it has learned from your speech). Press Calibrate voice and read aloud what appears.',
  listening: (c, v) => `Calibrating: ${v.passage ? 'read the passage aloud' : 'speak freely'}… ${Math.max(0, 20 - c.seconds).toFixed(0)} s left`,
  fitting: () => 'Calibrating: learning your voice…',
  calibrated: (c) => `Voice calibrated (${c.visemes} mouth shapes)${c.notes.length ? `: ${c.notes.join('; ')}` : ''}.`,
  failed: (c) => `Calibration failed: ${c.message}`,
};

/** Says where calibration is, and shows the passage while it listens. */
function showVoice() {
  const v = voice.view;
  if (!voice.running || !v) return;
  const c = v.calibration;
  $('voice-passage').hidden = c.state !== 'listening';
  $('voice-passage').textContent = v.passage
    || `There is no passage to read in ${v.language}: talk for 20 seconds in your own words, at your usual pace; the sounds you make teach the mouth your voice.`;
  const delay = /** @type {HTMLInputElement} */ ($('voice-delay'));
  delay.max = String(v.max_delay_ms);
  const learned = v.learned ? ` Learned from ${v.learned} stretch${v.learned === 1 ? '' : 'es'} of speech.` : '';
  const waits = v.awaits_map ? 'The mouth moves once the retarget map is made (its names say nothing of a mouth; see Retarget). ' : '';
  $('voice-stats').textContent = `${waits}${CALIBRATION_TEXT[c.state](c, v)}${learned} ${voice.latency_ms.toFixed(0)} ms voice → screen${voice.onset_lag_ms === null ? '' : `, the mouth opens ${voice.onset_lag_ms.toFixed(0)} ms after the voice starts`} (server ${voice.server_ms.toFixed(1)} ms).`;
  if (v.recording !== null && v.recording !== undefined) $('voice-record').textContent = `Stop (${v.recording.toFixed(0)} s)`;
}

async function stopVoice() {
  voice.running = false;
  for (let i = 0; i < 100 && inFlight; i++) await new Promise((r) => setTimeout(r, 20));
  stopTracks();
  if (context) await context.close().catch(() => {});
  context = null;
  $('voice-live').textContent = 'Microphone (live)';
  $('voice-record').textContent = 'Record';
  for (const id of ['voice-record', 'voice-calibrate']) /** @type {HTMLButtonElement} */ ($(id)).disabled = true;
  $('voice-passage').hidden = true;
  try { apply(await api('PUT', 'api/capture/voice', { on: false })); } catch { /* the server may be gone */ }
  showTakeFrame();
}

$('voice-live').onclick = () => (voice.running ? stopVoice() : startVoice());
/** Tells the server the language now in the speech field (its passage, its recognition). */
async function sendLanguage() {
  try { showError(''); apply(await api('PUT', 'api/capture/voice', { on: true, language: spokenLanguage() })); return true; }
  catch (e) { showError(String(e.message || e)); return false; }
}
$('speech-language').addEventListener('change', () => { if (voice.running) sendLanguage(); });
$('voice-calibrate').onclick = async () => {
  if (!(await sendLanguage())) return;
  if (await post('api/capture/voice/calibrate', {})) { voice.view = { ...voice.view, calibration: { state: 'listening', seconds: 0 } }; showVoice(); }
};
$('voice-delay').onchange = async () => {
  if (!voice.running) return;
  const delay_ms = Number(/** @type {HTMLInputElement} */ ($('voice-delay')).value) || 0;
  try { showError(''); apply(await api('PUT', 'api/capture/voice', { on: true, delay_ms })); }
  catch (e) { showError(String(e.message || e)); }
};
$('voice-record').onclick = async () => {
  const recording = voice.view && voice.view.recording !== null && voice.view.recording !== undefined;
  if (!recording) {
    if (await post('api/capture/voice/record', { on: true })) $('voice-record').textContent = 'Stop (0 s)';
  } else if (await post('api/capture/voice/record', { on: false })) {
    await stopVoice();
  }
};

window.addEventListener('pagehide', () => { voice.running = false; stopTracks(); });
