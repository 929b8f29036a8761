// faceanim studio: capture mode. A face video, photos or the webcam drive the character
// (seed 003's toolkit): the input frame beside the character, the frame diagram, corrections
// by name, keyframes, preference, the adapter (train, fine-tune), live webcam puppeteering and
// recording. The server owns the take; this file draws /api/capture/state and sends edits.
// Sketch strokes keep working on top: the take is the layer under them (playback's layer).

import { api } from './api.js';
import { turnHead } from './head-turn.js';
import { inCapture, onMode } from './mode.js';
import { applyLayer, currentFrame, onFrame, pause, setExtent, setFrame, setLayer, showSketch } from './playback.js';
import { showError, showFailure } from './status.js';
import * as store from './store.js';
import { drawTimeline } from './timeline.js';
import { live } from './live.js';
import { voice } from './voice.js';
import { visemes } from './visemes.js';
import { showMap } from './retarget.js';
import { showControls as showVmcControls, vmc } from './vmc.js';
import { setSound } from './sound.js';
import { apply, currentView, onShowTakeFrame, onView, post } from './take.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));
const input = (id) => /** @type {HTMLInputElement} */ (document.getElementById(id));

/** Name of the blendshape whose curve the diagram draws. */
let selectedName = 'jawOpen';
/** A slider being dragged: its name and value show on the character before the server has it. */
let preview = null;

/** Capture mode as scripts and tests see it (`window.studio.capture`). */
export const capture = {
  get view() { return currentView(); },
  /** Live webcam measurements (live.js). */
  live,
  /** Live microphone measurements (voice.js). */
  voice,
  /** Lip sync's viseme table (visemes.js). */
  visemes,
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
  const take = currentView()?.take;
  return { canUndo: !!(take && take.can_undo), canRedo: !!(take && take.can_redo) };
}

// ---------- state ----------
let polling = 0;
async function refresh() {
  const v = await api('GET', 'api/capture/state');
  apply(v);
  return v;
}

/** Draws a capture state the server answered with. */
onView((v, previous) => {
  const hadTake = previous && previous.take ? previous.take.id : null;
  const take = v.take;
  const newTake = take && take.id !== hadTake;
  if (newTake) shownFrame = -1;
  // A photo plays as its ramp (0 → peak → 0), which is what exports.
  setExtent(take ? (take.ramp ? take.ramp.length : take.frames) - 1 : 0);
  setSound(take && take.sound ? take.sound : null, take ? take.fps : 30);
  $('still-row').hidden = !(take && take.still);
  // Said once by the server: an autosaved take it could not open and set aside; and the
  // code page a picked transcript was read in, until the next input.
  const notice = [v.notice, transcriptNote].filter(Boolean).join(' ');
  $('capture-notice').hidden = !notice;
  $('capture-notice').textContent = notice;
  if (take && take.still && document.activeElement !== $('still-frames')) input('still-frames').value = String(take.still);
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
  input('train-samples').placeholder = String(a.default_samples);
  $('adapter-info').textContent = a.loaded
    ? `Adapter: ${a.path}${a.report ? ` (test MAE ${a.report.mae_test.toFixed(4)}, ${a.report.samples} renders${a.on_map ? ', on top of the retarget map' : ''})` : ''}.${a.note ? ` ${a.note}` : ''}${a.unseen.length ? ` Capture cannot drive ${a.unseen.length} of ${a.report ? a.report.shapes.length : '?'} shapes, each shown alone: ${a.unseen.join(', ')}. Sketch them or correct frames.` : ''}`
    : `No adapter: ${v.retarget.in_use ? 'capture is read through the retarget map' : 'estimating by ARKit name'}.${a.note ? ` ${a.note}` : ''} Train one to refine it on this character's renders.`;
  /** @type {HTMLButtonElement} */ ($('finetune')).disabled = running || !a.loaded || !take || !take.corrected.length;
  showMap(v.retarget, apply, running);
  // Filtering.
  const f = v.filtering;
  const s = f.smoothing || f.default_smoothing;
  input('one-euro').checked = !!f.smoothing;
  if (document.activeElement !== $('min-cutoff')) input('min-cutoff').value = String(s.min_cutoff);
  if (document.activeElement !== $('beta')) input('beta').value = String(s.beta);
  if (document.activeElement !== $('keyframe-every')) input('keyframe-every').value = String(f.keyframe_every);
  // Take.
  $('take-info').textContent = take
    ? `${take.source}: ${take.frames} frame(s) at ${take.fps} fps, ${take.keyframes.length} keyframes, ${take.corrected.length} corrected; ${take.sound ? 'lip-synced from its speech' : ESTIMATED[take.estimator] || take.estimator}${take.preference ? '; preference applied' : ''}.`
    : '';
  if (!take) $('capture-input-note').textContent = 'Open a video, photos, speech, a take (session, clip, animated GLB or VRM, Live Link CSV) or the webcam (right).';
  $('capture-input-note').hidden = (!!take && !frameImage.hidden) || live.running;
  for (const id of ['keyframe', 'uncorrect-frame', 'apply-preference', 'clear-preference']) /** @type {HTMLButtonElement} */ ($(id)).disabled = !take;
  showNeutralFrame(v);
  /** @type {HTMLButtonElement} */ ($('clear-preference')).disabled = !take || !take.preference;
  for (const a2 of document.querySelectorAll('#capture-panel .exports a')) a2.classList.toggle('disabled', !take);
  buildSliders(v);
  showVmcControls(v);
  notify();
  drawTimeline();
  setFrame(newTake ? 0 : currentFrame());
});

/** The weights under the sketch at `frame`: the live face, else the take (with a slider
 * being dragged shown at once). */
function layer(frame) {
  if (live.running && live.weights) return live.weights;
  if (voice.running && voice.weights) return voice.weights;
  if (vmc.running && vmc.weights) return vmc.weights;
  const take = currentView()?.take;
  if (!take) return null;
  if (take.ramp && !preview) return take.ramp[Math.min(Math.round(frame), take.ramp.length - 1)];
  const f = Math.min(Math.round(frame), take.frames - 1);
  const row = take.weights[f];
  if (!preview || preview.frame !== f) return row;
  const copy = row.slice();
  const index = currentView().blendshapes.indexOf(preview.name);
  copy[index] = preview.value;
  const partner = currentView().partners[index];
  if (preview.linked && partner !== null && partner !== undefined) copy[partner] = preview.value;
  return copy;
}

/** How the take-info line says where the estimates came from. */
const ESTIMATED = { adapter: 'estimated by the adapter', by_name: 'estimated by ARKit name', retarget: 'read through the retarget map', session_file: 'opened from a session' };

// ---------- input ----------
/** What the server said of the last transcript file read (its guessed code page), or '', and
 * the words it said it of: the note stands while the field still holds them. */
let transcriptNote = '';
let transcriptNoted = '';

const header = (file) => ({ 'x-filename': encodeURIComponent(file.name) });

/**
 * Puts the words of a transcript file (plain text or a subtitle) in the speech field, read by
 * the server in the encoding it was saved in (a Japanese subtitle in Shift_JIS, Notepad's
 * UTF-16), which the page cannot tell apart itself.
 */
async function readTranscript(file) {
  const language = input('speech-language').value.trim();
  const query = language ? `?${new URLSearchParams({ language })}` : '';
  const read = await api('POST', `api/capture/transcript${query}`, await file.arrayBuffer(), header(file));
  input('speech-text').value = read.text;
  transcriptNote = read.note || '';
  transcriptNoted = read.text;
}

/**
 * Opens `files` as the take: one video, speech file or take file, or a sequence of photos. A
 * transcript or subtitle picked with the speech (or alone, before it) fills the speech field.
 */
export async function openInput(files) {
  if (!files.length) return;
  showError('');
  // A transcript picked before its speech keeps its note while its words are in the field.
  const speech = files.some((f) => AUDIO.test(f.name) || TRANSCRIPT.test(f.name));
  if (!speech || input('speech-text').value !== transcriptNoted) transcriptNote = '';
  try {
    const transcripts = files.filter((f) => TRANSCRIPT.test(f.name));
    if (transcripts.length > 1) throw new Error('pick one transcript or subtitle with the speech');
    if (transcripts.length) {
      await readTranscript(transcripts[0]);
      files = files.filter((f) => f !== transcripts[0]);
      if (!files.length) {
        $('take-info').textContent = `The words of ${transcripts[0].name} are in the transcript field: now pick the speech they go with.`;
        $('capture-notice').hidden = !transcriptNote;
        $('capture-notice').textContent = transcriptNote;
        return;
      }
    }
    if (files.length === 1) {
      let url = 'api/capture/upload';
      if (AUDIO.test(files[0].name)) {
        $('take-info').textContent = `Lip sync of ${files[0].name}…`;
        // What was said, and in which language, when the user typed them; whose voice, when
        // the user chose.
        const query = new URLSearchParams();
        const text = input('speech-text').value.trim();
        const language = input('speech-language').value.trim();
        const voice = input('speech-voice').value;
        if (text) query.set('text', text);
        if (language) query.set('language', language);
        if (voice && voice !== 'auto') query.set('voice', voice);
        if ([...query].length) url += `?${query}`;
      }
      apply(await api('POST', url, await files[0].arrayBuffer(), header(files[0])));
      return;
    }
    // Several photos are one sequence, in name order, like a folder of frames.
    if (files.some((f) => !/\.(png|jpe?g)$/i.test(f.name))) throw new Error('pick one video, one speech file (with its transcript or subtitle, if you have one), one take (session, clip, GLB, VRM or Live Link CSV), or any number of PNG or JPEG photos');
    const batch = Date.now().toString(36) + Math.random().toString(36).slice(2, 8);
    for (const [index, file] of files.entries()) {
      $('take-info').textContent = `Sending ${file.name} (${index + 1} of ${files.length})…`;
      apply(await api('POST', `api/capture/upload?batch=${batch}&index=${index}&count=${files.length}`, await file.arrayBuffer(), header(file)));
    }
  } catch (e) { showError(String(e.message || e)); }
}

/** Speech the server lip-syncs (crates/studio: capture::audio_mime). */
export const AUDIO = /\.(wav|mp3|ogg|oga|opus|flac|m4a|aac)$/i;
/** Transcripts and subtitles the speech field takes (the command line's --text files). */
export const TRANSCRIPT = /\.(txt|text|lab|srt|vtt|ass|ssa|md)$/i;

input('capture-file').addEventListener('change', () => {
  const files = [...(input('capture-file').files || [])];
  input('capture-file').value = '';
  openInput(files);
});
$('capture-open').onclick = async () => {
  const path = input('capture-path').value.trim();
  if (!path) { showError('Type the path of a video, an image, a folder of images or a session file'); return; }
  try { showError(''); apply(await api('POST', 'api/capture/open', { path })); }
  catch (e) { showError(String(e.message || e)); }
};
$('capture-close').onclick = () => post('api/capture/close');
$('job-cancel').onclick = () => post('api/capture/cancel');

// ---------- adapter ----------
// Empty: the studio's default, shown as the placeholder.
$('train').onclick = () => {
  const samples = Math.round(Number(input('train-samples').value));
  post('api/capture/adapter/train', samples > 0 ? { samples } : {});
};
$('finetune').onclick = () => post('api/capture/adapter/finetune');

// ---------- smoothing ----------
async function sendFiltering() {
  const body = {
    keyframe_every: Math.round(Number(input('keyframe-every').value)),
    smoothing: input('one-euro').checked ? { min_cutoff: Number(input('min-cutoff').value), beta: Number(input('beta').value) } : null,
  };
  try { showError(''); apply(await api('PUT', 'api/capture/filtering', body)); }
  catch (e) { showError(String(e.message || e)); }
}
for (const id of ['one-euro', 'min-cutoff', 'beta', 'keyframe-every']) $(id).addEventListener('change', sendFiltering);
input('still-frames').addEventListener('change', async () => {
  try { showError(''); apply(await api('PUT', 'api/capture/still', { frames: Math.round(Number(input('still-frames').value)) })); }
  catch (e) { showFailure(e); }
});

// ---------- the current frame: keyframes, corrections, preference ----------
/** The take's frame under the playhead (a photo has one, however long its ramp plays). */
const shownFrameIndex = () => {
  const take = currentView()?.take;
  return take ? Math.min(Math.round(currentFrame()), take.frames - 1) : Math.round(currentFrame());
};
$('keyframe').onclick = () => {
  const take = currentView()?.take;
  if (!take) return;
  const f = shownFrameIndex();
  post('api/capture/keyframe', { frame: f, on: !take.keyframes.includes(f) });
};
$('uncorrect-frame').onclick = () => post('api/capture/uncorrect', { frame: shownFrameIndex() });
/** Which frame the take is read against; the buttons matter only where the estimate reads faces
 *  relative to a neutral one (an adapter's or a retarget map's, as the studio says). */
function showNeutralFrame(v) {
  const take = v.take, relative = Boolean(take && take.reads_neutral);
  for (const id of ['neutral-frame', 'neutral-auto']) /** @type {HTMLButtonElement} */ ($(id)).disabled = !relative;
  const warning = take && take.neutral_warning ? `Warning: ${take.neutral_warning}.` : '';
  // What reads faces against it, as the studio picks its estimate: the adapter when one is
  // loaded, else the retarget map (whatever made the take: a session file does not say).
  const reader = v.adapter.loaded ? 'the adapter' : 'the retarget map';
  $('neutral-info').textContent = !take ? ''
    : !take.neutral ? (relative ? warning : '')
    : relative
      ? `Neutral face: ${neutralFrames(take.neutral)}; ${reader} reads every frame relative to it.${warning ? ` ${warning}` : ''}`
      : `Neutral face: ${neutralFrames(take.neutral)} (unused: this estimate does not read faces relative to a neutral one).`;
}
/** Where a take's neutral face comes from, in words: the user's frame, or each part's. */
function neutralFrames(neutral) {
  if (neutral.chosen === 'user') return `frame ${neutral.frame} (yours)`;
  const p = neutral.parts;
  return p.lids === p.mouth && p.gaze === p.mouth && p.brows === p.mouth
    ? `frame ${p.mouth} (the calmest)`
    : `each part at its calmest frame (lids ${p.lids}, gaze ${p.gaze}, brows ${p.brows}, mouth ${p.mouth})`;
}
$('neutral-frame').onclick = () => post('api/capture/neutral', { frame: shownFrameIndex() });
$('neutral-auto').onclick = () => post('api/capture/neutral', { frame: null });
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
          preview = { frame: shownFrameIndex(), name, value: Number(range.value), linked: input('link-sides').checked };
          out.textContent = Number(range.value).toFixed(2);
          applyLayer();
        });
        range.addEventListener('change', async () => {
          const value = Number(range.value);
          const ok = await post('api/capture/correct', { frame: shownFrameIndex(), name, value, mirror: input('link-sides').checked });
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
  const take = currentView()?.take;
  const f = shownFrameIndex();
  const row = take ? take.weights[Math.min(f, take.frames - 1)] : null;
  const corrected = take ? take.corrections[String(f)] || {} : {};
  currentView().blendshapes.forEach((name, i) => {
    const s = sliders.get(name);
    if (!s) return;
    const value = row ? row[i] : 0;
    if (document.activeElement !== s.range) s.range.value = String(value);
    s.out.textContent = value.toFixed(2);
    s.range.disabled = !take || live.running;
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
  const take = currentView()?.take;
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
  const b = currentView().blendshapes.indexOf(selectedName);
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
  const take = currentView()?.take;
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


// The input frame, the sliders and the diagram follow the current frame.
let shownFrame = -1;
onFrame((frame) => {
  const take = currentView()?.take;
  if (!currentView()) return;
  const f = take ? Math.min(Math.round(frame), take.frames - 1) : -1;
  if (!live.running && !vmc.running && !voice.running) turnHead(take ? take.head[f] : null, take && take.bones ? take.bones[Math.min(Math.round(frame), take.bones.length - 1)] : null);
  if (take && !live.running && !vmc.running && f !== shownFrame) {
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
  const take = currentView()?.take;
  note.textContent = take && take.sound
    ? 'Lip sync: this take was made from speech; its sound plays with it (the sound row of the timeline).'
    : take && take.estimator === 'received'
      ? 'No picture: this take arrived as the character\'s weights.'
      : 'No preview of this frame: the take was opened from a session (or its autosave), which does not keep the input.';
  note.hidden = false;
}

// A live source asks for the take's frame again (after live mode, which drew over it).
onShowTakeFrame(() => {
  shownFrame = -1;
  setFrame(currentFrame());
});

// The take (or the live face) is the layer under the sketch.
setLayer(layer);

// A VRM avatar's take also downloads as a VRM Animation.
store.onCharacter((character) => {
  /** @type {HTMLElement} */ (document.getElementById('capture-export-vrma')).hidden = !character.vrm;
});

// "Sketch over the take": off, the page plays and the downloads hold the take alone.
const sketchOverTake = /** @type {HTMLInputElement} */ (document.getElementById('sketch-over-take'));
sketchOverTake.addEventListener('change', () => {
  showSketch(sketchOverTake.checked);
  for (const link of document.querySelectorAll('.exports a[id^="capture-export"]')) {
    const url = new URL(/** @type {HTMLAnchorElement} */ (link).getAttribute('href'), location.href);
    if (sketchOverTake.checked) url.searchParams.delete('sketch');
    else url.searchParams.set('sketch', 'false');
    link.setAttribute('href', url.pathname.replace(/^\//, '') + url.search);
  }
});
