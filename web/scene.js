// The 3D scene: renderer, camera and orbit controls, lights, the overlay groups, the draw loop
// (drawing only when something changed), and the geometry of rays and screen positions. Input
// comes as rays, never mouse-only events, so a WebXR controller can drive the same code.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const viewport = /** @type {HTMLElement} */ (document.getElementById('viewport'));
/** `?fast`: a cheaper viewport for machines without a GPU (see fastview.js). */
export const FAST = new URLSearchParams(location.search).has('fast');
export const renderer = new THREE.WebGLRenderer({ antialias: !FAST });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
viewport.appendChild(renderer.domElement);
export const scene = new THREE.Scene();
scene.background = new THREE.Color(0x2a2d33);
export const camera = new THREE.PerspectiveCamera(30, 1, 0.001, 1000);
export const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;
export const hemisphere = new THREE.HemisphereLight(0xffffff, 0x404050, 1.2);
scene.add(hemisphere);
export const key = new THREE.DirectionalLight(0xffffff, 1.6);
key.position.set(-1, 1.2, 2);
scene.add(key);
/** The character's own space: the character, its strokes and handles live here. On the desktop
 * it is the scene's; in VR (xr.js) it is placed life size in front of the user and moved by
 * navigation. */
export const world = new THREE.Group();
world.name = 'character space';
scene.add(world);
/** Strokes and handles. */
export const overlay = new THREE.Group();
world.add(overlay);
/** The candidate targets of a stroke. */
export const candidateGroup = new THREE.Group();
world.add(candidateGroup);

let dirty = true;
/** Asks for the viewport to be drawn again. */
export function invalidate() { dirty = true; }

const stats = { frameCount: 0, drawCalls: 0 };
/** Frames drawn so far and the draw calls of the last one. */
export const drawStats = () => stats;

/** @type {((now: number) => boolean)[]} */
const ticks = [];
/** Calls `tick(now)` every animation frame, before drawing; it returns true to be drawn. */
export function onTick(tick) { ticks.push(tick); }
/** @type {(() => void)[]} */
const beforeDraws = [];
/** Calls `listener()` just before every draw. */
export function beforeDraw(listener) { beforeDraws.push(listener); }
/** @type {((now: number, frame: XRFrame) => void)[]} */
const xrFrames = [];
/** Calls `listener(now, xrFrame)` on every XR frame, before drawing (xr.js). */
export function onXRFrame(listener) { xrFrames.push(listener); }
/** @type {(() => void)[]} */
const renders = [];
/** Calls `listener()` after every draw. */
export function onRender(listener) { renders.push(listener); }

function resize() {
  const { clientWidth: w, clientHeight: h } = viewport;
  renderer.setSize(w, h, false);
  invalidate();
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
new ResizeObserver(resize).observe(viewport);

/** Frames the camera on a bounding box (`{min, max}`), looking at `height` of it (0.58: the
 * eyes of a head; 0.5: the middle of a whole body), the box's larger side filling `fill` of
 * the view's height (below 1 crops a head close; above 1 leaves a margin round a body). */
export function frameCamera(bounds, height = 0.58, fill = 1.25) {
  const min = new THREE.Vector3(...bounds.min), max = new THREE.Vector3(...bounds.max);
  const size = max.clone().sub(min);
  const target = new THREE.Vector3((min.x + max.x) / 2, min.y + height * size.y, (min.z + max.z) / 2);
  const distance = 0.5 * Math.max(size.x, size.y) / fill / Math.tan(THREE.MathUtils.degToRad(15)) + 0.5 * size.z;
  camera.near = distance * 0.01; camera.far = distance * 20; camera.updateProjectionMatrix();
  camera.position.copy(target).add(new THREE.Vector3(0, 0, distance));
  controls.target.copy(target);
  controls.update();
  invalidate();
}

/** Screen position (CSS pixels, relative to the page) of a point in character space. */
export function project(p) {
  const v = new THREE.Vector3(p[0], p[1], p[2]).project(camera);
  const rect = renderer.domElement.getBoundingClientRect();
  return [rect.left + (v.x + 1) / 2 * rect.width, rect.top + (1 - v.y) / 2 * rect.height];
}

const raycaster = new THREE.Raycaster();
/** The ray under a screen position (`{clientX, clientY}`). */
export function rayFrom(event) {
  const rect = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1, -((event.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  return raycaster;
}

/** The plane through `point` facing the camera. */
export function planeFacingCamera(point) {
  const normal = new THREE.Vector3();
  camera.getWorldDirection(normal);
  return new THREE.Plane().setFromNormalAndCoplanarPoint(normal, point);
}

/** Where `ray` meets `plane`, or null. */
export function onPlane(ray, plane) {
  const p = new THREE.Vector3();
  return ray.ray.intersectPlane(plane, p) ? p : null;
}

/** Empties an overlay group, freeing its GPU buffers (overlays are rebuilt on every change). */
export function clearGroup(group) {
  invalidate();
  for (const child of group.children) {
    child.geometry?.dispose();
    child.material?.dispose();
  }
  group.clear();
}

// Draw only when something changed: an idle studio leaves the CPU to capture and training
// (and a laptop's battery alone). Pointer input and ticks that animate always redraw.
controls.addEventListener('change', invalidate);
for (const type of ['pointerdown', 'pointermove', 'pointerup', 'wheel', 'keydown']) viewport.addEventListener(type, invalidate, { passive: true });
window.addEventListener('keydown', invalidate);
renderer.setAnimationLoop((now, xrFrame) => {
  let animating = false;
  for (const tick of ticks) animating = tick(now) || animating;
  // A headset needs a picture every frame, whatever changed.
  if (xrFrame) for (const listener of xrFrames) listener(now, xrFrame);
  if (!dirty && !animating && !xrFrame) return;
  dirty = false;
  for (const listener of beforeDraws) listener();
  renderer.render(scene, camera);
  for (const listener of renders) listener();
  stats.drawCalls = renderer.info.render.calls;
  stats.frameCount++;
});
