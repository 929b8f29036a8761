// The captured head on the character, in the Capture tab only (strokes are drawn on the unturned
// face): where the view is skinned to the face's bones, the server's rotations of spine, neck,
// head, eyes and jaw (the export's turns); else the head pose turns the whole character. The
// user may uncheck "Turn the head as captured" (the eyes and jaw still follow).

import * as THREE from 'three';
import { inCapture } from './mode.js';
import { currentFrame, jointNames, setFrame, setPose, setTurn } from './playback.js';

const checkbox = /** @type {HTMLInputElement} */ (document.getElementById('head-turn'));

/** The joints a head pose turns, by the names the view's skin gives them (`faceanim_` and the
 * Rust side's `Bone::name`; tools/bones-view-e2e.mjs finds them and unchecks the box). */
const TURNED = ['faceanim_head', 'faceanim_neck', 'faceanim_upper_spine'];

/** Shows a captured head pose `[yaw, pitch, roll]` in degrees and the view's joints' rotations
 * `bones` (null where the server sends none), or the rest with nulls. Without a skinned view
 * the head pose turns the character (the export's convention: R = Ry(yaw)·Rx(−pitch)·Rz(roll);
 * the capture browser test compares the two). */
const headEuler = new THREE.Euler(0, 0, 0, 'YXZ');
export function turnHead(head, bones = null) {
  if (!inCapture()) { setTurn(null); setPose(null); return; }
  const names = jointNames();
  if (names) {
    setTurn(null);
    if (!bones) { setPose(null); return; }
    const identity = [0, 0, 0, 1];
    setPose(checkbox.checked ? bones : bones.map((q, k) => (TURNED.includes(names[k]) ? identity : q)));
    return;
  }
  setPose(null);
  if (!(head && checkbox.checked)) { setTurn(null); return; }
  const d = THREE.MathUtils.degToRad;
  headEuler.set(-d(head[1]), d(head[0]), d(head[2]), 'YXZ');
  setTurn(new THREE.Quaternion().setFromEuler(headEuler));
}
checkbox.addEventListener('change', () => setFrame(currentFrame()));
