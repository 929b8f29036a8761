// The panels of the VR world, pointed at with the other hand's ray and clicked with its trigger,
// drawn on canvas textures again only when what they show changed:
// - the timeline of seed section 3.9: one box per action with its name, orange start and end
//   handles (drag the start: the action starts later or earlier and keeps its end; drag the
//   end: it lasts longer or shorter), the body moves it whole; the current-frame bar (click the
//   ruler to set the frame; in the Timeline state the thumbstick scrubs it); Play/Pause; ▲ ▼
//   scroll through many actions;
// - the settings of seed figure 11: stroke thickness, candidate radius, pen distance, edit radius
//   and hook radius as sliders (in % of the character's size, as the desktop panel shows them),
//   subsampling, symmetry, and Save and Export GLB.

import * as THREE from 'three';
import { api } from './api.js';
import { currentFrame, isPlaying, lastFrame, onFrame, play, setFrame } from './playback.js';
import { showFailure, showStatus } from './status.js';
import * as store from './store.js';

const raycaster = new THREE.Raycaster();

/** A panel: a `w`×`h` canvas shown on a `widthM`×`heightM` plane (metres), with the canvas
 * pixel a ray points at (`pixelAt`, or null) and the reference-space point of a pixel
 * (`pointAt`). */
function makePanel(name, w, h, widthM, heightM) {
  const canvas = document.createElement('canvas');
  canvas.width = w; canvas.height = h;
  const texture = new THREE.CanvasTexture(canvas);
  texture.colorSpace = THREE.SRGBColorSpace;
  const mesh = new THREE.Mesh(new THREE.PlaneGeometry(widthM, heightM), new THREE.MeshBasicMaterial({ map: texture, side: THREE.DoubleSide }));
  mesh.name = name;
  return {
    canvas, texture, mesh,
    pixelAt(origin, direction) {
      raycaster.set(origin, direction);
      const hit = raycaster.intersectObject(mesh, false)[0];
      return hit && hit.uv ? { x: hit.uv.x * w, y: (1 - hit.uv.y) * h } : null;
    },
    pointAt(x, y) {
      mesh.updateMatrixWorld(true);
      return mesh.localToWorld(new THREE.Vector3((x / w - 0.5) * widthM, (0.5 - y / h) * heightM, 0));
    },
  };
}

// 1024 × 512 pixels on 0.64 m × 0.32 m: 1.6 px per mm; 28 px text is 17 mm high, legible at
// a metre (well over 20 px of a headset's view).
const W = 1024, H = 512, WIDTH_M = 0.64, HEIGHT_M = 0.32;
const ROW = 56, TOP = 84, LEFT = 190, RIGHT = 24, ROWS = 7;
const timeline = makePanel('timeline panel', W, H, WIDTH_M, HEIGHT_M);
const canvas = timeline.canvas, texture = timeline.texture;
/** The panel, placed by xr.js in the reference space. */
export const timelinePanel = timeline.mesh;
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

/** The other hand's ray, each XR frame: hover, and a trigger `press` (edge) or `held`. Returns
 * whether the ray is on the panel (then the trigger is the panel's). */
export function pointPanel(origin, direction, pressed, wasPressed) {
  if (pointSettings(origin, direction, pressed, wasPressed)) return true;
  const p = timeline.pixelAt(origin, direction);
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
  return timeline.pointAt(x, TOP + i * ROW + ROW / 2);
}

// ---------- the settings panel ----------
const SW = 768, SH = 640, SWIDTH_M = 0.42, SHEIGHT_M = 0.35;
const settingsBoard = makePanel('settings panel', SW, SH, SWIDTH_M, SHEIGHT_M);
const settingsCanvas = settingsBoard.canvas, settingsTexture = settingsBoard.texture;
/** The settings panel, placed by xr.js in the reference space. */
export const settingsPanel = settingsBoard.mesh;
let settingsDirty = true;
store.onState(() => { settingsDirty = true; });

/** The sliders: a setting, its label, and its range in % of the character's size. */
const SLIDERS = [
  ['stroke_thickness', 'Stroke thickness'],
  ['candidate_radius', 'Candidate radius'],
  ['pen_distance', 'Pen distance'],
  ['edit_radius', 'Edit radius'],
  ['hook_radius', 'Hook radius'],
];
const MAX_PERCENT = 25;
const SLIDER_LEFT = 380, SLIDER_RIGHT = SW - 40, ROW_H = 70, FIRST = 40;
const characterSize = () => Math.max(1e-9, store.character() ? store.character().diagonal : 1);
/** A distance as the slider's position in [0, 1] (square-root scale: fine near zero). */
const toSlider = (distance) => Math.sqrt(Math.min(1, Math.max(0, 100 * distance / characterSize() / MAX_PERCENT)));
const fromSlider = (s) => MAX_PERCENT / 100 * characterSize() * s * s;
/** The value a setting has now (its own, or what the character's size gives). */
function valueOf(state, key) {
  const own = state.settings[key];
  return own === null || own === undefined ? state.resolved[key] ?? 0 : own;
}
/** @type {null | {key: string}} */
let sliding = null;
/** A setting being changed, shown before the server has answered. */
let pendingSetting = null;

/** Redraws the settings panel when the state changed. */
export function refreshSettings() {
  if (!settingsDirty) return;
  settingsDirty = false;
  const state = store.state();
  const g = /** @type {CanvasRenderingContext2D} */ (settingsCanvas.getContext('2d'));
  g.fillStyle = '#1d2026'; g.fillRect(0, 0, SW, SH);
  if (!state) return;
  g.textBaseline = 'middle';
  SLIDERS.forEach(([key, name], i) => {
    const y = FIRST + i * ROW_H;
    const value = pendingSetting && pendingSetting.key === key ? pendingSetting.value : valueOf(state, key);
    g.fillStyle = '#e8e8e8'; g.font = '26px sans-serif';
    g.fillText(name, 20, y);
    g.fillStyle = '#9aa0aa'; g.font = '24px sans-serif';
    g.fillText(`${(100 * value / characterSize()).toPrecision(2)} %`, 250, y);
    g.fillStyle = '#3a4050'; g.fillRect(SLIDER_LEFT, y - 6, SLIDER_RIGHT - SLIDER_LEFT, 12);
    const x = SLIDER_LEFT + toSlider(value) * (SLIDER_RIGHT - SLIDER_LEFT);
    g.fillStyle = '#ff9a2e'; g.beginPath(); g.arc(x, y, 16, 0, 2 * Math.PI); g.fill();
  });
  const y = FIRST + SLIDERS.length * ROW_H;
  g.fillStyle = '#e8e8e8'; g.font = '28px sans-serif';
  g.fillText(`Subsampling  ${state.settings.subsample}`, 20, y);
  g.fillStyle = '#3a4050'; g.fillRect(SLIDER_LEFT, y - 26, 80, 52); g.fillRect(SLIDER_LEFT + 100, y - 26, 80, 52);
  g.fillStyle = '#f0f0f0'; g.fillText('−', SLIDER_LEFT + 30, y); g.fillText('+', SLIDER_LEFT + 130, y);
  const buttons = FIRST + (SLIDERS.length + 1) * ROW_H;
  const button = (x, w, text, on) => { g.fillStyle = on ? '#4a6fa5' : '#3a4050'; g.fillRect(x, buttons - 28, w, 56); g.fillStyle = '#f0f0f0'; g.fillText(text, x + 16, buttons); };
  button(20, 220, `Symmetry ${state.settings.symmetry ? 'on' : 'off'}`, !!state.settings.symmetry);
  button(260, 140, 'Save', false);
  button(420, 220, 'Export GLB', false);
  settingsTexture.needsUpdate = true;
}

/** The other hand's ray on the settings panel: returns whether it is on it. */
function pointSettings(origin, direction, pressed, wasPressed) {
  if (!settingsPanel.parent) return false;
  const p = settingsBoard.pixelAt(origin, direction);
  const state = store.state();
  if (sliding && !pressed) { finishSlide(); return !!p; }
  if (!p || !state) return false;
  if (sliding) {
    const s = Math.min(1, Math.max(0, (p.x - SLIDER_LEFT) / (SLIDER_RIGHT - SLIDER_LEFT)));
    pendingSetting = { key: sliding.key, value: fromSlider(s) };
    settingsDirty = true;
    return true;
  }
  if (!pressed || wasPressed) return true;
  const row = Math.round((p.y - FIRST) / ROW_H);
  if (row < SLIDERS.length && p.x >= SLIDER_LEFT - 20) {
    sliding = { key: SLIDERS[row][0] };
    return pointSettings(origin, direction, pressed, false);
  }
  const settings = { ...state.settings };
  if (row === SLIDERS.length) {
    if (p.x >= SLIDER_LEFT && p.x < SLIDER_LEFT + 80) settings.subsample = Math.max(1, settings.subsample - 1);
    else if (p.x >= SLIDER_LEFT + 100 && p.x < SLIDER_LEFT + 180) settings.subsample = settings.subsample + 1;
    else return true;
    store.run('PUT', 'api/settings', settings);
  } else if (row === SLIDERS.length + 1) {
    if (p.x < 240) store.run('PUT', 'api/settings', { ...settings, symmetry: !settings.symmetry });
    else if (p.x < 400) api('POST', 'api/project/save').then((r) => showStatus(`Saved ${r.saved}`)).catch(showFailure);
    else if (p.x < 640) {
      const link = document.createElement('a');
      link.href = 'api/export.glb';
      link.download = '';
      link.click();
    }
  }
  return true;
}

async function finishSlide() {
  const done = pendingSetting;
  sliding = null;
  pendingSetting = null;
  settingsDirty = true;
  const state = store.state();
  if (!done || !state) return;
  await store.run('PUT', 'api/settings', { ...state.settings, [done.key]: done.value });
}

/** Where the settings panel shows a slider's `key` at position `s` in [0, 1], or a button
 * (`'save'`, `'export'`, `'symmetry'`), in the reference space: where a test points. */
export function settingsPoint(key, s = 0.5) {
  let x, y;
  const slider = SLIDERS.findIndex(([k]) => k === key);
  if (slider >= 0) { x = SLIDER_LEFT + s * (SLIDER_RIGHT - SLIDER_LEFT); y = FIRST + slider * ROW_H; }
  else {
    y = FIRST + (SLIDERS.length + 1) * ROW_H;
    x = key === 'symmetry' ? 130 : key === 'save' ? 330 : 530;
  }
  return settingsBoard.pointAt(x, y);
}
