// What is drawn over the character: each action's stroke with its handles (the red end arrow,
// the yellow middle sphere, green when straight), the candidate targets of a stroke start, and
// the ghost of the blendshape a stroke's end selects.

import * as THREE from 'three';
import { beforeDraw, camera, candidateGroup, clearGroup, invalidate, overlay, project, renderer, world } from './scene.js';
import { characterMeshes, isPlaying, onPlaying } from './playback.js';
import * as store from './store.js';

/** The handle meshes (arrow, sphere) a ray can grab. */
const handleTargets = [];
/** Draws every action's stroke, and the handles of each stroke's own side. */
export function drawOverlays() {
  clearGroup(overlay);
  handleTargets.length = 0;
  const state = store.state();
  if (!state) return;
  const d = store.character().diagonal;
  const thickness = state.resolved.stroke_thickness || d / 400;
  for (const action of state.actions) {
    action.sides.forEach((side, sideIndex) => {
      const selected = store.selection() === action.stroke;
      const points = side.path.map((p) => new THREE.Vector3(...p));
      const curve = new THREE.CatmullRomCurve3(points);
      const tube = new THREE.Mesh(new THREE.TubeGeometry(curve, 48, thickness, 6, false),
        new THREE.MeshBasicMaterial({ color: selected ? 0xffffff : 0x80c0ff, depthTest: false, transparent: true, opacity: sideIndex ? 0.5 : 0.9 }));
      tube.renderOrder = 10;
      overlay.add(tube);
      // Handles only on the selected action's own side: the rest of the face stays visible.
      if (sideIndex > 0 || !selected) return;
      // Red end arrow, just beyond the stroke's end, pointing along its last direction; a few
      // pixels long whatever the zoom (sized before each draw), so it never hides the mouth.
      const end = points[points.length - 1];
      const dir = end.clone().sub(points[points.length - 2]).normalize();
      const arrow = new THREE.ConeGeometry(0.3, 1, 12).translate(0, 0.5, 0);
      const cone = new THREE.Mesh(arrow, new THREE.MeshBasicMaterial({ color: 0xe03030, depthTest: false }));
      cone.position.copy(end);
      cone.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), dir);
      cone.renderOrder = 11;
      cone.userData = { handle: 'end', stroke: action.stroke, point: end.toArray(), pixels: 14 };
      overlay.add(cone); handleTargets.push(cone);
      // Yellow middle sphere; green when the stroke is straight.
      const sphere = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: side.straight ? 0x30d050 : 0xf0d020, depthTest: false }));
      sphere.position.set(...side.mid);
      sphere.renderOrder = 11;
      sphere.userData = { handle: 'mid', stroke: action.stroke, path: side.path, point: side.mid, pixels: 5 };
      overlay.add(sphere); handleTargets.push(sphere);
    });
  }
}

// Handles keep their size on screen: before each draw, each is scaled to its `pixels`.
beforeDraw(() => {
  const height = Math.max(1, renderer.domElement.clientHeight);
  const perPixel = 2 * Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2) / height;
  for (const handle of handleTargets) {
    handle.scale.setScalar(handle.userData.pixels * perPixel * camera.position.distanceTo(handle.position));
  }
});

/** The handle under `ray`, or else the one whose point is within `pixels` of the screen
 * position `(x, y)` (`{handle: 'end'|'mid', stroke, path}` and its position), or null. */
export function handleUnder(ray, x, y, pixels) {
  if (!overlay.visible) return null;
  const hit = ray.intersectObjects(handleTargets, false)[0];
  let object = hit ? hit.object : null;
  if (!object) {
    let best = pixels;
    for (const handle of handleTargets) {
      const [hx, hy] = project(handle.userData.point);
      const distance = Math.hypot(hx - x, hy - y);
      if (distance <= best) { best = distance; object = handle; }
    }
  }
  return object ? { ...object.userData, position: new THREE.Vector3(...object.userData.point) } : null;
}

/** The handle (of `kind` `'end'` or `'mid'`, or either) whose point is nearest `point` in
 * character space, within `radius`, or null: how a VR controller's pen tip finds one. */
export function handleNear(point, radius, kind = null) {
  if (!overlay.visible) return null;
  let best = radius, object = null;
  for (const handle of handleTargets) {
    if (kind && handle.userData.handle !== kind) continue;
    const [x, y, z] = handle.userData.point;
    const distance = Math.hypot(x - point.x, y - point.y, z - point.z);
    if (distance <= best) { best = distance; object = handle; }
  }
  return object ? { ...object.userData, position: new THREE.Vector3(...object.userData.point) } : null;
}

// ---------- showing and hiding overlays ----------
let overlaysOn = true;
/** Shows or hides every overlay (Alt+Shift+Z, as in Blender); they hide while playing too. */
export function toggleOverlays() { overlaysOn = !overlaysOn; updateVisibility(); }
function updateVisibility() {
  overlay.visible = overlaysOn && !isPlaying();
  candidateGroup.visible = overlay.visible;
  invalidate();
}
onPlaying(updateVisibility);

/** @type {any} The candidate targets last shown (what a stroke starting there can reach). */
let shown = null;
/** The candidates shown (the answer of POST /api/candidates), or null. */
export const shownCandidates = () => shown;

/** Shows the candidate targets of a stroke start (`found`: the API's answer; `faint` while
 * hovering), or none. */
export function showCandidates(found, faint) {
  shown = found;
  if (enlarged) labelCandidate(null, 0);
  clearGroup(candidateGroup);
  if (!found) return;
  const r = store.character().diagonal / 220;
  for (const c of found.candidates) {
    const s = new THREE.Mesh(new THREE.SphereGeometry(r, 12, 8), new THREE.MeshBasicMaterial({ color: 0x40e0ff, transparent: true, opacity: faint ? 0.35 : 0.8, depthTest: false }));
    s.position.set(...c.position);
    s.renderOrder = 12;
    s.userData = { name: c.name };
    candidateGroup.add(s);
  }
}

// ---------- ghost: the blendshape a stroke's end currently selects ----------
/** @type {THREE.Mesh|null} */
let ghost = null;
/** Shows the region blendshape `name` moves, at full weight, tinted (fading out where it moves
 * little, absent where it does not move, drawn just in front of the face so it never fights
 * with it), or nothing. */
export function showGhost(name) {
  invalidate();
  const base = characterMeshes()[0];
  const index = name && base && base.morphTargetDictionary ? base.morphTargetDictionary[name] : undefined;
  if (index === undefined) { if (ghost) ghost.visible = false; return; }
  if (!ghost || ghost.userData.base !== base.geometry || ghost.userData.index !== index) {
    if (ghost) { world.remove(ghost); ghost.geometry.dispose(); ghost.material.dispose(); }
    ghost = new THREE.Mesh(ghostGeometry(base, index), new THREE.MeshBasicMaterial({
      color: 0x60d0ff, vertexColors: true, transparent: true, depthWrite: false,
      polygonOffset: true, polygonOffsetFactor: -2, polygonOffsetUnits: -2, side: THREE.DoubleSide,
    }));
    ghost.userData = { base: base.geometry, index };
    ghost.matrixAutoUpdate = false;
    ghost.renderOrder = 5;
    ghost.frustumCulled = false;
    world.add(ghost);
  }
  ghost.matrix.copy(base.matrixWorld);
  ghost.matrixWorldNeedsUpdate = true;
  ghost.visible = true;
}

/** The face with target `index` at weight 1, and per vertex an opacity that grows with how far
 * the target moves it (none where it does not). */
function ghostGeometry(base, index) {
  const cpu = base.userData.cpuMorph;
  const rest = cpu ? cpu.basePosition : base.geometry.attributes.position.array;
  const positions = Float32Array.from(rest);
  const moved = new Float32Array(positions.length / 3);
  const add = (vertex, dx, dy, dz) => {
    positions[3 * vertex] += dx; positions[3 * vertex + 1] += dy; positions[3 * vertex + 2] += dz;
    moved[vertex] = Math.hypot(dx, dy, dz);
  };
  if (cpu) {
    const target = cpu.targets[index].position;
    if (target) for (let k = 0; k < target.indices.length; k++) add(target.indices[k], target.values[3 * k], target.values[3 * k + 1], target.values[3 * k + 2]);
  } else {
    const delta = base.geometry.morphAttributes.position[index];
    for (let v = 0; v < delta.count; v++) add(v, delta.getX(v), delta.getY(v), delta.getZ(v));
  }
  const most = Math.max(1e-9, ...moved);
  const colours = new Float32Array(moved.length * 4);
  moved.forEach((m, v) => { colours.set([1, 1, 1, Math.min(1, 4 * m / most) * 0.55], 4 * v); });
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(colours, 4));
  if (base.geometry.index) geometry.setIndex(base.geometry.index);
  return geometry;
}

// ---------- the candidate nearest the pointer, named ----------
const label = document.createElement('div');
label.id = 'candidate-label';
label.hidden = true;
document.getElementById('viewport').appendChild(label);
/** The candidate whose sphere is drawn larger. */
let enlarged = null;

/** Names the candidate `c` beside its sphere (with the weight the stroke reaches so far) and
 * draws it larger; `null` hides the label. */
export function labelCandidate(c, weight) {
  for (const sphere of candidateGroup.children) {
    const on = c !== null && sphere.userData.name === c.name && sphere.position.distanceToSquared(new THREE.Vector3(...c.position)) < 1e-12;
    sphere.scale.setScalar(on ? 1.8 : 1);
  }
  enlarged = c;
  invalidate();
  if (!c) { label.hidden = true; return; }
  const [x, y] = project(c.position);
  const rect = label.parentElement.getBoundingClientRect();
  label.textContent = `${c.name ?? c.goal} ${weight.toFixed(2)}`;
  label.style.left = `${x - rect.left + 12}px`;
  label.style.top = `${y - rect.top - 10}px`;
  label.hidden = false;
}

/** The weight a stroke from the reference vertex reaches towards candidate `c` when its end is
 * at `point`: its projection on the way to the target, 0 to 1. */
export function weightTowards(c, point) {
  const found = shown;
  if (!found) return 0;
  const from = new THREE.Vector3(...found.reference_position);
  const way = new THREE.Vector3(...c.position).sub(from);
  const length = way.lengthSq();
  return length > 0 ? Math.min(1, Math.max(0, point.clone().sub(from).dot(way) / length)) : 0;
}

/** The candidate sphere nearest the pointer on screen, if any is shown. */
export function nearestCandidate(x, y) {
  const found = shown;
  if (!found) return null;
  let best = null, bestPixels = Infinity;
  for (const c of found.candidates) {
    const [cx, cy] = project(c.position);
    const pixels = Math.hypot(cx - x, cy - y);
    if (pixels < bestPixels) { bestPixels = pixels; best = c; }
  }
  return best;
}
