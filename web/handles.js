// Dragging a stroke's handles: the red arrow moves its end (re-targeting blendshape, weight and
// exaggeration), the yellow sphere its curvature, and with Shift the sphere slides along the
// stroke (the easing α). Every step of one drag is one gesture, undone as one.

import * as THREE from 'three';
import { api } from './api.js';
import { loadBaked } from './playback.js';
import { handleNear, handleUnder, showGhost } from './overlays.js';
import { planeFacingCamera } from './scene.js';
import { showError, showFailure } from './status.js';
import * as store from './store.js';

/** @type {null | {handle: string, stroke: number, path: any[], plane: THREE.Plane, ease: boolean, pending: boolean, gesture: string}} */
let drag = null;

/** Whether a handle is being dragged. */
export const dragging = () => drag !== null;
/** The plane the dragged handle moves on. */
export const dragPlane = () => drag && drag.plane;

/** Pixels from a handle's point within which a press grabs it. */
const GRAB_PIXELS = 8;

/** Grabs the handle under `ray`, or whose point is within a few pixels of the press at `(x, y)`,
 * if there is one (`ease`: slide the sphere instead of bending). Handles win over new strokes. */
export function grab(ray, x, y, ease) {
  return start(handleUnder(ray, x, y, GRAB_PIXELS), ease);
}

/** Grabs the handle (of `kind`, or either) nearest `point` in character space within `radius`
 * (a VR pen tip), if there is one: the selected action's first, else any action's, which is
 * then selected (its handles are drawn at once, by the selection's listener). */
export function grabNear(point, radius, ease, kind = null) {
  if (start(handleNear(point, radius, kind), ease)) return true;
  const state = store.state();
  if (!state) return false;
  let best = radius, stroke = null;
  for (const action of state.actions) {
    const side = action.sides[0];
    for (const [name, p] of [['end', side.end], ['mid', side.mid]]) {
      if (kind && kind !== name) continue;
      const distance = Math.hypot(p[0] - point.x, p[1] - point.y, p[2] - point.z);
      if (distance <= best) { best = distance; stroke = action.stroke; }
    }
  }
  if (stroke === null) return false;
  store.select(stroke);
  return start(handleNear(point, radius, kind), ease);
}

function start(handle, ease) {
  if (!handle) return false;
  store.select(handle.stroke);
  drag = {
    handle: handle.handle,
    stroke: handle.stroke,
    path: handle.path,
    plane: planeFacingCamera(handle.position),
    ease: ease && handle.handle === 'mid',
    pending: false,
    gesture: `${Date.now()}-${Math.random()}`,
  };
  return true;
}

/** Moves the grabbed handle to `p` (a step of the drag; skipped while the last is on its way). */
export async function moveTo(p) {
  if (!drag || drag.pending) return;
  let edit;
  if (drag.handle === 'end') edit = { end: p.toArray() };
  else if (drag.ease) {
    // Slide along the stroke: the easing α is where along the path the sphere is.
    let best = 0, bestDistance = Infinity;
    drag.path.forEach((q, i) => { const dd = p.distanceToSquared(new THREE.Vector3(...q)); if (dd < bestDistance) { bestDistance = dd; best = i; } });
    edit = { ease: Math.min(0.98, Math.max(0.02, best / (drag.path.length - 1))) };
  } else edit = { mid: p.toArray() };
  const moving = drag;
  moving.pending = true;
  try {
    const state = await api('PATCH', `api/strokes/${moving.stroke}`, edit, { 'x-gesture': moving.gesture });
    store.setState(state, false);
    showError('');
    const action = state.actions.find((a) => a.stroke === moving.stroke);
    if (drag === moving && action) showGhost(action.sides[0].target);
  } catch (e) { showFailure(e); }
  finally { moving.pending = false; }
}

/** Lets go: waits for the last step, then shows the bake of the final handle position. */
export async function release() {
  const finished = drag;
  drag = null;
  showGhost(null);
  if (!finished) return;
  while (finished.pending) await new Promise((r) => setTimeout(r, 10));
  await loadBaked();
}
