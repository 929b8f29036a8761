// The character and its animation: loads the studio's view of the export (GET /api/view.glb:
// the character as one mesh, the baked corrective targets of arcs and exaggerations, the same
// weight tracks as the GLB download writes into the user's own file) and
// plays it, so the viewport shows exactly what Blender or an engine will play. Owns the current
// frame, playing, the layer under the sketch (a captured take or the live face) and the
// character's turn.

import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { FAST, beforeDraw, invalidate, onTick, world } from './scene.js';
import { blendNow, blendOnCpu, vertexLitMaterial } from './fastview.js';
import { showFailure } from './status.js';
import * as store from './store.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

/** @type {THREE.Mesh[]} */
let meshes = [];
/** @type {THREE.Object3D|null} */
let root = null;
/** @type {{mixer: THREE.AnimationMixer, action: THREE.AnimationAction}[]} */
let players = [];
let ready = false;
let frame = 0;
let playing = false;
/** Playback direction: 1 forwards, -1 backwards. */
let direction = 1;
let lastTime = 0;
/** Frames beyond the sketch's own (a captured take) that playback covers. */
let extent = 0;
/** @type {((frame: number) => number[]|null)|null} */
let layer = null;
/** While a stroke or handle is dragged the character stays at rest (no captured turn). */
let resting = false;
/** Whether the sketch's weights are added over the layer (off: the layer alone). */
let sketchShown = true;
/** @type {THREE.Quaternion|null} The turn asked for (a captured head pose), when not resting. */
let turn = null;
/** @type {((frame: number) => void)[]} */
const frameListeners = [];

/** The meshes of the character (one per primitive). */
export const characterMeshes = () => meshes;
/** The character's root node. */
export const characterRoot = () => root;
/** Whether the baked animation is loaded and playing. */
export const isReady = () => ready;
/** The current frame (fractional while playing). */
export const currentFrame = () => frame;
/** Whether it plays. */
export const isPlaying = () => playing;

/** Calls `listener(frame)` after every frame change. */
export function onFrame(listener) { frameListeners.push(listener); }

/** Sets the weights added under the sketch's at a frame (`fn(frame)` → weights of the
 * character's own targets, or null), or none. */
export function setLayer(fn) { layer = fn; applyLayer(); }

/** Shows the sketch over the layer, or (false) the layer alone; with no layer the sketch always
 * shows. */
export function showSketch(on) { sketchShown = on; applyLayer(); }

/** Makes playback cover `frames` frames at least (a captured take's length). */
export function setExtent(frames) { extent = frames; }

/** The last frame with animation: the sketch's or the captured take's. */
export function lastFrame() {
  const state = store.state();
  return Math.max(0, Math.ceil(state ? state.last_frame : 0), extent);
}

const loader = new GLTFLoader();
let bakeGeneration = 0;
/** Loads the export and plays it (a newer call wins over one still loading). */
export async function loadBaked() {
  const generation = ++bakeGeneration;
  const response = await fetch('api/view.glb');
  if (!response.ok) throw new Error(await response.text());
  const buffer = await response.arrayBuffer();
  if (generation !== bakeGeneration) return;
  const gltf = await loader.parseAsync(buffer, '');
  if (generation !== bakeGeneration) return;
  if (root) { world.remove(root); root.traverse((o) => { if (o.isMesh) o.geometry.dispose(); }); }
  meshes = [];
  root = gltf.scene;
  root.traverse((o) => {
    if (!o.isMesh) return;
    if (FAST) { const m = o.material; o.material = vertexLitMaterial(m); m.dispose(); blendOnCpu(o); }
    o.material.side = THREE.DoubleSide;
    meshes.push(o);
  });
  world.add(root);
  if (gltf.animations.length && meshes.length) {
    // The clip targets the node by name; bind its weight tracks to each mesh (primitive) directly.
    const clip = gltf.animations[0];
    for (const track of clip.tracks) { track.name = '.morphTargetInfluences'; }
    // Once, held at its last frame beyond its end: under a longer take the sketch's last pose
    // stays, as in the export (a repeating action would start the strokes over).
    players = meshes.map((m) => {
      const mixer = new THREE.AnimationMixer(m);
      const action = mixer.clipAction(clip);
      action.setLoop(THREE.LoopOnce, 1);
      action.clampWhenFinished = true;
      action.play();
      return { mixer, action };
    });
  } else {
    players = [];
  }
  ready = true;
  applyTurn();
  setFrame(frame);
}

/** Shows frame `f` (0 or later). */
export function setFrame(f) {
  const last = lastFrame();
  // Beyond the last frame is allowed (the animator types where the next stroke starts); the
  // animation holds its last pose there.
  frame = Math.max(0, f);
  const state = store.state();
  const fps = state ? state.fps : 30;
  // The mixer writes a track only when its value changes, so the sketch's own values go back
  // before it runs, and are kept after it for the layer to add to.
  for (const mesh of meshes) { if (mesh.userData.sketch && mesh.morphTargetInfluences) mesh.morphTargetInfluences.splice(0, Infinity, ...mesh.userData.sketch); }
  for (const { mixer, action } of players) {
    // A finished action is paused at its end; it must follow the frame asked for again.
    action.paused = false;
    mixer.setTime(frame / fps);
  }
  for (const mesh of meshes) {
    const influences = mesh.morphTargetInfluences;
    if (influences) mesh.userData.sketch = players.length ? influences.slice() : influences.map(() => 0);
  }
  applyLayer();
  $('frame-label').textContent = `/ ${last}`;
  const field = /** @type {HTMLInputElement} */ ($('current-frame'));
  if (document.activeElement !== field) field.value = frame.toFixed(0);
  for (const listener of frameListeners) listener(frame);
}

/** Shows the sketch's values at the current frame (kept by setFrame) plus the layer's weights
 * on the character's own targets, clamped to [0, 1]: the rule of `faceanim_take::layer`, which
 * the export applies (the capture browser test compares the two). */
export function applyLayer() {
  invalidate();
  const weights = layer ? layer(frame) : null;
  for (const mesh of meshes) {
    const influences = mesh.morphTargetInfluences;
    const sketch = mesh.userData.sketch;
    if (!influences || !sketch) continue;
    const own = weights && !sketchShown ? 0 : 1;
    for (let i = 0; i < influences.length; i++) {
      const w = weights && i < weights.length ? weights[i] : 0;
      influences[i] = Math.min(1, Math.max(0, own * sketch[i] + w));
    }
  }
}

/** Turns the character by `quaternion` (a captured head pose), or back to rest with null. */
export function setTurn(quaternion) {
  turn = quaternion;
  applyTurn();
}

/** Keeps the character at rest while a stroke or handle is dragged (strokes and handles live in
 * the character's own space), or lets it turn again. */
export function holdRest(on) {
  resting = on;
  applyTurn();
}

function applyTurn() {
  if (!root) return;
  if (turn && !resting) root.quaternion.copy(turn);
  else root.quaternion.identity();
  root.updateMatrixWorld(true);
  invalidate();
}

/** The nearest point of the character under `ray`, or null. */
export function hitFace(ray) {
  if (FAST) for (const mesh of meshes) blendNow(mesh);
  const hits = ray.intersectObjects(meshes, false);
  return hits.length ? hits[0].point : null;
}

/** @type {((playing: boolean) => void)[]} */
const playingListeners = [];
/** Calls `listener(playing)` when playback starts or stops. */
export function onPlaying(listener) { playingListeners.push(listener); }

function setPlaying(on, towards) {
  const changed = playing !== on;
  playing = on;
  if (towards) direction = towards;
  $('play').textContent = playing ? 'Pause' : 'Play';
  lastTime = performance.now();
  if (changed) for (const listener of playingListeners) listener(playing);
}
/** Plays forwards, or pauses when playing. */
export function play() { setPlaying(!playing, 1); }
/** Plays backwards. */
export function playBackwards() { setPlaying(true, -1); }
/** Pauses. */
export function pause() { setPlaying(false); }
/** Pauses and steps `by` whole frames. */
export function step(by) { pause(); setFrame(Math.round(frame) + by); }

/** @type {(() => number|null)|null} */
let clock = null;
/** Lets `fn()` give the playing time in seconds (a sound's own clock, which the picture then
 * follows forwards), or null while it has none; `null` removes it. */
export function setClock(fn) { clock = fn; }

onTick((now) => {
  const advancing = playing && !!store.state();
  if (advancing) {
    const fps = store.state().fps;
    const last = Math.max(1, lastFrame());
    const loop = /** @type {HTMLInputElement} */ ($('loop')).checked;
    const heard = clock && direction === 1 ? clock() : null;
    let f = heard !== null ? heard * fps : frame + direction * (now - lastTime) / 1000 * fps;
    if (f > last) { if (loop) f = f % last; else { f = last; pause(); } }
    if (f < 0) { if (loop) f = last + (f % last); else { f = 0; pause(); } }
    setFrame(f);
  }
  lastTime = now;
  return advancing;
});
if (FAST) beforeDraw(() => { for (const mesh of meshes) blendNow(mesh); });

/** Whether the character stands at rest (capture mode turns it by the captured head pose). */
export function atRest() {
  const q = root ? root.quaternion : null;
  return !q || (q.x === 0 && q.y === 0 && q.z === 0);
}

// A change of the animation (a new stroke, an edit, undo) is played from its new export.
store.onState((_, rebake) => { if (rebake) loadBaked().catch(showFailure); });
