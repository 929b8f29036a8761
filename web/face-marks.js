// Marking the character's face by hand, where the face model finds none (a stylised face, a
// head that does not look along +Z): the ten points the server names, clicked or tapped on
// the character at rest, in turn; then sent, and the server makes the map from them. A press
// that misses the character orbits as usual. The server owns the list of points and checks
// them; this module owns only the marking in progress and its markers.

import * as THREE from 'three';
import { api } from './api.js';
import { showError } from './status.js';
import { camera, invalidate, rayFrom, world } from './scene.js';
import { hitFace, holdRest, isReady } from './playback.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

/** The markers of the marking in progress. */
const markers = new THREE.Group();
markers.name = 'face marks';
world.add(markers);

/** @type {{point: string, describe: string}[]} */
let asked = [];
/** The marking in progress: the points placed so far, in the order asked; null when none. */
/** @type {number[][] | null} */
let placed = null;
/** Where the server's answer goes (given by `showMarks`). */
let applyState = (/** @type {any} */ _view) => {};
/** What the prompt says when no marking is in progress. */
let idleText = '';

function prompt() {
  const start = /** @type {HTMLButtonElement} */ ($('face-marks-start'));
  $('face-marks-undo').hidden = !placed;
  $('face-marks-cancel').hidden = !placed;
  start.hidden = Boolean(placed);
  $('face-marks-prompt').textContent = placed
    ? `Mark ${placed.length + 1} of ${asked.length}: ${asked[placed.length].describe}.`
    : idleText;
}

function clearMarkers() {
  for (const child of markers.children) {
    /** @type {any} */ (child).geometry?.dispose();
    /** @type {any} */ (child).material?.dispose();
  }
  markers.clear();
  invalidate();
}

function stop() {
  placed = null;
  clearMarkers();
  holdRest(false);
  prompt();
}

/** Shows what the map view says of the marks (`map.marks`, `map.face_points`, `map.no_face`);
 * `apply` takes the state the server answers with. */
export function showMarks(/** @type {any} */ map, /** @type {(view: any) => void} */ apply, /** @type {boolean} */ busy) {
  applyState = apply;
  asked = map.marks;
  const marked = map.face_points ? Object.keys(map.face_points).length : 0;
  idleText = map.no_face
    ? 'The face model found no face on this character: mark ten points on it and the map is made from them.'
    : marked ? `Its face is placed by the ${marked} points you marked.` : '';
  const start = /** @type {HTMLButtonElement} */ ($('face-marks-start'));
  start.textContent = marked ? 'Mark the face again' : 'Mark the face';
  start.disabled = busy;
  start.classList.toggle('asked', Boolean(map.no_face));
  if (!placed) prompt();
}

$('face-marks-start').onclick = () => {
  if (!asked.length || !isReady()) return;
  placed = [];
  holdRest(true);
  prompt();
};
$('face-marks-cancel').onclick = stop;
$('face-marks-undo').onclick = () => {
  if (!placed || !placed.length) return;
  placed.pop();
  const last = markers.children[markers.children.length - 1];
  if (last) { markers.remove(last); /** @type {any} */ (last).geometry.dispose(); invalidate(); }
  prompt();
};

async function send() {
  const points = Object.fromEntries(asked.map((a, k) => [a.point, /** @type {number[][]} */ (placed)[k]]));
  stop();
  try { showError(''); applyState(await api('PUT', 'api/capture/face-points', { points })); }
  catch (e) { showError(String(/** @type {any} */ (e).message || e)); }
}

// Before the strokes and the orbit controls see the press: while marking, a press on the
// character is a mark.
$('viewport').addEventListener('pointerdown', (event) => {
  if (!placed || (event.pointerType === 'mouse' && event.button !== 0)) return;
  const hit = hitFace(rayFrom(event));
  if (!hit) return;
  event.stopPropagation();
  event.preventDefault();
  const local = world.worldToLocal(hit.clone());
  placed.push(local.toArray());
  const radius = 0.006 * camera.position.distanceTo(hit);
  const marker = new THREE.Mesh(new THREE.SphereGeometry(radius, 12, 8), new THREE.MeshBasicMaterial({ color: 0x40e0ff, depthTest: false }));
  marker.renderOrder = 20;
  marker.position.copy(local);
  markers.add(marker);
  invalidate();
  if (placed.length === asked.length) send();
  else prompt();
}, { capture: true });
// While marking, hovering shows no stroke targets (a drag that missed the face still orbits).
$('viewport').addEventListener('pointermove', (event) => {
  if (placed && event.buttons === 0) event.stopPropagation();
}, { capture: true });
