// What is drawn over the character: each action's stroke with its handles (the red end arrow,
// the yellow middle sphere, green when straight), the candidate targets of a stroke start, and
// the ghost of the blendshape a stroke's end selects.

import * as THREE from 'three';
import { candidateGroup, clearGroup, invalidate, overlay, project, scene } from './scene.js';
import { characterMeshes } from './playback.js';
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
      if (sideIndex > 0) return;
      // Red end arrow, pointing along the stroke's last direction.
      const end = points[points.length - 1];
      const dir = end.clone().sub(points[points.length - 2]).normalize();
      const cone = new THREE.Mesh(new THREE.ConeGeometry(d / 120, d / 40, 12), new THREE.MeshBasicMaterial({ color: 0xe03030, depthTest: false }));
      cone.position.copy(end);
      cone.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), dir);
      cone.renderOrder = 11;
      cone.userData = { handle: 'end', stroke: action.stroke };
      overlay.add(cone); handleTargets.push(cone);
      // Yellow middle sphere; green when the stroke is straight.
      const sphere = new THREE.Mesh(new THREE.SphereGeometry(d / 150, 16, 12), new THREE.MeshBasicMaterial({ color: side.straight ? 0x30d050 : 0xf0d020, depthTest: false }));
      sphere.position.set(...side.mid);
      sphere.renderOrder = 11;
      sphere.userData = { handle: 'mid', stroke: action.stroke, path: side.path };
      overlay.add(sphere); handleTargets.push(sphere);
    });
  }
}

/** The handle under `ray` (`{handle: 'end'|'mid', stroke, path}` and its position), or null. */
export function handleUnder(ray) {
  const hit = ray.intersectObjects(handleTargets, false)[0];
  return hit ? { ...hit.object.userData, position: hit.object.position.clone() } : null;
}

/** @type {any} The candidate targets last shown (what a stroke starting there can reach). */
let shown = null;
/** The candidates shown (the answer of POST /api/candidates), or null. */
export const shownCandidates = () => shown;

/** Shows the candidate targets of a stroke start (`found`: the API's answer; `faint` while
 * hovering), or none. */
export function showCandidates(found, faint) {
  shown = found;
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
/** Shows the blendshape `name` at full weight as a translucent copy of the face, or nothing. */
export function showGhost(name) {
  invalidate();
  const base = characterMeshes()[0];
  const index = name && base && base.morphTargetDictionary ? base.morphTargetDictionary[name] : undefined;
  if (index === undefined) { if (ghost) ghost.visible = false; return; }
  const cpu = base.userData.cpuMorph;
  if (!ghost || ghost.userData.base !== base.geometry || (cpu && ghost.userData.index !== index)) {
    if (ghost) { scene.remove(ghost); if (ghost.geometry !== base.geometry) ghost.geometry.dispose(); }
    let geometry = base.geometry;
    if (cpu) {
      // Blended on the CPU (`?fast`): the ghost gets the target's own positions.
      const positions = Float32Array.from(cpu.basePosition);
      const target = cpu.targets[index].position;
      if (target) for (let k = 0; k < target.indices.length; k++) { const o = target.indices[k] * 3; for (let c = 0; c < 3; c++) positions[o + c] += target.values[3 * k + c]; }
      geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
      if (base.geometry.index) geometry.setIndex(base.geometry.index);
    }
    ghost = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ color: 0x60d0ff, transparent: true, opacity: 0.22, depthWrite: false }));
    ghost.userData = { base: base.geometry, index };
    ghost.updateMorphTargets();
    ghost.matrixAutoUpdate = false;
    ghost.renderOrder = 5;
    ghost.frustumCulled = !cpu;
    scene.add(ghost);
  }
  ghost.matrix.copy(base.matrixWorld);
  ghost.matrixWorldNeedsUpdate = true;
  if (ghost.morphTargetInfluences) { ghost.morphTargetInfluences.fill(0); ghost.morphTargetInfluences[index] = 1; }
  ghost.visible = true;
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
