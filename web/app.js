// faceanim studio: the page. Plain ES modules, no build step; each module has one job and owns
// its state (others call its functions):
//   api.js       the HTTP/JSON API client          status.js    the error banner and status line
//   store.js     the sketch's state and selection  mode.js      the Sketch and Capture tabs
//   scene.js     renderer, camera, draw loop, rays  fastview.js  the `?fast` viewport
//   playback.js  the character, its animation, the current frame, the layer under the sketch
//   overlays.js  strokes, handles, candidates, ghost  strokes.js  pointer input and strokes
//   handles.js   dragging the arrow and the sphere  timeline.js  the timeline
//   settings.js  the settings panel                 commands.js  toolbar and keyboard
//   inspector.js the selected action's numbers   shapes.js    the blendshape list
//   capture.js   capture mode: the take, its corrections, the frame diagram
//   take.js      the take's state as the server last sent it, and sending edits to it
//   head-turn.js the captured head on the character: its bones where it has them, else whole
//   sound.js     a lip-sync take's sound, played and scrubbed with the animation
//   live.js      capture from the webcam in real time
//   voice.js     the microphone drives the mouth in real time (voice-worklet.js: its samples)
//   visemes.js   lip sync's viseme table, edited
//   retarget.js  the retarget map: which of the character's shapes answer to each ARKit channel
//   face-marks.js marking the face by hand where the face model finds none
//   medians.js   running medians of live measurements
//   vmc.js       VMC in: a phone tracker or another app drives the character
//   xr.js        immersive sketching in a headset (WebXR): pens, the seed's states, navigation
//   xrpanel.js   the VR world's panels: the timeline and the settings
//   slow-hint.js tells a slow display about the `?fast` viewport
//   downloads.js saves the API's files, or shows why there is none, with the exporter's notes
// The server owns the project and the engines; the page draws what the API describes. This
// file starts the page and publishes `window.studio`, the read-only hook scripts and tests use
// (crates/studio/API.md).

import { capture } from './capture.js';
import { sound } from './sound.js';
import './commands.js';
import './downloads.js';
import './generate.js';
import { setMode } from './mode.js';
import { characterMeshes, characterRoot, currentFrame, isPlaying, isReady } from './playback.js';
import { drawStats, project } from './scene.js';
import './inspector.js';
import './settings.js';
import './shapes.js';
import './slow-hint.js';
import { showFailure } from './status.js';
import * as store from './store.js';
import { faceAt, strokeLatency } from './strokes.js';
import './timeline.js';
import { drawOverlays } from './overlays.js';
import { xrHook } from './xr.js';

store.onState(() => drawOverlays());
store.onSelection(() => drawOverlays());

/** The read-only hook for scripts and tests. */
window.studio = Object.freeze({
  /** Screen position (CSS pixels) of a point in character space. */
  project,
  /** The face point under a screen position, or null. */
  hit: faceAt,
  get state() { return store.state(); },
  get character() { return store.character(); },
  get frame() { return currentFrame(); },
  get playing() { return isPlaying(); },
  get bakedReady() { return isReady(); },
  get meshes() { return characterMeshes(); },
  get root() { return characterRoot(); },
  get lastStrokeMs() { return strokeLatency(); },
  get frameCount() { return drawStats().frameCount; },
  get drawCalls() { return drawStats().drawCalls; },
  /** The VR session and its state (xr.js). */
  xr: xrHook,
  capture,
  /** A lip-sync take's sound (sound.js). */
  sound,
});

(async () => {
  try {
    await store.loadCharacter();
    await store.run('GET', 'api/state');
  } catch (e) { showFailure(e); }
  // Open in capture mode with `#capture` in the address.
  if (location.hash === '#capture') setMode('capture');
})();
