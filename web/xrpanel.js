// The timeline of seed section 3.9 as a panel in the VR world, pointed at with the other hand's
// ray and clicked with its trigger: one box per action with its name, orange start and end
// handles (drag the start: the action starts later or earlier and keeps its end; drag the end:
// it lasts longer or shorter), the body moves it whole; the current-frame bar (click the ruler
// to set the frame; in the Timeline state the thumbstick scrubs it); Play/Pause; ▲ ▼ scroll
// through many actions. Drawn on a canvas texture, again only when the state or frame changed.

import * as THREE from 'three';
import { api } from './api.js';
import { currentFrame, isPlaying, lastFrame, onFrame, play, setFrame } from './playback.js';
import { showFailure } from './status.js';
import * as store from './store.js';

// 1024 × 512 pixels on 0.64 m × 0.32 m: 1.6 px per mm; 28 px text is 17 mm high, legible at
// a metre (well over 20 px of a headset's view).
const W = 1024, H = 512, WIDTH_M = 0.64, HEIGHT_M = 0.32;
const ROW = 56, TOP = 84, LEFT = 190, RIGHT = 24, ROWS = 7;
const canvas = document.createElement('canvas');
canvas.width = W; canvas.height = H;
const texture = new THREE.CanvasTexture(canvas);
texture.colorSpace = THREE.SRGBColorSpace;
/** The panel, placed by xr.js in the reference space. */
export const timelinePanel = new THREE.Mesh(new THREE.PlaneGeometry(WIDTH_M, HEIGHT_M), new THREE.MeshBasicMaterial({ map: texture, side: THREE.DoubleSide }));
timelinePanel.name = 'timeline panel';
let scroll = 0;
let dirty = true;
/** @type {null | {stroke: number, part: 'start' | 'end' | 'body', grabFrame: number, start: number, duration: number, edit: any}} */
let drag = null;
let hover = { x: -1, y: -1 };

store.onState(() => { dirty = true; });
onFrame(() => { dirty = true; });

function span() {
  const state = store.state();
  const last = Math.max(1, lastFrame(), ...(state ? state.actions.map((a) => a.end_frame) : [0]));
  return Math.ceil(last * 1.1 + 1);
}
const frameX = (f) => LEFT + (W - LEFT - RIGHT) * f / span();
const xFrame = (x) => (x - LEFT) / (W - LEFT - RIGHT) * span();

function rows() {
  const state = store.state();
  return state ? state.actions.slice(scroll, scroll + ROWS) : [];
}

/** Redraws the panel when something it shows changed. */
export function refreshPanel() {
  if (!dirty) return;
  dirty = false;
  const g = /** @type {CanvasRenderingContext2D} */ (canvas.getContext('2d'));
  g.fillStyle = '#1d2026'; g.fillRect(0, 0, W, H);
  g.font = 'bold 30px sans-serif'; g.textBaseline = 'middle';
  // Play / pause and scrolling.
  g.fillStyle = '#3a4050'; g.fillRect(12, 12, 150, 56); g.fillRect(W - 150, 12, 60, 56); g.fillRect(W - 80, 12, 60, 56);
  g.fillStyle = '#f0f0f0'; g.fillText(isPlaying() ? 'Pause' : 'Play', 36, 40); g.fillText('▲', W - 134, 40); g.fillText('▼', W - 64, 40);
  // The ruler and the current frame.
  g.fillStyle = '#2b303a'; g.fillRect(LEFT, 12, W - LEFT - RIGHT - 170, 56);
  g.fillStyle = '#c0c4cc'; g.font = '26px sans-serif';
  g.fillText(`frame ${Math.round(currentFrame())} / ${Math.round(lastFrame())}`, LEFT + 12, 40);
  const state = store.state();
  const actions = rows();
  g.font = '28px sans-serif';
  actions.forEach((action, i) => {
    const y = TOP + i * ROW;
    g.fillStyle = '#e8e8e8';
    g.fillText(action.name.slice(0, 11), 16, y + ROW / 2);
    const x0 = frameX(action.start_frame), x1 = Math.max(x0 + 8, frameX(action.end_frame));
    g.fillStyle = store.selection() === action.stroke ? '#5d8fd8' : '#4a6fa5';
    g.fillRect(x0, y + 8, x1 - x0, ROW - 16);
    g.fillStyle = '#ff9a2e';
    g.fillRect(x0 - 6, y + 4, 14, ROW - 8);
    g.fillRect(x1 - 8, y + 4, 14, ROW - 8);
  });
  if (state && state.actions.length > ROWS) {
    g.fillStyle = '#9aa0aa'; g.font = '22px sans-serif';
    g.fillText(`${scroll + 1}–${Math.min(state.actions.length, scroll + ROWS)} of ${state.actions.length}`, 16, H - 20);
  }
  const bar = frameX(currentFrame());
  g.fillStyle = '#ff4040'; g.fillRect(bar - 2, 12, 4, H - 24);
  if (hover.x >= 0) { g.fillStyle = 'rgba(255,255,255,0.8)'; g.beginPath(); g.arc(hover.x, hover.y, 7, 0, 2 * Math.PI); g.fill(); }
  texture.needsUpdate = true;
}

const raycaster = new THREE.Raycaster();
/** The panel pixel a ray points at, or null. */
function pixelOf(origin, direction) {
  raycaster.set(origin, direction);
  const hit = raycaster.intersectObject(timelinePanel, false)[0];
  if (!hit || !hit.uv) return null;
  return { x: hit.uv.x * W, y: (1 - hit.uv.y) * H };
}

/** The other hand's ray, each XR frame: hover, and a trigger `press` (edge) or `held`. Returns
 * whether the ray is on the panel (then the trigger is the panel's). */
export function pointPanel(origin, direction, pressed, wasPressed) {
  const p = pixelOf(origin, direction);
  const moved = p ? Math.abs(p.x - hover.x) + Math.abs(p.y - hover.y) > 2 : hover.x >= 0;
  hover = p || { x: -1, y: -1 };
  if (moved) dirty = true;
  if (drag && p && pressed) dragTo(p);
  if (drag && !pressed) { finishDrag(); return !!p; }
  if (!p || !pressed || wasPressed) return !!p;
  // A click.
  if (p.y < 72) {
    if (p.x < 170) play();
    else if (p.x > W - 154 && p.x < W - 86) scroll = Math.max(0, scroll - 1);
    else if (p.x > W - 84) scroll = Math.min(Math.max(0, (store.state() ? store.state().actions.length : 0) - ROWS), scroll + 1);
    else setFrame(Math.max(0, Math.round(xFrame(p.x))));
    dirty = true;
    return true;
  }
  const i = Math.floor((p.y - TOP) / ROW);
  const action = rows()[i];
  if (!action) return true;
  const x0 = frameX(action.start_frame), x1 = Math.max(x0 + 8, frameX(action.end_frame));
  const part = Math.abs(p.x - x0) <= 14 ? 'start' : Math.abs(p.x - x1) <= 14 ? 'end' : p.x > x0 && p.x < x1 ? 'body' : null;
  store.select(action.stroke);
  if (part) drag = { stroke: action.stroke, part, grabFrame: xFrame(p.x), start: action.start_frame, duration: action.end_frame - action.start_frame, edit: null };
  dirty = true;
  return true;
}

function dragTo(p) {
  const df = Math.round(xFrame(p.x) - drag.grabFrame);
  const { start, duration } = drag;
  if (drag.part === 'start') {
    const s = Math.min(start + duration - 1, Math.max(0, start + df));
    drag.edit = { start_frame: s, duration: start + duration - s };
  } else if (drag.part === 'end') drag.edit = { start_frame: start, duration: Math.max(1, duration + df) };
  else drag.edit = { start_frame: Math.max(0, start + df), duration };
}

async function finishDrag() {
  const finished = drag;
  drag = null;
  if (!finished || !finished.edit) return;
  try {
    const state = await api('PATCH', `api/strokes/${finished.stroke}`, finished.edit);
    store.setState(state, true);
  } catch (e) { showFailure(e); }
}

/** The reference-space point of an action's `part` (`'start'` or `'end'` handle) on the panel,
 * or null when its row is scrolled away: where a test points the other hand's ray. */
export function panelHandle(stroke, part) {
  const actions = rows();
  const i = actions.findIndex((a) => a.stroke === stroke);
  if (i < 0) return null;
  const action = actions[i];
  const x = part === 'end' ? Math.max(frameX(action.start_frame) + 8, frameX(action.end_frame)) : frameX(action.start_frame);
  const y = TOP + i * ROW + ROW / 2;
  timelinePanel.updateMatrixWorld(true);
  return timelinePanel.localToWorld(new THREE.Vector3((x / W - 0.5) * WIDTH_M, (0.5 - y / H) * HEIGHT_M, 0));
}
