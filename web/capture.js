// faceanim studio: capture mode. A face video, photos or the webcam drive the character
// (seed 003's toolkit): the input frame beside the character, the frame diagram, corrections
// by name, keyframes, preference, the adapter (train, fine-tune), live webcam puppeteering and
// recording. The server owns the take; this file draws /api/capture/state and sends edits.
// Sketch strokes keep working on top: the take is the layer under them (playback's layer).

import * as THREE from 'three';
import { api } from './api.js';
import { inCapture, onMode } from './mode.js';
import { applyLayer, currentFrame, onFrame, pause, setExtent, setFrame, setLayer, setTurn } from './playback.js';
import { onRender } from './scene.js';
import { showError, showFailure } from './status.js';
import * as store from './store.js';
import { drawTimeline } from './timeline.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));
const input = (id) => /** @type {HTMLInputElement} */ (document.getElementById(id));

/** @type {any} The last /api/capture/state. */
let view = null;
/** Name of the blendshape whose curve the diagram draws. */
let selectedName = 'jawOpen';
/** A slider being dragged: its name and value show on the character before the server has it. */
let preview = null;

/** Capture mode as scripts and tests see it (`window.studio.capture`). */
export const capture = {
  get view() { return view; },
  /** Live webcam measurements: frames per second and camera-to-screen latency (ms). */
  live: {
    running: false, fps: 0, latency_ms: 0, server_ms: 0, frames: 0,
    /** Where the latency goes (ms, last frame): reading the camera frame, the round trip to
     * the server, and drawing the character. */
    stages: { grab_ms: 0, round_trip_ms: 0, draw_ms: 0 },
    /** The pixel format frames are sent in (the camera's own YUV when the browser gives it). */
    format: '',
    /** @type {number|null} frames recorded so far */ recorded: null,
    /** @type {number[]|null} */ weights: null,
    latencies: /** @type {number[]} */ ([]),
    /** Frames sent to the server and not yet answered, at most: a newer camera frame waits
     * for a free slot and is dropped if another comes first, so a slow server costs frames,
     * not latency. One: the server tracks one frame at a time, so a second one only queues
     * behind it. Without a GPU (tools/live-bench.mjs) two gave 24 % more frames per second for
     * 14 % more median latency and 27 % more at the 90th percentile; with a GPU the server is
     * the limit and a queued frame adds latency only. */
    maxInFlight: 1,
  },
  /** Waits until no job runs; resolves with the last job's view. */
  async settled(timeoutMs = 600000) {
    const until = Date.now() + timeoutMs;
    for (;;) {
      const v = await refresh();
      if (!v.job || !v.job.running) return v.job;
      if (Date.now() > until) throw new Error('timed out waiting for the capture job');
      await new Promise((r) => setTimeout(r, 250));
    }
  },
  refresh: () => refresh(),
};

// ---------- tab and history ----------
onMode((mode) => {
  if (mode === 'capture') { refresh().catch(showFailure); setFrame(currentFrame()); }
  else turnHead(null);
  notify();
});

/** @type {(() => void)[]} */
const changeListeners = [];
/** Calls `listener()` after every new capture state. */
export function onChange(listener) { changeListeners.push(listener); }
function notify() { for (const listener of changeListeners) listener(); }

// In the Capture tab, undo and redo (Ctrl+Z, the toolbar) step through the take's edits; the
// strokes' own history is the Sketch tab's.
/** Undoes one edit of the take. */
export const undo = () => post('api/capture/undo');
/** Redoes one undone edit of the take. */
export const redo = () => post('api/capture/redo');
/** Whether the take has an edit to undo or redo. */
export function history() {
  const take = view && view.take;
  return { canUndo: !!(take && take.can_undo), canRedo: !!(take && take.can_redo) };
}

// ---------- state ----------
let polling = 0;
async function refresh() {
  const v = await api('GET', 'api/capture/state');
  apply(v);
  return v;
}

function apply(v) {
  const hadTake = view && view.take ? view.take.id : null;
  view = v;
  const take = v.take;
  const newTake = take && take.id !== hadTake;
  if (newTake) shownFrame = -1;
  setExtent(take ? take.frames - 1 : 0);
  const sketch = store.state();
  if (newTake && sketch && Math.abs(sketch.fps - take.fps) > 1e-3) {
    // Strokes layered on the take count frames at the take's rate.
    store.run('PUT', 'api/fps', { fps: take.fps });
  }
  // Job and progress.
  const job = v.job;
  const running = !!(job && job.running);
  $('job').hidden = !job || (!running && !job.error && !job.result);
  if (job) {
    const fraction = job.total ? job.done / job.total : 0;
    $('job-stage').textContent = running
      ? `${job.title}: ${job.stage} ${job.total ? `${job.done}/${job.total}` : ''}${job.cancelling ? ' (cancelling…)' : ''}`
      : job.error ? `${job.title}: ${job.error}` : `${job.title}: ${job.result}`;
    $('job-stage').className = job.error ? 'error-text' : '';
    /** @type {HTMLProgressElement} */ ($('job-progress')).value = running ? fraction : 1;
    $('job-progress').hidden = !running;
    $('job-cancel').hidden = !running;
  }
  for (const id of ['train', 'finetune', 'capture-open', 'capture-close']) /** @type {HTMLButtonElement} */ ($(id)).disabled = running;
  input('capture-file').disabled = running;
  if (running && !polling) polling = window.setInterval(() => refresh().catch(() => {}), 300);
  if (!running && polling) { window.clearInterval(polling); polling = 0; }
  // Adapter.
  const a = v.adapter;
  $('adapter-info').textContent = a.loaded
    ? `Adapter: ${a.path}${a.report ? ` (test MAE ${a.report.mae_test.toFixed(4)}, ${a.report.samples} renders)` : ''}.${a.note ? ` ${a.note}` : ''}`
    : `No adapter yet: estimating by ARKit name.${a.note ? ` ${a.note}` : ''} Train one to drive every shape of this character.`;
  /** @type {HTMLButtonElement} */ ($('finetune')).disabled = running || !a.loaded || !take || !take.corrected.length;
  // Filtering.
  const f = v.filtering;
  const s = f.smoothing || f.default_smoothing;
  input('one-euro').checked = !!f.smoothing;
  if (document.activeElement !== $('min-cutoff')) input('min-cutoff').value = String(s.min_cutoff);
  if (document.activeElement !== $('beta')) input('beta').value = String(s.beta);
  if (document.activeElement !== $('keyframe-every')) input('keyframe-every').value = String(f.keyframe_every);
  // Take.
  $('take-info').textContent = take
    ? `${take.source}: ${take.frames} frame(s) at ${take.fps} fps, ${take.keyframes.length} keyframes, ${take.corrected.length} corrected; ${ESTIMATED[take.estimator] || take.estimator}${take.preference ? '; preference applied' : ''}.`
    : '';
  if (!take) $('capture-input-note').textContent = 'Open a video, photos, a session or the webcam (right).';
  $('capture-input-note').hidden = (!!take && !frameImage.hidden) || capture.live.running;
  for (const id of ['keyframe', 'uncorrect-frame', 'apply-preference', 'clear-preference']) /** @type {HTMLButtonElement} */ ($(id)).disabled = !take;
  /** @type {HTMLButtonElement} */ ($('clear-preference')).disabled = !take || !take.preference;
  for (const a2 of document.querySelectorAll('#capture-panel .exports a')) a2.classList.toggle('disabled', !take);
  buildSliders(v);
  notify();
  drawTimeline();
  setFrame(newTake ? 0 : currentFrame());
}

/** The weights under the sketch at `frame`: the live face, else the take (with a slider
 * being dragged shown at once). */
function layer(frame) {
  if (capture.live.running && capture.live.weights) return capture.live.weights;
  const take = view && view.take;
  if (!take) return null;
  const f = Math.min(Math.round(frame), take.frames - 1);
  const row = take.weights[f];
  if (!preview || preview.frame !== f) return row;
  const copy = row.slice();
  copy[view.blendshapes.indexOf(preview.name)] = preview.value;
  return copy;
}

/** How the take-info line says where the estimates came from. */
const ESTIMATED = { adapter: 'estimated by the adapter', by_name: 'estimated by ARKit name', session_file: 'opened from a session' };

// ---------- input ----------
input('capture-file').addEventListener('change', async () => {
  const files = [...(input('capture-file').files || [])];
  input('capture-file').value = '';
  if (!files.length) return;
  showError('');
  const header = (file) => ({ 'x-filename': file.name.replace(/[^\x20-\x7e]/g, '_') });
  try {
    if (files.length === 1) {
      apply(await api('POST', 'api/capture/upload', await files[0].arrayBuffer(), header(files[0])));
      return;
    }
    // Several photos are one sequence, in name order, like a folder of frames.
    if (files.some((f) => !/\.(png|jpe?g)$/i.test(f.name))) throw new Error('pick one video, one session, or any number of PNG or JPEG photos');
    const batch = Date.now().toString(36) + Math.random().toString(36).slice(2, 8);
    for (const [index, file] of files.entries()) {
      $('take-info').textContent = `Sending ${file.name} (${index + 1} of ${files.length})…`;
      apply(await api('POST', `api/capture/upload?batch=${batch}&index=${index}&count=${files.length}`, await file.arrayBuffer(), header(file)));
    }
  } catch (e) { showError(String(e.message || e)); }
});
$('capture-open').onclick = async () => {
  const path = input('capture-path').value.trim();
  if (!path) { showError('Type the path of a video, an image, a folder of images or a session file'); return; }
  try { showError(''); apply(await api('POST', 'api/capture/open', { path })); }
  catch (e) { showError(String(e.message || e)); }
};
$('capture-close').onclick = () => post('api/capture/close');
$('job-cancel').onclick = () => post('api/capture/cancel');

async function post(path, body) {
  try { showError(''); apply(await api('POST', path, body)); return true; }
  catch (e) { showError(String(e.message || e)); return false; }
}

// ---------- adapter ----------
$('train').onclick = () => post('api/capture/adapter/train', { samples: Math.max(100, Math.round(Number(input('train-samples').value) || 10000)) });
$('finetune').onclick = () => post('api/capture/adapter/finetune');

// ---------- smoothing ----------
async function sendFiltering() {
  const body = {
    keyframe_every: Math.max(1, Math.round(Number(input('keyframe-every').value) || 1)),
    smoothing: input('one-euro').checked ? { min_cutoff: Number(input('min-cutoff').value), beta: Number(input('beta').value) } : null,
  };
  try { showError(''); apply(await api('PUT', 'api/capture/filtering', body)); }
  catch (e) { showError(String(e.message || e)); }
}
for (const id of ['one-euro', 'min-cutoff', 'beta', 'keyframe-every']) $(id).addEventListener('change', sendFiltering);

// ---------- the current frame: keyframes, corrections, preference ----------
const shownFrameIndex = () => Math.round(currentFrame());
$('keyframe').onclick = () => {
  const take = view && view.take;
  if (!take) return;
  const f = shownFrameIndex();
  post('api/capture/keyframe', { frame: f, on: !take.keyframes.includes(f) });
};
$('uncorrect-frame').onclick = () => post('api/capture/uncorrect', { frame: shownFrameIndex() });
$('apply-preference').onclick = () => post('api/capture/preference', { on: true });
$('clear-preference').onclick = () => post('api/capture/preference', { on: false });

const GROUP_TITLES = { eye: 'Eyes', brow: 'Brows', jaw: 'Jaw', mouth: 'Mouth', cheek: 'Cheeks', nose: 'Nose', tongue: 'Tongue', other: 'Other' };
let sliderSignature = '';
/** @type {Map<string, {row: HTMLElement, range: HTMLInputElement, out: HTMLOutputElement}>} */
const sliders = new Map();
function buildSliders(v) {
  const signature = v.blendshapes.join('|');
  if (signature !== sliderSignature) {
    sliderSignature = signature;
    sliders.clear();
    const box = $('sliders');
    box.innerHTML = '';
    const groups = new Map();
    v.blendshapes.forEach((name, i) => {
      const g = v.groups[i];
      if (!groups.has(g)) groups.set(g, []);
      groups.get(g).push(name);
    });
    const grouped = groups.size > 1 || !groups.has('other');
    for (const [g, names] of groups) {
      const parent = grouped ? document.createElement('details') : box;
      if (grouped) {
        parent.open = true;
        const summary = document.createElement('summary');
        summary.textContent = `${GROUP_TITLES[g] || g} (${names.length})`;
        parent.appendChild(summary);
        box.appendChild(parent);
      }
      for (const name of names) {
        const row = document.createElement('div');
        row.className = 'slider';
        row.dataset.name = name;
        const label = document.createElement('span');
        label.className = 'name';
        label.textContent = name;
        label.title = `${name}: click to draw its curve in the frame diagram`;
        label.onclick = () => { selectedName = name; drawDiagram(); markSelected(); };
        const range = document.createElement('input');
        range.type = 'range'; range.min = '0'; range.max = '1'; range.step = '0.01';
        range.setAttribute('aria-label', name);
        const out = document.createElement('output');
        const clear = document.createElement('button');
        clear.textContent = '×';
        clear.title = `Remove the correction of ${name} on this frame`;
        range.addEventListener('input', () => {
          preview = { frame: shownFrameIndex(), name, value: Number(range.value) };
          out.textContent = Number(range.value).toFixed(2);
          applyLayer();
        });
        range.addEventListener('change', async () => {
          const value = Number(range.value);
          const ok = await post('api/capture/correct', { frame: shownFrameIndex(), name, value });
          preview = null;
          if (ok) { selectedName = name; markSelected(); drawDiagram(); }
        });
        clear.onclick = () => post('api/capture/uncorrect', { frame: shownFrameIndex(), name });
        row.append(label, range, out, clear);
        parent.appendChild(row);
        sliders.set(name, { row, range, out });
      }
    }
    filterSliders();
    markSelected();
  }
  fillSliders();
}
function markSelected() {
  for (const [name, s] of sliders) s.row.classList.toggle('selected', name === selectedName);
  $('diagram-curve-name').textContent = selectedName;
}
function fillSliders() {
  const take = view && view.take;
  const f = shownFrameIndex();
  const row = take ? take.weights[Math.min(f, take.frames - 1)] : null;
  const corrected = take ? take.corrections[String(f)] || {} : {};
  view.blendshapes.forEach((name, i) => {
    const s = sliders.get(name);
    if (!s) return;
    const value = row ? row[i] : 0;
    if (document.activeElement !== s.range) s.range.value = String(value);
    s.out.textContent = value.toFixed(2);
    s.range.disabled = !take || capture.live.running;
    s.row.classList.toggle('corrected', name in corrected);
    /** @type {HTMLButtonElement} */ (s.row.querySelector('button')).disabled = !(name in corrected);
  });
  $('frame-title').textContent = take ? `Frame ${f}${take.names[Math.min(f, take.frames - 1)] ? ` — ${take.names[Math.min(f, take.frames - 1)]}` : ''}` : 'Frame';
  if (take) $('keyframe').textContent = take.keyframes.includes(f) ? 'Remove keyframe' : 'Add keyframe';
}
function filterSliders() {
  const q = input('slider-search').value.trim().toLowerCase();
  for (const [name, s] of sliders) s.row.hidden = !!q && !name.toLowerCase().includes(q);
  for (const d of document.querySelectorAll('#sliders details')) {
    d.hidden = [...d.querySelectorAll('.slider')].every((r) => /** @type {HTMLElement} */ (r).hidden);
  }
}
$('slider-search').addEventListener('input', filterSliders);

// ---------- frame diagram (the seed's figure 3) ----------
const diagram = /** @type {HTMLCanvasElement} */ ($('diagram'));
function drawDiagram() {
  const take = view && view.take;
  const ratio = window.devicePixelRatio || 1;
  const w = diagram.clientWidth, h = diagram.clientHeight;
  if (!w || !h) return;
  diagram.width = Math.round(w * ratio); diagram.height = Math.round(h * ratio);
  const g = diagram.getContext('2d');
  if (!g) return;
  g.setTransform(ratio, 0, 0, ratio, 0, 0);
  g.clearRect(0, 0, w, h);
  if (!take) { g.fillStyle = '#9aa0a8'; g.fillText('No take: open a video, photos or the webcam', 10, h / 2); return; }
  const n = take.frames;
  const pad = 8;
  const x = (f) => pad + (n > 1 ? f / (n - 1) : 0.5) * (w - 2 * pad);
  const maxMean = Math.max(0.05, ...take.mean) * 1.15;
  const yMean = (m) => h - pad - (m / maxMean) * (h - 2 * pad);
  const yCurve = (v) => h - pad - v * (h - 2 * pad);
  // The selected blendshape's curve (scale 0..1) behind the points.
  const b = view.blendshapes.indexOf(selectedName);
  if (b >= 0) {
    g.strokeStyle = '#3fc07a'; g.lineWidth = 1.5; g.beginPath();
    take.weights.forEach((row, f) => { const px = x(f), py = yCurve(row[b]); if (f) g.lineTo(px, py); else g.moveTo(px, py); });
    g.stroke();
  }
  const keys = new Set(take.keyframes), corrected = new Set(take.corrected);
  const radius = n > 400 ? 1.5 : n > 150 ? 2.5 : 3.5;
  take.mean.forEach((m, f) => {
    g.fillStyle = corrected.has(f) ? '#e07a30' : keys.has(f) ? '#4a8fe0' : '#7d8590';
    g.beginPath(); g.arc(x(f), yMean(m), corrected.has(f) || keys.has(f) ? radius + 1 : radius, 0, Math.PI * 2); g.fill();
  });
  g.strokeStyle = '#e04040'; g.lineWidth = 2;
  const cx = x(Math.min(currentFrame(), n - 1));
  g.beginPath(); g.moveTo(cx, 0); g.lineTo(cx, h); g.stroke();
}
function frameAt(clientX) {
  const take = view && view.take;
  if (!take) return 0;
  const rect = diagram.getBoundingClientRect();
  const u = (clientX - rect.left - 8) / Math.max(1, rect.width - 16);
  return Math.round(Math.min(1, Math.max(0, u)) * (take.frames - 1));
}
diagram.addEventListener('pointerdown', (e) => {
  pause();
  setFrame(frameAt(e.clientX));
  diagram.setPointerCapture(e.pointerId);
  diagram.onpointermove = (ev) => setFrame(frameAt(ev.clientX));
  diagram.onpointerup = () => { diagram.onpointermove = null; };
});
new ResizeObserver(drawDiagram).observe(diagram);

/** Turns the character by a captured head pose `[yaw, pitch, roll]` in degrees (the export's
 * convention: R = Ry(yaw)·Rx(−pitch)·Rz(roll); the capture browser test compares the two), or
 * back to rest. Only in this tab: strokes are drawn on the unturned face. */
const headEuler = new THREE.Euler(0, 0, 0, 'YXZ');
function turnHead(head) {
  if (!(head && inCapture() && input('head-turn').checked)) { setTurn(null); return; }
  const d = THREE.MathUtils.degToRad;
  headEuler.set(-d(head[1]), d(head[0]), d(head[2]), 'YXZ');
  setTurn(new THREE.Quaternion().setFromEuler(headEuler));
}
$('head-turn').addEventListener('change', () => setFrame(currentFrame()));

// The input frame, the sliders and the diagram follow the current frame.
let shownFrame = -1;
onFrame((frame) => {
  const take = view && view.take;
  if (!view) return;
  const f = take ? Math.min(Math.round(frame), take.frames - 1) : -1;
  if (!capture.live.running) turnHead(take ? take.head[f] : null);
  if (take && !capture.live.running && f !== shownFrame) {
    shownFrame = f;
    if (f < take.previews) frameImage.src = `api/capture/frame/${f}.png?take=${take.id}`;
    else noPreview();
    fillSliders();
  }
  drawDiagram();
});

// A take reopened from the autosave or opened from a session file has no previews (a session
// does not keep its input).
const frameImage = /** @type {HTMLImageElement} */ ($('capture-frame'));
frameImage.addEventListener('load', () => { frameImage.hidden = false; });
frameImage.addEventListener('error', noPreview);
function noPreview() {
  frameImage.hidden = true;
  frameImage.removeAttribute('src');
  const note = $('capture-input-note');
  note.textContent = 'No preview of this frame: the take was opened from a session (or its autosave), which does not keep the input.';
  note.hidden = false;
}

// ---------- live webcam ----------
const video = /** @type {HTMLVideoElement} */ ($('capture-video'));
const grab = document.createElement('canvas');
let stream = /** @type {MediaStream|null} */ (null);
let inFlight = 0;
/** Timings of the frame whose weights are on the character but not yet drawn. */
let pendingShown = /** @type {{captured: number, sent: number, received: number}|null} */ (null);
let fpsWindow = { start: 0, count: 0 };

async function startLive() {
  showError('');
  try {
    stream = await navigator.mediaDevices.getUserMedia({ video: { width: { ideal: 640 }, height: { ideal: 480 }, frameRate: { ideal: 30 } }, audio: false });
  } catch (e) { showError(`The webcam could not be opened: ${e.message || e}`); return; }
  try { apply(await api('POST', 'api/capture/live/start')); }
  catch (e) { showError(String(e.message || e)); stopLive(); return; }
  $('capture-frame').hidden = true;
  Object.assign(capture.live, { running: true, fps: 0, latency_ms: 0, frames: 0, weights: null, latencies: [] });
  fpsWindow = { start: performance.now(), count: 0 };
  $('live').textContent = 'Stop webcam';
  /** @type {HTMLButtonElement} */ ($('record')).disabled = false;
  pause();
  const track = stream.getVideoTracks()[0];
  const Processor = /** @type {any} */ (window).MediaStreamTrackProcessor;
  if (Processor && typeof VideoFrame !== 'undefined') {
    // Frames straight from the camera track: independent of how fast the page is drawn, which
    // matters on machines that draw in software.
    shownCanvas.hidden = false;
    readTrack(new Processor({ track }).readable.getReader());
  } else {
    video.srcObject = stream;
    video.hidden = false;
    await video.play();
    nextVideoFrame();
  }
}

/** The input frame shown beside the character in live mode: the frame last sent. */
const shownCanvas = document.createElement('canvas');
shownCanvas.id = 'capture-live';
shownCanvas.hidden = true;
$('capture-input').appendChild(shownCanvas);

/** The newest camera frame not yet sent, with the time it arrived: a frame that arrives while
 * the server is busy waits here (replacing an older one), so that the next is sent the moment
 * an answer comes back instead of when the camera next delivers. */
let waiting = /** @type {{frame: any, captured: number}|null} */ (null);

async function readTrack(reader) {
  while (capture.live.running) {
    const { value: frame, done } = await reader.read();
    if (done || !frame) break;
    if (!capture.live.running) { frame.close(); continue; }
    if (waiting) waiting.frame.close();
    waiting = { frame, captured: performance.now() };
    sendWaiting();
  }
  if (waiting) { waiting.frame.close(); waiting = null; }
  reader.releaseLock();
}

/** Sends the waiting frame if a slot with the server is free. */
async function sendWaiting() {
  if (!waiting || !capture.live.running || inFlight >= capture.live.maxInFlight) return;
  const { frame, captured } = waiting;
  waiting = null;
  inFlight++; // the slot is taken while the frame is read, too
  try {
    const { pixels, width, height, format } = await frameBytes(frame);
    if (shownCanvas.width !== width) { shownCanvas.width = width; shownCanvas.height = height; }
    shownCanvas.getContext('2d')?.drawImage(frame, 0, 0, width, height);
    send(pixels, width, height, format, captured, performance.now());
  } catch (e) {
    inFlight--;
    if (capture.live.running) showError(`The webcam frame could not be read: ${e.message || e}`);
  } finally { frame.close(); }
}

/** Pixel-format headers of a frame the page converted to RGBA itself. */
const RGBA = { 'x-pixel-format': 'RGBA' };

/** A camera frame's bytes as the server reads them: the camera's own 4:2:0 planes when it
 * gives them (no conversion in the page, and 3/8 of the bytes of RGBA), else RGBA. */
async function frameBytes(/** @type {any} */ frame) {
  const { width, height } = frame.visibleRect;
  const cw = Math.ceil(width / 2), ch = Math.ceil(height / 2);
  if (frame.format === 'I420' || frame.format === 'NV12') {
    // Tightly packed planes, whatever the camera's own strides.
    const layout = frame.format === 'I420'
      ? [{ offset: 0, stride: width }, { offset: width * height, stride: cw }, { offset: width * height + cw * ch, stride: cw }]
      : [{ offset: 0, stride: width }, { offset: width * height, stride: 2 * cw }];
    try {
      const pixels = new Uint8Array(width * height + 2 * cw * ch);
      await frame.copyTo(pixels, { layout });
      const space = frame.colorSpace || {};
      const format = {
        'x-pixel-format': frame.format,
        // BT.709 for HD cameras (and BT.2020, nearer to it than to BT.601); BT.601 otherwise.
        'x-yuv-matrix': space.matrix === 'bt709' || space.matrix === 'bt2020-ncl' ? 'bt709' : 'bt601',
        'x-yuv-range': space.fullRange ? 'full' : 'limited',
      };
      return { pixels, width, height, format };
    } catch { /* fall through to RGBA */ }
  }
  try {
    const pixels = new Uint8Array(frame.allocationSize({ format: 'RGBA' }));
    await frame.copyTo(pixels, { format: 'RGBA' });
    return { pixels, width, height, format: RGBA };
  } catch {
    grab.width = width; grab.height = height;
    const g = /** @type {CanvasRenderingContext2D} */ (grab.getContext('2d', { willReadFrequently: true }));
    g.drawImage(frame, 0, 0, width, height);
    return { pixels: g.getImageData(0, 0, width, height).data, width, height, format: RGBA };
  }
}

function nextVideoFrame() {
  if (!capture.live.running) return;
  if ('requestVideoFrameCallback' in video) video.requestVideoFrameCallback((_now, meta) => onVideoFrame(meta.captureTime || meta.presentationTime || performance.now()));
  else requestAnimationFrame(() => onVideoFrame(performance.now()));
}

/** Sends the newest camera frame when a slot is free (a slow server drops frames instead of
 * falling behind). */
function onVideoFrame(captured) {
  nextVideoFrame();
  if (inFlight >= capture.live.maxInFlight || !video.videoWidth) return;
  const scale = Math.min(1, 640 / video.videoWidth);
  const width = Math.round(video.videoWidth * scale), height = Math.round(video.videoHeight * scale);
  grab.width = width; grab.height = height;
  const g = grab.getContext('2d', { willReadFrequently: true });
  if (!g) return;
  g.drawImage(video, 0, 0, width, height);
  inFlight++;
  send(g.getImageData(0, 0, width, height).data, width, height, RGBA, captured, performance.now());
}

/** Sends one frame (`format`: its pixel-format headers) in a slot already taken; its weights
 * go on the character when they come back, and the slot goes to the waiting frame. */
function send(pixels, width, height, format, captured, sent) {
  capture.live.format = format['x-pixel-format'];
  // A Blob, not the array itself: Chromium hands a Blob to its network process without copying
  // it through a pipe, which took ~70 ms of the round trip for a 480×480 frame here.
  const headers = { 'x-width': String(width), 'x-height': String(height), ...format };
  fetch('api/capture/live/frame', { method: 'POST', headers, body: new Blob([pixels]) })
    .then(async (response) => {
      const result = await response.json();
      if (!response.ok) throw new Error(result.error || response.statusText);
      if (!capture.live.running || !result.live) return;
      capture.live.weights = result.weights;
      if (result.head) turnHead(result.head);
      capture.live.server_ms = result.server_ms;
      capture.live.frames++;
      fpsWindow.count++;
      pendingShown = { captured, sent, received: performance.now() };
      applyLayer();
      capture.live.recorded = result.recorded ?? null;
      if (result.recorded !== null && result.recorded !== undefined) $('record').textContent = `Stop (${result.recorded})`;
    })
    .catch((e) => { if (capture.live.running) showError(String(e.message || e)); })
    .finally(() => { inFlight--; sendWaiting(); });
}

// Latency is measured when the character showing the frame's weights has been drawn.
onRender(() => {
  if (pendingShown === null) return;
  const drawn = performance.now();
  const { captured, sent, received } = pendingShown;
  const latency = drawn - captured;
  capture.live.stages = { grab_ms: sent - captured, round_trip_ms: received - sent, draw_ms: drawn - received };
  pendingShown = null;
  const l = capture.live.latencies;
  l.push(latency);
  if (l.length > 120) l.shift();
  const sorted = l.slice().sort((a, b) => a - b);
  capture.live.latency_ms = sorted[Math.floor(sorted.length / 2)];
  const now = performance.now();
  if (now - fpsWindow.start >= 1000) {
    capture.live.fps = fpsWindow.count * 1000 / (now - fpsWindow.start);
    fpsWindow = { start: now, count: 0 };
    $('live-stats').textContent = `Live: ${capture.live.fps.toFixed(1)} fps, ${capture.live.latency_ms.toFixed(0)} ms camera → screen (server ${capture.live.server_ms.toFixed(0)} ms)`;
  }
});

async function stopLive() {
  capture.live.running = false;
  // Let frames already on their way come back before the server stops tracking.
  for (let i = 0; i < 100 && inFlight > 0; i++) await new Promise((r) => setTimeout(r, 20));
  if (stream) for (const t of stream.getTracks()) t.stop();
  stream = null;
  video.hidden = true;
  video.srcObject = null;
  shownCanvas.hidden = true;
  $('live').textContent = 'Webcam (live)';
  $('record').textContent = 'Record';
  /** @type {HTMLButtonElement} */ ($('record')).disabled = true;
  try { apply(await api('POST', 'api/capture/live/stop')); } catch { /* the server may be gone */ }
  shownFrame = -1;
  setFrame(currentFrame());
}
$('live').onclick = () => (capture.live.running ? stopLive() : startLive());
$('record').onclick = async () => {
  const recording = view && view.live && view.live.recording !== null && view.live.recording !== undefined;
  if (!recording) {
    if (await post('api/capture/live/record', { on: true })) $('record').textContent = 'Stop (0)';
  } else if (await post('api/capture/live/record', { on: false })) {
    await stopLive();
  }
};

// The take (or the live face) is the layer under the sketch.
setLayer(layer);
