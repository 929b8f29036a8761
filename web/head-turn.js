// The captured head turn on the character, in the Capture tab only (strokes are drawn on the
// unturned face), unless the user unchecks "Turn the head as captured".

import * as THREE from 'three';
import { inCapture } from './mode.js';
import { currentFrame, setFrame, setTurn } from './playback.js';

const checkbox = /** @type {HTMLInputElement} */ (document.getElementById('head-turn'));

/** Turns the character by a captured head pose `[yaw, pitch, roll]` in degrees (the export's
 * convention: R = Ry(yaw)·Rx(−pitch)·Rz(roll); the capture browser test compares the two), or
 * back to rest. */
const headEuler = new THREE.Euler(0, 0, 0, 'YXZ');
export function turnHead(head) {
  if (!(head && inCapture() && checkbox.checked)) { setTurn(null); return; }
  const d = THREE.MathUtils.degToRad;
  headEuler.set(-d(head[1]), d(head[0]), d(head[2]), 'YXZ');
  setTurn(new THREE.Quaternion().setFromEuler(headEuler));
}
checkbox.addEventListener('change', () => setFrame(currentFrame()));
