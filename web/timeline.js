// The timeline (seed section 3.9): one row per action with its box (drag to move it, drag an
// end to rescale it), the ruler that sets the current frame, and the playhead.

import { currentFrame, isPlaying, lastFrame, onFrame, setFrame } from './playback.js';
import { api } from './api.js';
import { showError, showFailure } from './status.js';
import * as store from './store.js';
import { onWaveform, waveform } from './sound.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

const timeline = $('timeline');
/** The last frame the ruler shows. */
let drawnTo = 0;
const LABEL = 200; // label column width
/** Pixels per frame: Ctrl+wheel zooms, Home fits everything. */
let PX = 8;
function frameX(f) { return LABEL + f * PX; }
function drawPlayhead() {
  const head = timeline.querySelector('.playhead');
  const x = frameX(currentFrame());
  if (head) head.style.left = `${x}px`;
  // While playing, the view follows the playhead.
  if (isPlaying() && (x > timeline.scrollLeft + timeline.clientWidth - 40 || x < timeline.scrollLeft + LABEL)) {
    timeline.scrollLeft = Math.max(0, x - LABEL - 40);
  }
}

/** Zooms the timeline so that every action fits its width. */
export function fitTimeline() {
  PX = Math.min(40, Math.max(0.5, (timeline.clientWidth - LABEL - 40) / Math.max(1, lastFrame())));
  timeline.scrollLeft = 0;
  drawTimeline();
}

// Ctrl+wheel zooms about the frame under the pointer.
timeline.addEventListener('wheel', (e) => {
  if (!e.ctrlKey) return;
  e.preventDefault();
  const rect = timeline.getBoundingClientRect();
  const frameUnder = (e.clientX - rect.left + timeline.scrollLeft - LABEL) / PX;
  PX = Math.min(40, Math.max(0.5, PX * Math.exp(-e.deltaY * 0.002)));
  drawTimeline();
  timeline.scrollLeft = Math.max(0, LABEL + frameUnder * PX - (e.clientX - rect.left));
}, { passive: false });
/** Draws the ruler, the animated window, one row per action and the playhead. */
export function drawTimeline() {
  const state = store.state();
  if (!state) return;
  timeline.innerHTML = '';
  const last = Math.max(lastFrame(), Math.ceil(currentFrame())) + 30;
  drawnTo = last;
  const width = frameX(last) + 20;
  const ruler = document.createElement('div');
  ruler.className = 'ruler';
  ruler.style.width = `${width}px`;
  for (let f = 0; f <= last; f += 10) { const s = document.createElement('span'); s.style.left = `${frameX(f)}px`; s.textContent = String(f); ruler.appendChild(s); }
  ruler.addEventListener('pointerdown', (e) => {
    const scrub = (ev) => { const rect = ruler.getBoundingClientRect(); setFrame(Math.round((ev.clientX - rect.left - LABEL) / PX)); };
    scrub(e);
    ruler.setPointerCapture(e.pointerId);
    ruler.onpointermove = scrub;
    ruler.onpointerup = () => { ruler.onpointermove = null; };
  });
  timeline.appendChild(ruler);
  // The temporal window: where animation exists.
  const win = document.createElement('div');
  win.className = 'window';
  win.style.left = `${frameX(0)}px`; win.style.width = `${state.last_frame * PX}px`;
  timeline.appendChild(win);
  // A lip-sync take's sound: its loudness per frame, under the ruler.
  const peaks = waveform();
  if (peaks) {
    const row = document.createElement('div');
    row.className = 'row sound';
    row.style.width = `${width}px`;
    const label = document.createElement('div');
    label.className = 'label';
    label.textContent = 'sound';
    const canvas = document.createElement('canvas');
    canvas.width = Math.max(1, peaks.length * PX);
    canvas.height = 24;
    canvas.style.position = 'absolute';
    canvas.style.left = `${frameX(0)}px`;
    const g = canvas.getContext('2d');
    if (g) {
      g.fillStyle = '#6fa8dc';
      peaks.forEach((p, f) => { const h = Math.max(1, p * 22); g.fillRect(f * PX, 12 - h / 2, Math.max(1, PX - 1), h); });
    }
    row.append(label, canvas);
    timeline.appendChild(row);
  }
  const chainColours = ['#4a7bd0', '#3fa36b', '#b0609c', '#c7843a', '#5aa8b8', '#9a8a3f'];
  for (const action of state.actions) {
    const row = document.createElement('div');
    row.className = 'row';
    row.style.width = `${width}px`;
    row.dataset.stroke = String(action.stroke);
    const label = document.createElement('div');
    label.className = 'label';
    // The action's own mirror, toggled here as in the inspector.
    const mirror = document.createElement('button');
    mirror.className = 'mirror' + (action.symmetric ? ' on' : '');
    mirror.textContent = '⇋';
    mirror.title = action.symmetric ? 'Mirrored: click for this side only' : 'One side: click to mirror it';
    mirror.setAttribute('aria-label', `Mirror ${action.name}`);
    mirror.setAttribute('aria-pressed', String(action.symmetric));
    mirror.onclick = (e) => { e.stopPropagation(); store.run('PATCH', `api/strokes/${action.stroke}`, { symmetry: !action.symmetric }); };
    label.append(mirror, action.name);
    label.onclick = () => store.select(action.stroke);
    row.appendChild(label);
    const box = document.createElement('div');
    box.className = 'box' + (store.selectedGroup().has(action.stroke) ? ' selected' : '');
    box.style.left = `${frameX(action.start_frame)}px`;
    box.style.width = `${Math.max(4, (action.end_frame - action.start_frame) * PX)}px`;
    box.style.background = chainColours[action.chain % chainColours.length];
    box.title = `${action.name}: frames ${action.start_frame.toFixed(1)}–${action.end_frame.toFixed(1)}${action.previous !== null ? ' (continues the stroke before it)' : ''}${action.symmetric ? ' (with its mirror)' : ''}`;
    if (action.previous !== null || action.symmetric) {
      const link = document.createElement('span');
      link.className = 'link';
      link.textContent = action.symmetric ? '⇋' : '⛓';
      box.appendChild(link);
    }
    // The weight over the action's time, as the engine plays it.
    const weight = action.sides[0].weight;
    const curve = document.createElementNS('http://www.w3.org/2000/svg', 'svg');
    curve.setAttribute('class', 'curve');
    curve.setAttribute('viewBox', '0 0 100 100');
    curve.setAttribute('preserveAspectRatio', 'none');
    const line = document.createElementNS('http://www.w3.org/2000/svg', 'polyline');
    line.setAttribute('points', action.progress.map((p, k) => `${100 * k / (action.progress.length - 1)},${100 - 90 * p * weight}`).join(' '));
    curve.appendChild(line);
    box.appendChild(curve);
    for (const side of ['left', 'right']) { const g = document.createElement('div'); g.className = `grip ${side}`; g.dataset.grip = side; box.appendChild(g); }
    box.addEventListener('pointerdown', (e) => timelineDrag(e, action, box));
    row.appendChild(box);
    timeline.appendChild(row);
  }
  const head = document.createElement('div');
  head.className = 'playhead';
  timeline.appendChild(head);
  drawPlayhead();
}
function timelineDrag(event, action, box) {
  event.stopPropagation();
  // No text selection or native drag may take the pointer away mid-drag.
  event.preventDefault();
  // Shift+click adds the action to the selection (or takes it out); a drag then moves, and a
  // dragged end rescales, every selected action together, as one undo step.
  if (event.shiftKey) { store.select(action.stroke, true); return; }
  if (!store.selectedGroup().has(action.stroke)) store.select(action.stroke);
  const state = store.state();
  const moving = state.actions.filter((a) => store.selectedGroup().has(a.stroke));
  const first = Math.min(...moving.map((a) => a.start_frame));
  const last = Math.max(...moving.map((a) => a.end_frame));
  const grip = /** @type {HTMLElement} */ (event.target).dataset.grip;
  const x0 = event.clientX;
  box.setPointerCapture(event.pointerId);
  /** @type {Map<number, {start_frame: number, duration: number}>} */
  let edits = new Map();
  box.onpointermove = (e) => {
    const df = Math.round((e.clientX - x0) / PX);
    edits = new Map();
    for (const a of moving) {
      const start = a.start_frame, duration = a.end_frame - a.start_frame;
      let edit;
      if (grip === 'right') {
        // Rescale about the first start: the whole group's span grows by df frames.
        const factor = Math.max(1, last - first + df) / Math.max(1, last - first);
        edit = { start_frame: Math.round(first + (start - first) * factor), duration: Math.max(1, Math.round(duration * factor)) };
      } else if (grip === 'left' && moving.length === 1) {
        const s = Math.min(start + duration - 1, Math.max(0, start + df));
        edit = { start_frame: s, duration: start + duration - s };
      } else {
        edit = { start_frame: Math.max(0, start + Math.max(df, -first)), duration };
      }
      edits.set(a.stroke, edit);
      const shown = timeline.querySelector(`.row[data-stroke="${a.stroke}"] .box`);
      if (shown) { /** @type {HTMLElement} */ (shown).style.left = `${frameX(edit.start_frame)}px`; /** @type {HTMLElement} */ (shown).style.width = `${edit.duration * PX}px`; }
    }
  };
  box.onpointerup = async () => {
    box.onpointermove = null; box.onpointerup = null;
    if (!edits.size) { drawTimeline(); return; }
    const gesture = `${Date.now()}-${Math.random()}`;
    try {
      let answer = null;
      for (const [stroke, edit] of edits) answer = await api('PATCH', `api/strokes/${stroke}`, edit, { 'x-gesture': gesture });
      store.setState(answer, true);
      showError('');
    } catch (e) { showFailure(e); drawTimeline(); }
  };
}

store.onState(() => drawTimeline());
// A take's sound, once decoded, draws its waveform under the rows.
onWaveform(() => drawTimeline());
// A selection changes only the boxes' look: redrawing would replace the box being pressed.
store.onSelection(() => {
  for (const row of timeline.querySelectorAll('.row')) {
    const stroke = Number(/** @type {HTMLElement} */ (row).dataset.stroke);
    row.querySelector('.box')?.classList.toggle('selected', store.selectedGroup().has(stroke));
  }
});
// A playhead typed or played past the ruler's end gets a longer ruler.
onFrame((frame) => (frame > drawnTo - 5 ? drawTimeline() : drawPlayhead()));
