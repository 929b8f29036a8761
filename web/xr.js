// Immersive sketching (seed 000, sections 3.1 and 3.6–3.9): the same studio in a headset through
// WebXR. The character stands life size in front of the animator; the dominant hand draws from
// a pen tip ahead of its controller, the other hand flicks its thumbstick for commands and
// holds Y/B for navigation. One project: strokes go to the same server, undo and autosave are
// the server's, and a desktop page of the same studio follows (store.js polls).
//
// The seed's state machine, shown as a label beside the other hand:
//   waiting      nothing held
//   interaction  drawing (dominant trigger) or dragging a handle (squeeze, or trigger on the
//                sphere to slide it: the easing)
//   navigation   Y/B toggles it; squeeze one hand to move and turn the world, both to scale it
//   timeline     thumbstick up toggles it; the thumbstick scrubs the current frame
// Other hand's thumbstick flicks (|axis| > 0.7; up is y < 0): left undoes (the seed's "delete
// the last stroke": a stroke just drawn goes), right redoes (it comes back), down toggles
// symmetry, up enters or leaves the timeline. Undo is the project's one history, the desktop's.
//
// The timeline panel (xrpanel.js) stands to the left; the other hand's ray points at it and its
// trigger clicks. The frame loop keeps its vectors and matrices here and reuses them; candidate
// queries go to the server once per stroke, asynchronously.

import * as THREE from 'three';
import { api } from './api.js';
import * as handles from './handles.js';
import { showCandidates } from './overlays.js';
import { currentFrame, lastFrame, setFrame, holdRest } from './playback.js';
import { candidateGroup, clearGroup, frameCamera, invalidate, onXRFrame, renderer, scene, world } from './scene.js';
import { showFailure } from './status.js';
import * as store from './store.js';
import { panelHandle, pointPanel, refreshPanel, refreshSettings, settingsPanel, settingsPoint, timelinePanel } from './xrpanel.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

// The renderer draws the headset's views while a session runs (and the desktop's otherwise).
renderer.xr.enabled = true;

/** @typedef {'waiting' | 'interaction' | 'navigation' | 'timeline'} Mode */
/** @type {Mode} */
let mode = 'waiting';
/** @type {XRSession | null} */
let session = null;
let frames = 0;
/** The JavaScript time of each of the last 100 XR frames' handling (ms), a ring. */
const frameTimes = new Float64Array(100);
const sortedTimes = new Float64Array(100);

// ---------- the two hands ----------
/** @typedef {{controller: THREE.Group, source: XRInputSource | null, tip: THREE.Mesh, pen: THREE.Group, buttons: boolean[], flick: string | null}} Hand */
/** @type {{left: Hand, right: Hand}} */
const hands = { left: makeHand(0), right: makeHand(1) };

function makeHand(index) {
  const controller = renderer.xr.getController(index);
  // Our own proxy (no controller models fetched from a CDN): a short grey stick along the ray
  // and the pen tip, a small sphere, placed at the pen distance ahead of it.
  const pen = new THREE.Group();
  const stick = new THREE.Mesh(new THREE.CylinderGeometry(0.006, 0.009, 0.12, 12), new THREE.MeshStandardMaterial({ color: 0x8890a0 }));
  stick.rotation.x = Math.PI / 2;
  stick.position.z = 0.03;
  pen.add(stick);
  const tip = new THREE.Mesh(new THREE.SphereGeometry(0.006, 16, 8), new THREE.MeshBasicMaterial({ color: 0xffe080 }));
  pen.add(tip);
  const ray = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3(0, 0, -1)]), new THREE.LineBasicMaterial({ color: 0x8fb4ff, transparent: true, opacity: 0.35 }));
  pen.add(ray);
  controller.add(pen);
  controller.visible = false;
  /** @type {Hand} */
  const hand = { controller, source: null, tip, pen, buttons: [false, false, false, false, false, false], flick: null };
  controller.addEventListener('connected', (event) => {
    const source = /** @type {any} */ (event).data;
    hand.source = source;
    controller.visible = true;
    // Which hand this controller is, whatever index the runtime gave it.
    const side = source.handedness === 'left' ? 'left' : 'right';
    if (hands[side] !== hand) { const other = hands[side]; hands[side] = hand; hands[side === 'left' ? 'right' : 'left'] = other; }
  });
  controller.addEventListener('disconnected', () => { hand.source = null; controller.visible = false; });
  scene.add(controller);
  return hand;
}

/** The dominant hand (right unless the VR panel says left). */
const dominant = () => (/** @type {HTMLSelectElement} */ ($('xr-hand')).value === 'left' ? 'left' : 'right');
const other = () => (dominant() === 'left' ? 'right' : 'left');

// ---------- the label beside the other hand ----------
const labelCanvas = document.createElement('canvas');
labelCanvas.width = 512; labelCanvas.height = 128;
const labelTexture = new THREE.CanvasTexture(labelCanvas);
const label = new THREE.Mesh(new THREE.PlaneGeometry(0.16, 0.04), new THREE.MeshBasicMaterial({ map: labelTexture, transparent: true, depthTest: false }));
label.renderOrder = 20;
label.position.set(0, 0.06, -0.02);
label.rotation.x = -0.5;
function drawLabel() {
  const g = /** @type {CanvasRenderingContext2D} */ (labelCanvas.getContext('2d'));
  g.clearRect(0, 0, 512, 128);
  g.fillStyle = 'rgba(20, 22, 28, 0.85)';
  g.fillRect(0, 0, 512, 128);
  g.fillStyle = '#f0c060';
  // 72 px on a 16 cm plane: about 2.3 cm letters, readable at arm's length (20 px at 1 m).
  g.font = 'bold 72px sans-serif';
  g.textBaseline = 'middle';
  g.fillText(mode[0].toUpperCase() + mode.slice(1), 24, 66);
  labelTexture.needsUpdate = true;
}
function setMode(next) {
  if (mode === next) return;
  mode = next;
  drawLabel();
}
drawLabel();

// ---------- placing the character ----------
const placed = { position: new THREE.Vector3(), quaternion: new THREE.Quaternion(), scale: 1 };
/** Puts the character's face at eye height about 0.5 m ahead, life size whatever its units. */
function place(floor) {
  const character = store.character();
  if (!character) return;
  const min = new THREE.Vector3(...character.head.min), max = new THREE.Vector3(...character.head.max);
  const size = min.distanceTo(max);
  // A human head's box is about 0.45 m across its diagonal.
  const scale = size > 0 ? 0.45 / size : 1;
  const eyes = new THREE.Vector3((min.x + max.x) / 2, min.y + 0.58 * (max.y - min.y), max.z);
  world.scale.setScalar(scale);
  world.quaternion.identity();
  world.position.set(0, floor ? 1.6 : 0, -0.5).addScaledVector(eyes, -scale);
  world.updateMatrixWorld(true);
  placed.position.copy(world.position);
  placed.quaternion.copy(world.quaternion);
  placed.scale = scale;
}

// ---------- entering and leaving ----------
const enter = /** @type {HTMLButtonElement} */ ($('xr-enter'));
async function offerVR() {
  try {
    if (navigator.xr && await navigator.xr.isSessionSupported('immersive-vr')) { enter.hidden = false; $('xr-hand-label').hidden = false; }
  } catch { /* no WebXR here */ }
}
offerVR();

enter.addEventListener('click', async () => {
  if (session) { await session.end(); return; }
  try {
    const next = await navigator.xr.requestSession('immersive-vr', { optionalFeatures: ['local-floor'] });
    let floor = true;
    try {
      renderer.xr.setReferenceSpaceType('local-floor');
      await renderer.xr.setSession(next);
    } catch {
      floor = false;
      renderer.xr.setReferenceSpaceType('local');
      await renderer.xr.setSession(next);
    }
    session = next;
    frames = 0;
    frameTimes.fill(0);
    place(floor);
    // The timeline panel, to the left and facing the animator (seed figure 9).
    timelinePanel.position.set(-0.42, floor ? 1.3 : -0.3, -0.6);
    timelinePanel.rotation.set(-0.2, Math.PI / 5, 0, 'YXZ');
    scene.add(timelinePanel);
    // The settings (seed figure 11), to the right.
    settingsPanel.position.set(0.42, floor ? 1.3 : -0.3, -0.6);
    settingsPanel.rotation.set(-0.2, -Math.PI / 5, 0, 'YXZ');
    scene.add(settingsPanel);
    // The character stands at rest in VR: strokes live in its own space.
    holdRest(true);
    enter.textContent = 'Exit VR';
    next.addEventListener('end', leave);
  } catch (e) { showFailure(e); }
});

function leave() {
  session = null;
  scene.remove(timelinePanel);
  scene.remove(settingsPanel);
  setMode('waiting');
  endStroke(false);
  world.position.set(0, 0, 0);
  world.quaternion.identity();
  world.scale.setScalar(1);
  world.updateMatrixWorld(true);
  holdRest(false);
  enter.textContent = 'Enter VR';
  const character = store.character();
  if (character) frameCamera(character.head);
  invalidate();
}

// ---------- reused per frame ----------
const tipWorld = new THREE.Vector3();
const tipLocal = new THREE.Vector3();
const inverse = new THREE.Matrix4();

/** The pen tip of `hand` in the reference space (metres), into `out`. */
function tipOf(hand, out) {
  return hand.tip.getWorldPosition(out);
}

/** The pen tip of `hand` in the character's own space (the one shared vector, reused). */
function tipInCharacter(hand) {
  tipOf(hand, tipWorld);
  inverse.copy(world.matrixWorld).invert();
  return tipLocal.copy(tipWorld).applyMatrix4(inverse);
}

/** Resolved distances (character units) from the state, with VR-friendly floors in metres. */
function resolved(name) {
  const state = store.state();
  return state ? state.resolved[name] : 0;
}

/** Places each pen tip at the pen distance ahead of its controller. */
function updatePens() {
  const pen = resolved('pen_distance') * world.scale.x;
  const distance = Math.min(0.15, Math.max(0.02, pen || 0.04));
  hands.left.tip.position.set(0, 0, -distance);
  hands.right.tip.position.set(0, 0, -distance);
}

// ---------- drawing ----------
/** @type {null | {t0: number, samples: {t: number, p: number[]}[], line: THREE.Line, positions: Float32Array, frame: number, found: any, asked: Promise<void>}} */
let stroke = null;
const MAX_SAMPLES = 4096;

function beginStroke(now) {
  const positions = new Float32Array(MAX_SAMPLES * 3);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setDrawRange(0, 0);
  const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: 0xffe080, depthTest: false }));
  line.renderOrder = 13;
  line.frustumCulled = false;
  world.add(line);
  const frame = Math.round(currentFrame());
  const drawing = { t0: now, samples: [], line, positions, frame, found: null, asked: Promise.resolve() };
  stroke = drawing;
  addSample(now);
  const point = drawing.samples[0].p;
  // The candidate targets reachable from the start, as red spheres (once, asynchronously).
  drawing.asked = api('POST', 'api/candidates', { point, frame }).then((found) => { drawing.found = found; if (stroke === drawing) showCandidates(found, false); }).catch(() => {});
  setMode('interaction');
}

function addSample(now) {
  if (!stroke || stroke.samples.length >= MAX_SAMPLES) return;
  const tip = tipInCharacter(hands[dominant()]);
  const k = stroke.samples.length;
  stroke.positions[3 * k] = tip.x; stroke.positions[3 * k + 1] = tip.y; stroke.positions[3 * k + 2] = tip.z;
  stroke.samples.push({ t: (now - stroke.t0) / 1000, p: [tip.x, tip.y, tip.z] });
  stroke.line.geometry.setDrawRange(0, k + 1);
  stroke.line.geometry.attributes.position.needsUpdate = true;
}

async function endStroke(send) {
  const finished = stroke;
  stroke = null;
  if (mode === 'interaction') setMode('waiting');
  if (!finished) return;
  world.remove(finished.line);
  finished.line.geometry.dispose();
  clearGroup(candidateGroup);
  if (!send || finished.samples.length < 2) return;
  await finished.asked;
  try {
    const continues = finished.found && finished.found.continues !== null && finished.found.continues !== undefined;
    const settings = store.state().settings;
    const state = await api('POST', 'api/strokes', { samples: finished.samples, start_frame: continues ? null : finished.frame, symmetry: !!settings.symmetry });
    store.select(state.added);
    store.setState(state, true);
  } catch (e) { showFailure(e); }
}

// ---------- commands from the other hand ----------
function toggleSymmetry() {
  const state = store.state();
  if (!state) return;
  store.run('PUT', 'api/settings', { ...state.settings, symmetry: !state.settings.symmetry });
}
function flick(direction) {
  if (direction === 'left') store.run('POST', 'api/undo');
  else if (direction === 'right') store.run('POST', 'api/redo');
  else if (direction === 'down') toggleSymmetry();
  else if (direction === 'up') setMode(mode === 'timeline' ? 'waiting' : 'timeline');
}

// ---------- navigation ----------
/** @type {null | {hands: number, start: THREE.Matrix4, grip: THREE.Matrix4, distance: number, mid: THREE.Vector3}} */
let grab = null;
const gripNow = new THREE.Matrix4();
const delta = new THREE.Matrix4();
const other3 = new THREE.Vector3();
const worldStart = new THREE.Matrix4();
const navigate = { start: new THREE.Matrix4(), grip: new THREE.Matrix4(), mid: new THREE.Vector3(), distance: 0 };

function navigation(leftSqueeze, rightSqueeze) {
  const count = (leftSqueeze ? 1 : 0) + (rightSqueeze ? 1 : 0);
  if (count === 0) { grab = null; return; }
  if (count === 2) {
    tipOf(hands.left, tipWorld); tipOf(hands.right, other3);
    const distance = tipWorld.distanceTo(other3);
    const mid = tipWorld.add(other3).multiplyScalar(0.5);
    if (!grab || grab.hands !== 2) {
      grab = { hands: 2, start: navigate.start.copy(world.matrix), grip: navigate.grip, distance, mid: navigate.mid.copy(mid) };
      return;
    }
    // Scale about the hands' midpoint by how far apart they moved.
    const factor = distance / Math.max(1e-6, grab.distance);
    delta.makeTranslation(grab.mid.x, grab.mid.y, grab.mid.z)
      .multiply(gripNow.makeScale(factor, factor, factor))
      .multiply(worldStart.makeTranslation(-grab.mid.x, -grab.mid.y, -grab.mid.z));
    world.matrix.multiplyMatrices(delta, grab.start);
    world.matrix.decompose(world.position, world.quaternion, world.scale);
    world.updateMatrixWorld(true);
    return;
  }
  const hand = leftSqueeze ? hands.left : hands.right;
  hand.controller.updateMatrixWorld(true);
  if (!grab || grab.hands !== 1) {
    grab = { hands: 1, start: navigate.start.copy(world.matrix), grip: navigate.grip.copy(hand.controller.matrixWorld), distance: 0, mid: navigate.mid };
    return;
  }
  // The world follows the hand: moved and turned as the controller moved and turned.
  delta.copy(grab.grip).invert().premultiply(hand.controller.matrixWorld);
  world.matrix.multiplyMatrices(delta, grab.start);
  world.matrix.decompose(world.position, world.quaternion, world.scale);
  world.updateMatrixWorld(true);
}

// ---------- the frame ----------
const rayOrigin = new THREE.Vector3();
const rayDirection = new THREE.Vector3();
const pressed = (hand, i) => {
  const gamepad = hand.source && hand.source.gamepad;
  return !!(gamepad && gamepad.buttons[i] && gamepad.buttons[i].pressed);
};
let lastNow = 0;

onXRFrame((now) => {
  const started = performance.now();
  frames++;
  updatePens();
  const main = hands[dominant()], off = hands[other()];
  // The state's label rides the other hand (whichever controller that turned out to be).
  if (label.parent !== off.controller) off.controller.add(label);
  const trigger = pressed(main, 0), squeeze = pressed(main, 1);
  const wasTrigger = main.buttons[0], wasSqueeze = main.buttons[1];
  const offY = pressed(off, 5), wasOffY = off.buttons[5];
  // The other hand's ray on a panel: its trigger is the panel's.
  off.controller.getWorldPosition(rayOrigin);
  off.controller.getWorldDirection(rayDirection).negate();
  pointPanel(rayOrigin, rayDirection, pressed(off, 0), off.buttons[0]);
  refreshPanel();
  refreshSettings();
  // Y/B on the other hand: navigation on or off.
  if (offY && !wasOffY) setMode(mode === 'navigation' ? 'waiting' : 'navigation');

  if (mode === 'navigation') {
    navigation(pressed(hands.left, 1), pressed(hands.right, 1));
  } else {
    // Dominant hand: squeeze grabs a handle near the tip; trigger on the sphere slides it;
    // trigger elsewhere draws.
    const radius = Math.max(resolved('hook_radius'), 0.015 / world.scale.x);
    if (squeeze && !wasSqueeze && !stroke && !handles.dragging()) {
      if (handles.grabNear(tipInCharacter(main), radius, false)) setMode('interaction');
    }
    if (trigger && !wasTrigger && !stroke && !handles.dragging()) {
      if (handles.grabNear(tipInCharacter(main), radius, true, 'mid')) setMode('interaction');
      else beginStroke(now);
    } else if (trigger && stroke) addSample(now);
    if (handles.dragging()) {
      handles.moveTo(tipInCharacter(main).clone());
      if (!trigger && !squeeze) { handles.release(); setMode('waiting'); }
    }
    if (!trigger && wasTrigger && stroke) { addSample(now); endStroke(true); }
  }

  // Other hand's thumbstick: flicks (edge-triggered with hysteresis), or scrubbing in the
  // timeline state.
  const gamepad = off.source && off.source.gamepad;
  if (gamepad && gamepad.axes.length >= 4) {
    const x = gamepad.axes[2], y = gamepad.axes[3];
    if (mode === 'timeline') {
      const fps = store.state() ? store.state().fps : 30;
      const dt = lastNow ? (now - lastNow) / 1000 : 0;
      if (Math.abs(x) > 0.2) setFrame(Math.min(Math.max(0, currentFrame() + x * fps * dt * 2), Math.max(lastFrame(), 1)));
    }
    const direction = Math.abs(x) > 0.7 ? (x < 0 ? 'left' : 'right') : Math.abs(y) > 0.7 ? (y < 0 ? 'up' : 'down') : null;
    if (direction && !off.flick) { off.flick = direction; flick(direction); }
    else if (!direction && Math.abs(x) < 0.5 && Math.abs(y) < 0.5) off.flick = null;
  }
  for (const hand of [hands.left, hands.right]) for (let i = 0; i < 6; i++) hand.buttons[i] = pressed(hand, i);
  lastNow = now;
  frameTimes[frames % 100] = performance.now() - started;
});

/** Median of the last (up to) 100 XR frames' handling times, in milliseconds. */
function frameMs() {
  const n = Math.min(frames, 100);
  if (!n) return 0;
  sortedTimes.set(frameTimes);
  const used = sortedTimes.subarray(0, 100).sort();
  // The ring holds zeros for frames not yet seen: take the median of the filled part.
  return used[100 - n + Math.floor(n / 2)];
}

/** A point on a panel with the panel's facing (`normal`), its left-to-right direction and its
 * turn: what pointing a ray at it needs. */
function aimAt(panel, point) {
  const turn = panel.getWorldQuaternion(new THREE.Quaternion());
  return {
    point: point.toArray(),
    normal: new THREE.Vector3(0, 0, 1).applyQuaternion(turn).toArray(),
    along: new THREE.Vector3(1, 0, 0).applyQuaternion(turn).toArray(),
    quaternion: turn.toArray(),
  };
}

/** The hook scripts and tests use: `window.studio.xr` (crates/studio/API.md). */
export const xrHook = Object.freeze({
  get session() { return session; },
  get mode() { return mode; },
  get frames() { return frames; },
  get frameMs() { return frameMs(); },
  /** The reference-space position (metres) of a point in the character's own space. */
  toWorld(p) { return world.localToWorld(new THREE.Vector3(p[0], p[1], p[2])).toArray(); },
  /** The pen tip of a hand in the reference space (metres). */
  tip(hand) { return tipOf(hands[hand === 'left' ? 'left' : 'right'], new THREE.Vector3()).toArray(); },
  /** Where the timeline panel shows an action's `'start'` or `'end'` handle (reference space),
   * and the panel's facing direction, or null. */
  panelHandle(stroke, part) {
    const p = panelHandle(stroke, part);
    return p ? aimAt(timelinePanel, p) : null;
  },
  /** Where the settings panel shows a slider (`'pen_distance'`…) at position `s` in [0, 1], or a
   * button (`'symmetry'`, `'save'`, `'export'`), with the panel's facing. */
  settingsPoint(key, s) { return aimAt(settingsPanel, settingsPoint(key, s)); },
});
