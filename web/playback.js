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
/** @type {THREE.Skeleton|null} The face's bones, where the view is skinned to them (a file with a
 * head bone: see `faceanim_export::bones::ViewRig`). */
let skeleton = null;
/** @type {number[][]|null} Each of the skeleton's joints' rotation asked for, when not resting. */
let pose = null;
/** @type {number[][]|null} Each joint's rotation the sketch's animation gives at the frame. */
let sketchPose = null;
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
  skeleton = null;
  sketchPose = null;
  root = gltf.scene;
  root.traverse((o) => {
    if (!o.isMesh) return;
    if (o.isSkinnedMesh) skeleton = o.skeleton;
    if (FAST) { const m = o.material; o.material = vertexLitMaterial(m); m.dispose(); blendOnCpu(o); }
    o.material.side = THREE.DoubleSide;
    meshes.push(o);
  });
  world.add(root);
  if (gltf.animations.length && meshes.length) {
    // The clip targets the node by name; bind its weight tracks to each mesh (primitive)
    // directly. Its rotation tracks turn the skeleton's joints (the eyes and jaw the sketch's
    // gaze and jawOpen turn, as the export does), found by name under the root.
    const clip = gltf.animations[0];
    const weights = clip.tracks.filter((t) => t.name.endsWith('.morphTargetInfluences'));
    for (const track of weights) { track.name = '.morphTargetInfluences'; }
    const turns = clip.tracks.filter((t) => t.name.endsWith('.quaternion'));
    const once = (target, tracks) => {
      const mixer = new THREE.AnimationMixer(target);
      const action = mixer.clipAction(new THREE.AnimationClip(clip.name, clip.duration, tracks));
      // Once, held at its last frame beyond its end: under a longer take the sketch's last pose
      // stays, as in the export (a repeating action would start the strokes over).
      action.setLoop(THREE.LoopOnce, 1);
      action.clampWhenFinished = true;
      action.play();
      return { mixer, action };
    };
    players = meshes.map((m) => once(m, weights));
    if (skeleton && turns.length) players.push(once(root, turns));
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
  if (skeleton) skeleton.bones.forEach((b, k) => { if (sketchPose) b.quaternion.fromArray(sketchPose[k]); else b.quaternion.identity(); });
  for (const { mixer, action } of players) {
    // A finished action is paused at its end; it must follow the frame asked for again.
    action.paused = false;
    mixer.setTime(frame / fps);
  }
  for (const mesh of meshes) {
    const influences = mesh.morphTargetInfluences;
    if (influences) mesh.userData.sketch = players.length ? influences.slice() : influences.map(() => 0);
  }
  // The sketch's own turns of the joints (rest where it turns none), under a captured pose.
  sketchPose = skeleton ? skeleton.bones.map((b) => b.quaternion.toArray()) : null;
  applyTurn();
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

/** The names of the view's joints in order (`faceanim_head`…), or null where the view is not
 * skinned to the face's bones (a head pose then turns the whole character). */
export const jointNames = () => (skeleton ? skeleton.bones.map((b) => b.name) : null);

/** Turns the character by `quaternion` (a captured head pose), or back to rest with null. */
export function setTurn(quaternion) {
  turn = quaternion;
  applyTurn();
}

/** Turns the skeleton's joints (`[x, y, z, w]` each, in its joints' order, as the server sends
 * them), or back to rest with null. */
export function setPose(rotations) {
  pose = rotations;
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
  if (skeleton) {
    // A captured pose replaces the sketch's (the export takes a take's gaze and jaw too).
    skeleton.bones.forEach((bone, k) => {
      const q = (pose && !resting ? pose[k] : null) || (sketchPose ? sketchPose[k] : null);
      if (q && q.length === 4) bone.quaternion.fromArray(q);
      else bone.quaternion.identity();
    });
  }
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
