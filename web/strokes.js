// Pointer input on the viewport (mouse, pen, touch): a press on a handle drags it (handles.js),
// a press on the face draws a stroke, elsewhere the camera orbits. A stroke is sampled with its
// times, so the drawing speed becomes the timing; the candidate targets of its start show while
// drawing, and the ghost of the one nearest the pointer.

import * as THREE from 'three';
import { api } from './api.js';
import * as handles from './handles.js';
import { atRest, hitFace, holdRest, currentFrame, isReady } from './playback.js';
import { labelCandidate, nearestCandidate, shownCandidates, showCandidates, showGhost, weightTowards } from './overlays.js';
import { camera, candidateGroup, clearGroup, controls, onPlane, planeFacingCamera, project, rayFrom, renderer, world } from './scene.js';
import { showError, showFailure } from './status.js';
import { offerAlternatives } from './inspector.js';
import * as store from './store.js';

const canvas = renderer.domElement;

/** @type {null | {plane: THREE.Plane, t0: number, samples: any[], pending: {p: number[], at: number}[], line: THREE.Line, found: any, frame: number, asked?: Promise<void>}} */
let stroke = null;
let lastStrokeMs = 0;

// ---------- timing of new strokes ----------
const timingMode = /** @type {HTMLSelectElement} */ (document.getElementById('timing-mode'));
const timingValue = /** @type {HTMLInputElement} */ (document.getElementById('timing-value'));
timingMode.addEventListener('change', () => {
  const mode = timingMode.value;
  document.getElementById('timing-value-label').hidden = mode === 'speed';
  document.getElementById('timing-value-name').textContent = mode === 'fixed' ? 'frames' : 'k';
  timingValue.value = mode === 'fixed' ? '24' : '1';
});

/** The frames a stroke drawn over `seconds` lasts, by the timing chosen (whole frames). */
function strokeFrames(seconds) {
  const fps = store.state() ? store.state().fps : 30;
  const value = Number(timingValue.value);
  const frames = timingMode.value === 'fixed' ? value : seconds * fps * (timingMode.value === 'scaled' ? value : 1);
  return Math.max(1, Math.round(Number.isFinite(frames) ? frames : seconds * fps));
}

/** The read-out beside the cursor while drawing: "0.8 s · 24 f". */
const readout = document.createElement('div');
readout.id = 'stroke-timing';
readout.hidden = true;
document.getElementById('viewport').appendChild(readout);
function showReadout(event, seconds) {
  const frames = strokeFrames(seconds);
  const fps = store.state() ? store.state().fps : 30;
  readout.textContent = `${(frames / fps).toFixed(1)} s · ${frames} f`;
  const rect = canvas.getBoundingClientRect();
  readout.style.left = `${event.clientX - rect.left + 14}px`;
  readout.style.top = `${event.clientY - rect.top + 14}px`;
  readout.hidden = false;
}
/** Milliseconds from the release of the last stroke to its action drawn. */
export const strokeLatency = () => lastStrokeMs;

/** The point of the face under a screen position (CSS pixels), or null. */
export function faceAt(x, y) {
  const p = hitFace(rayFrom({ clientX: x, clientY: y }));
  return p ? p.toArray() : null;
}


canvas.addEventListener('pointerdown', (event) => {
  if (event.button !== 0 || !isReady()) return;
  // Strokes and handles live in the character's own space: draw on the face at rest.
  holdRest(true);
  const ray = rayFrom(event);
  if (handles.grab(ray, event.clientX, event.clientY, event.shiftKey)) {
    controls.enabled = false;
    canvas.setPointerCapture(event.pointerId);
    return;
  }
  const hit = hitFace(ray);
  if (!hit) { holdRest(false); return; } // orbit
  controls.enabled = false;
  canvas.setPointerCapture(event.pointerId);
  const geometry = new THREE.BufferGeometry().setFromPoints([hit, hit]);
  const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: 0xffe080, depthTest: false }));
  line.renderOrder = 13;
  world.add(line);
  const drawing = { plane: planeFacingCamera(hit), t0: eventTime(event), samples: [{ t: 0, p: hit.toArray() }], pending: [], line, found: null, frame: Math.round(currentFrame()) };
  stroke = drawing;
  drawing.asked = api('POST', 'api/candidates', { point: hit.toArray(), frame: drawing.frame }).then((found) => { drawing.found = found; showCandidates(found, false); }).catch(() => {});
});

/**
 * When an input event happened, on `performance.now()`'s clock: its own `timeStamp` (when the
 * hand moved, even if the page handles it late), else now.
 */
function eventTime(/** @type {Event} */ event) {
  const now = performance.now();
  const t = event.timeStamp;
  return Number.isFinite(t) && t > 0 && t <= now + 1 && now - t < 10000 ? t : now;
}

let hoverTimer = 0;
canvas.addEventListener('pointermove', (event) => {
  if (!stroke && !handles.dragging()) {
    // The paper's users asked to see the targets before drawing: show them on hover.
    if (event.pointerType !== 'touch' && isReady() && performance.now() - hoverTimer > 120) {
      hoverTimer = performance.now();
      const hit = atRest() ? hitFace(rayFrom(event)) : null;
      if (hit) api('POST', 'api/candidates', { point: hit.toArray(), frame: currentFrame() }).then((f) => { if (!stroke) showCandidates(f, true); }).catch(() => {});
      else clearGroup(candidateGroup);
    }
    return;
  }
  const events = event.getCoalescedEvents ? event.getCoalescedEvents() : [event];
  const plane = stroke ? stroke.plane : handles.dragPlane();
  for (const e of events.length ? events : [event]) {
    const p = onPlane(rayFrom(e), plane);
    if (!p) continue;
    if (stroke) stroke.pending.push({ p: p.toArray(), at: eventTime(e) });
    else handles.moveTo(p);
  }
  if (stroke) {
    // A stroke's timing is the hand's, not the page's: each point at its input event's own
    // time, so that a slow display (which handles the moves late, in bunches) does not stretch
    // the stroke. Where the events' times cannot be trusted (missing, out of order), the points
    // are spread evenly between the previous sample and now.
    // Times strictly increase (the stroke's rule, sketch::project): events stamped alike (a
    // coarse clock) are a tenth of a millisecond apart.
    const previous = stroke.samples[stroke.samples.length - 1].t;
    const times = stroke.pending.map((q) => (q.at - stroke.t0) / 1000);
    const trusted = times.every((t, i) => t >= (i ? times[i - 1] : previous));
    const now = Math.max(trusted && times.length ? times[times.length - 1] : (performance.now() - stroke.t0) / 1000, previous);
    let latest = previous;
    stroke.pending.forEach((q, i) => {
      const t = trusted ? times[i] : previous + (now - previous) * (i + 1) / stroke.pending.length;
      latest = Math.max(t, latest + 1e-4);
      stroke.samples.push({ t: latest, p: q.p });
    });
    stroke.pending = [];
    showReadout(event, now);
    const nearest = nearestCandidate(event.clientX, event.clientY);
    showGhost(nearest && nearest.name);
    const last = stroke.samples[stroke.samples.length - 1].p;
    labelCandidate(nearest, nearest ? weightTowards(nearest, new THREE.Vector3(...last)) : 0);
    stroke.line.geometry.dispose();
    stroke.line.geometry = new THREE.BufferGeometry().setFromPoints(stroke.samples.map((s) => new THREE.Vector3(...s.p)));
  }
});

/** Pixels within which a release counts as "on" a candidate sphere. */
const SPHERE_PICK_PIXELS = 14;

/**
 * A stroke drawn on a screen has no depth of its own: it lies on the plane through its start
 * facing the camera. When it is released on a candidate sphere, the user meant that sphere, so
 * the stroke is carried along each sample's view ray, progressively (none at the start, all at
 * the end), to end at the sphere's depth. On screen nothing moves.
 */
function aimAtReleasedSphere(samples) {
  const found = shownCandidates();
  if (!found || !found.candidates.length) return;
  const last = samples[samples.length - 1].p;
  const [lx, ly] = project(last);
  let best = null, bestPixels = SPHERE_PICK_PIXELS;
  for (const c of found.candidates) {
    const [x, y] = project(c.position);
    const pixels = Math.hypot(x - lx, y - ly);
    if (pixels < bestPixels) { bestPixels = pixels; best = c; }
  }
  if (!best) return;
  const eye = camera.position.clone();
  const forward = new THREE.Vector3();
  camera.getWorldDirection(forward);
  const depthOf = (p) => new THREE.Vector3(...p).sub(eye).dot(forward);
  const startDepth = depthOf(samples[0].p);
  const endDepth = depthOf(best.position);
  const lengths = [0];
  for (let i = 1; i < samples.length; i++) lengths.push(lengths[i - 1] + new THREE.Vector3(...samples[i].p).distanceTo(new THREE.Vector3(...samples[i - 1].p)));
  const total = lengths[lengths.length - 1] || 1;
  samples.forEach((sample, i) => {
    const p = new THREE.Vector3(...sample.p);
    const ray = p.clone().sub(eye);
    const depth = startDepth + (endDepth - startDepth) * (lengths[i] / total);
    sample.p = eye.clone().add(ray.multiplyScalar(depth / ray.dot(forward))).toArray();
  });
}

async function endDrag(event) {
  holdRest(false);
  controls.enabled = true;
  try { canvas.releasePointerCapture(event.pointerId); } catch { /* already released */ }
  if (handles.dragging()) { await handles.release(); return; }
  if (!stroke) return;
  const finished = stroke;
  stroke = null;
  showGhost(null);
  labelCandidate(null, 0);
  readout.hidden = true;
  world.remove(finished.line);
  finished.line.geometry.dispose();
  clearGroup(candidateGroup);
  if (finished.samples.length < 2) return;
  const released = performance.now();
  // Its start's candidates (where it may end, whether it continues a chain): wait for them if
  // a quick stroke ended first.
  await finished.asked;
  aimAtReleasedSphere(finished.samples);
  try {
    // A new chain starts at the playhead; a stroke from a chain's end starts where that ends.
    // It is mirrored when the switch is on now, and stays so whatever the switch does later.
    const continues = finished.found && finished.found.continues !== null && finished.found.continues !== undefined;
    const settings = store.state().settings;
    const seconds = finished.samples[finished.samples.length - 1].t;
    const duration = timingMode.value === 'speed' ? null : strokeFrames(seconds);
    const state = await api('POST', 'api/strokes', { samples: finished.samples, start_frame: continues ? null : finished.frame, duration, symmetry: !!settings.symmetry });
    store.select(state.added);
    store.setState(state, true);
    // From release to the action drawn (arc, handles, timeline row); the bake for playback follows.
    lastStrokeMs = performance.now() - released;
    const rejected = state.rejected.find((r) => r.stroke === state.added);
    showError(rejected ? `That stroke made no action: ${rejected.reason}` : '');
    // The two next-nearest targets, one click away if the stroke picked the wrong one.
    const action = state.actions.find((a) => a.stroke === state.added);
    if (action && finished.found) {
      const end = new THREE.Vector3(...action.sides[0].end);
      const others = finished.found.candidates
        .filter((c) => c.name && c.name !== action.sides[0].target)
        .sort((a, b) => end.distanceToSquared(new THREE.Vector3(...a.position)) - end.distanceToSquared(new THREE.Vector3(...b.position)))
        .slice(0, 2);
      offerAlternatives(state.added, others);
    }
  } catch (e) { showFailure(e); }
}
canvas.addEventListener('pointerup', endDrag);
canvas.addEventListener('pointercancel', endDrag);
