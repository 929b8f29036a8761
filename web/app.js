// faceanim studio: the page. Plain ES module, no build step. The server owns the project and
// the engines; this file draws what /api/state describes, plays the exported GLB and turns
// pointer input (mouse, pen, touch; later XR controllers) into strokes and handle edits.
// Everything goes through pointer events and rays, never mouse-only events, so the same code
// can be driven from a WebXR controller ray.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

/** @typedef {{stroke:number,name:string,chain:number,previous:number|null,start_frame:number,end_frame:number,ease:number,symmetric:boolean,sides:any[]}} ActionView */

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

// ---------- API ----------
async function api(method, path, body, headers = {}) {
  const init = { method, headers: { ...headers } };
  if (body !== undefined) {
    if (body instanceof ArrayBuffer || body instanceof Blob) { init.body = body; }
    else { init.body = JSON.stringify(body); init.headers['content-type'] = 'application/json'; }
  }
  const response = await fetch(path, init);
  const text = await response.text();
  let json = null;
  try { json = text ? JSON.parse(text) : null; } catch { json = null; }
  if (!response.ok) throw new Error(json && json.error ? json.error : text || response.statusText);
  return json;
}

function showError(message) {
  const box = $('error');
  box.textContent = message;
  box.hidden = !message;
}

// ---------- scene ----------
const viewport = $('viewport');
// `?fast`: a cheaper viewport for machines without a GPU: no antialiasing, morph targets blended
// on the CPU (blendOnCpu) and lighting computed per vertex (vertexLitMaterial).
const FAST = new URLSearchParams(location.search).has('fast');
const renderer = new THREE.WebGLRenderer({ antialias: !FAST });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
viewport.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x2a2d33);
const camera = new THREE.PerspectiveCamera(30, 1, 0.001, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;
const hemisphere = new THREE.HemisphereLight(0xffffff, 0x404050, 1.2);
scene.add(hemisphere);
const key = new THREE.DirectionalLight(0xffffff, 1.6);
key.position.set(-1, 1.2, 2);
scene.add(key);
const overlay = new THREE.Group();
scene.add(overlay);
const candidateGroup = new THREE.Group();
scene.add(candidateGroup);

const studio = {
  /** @type {any} */ state: null,
  /** @type {any} */ character: null,
  frame: 0,
  playing: false,
  selected: /** @type {number|null} */ (null),
  /** @type {THREE.Mesh[]} */ meshes: [],
  /** @type {THREE.Object3D|null} */ root: null,
  /** @type {{mixer: THREE.AnimationMixer, a: THREE.AnimationAction}[]} */ actions: [],
  bakedReady: false,
  lastFrameTime: 0,
  frameCount: 0,
  drawCalls: 0,
  lastStrokeMs: 0,
  /** @type {any} The candidate targets last shown (what a stroke starting there can reach). */
  candidates: null,
  /** Playback direction: 1 forwards, -1 backwards. */
  direction: 1,
  /** Frames beyond the sketch's own (a captured take) that the timeline and playback cover. */
  extraLastFrame: 0,
  /** @type {((frame: number) => number[]|null)|null} Weights of the character's own targets
   * added under the sketch at a frame (capture mode's take or live face), or null. */
  layer: null,
  /** @type {((frame: number) => void)[]} Called after every frame change. */
  onFrame: [],
  /** @type {(() => void)[]} Called after every render of the viewport. */
  onRender: [],
  /** While a stroke or handle is dragged the character stays at rest (no captured head turn). */
  holdRest: false,
  /** The point of the face under a screen position (CSS pixels), or null. */
  hit(x, y) {
    const p = hitFace(rayFrom({ clientX: x, clientY: y }));
    return p ? p.toArray() : null;
  },
  /** Screen position (CSS pixels, relative to the page) of a point in character space. */
  project(p) {
    const v = new THREE.Vector3(p[0], p[1], p[2]).project(camera);
    const rect = renderer.domElement.getBoundingClientRect();
    return [rect.left + (v.x + 1) / 2 * rect.width, rect.top + (1 - v.y) / 2 * rect.height];
  },
};
// Scripts and tests drive the studio through this object and the HTTP API; capture.js builds
// capture mode on the same object.
window.studio = studio;

function resize() {
  const { clientWidth: w, clientHeight: h } = viewport;
  renderer.setSize(w, h, false);
  studio.invalidate?.();
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
new ResizeObserver(resize).observe(viewport);

function frameCamera() {
  const b = studio.character.bounds;
  const min = new THREE.Vector3(...b.min), max = new THREE.Vector3(...b.max);
  const size = max.clone().sub(min);
  const target = new THREE.Vector3((min.x + max.x) / 2, min.y + 0.58 * size.y, (min.z + max.z) / 2);
  const distance = 0.5 * Math.max(size.x, size.y) * 0.8 / Math.tan(THREE.MathUtils.degToRad(15)) + 0.5 * size.z;
  camera.near = distance * 0.01; camera.far = distance * 20; camera.updateProjectionMatrix();
  camera.position.copy(target).add(new THREE.Vector3(0, 0, distance));
  controls.target.copy(target);
  controls.update();
  studio.invalidate?.();
}

const loader = new GLTFLoader();
let bakeGeneration = 0;
/** Loads the export (character + baked corrective targets + animation) and plays it. */
async function loadBaked() {
  const generation = ++bakeGeneration;
  const response = await fetch('api/export.glb');
  if (!response.ok) throw new Error(await response.text());
  const buffer = await response.arrayBuffer();
  if (generation !== bakeGeneration) return;
  const gltf = await loader.parseAsync(buffer, '');
  if (generation !== bakeGeneration) return;
  if (studio.root) { scene.remove(studio.root); studio.root.traverse((o) => { if (o.isMesh) o.geometry.dispose(); }); }
  studio.meshes = [];
  const root = gltf.scene;
  root.traverse((o) => {
    if (!o.isMesh) return;
    if (FAST) { const m = o.material; o.material = vertexLitMaterial(m); m.dispose(); blendOnCpu(o); }
    o.material.side = THREE.DoubleSide;
    studio.meshes.push(o);
  });
  scene.add(root);
  studio.root = root;
  if (gltf.animations.length && studio.meshes.length) {
    // The clip targets the node by name; bind its weight tracks to each mesh (primitive) directly.
    const clip = gltf.animations[0];
    for (const track of clip.tracks) { track.name = '.morphTargetInfluences'; }
    studio.actions = studio.meshes.map((m) => { const mixer = new THREE.AnimationMixer(m); const a = mixer.clipAction(clip); a.play(); return { mixer, a }; });
  } else {
    studio.actions = [];
  }
  studio.bakedReady = true;
  setFrame(studio.frame);
}

/** The last frame with animation: the sketch's or the captured take's. */
function lastFrame() {
  return Math.max(0, Math.ceil(studio.state ? studio.state.last_frame : 0), studio.extraLastFrame);
}

/** The same lights as the scene's, evaluated once per vertex instead of once per pixel: software
 * GL (SwiftShader, 2 cores) drew capture mode's view of the 49k-triangle ICT head at 12–14 frames
 * per second with three.js's Lambert material and at 16–20 with this one. The lit colour is turned to sRGB in the vertex shader
 * too, so a pixel only interpolates it (and multiplies a texture, left sRGB-encoded: gamma is a
 * power law, so encoding the product or the factors agrees). Both faces are lit: the fragment
 * picks the side it sees. */
function vertexLitMaterial(/** @type {any} */ source) {
  const map = source.map ? source.map.clone() : null;
  if (map) { map.colorSpace = THREE.NoColorSpace; map.needsUpdate = true; }
  return new THREE.ShaderMaterial({
    vertexColors: !!source.vertexColors,
    defines: map ? { FAST_MAP: '' } : {},
    uniforms: {
      albedo: { value: (source.color || new THREE.Color(1, 1, 1)).clone() },
      map: { value: map },
      sky: { value: hemisphere.color.clone().multiplyScalar(hemisphere.intensity) },
      ground: { value: hemisphere.groundColor.clone().multiplyScalar(hemisphere.intensity) },
      keyColor: { value: key.color.clone().multiplyScalar(key.intensity) },
      keyDirection: { value: key.position.clone().sub(key.target.position).normalize() },
    },
    vertexShader: `
      uniform vec3 albedo, sky, ground, keyColor, keyDirection;
      varying vec3 litFront, litBack;
      #ifdef FAST_MAP
      varying vec2 texCoord;
      #endif
      vec3 encodeSrgb(vec3 c) {
        c = clamp(c, 0.0, 1.0);
        return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
      }
      vec3 lit(vec3 n, vec3 up, vec3 toKey, vec3 base) {
        vec3 irradiance = mix(ground, sky, 0.5 * dot(n, up) + 0.5) + keyColor * max(dot(n, toKey), 0.0);
        return encodeSrgb(base * irradiance / 3.14159265);
      }
      void main() {
        vec3 n = normalize(normalMatrix * normal);
        vec3 up = normalize((viewMatrix * vec4(0.0, 1.0, 0.0, 0.0)).xyz);
        vec3 toKey = normalize((viewMatrix * vec4(keyDirection, 0.0)).xyz);
        vec3 base = albedo;
        #ifdef USE_COLOR
        base *= color.rgb;
        #endif
        litFront = lit(n, up, toKey, base);
        litBack = lit(-n, up, toKey, base);
        #ifdef FAST_MAP
        texCoord = uv;
        #endif
        gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
      }`,
    fragmentShader: `
      varying vec3 litFront, litBack;
      #ifdef FAST_MAP
      uniform sampler2D map;
      varying vec2 texCoord;
      #endif
      void main() {
        vec3 c = gl_FrontFacing ? litFront : litBack;
        #ifdef FAST_MAP
        c *= texture2D(map, texCoord).rgb;
        #endif
        gl_FragColor = vec4(c, 1.0);
      }`,
  });
}

/** Without a GPU, morphing 50 targets per vertex in the (software) vertex shader costs most of
 * a frame. `?fast` moves it to the CPU instead: each target is kept as the sparse list of the
 * vertices it moves, and only targets with weight are added, once per drawn frame. The mesh
 * keeps its `morphTargetInfluences` (the mixer and the layers write them as before). */
function blendOnCpu(mesh) {
  const geometry = mesh.geometry;
  const morphs = geometry.morphAttributes.position;
  if (!morphs || !morphs.length || !geometry.morphTargetsRelative) return;
  const sparse = (attribute) => {
    if (!attribute) return null;
    const indices = [], values = [];
    for (let v = 0; v < attribute.count; v++) {
      const x = attribute.getX(v), y = attribute.getY(v), z = attribute.getZ(v);
      if (x !== 0 || y !== 0 || z !== 0) { indices.push(v); values.push(x, y, z); }
    }
    return { indices: Int32Array.from(indices), values: Float32Array.from(values) };
  };
  const normals = geometry.morphAttributes.normal || [];
  mesh.userData.cpuMorph = {
    basePosition: Float32Array.from(geometry.attributes.position.array),
    baseNormal: geometry.attributes.normal ? Float32Array.from(geometry.attributes.normal.array) : null,
    targets: morphs.map((m, i) => ({ position: sparse(m), normal: sparse(normals[i]) })),
    shown: /** @type {number[]|null} */ (null),
  };
  geometry.morphAttributes = {};
  mesh.frustumCulled = false;
}

/** Applies the CPU blend of `mesh` when its weights changed since it was last drawn. */
function blendNow(mesh) {
  const cpu = mesh.userData.cpuMorph;
  const weights = mesh.morphTargetInfluences;
  if (!cpu || !weights) return;
  if (cpu.shown && cpu.shown.length === weights.length && cpu.shown.every((w, i) => w === weights[i])) return;
  cpu.shown = Array.from(weights);
  const add = (out, base, kind) => {
    out.set(base);
    cpu.targets.forEach((target, t) => {
      const w = weights[t], part = target[kind];
      if (!part || Math.abs(w) < 1e-4) return;
      const { indices, values } = part;
      for (let k = 0; k < indices.length; k++) {
        const o = indices[k] * 3;
        out[o] += w * values[3 * k]; out[o + 1] += w * values[3 * k + 1]; out[o + 2] += w * values[3 * k + 2];
      }
    });
  };
  const position = mesh.geometry.attributes.position;
  add(position.array, cpu.basePosition, 'position');
  position.needsUpdate = true;
  const normal = mesh.geometry.attributes.normal;
  if (normal && cpu.baseNormal) { add(normal.array, cpu.baseNormal, 'normal'); normal.needsUpdate = true; }
}

function setFrame(frame) {
  const last = lastFrame();
  studio.frame = Math.min(Math.max(0, frame), last);
  const fps = studio.state ? studio.state.fps : 30;
  // The mixer writes a track only when its value changes, so the sketch's own values go back
  // before it runs, and are kept after it for the layer to add to.
  for (const mesh of studio.meshes) { if (mesh.userData.sketch && mesh.morphTargetInfluences) mesh.morphTargetInfluences.splice(0, Infinity, ...mesh.userData.sketch); }
  for (const { mixer } of studio.actions || []) { mixer.setTime(studio.frame / fps); }
  const sketchPlays = (studio.actions || []).length > 0;
  for (const mesh of studio.meshes) {
    const influences = mesh.morphTargetInfluences;
    if (influences) mesh.userData.sketch = sketchPlays ? influences.slice() : influences.map(() => 0);
  }
  applyLayer();
  $('frame-label').textContent = `frame ${studio.frame.toFixed(0)} / ${last}`;
  drawPlayhead();
  for (const f of studio.onFrame) f(studio.frame);
}

/** Shows the sketch's values at the current frame (kept by setFrame) plus the layer's weights
 * (a captured take, the live face) on the character's own targets. */
function applyLayer() {
  studio.invalidate?.();
  const weights = studio.layer ? studio.layer(studio.frame) : null;
  for (const mesh of studio.meshes) {
    const influences = mesh.morphTargetInfluences;
    const sketch = mesh.userData.sketch;
    if (!influences || !sketch) continue;
    for (let i = 0; i < influences.length; i++) {
      const w = weights && i < weights.length ? weights[i] : 0;
      influences[i] = Math.min(1, Math.max(0, sketch[i] + w));
    }
  }
}

/** Empties an overlay group, freeing its GPU buffers (overlays are rebuilt on every change). */
function clearGroup(group) {
  studio.invalidate?.();
  for (const child of group.children) {
    child.geometry?.dispose();
    child.material?.dispose();
  }
  group.clear();
}

// ---------- overlays: strokes, arrows, spheres ----------
const handleTargets = [];
function drawOverlays() {
  clearGroup(overlay);
  handleTargets.length = 0;
  if (!studio.state) return;
  const d = studio.character.diagonal;
  const thickness = studio.state.resolved.stroke_thickness || d / 400;
  for (const action of studio.state.actions) {
    action.sides.forEach((side, sideIndex) => {
      const selected = studio.selected === action.stroke;
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

function showCandidates(found, faint) {
  clearGroup(candidateGroup);
  if (!found) return;
  const r = studio.character.diagonal / 220;
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
function showGhost(name) {
  studio.invalidate?.();
  const base = studio.meshes[0];
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
function nearestCandidate(x, y) {
  const found = studio.candidates;
  if (!found) return null;
  let best = null, bestPixels = Infinity;
  for (const c of found.candidates) {
    const [cx, cy] = studio.project(c.position);
    const pixels = Math.hypot(cx - x, cy - y);
    if (pixels < bestPixels) { bestPixels = pixels; best = c; }
  }
  return best;
}

// ---------- pointer input ----------
const raycaster = new THREE.Raycaster();
function rayFrom(event) {
  const rect = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1, -((event.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  return raycaster;
}
function hitFace(ray) {
  if (FAST) for (const mesh of studio.meshes) blendNow(mesh);
  const hits = ray.intersectObjects(studio.meshes, false);
  return hits.length ? hits[0].point : null;
}
function planeFacingCamera(point) {
  const normal = new THREE.Vector3();
  camera.getWorldDirection(normal);
  return new THREE.Plane().setFromNormalAndCoplanarPoint(normal, point);
}
function onPlane(ray, plane) {
  const p = new THREE.Vector3();
  return ray.ray.intersectPlane(plane, p) ? p : null;
}

/** @type {null | {kind:'stroke', plane:THREE.Plane, t0:number, samples:any[], pending:number[][], line:THREE.Line} | {kind:'handle', handle:string, stroke:number, plane:THREE.Plane, path?:any[], ease:boolean, pending:boolean, gesture:string}} */
let drag = null;

/** Whether the character stands at rest (capture mode turns it by the captured head pose). */
function atRest() {
  const q = studio.root ? studio.root.quaternion : null;
  return !q || (q.x === 0 && q.y === 0 && q.z === 0);
}

renderer.domElement.addEventListener('pointerdown', async (event) => {
  if (event.button !== 0 || !studio.bakedReady) return;
  if (!atRest()) {
    // Strokes and handles live in the character's own space: draw on the face at rest.
    studio.holdRest = true;
    studio.root.quaternion.identity();
    studio.root.updateMatrixWorld(true);
    studio.invalidate();
  }
  const ray = rayFrom(event);
  const handle = ray.intersectObjects(handleTargets, false)[0];
  if (handle) {
    controls.enabled = false;
    renderer.domElement.setPointerCapture(event.pointerId);
    const { handle: kind, stroke, path } = handle.object.userData;
    studio.selected = stroke;
    drag = { kind: 'handle', handle: kind, stroke, path, plane: planeFacingCamera(handle.object.position), ease: event.shiftKey && kind === 'mid', pending: false, gesture: `${Date.now()}-${Math.random()}` };
    return;
  }
  const hit = hitFace(ray);
  if (!hit) return; // orbit
  controls.enabled = false;
  renderer.domElement.setPointerCapture(event.pointerId);
  const geometry = new THREE.BufferGeometry().setFromPoints([hit, hit]);
  const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: 0xffe080, depthTest: false }));
  line.renderOrder = 13;
  scene.add(line);
  drag = { kind: 'stroke', plane: planeFacingCamera(hit), t0: performance.now(), samples: [{ t: 0, p: hit.toArray() }], pending: [], line };
  api('POST', 'api/candidates', { point: hit.toArray(), frame: studio.frame }).then((found) => { studio.candidates = found; showCandidates(found, false); }).catch(() => {});
});

let hoverTimer = 0;
renderer.domElement.addEventListener('pointermove', (event) => {
  if (!drag) {
    // The paper's users asked to see the targets before drawing: show them on hover.
    if (event.pointerType !== 'touch' && studio.bakedReady && performance.now() - hoverTimer > 120) {
      hoverTimer = performance.now();
      const hit = atRest() ? hitFace(rayFrom(event)) : null;
      if (hit) api('POST', 'api/candidates', { point: hit.toArray(), frame: studio.frame }).then((f) => { if (!drag) showCandidates(f, true); }).catch(() => {});
      else clearGroup(candidateGroup);
    }
    return;
  }
  const events = event.getCoalescedEvents ? event.getCoalescedEvents() : [event];
  for (const e of events.length ? events : [event]) {
    const p = onPlane(rayFrom(e), drag.plane);
    if (!p) continue;
    if (drag.kind === 'stroke') {
      drag.pending.push(p.toArray());
    } else {
      dragHandleTo(p);
    }
  }
  if (drag.kind === 'stroke') {
    // Coalesced points of this event share its arrival time span: spread them evenly between
    // the previous sample's time and now (event timestamps are not reliable across devices).
    const now = (performance.now() - drag.t0) / 1000;
    const previous = drag.samples[drag.samples.length - 1].t;
    drag.pending.forEach((q, i) => drag.samples.push({ t: previous + (now - previous) * (i + 1) / drag.pending.length, p: q }));
    drag.pending = [];
    const nearest = nearestCandidate(event.clientX, event.clientY);
    showGhost(nearest && nearest.name);
    drag.line.geometry.dispose();
    drag.line.geometry = new THREE.BufferGeometry().setFromPoints(drag.samples.map((s) => new THREE.Vector3(...s.p)));
  }
});

async function dragHandleTo(p) {
  if (!drag || drag.kind !== 'handle' || drag.pending) return;
  let edit;
  if (drag.handle === 'end') edit = { end: p.toArray() };
  else if (drag.ease) {
    // Slide along the stroke: the easing α is where along the path the sphere is.
    let best = 0, bestDistance = Infinity;
    drag.path.forEach((q, i) => { const dd = p.distanceToSquared(new THREE.Vector3(...q)); if (dd < bestDistance) { bestDistance = dd; best = i; } });
    edit = { ease: Math.min(0.98, Math.max(0.02, best / (drag.path.length - 1))) };
  } else edit = { mid: p.toArray() };
  drag.pending = true;
  try {
    const state = await api('PATCH', `api/strokes/${drag.stroke}`, edit, { 'x-gesture': drag.gesture });
    applyState(state, false);
    showError('');
    const action = state.actions.find((a) => a.stroke === drag?.stroke);
    if (drag && action) showGhost(action.sides[0].target);
  }
  catch (e) { showError(String(e.message || e)); }
  finally { if (drag) drag.pending = false; }
}

/** Pixels within which a release counts as "on" a candidate sphere. */
const SPHERE_PICK_PIXELS = 14;

/**
 * A stroke drawn on a screen has no depth of its own: it lies on the plane through its start
 * facing the camera. When it is released on a candidate sphere, the user meant that sphere, so
 * the stroke is carried along each sample's view ray, progressively (none at the start, all at
 * the end), to end at the sphere's depth. On screen nothing moves.
 */
function aimAtReleasedSphere(samples) {
  const found = studio.candidates;
  if (!found || !found.candidates.length) return;
  const last = samples[samples.length - 1].p;
  const [lx, ly] = studio.project(last);
  let best = null, bestPixels = SPHERE_PICK_PIXELS;
  for (const c of found.candidates) {
    const [x, y] = studio.project(c.position);
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
  if (studio.holdRest) { studio.holdRest = false; setFrame(studio.frame); }
  if (!drag) return;
  const finished = drag;
  drag = null;
  controls.enabled = true;
  showGhost(null);
  try { renderer.domElement.releasePointerCapture(event.pointerId); } catch { /* already released */ }
  if (finished.kind === 'stroke') {
    scene.remove(finished.line);
    clearGroup(candidateGroup);
    if (finished.samples.length < 2) return;
    const released = performance.now();
    aimAtReleasedSphere(finished.samples);
    try {
      const state = await api('POST', 'api/strokes', { samples: finished.samples });
      studio.selected = state.added;
      applyState(state, true);
      // From release to the action drawn (arc, handles, timeline row); the bake for playback follows.
      studio.lastStrokeMs = performance.now() - released;
      const rejected = state.rejected.find((r) => r.stroke === state.added);
      showError(rejected ? `That stroke made no action: ${rejected.reason}` : '');
    } catch (e) { showError(String(e.message || e)); }
  } else {
    // Wait for the last live edit, then show the bake of the final handle position.
    while (finished.pending) await new Promise((r) => setTimeout(r, 10));
    await loadBaked();
  }
}
renderer.domElement.addEventListener('pointerup', endDrag);
renderer.domElement.addEventListener('pointercancel', endDrag);

// ---------- state ----------
function applyState(state, rebake) {
  studio.state = state;
  $('undo').disabled = !state.can_undo;
  $('redo').disabled = !state.can_redo;
  $('delete').disabled = studio.selected === null;
  $('fps').value = state.fps;
  fillSettings(state);
  drawOverlays();
  drawTimeline();
  $('status').textContent = `${state.actions.length} action(s); ${state.rejected.length} stroke(s) ignored; project: ${state.project_path}`;
  if (rebake) loadBaked().catch((e) => showError(String(e.message || e)));
}

async function run(method, path, body) {
  try { const state = await api(method, path, body); applyState(state, true); showError(''); return state; }
  catch (e) { showError(String(e.message || e)); return null; }
}

// ---------- timeline ----------
const timeline = $('timeline');
const LABEL = 200, PX = 8; // label column width and pixels per frame
function frameX(f) { return LABEL + f * PX; }
function drawPlayhead() {
  const head = timeline.querySelector('.playhead');
  if (head) head.style.left = `${frameX(studio.frame)}px`;
}
function drawTimeline() {
  const state = studio.state;
  timeline.innerHTML = '';
  const last = lastFrame() + 30;
  const width = frameX(last) + 20;
  const ruler = document.createElement('div');
  ruler.className = 'ruler';
  ruler.style.width = `${width}px`;
  for (let f = 0; f <= last; f += 10) { const s = document.createElement('span'); s.style.left = `${frameX(f)}px`; s.textContent = String(f); ruler.appendChild(s); }
  ruler.addEventListener('pointerdown', (e) => {
    const scrub = (ev) => { const rect = ruler.getBoundingClientRect(); setFrame(Math.round((ev.clientX - rect.left - LABEL) / PX)); };
    scrub(e);
    ruler.setPointerCapture(e.pointerId);
    ruler.onpointermove = scrub;
    ruler.onpointerup = () => { ruler.onpointermove = null; };
  });
  timeline.appendChild(ruler);
  // The temporal window: where animation exists.
  const win = document.createElement('div');
  win.className = 'window';
  win.style.left = `${frameX(0)}px`; win.style.width = `${state.last_frame * PX}px`;
  timeline.appendChild(win);
  const chainColours = ['#4a7bd0', '#3fa36b', '#b0609c', '#c7843a', '#5aa8b8', '#9a8a3f'];
  for (const action of state.actions) {
    const row = document.createElement('div');
    row.className = 'row';
    row.style.width = `${width}px`;
    row.dataset.stroke = String(action.stroke);
    const label = document.createElement('div');
    label.className = 'label';
    label.textContent = action.name;
    row.appendChild(label);
    const box = document.createElement('div');
    box.className = 'box' + (studio.selected === action.stroke ? ' selected' : '');
    box.style.left = `${frameX(action.start_frame)}px`;
    box.style.width = `${Math.max(4, (action.end_frame - action.start_frame) * PX)}px`;
    box.style.background = chainColours[action.chain % chainColours.length];
    box.title = `${action.name}: frames ${action.start_frame.toFixed(1)}–${action.end_frame.toFixed(1)}${action.previous !== null ? ' (continues the stroke before it)' : ''}${action.symmetric ? ' (with its mirror)' : ''}`;
    if (action.previous !== null || action.symmetric) {
      const link = document.createElement('span');
      link.className = 'link';
      link.textContent = action.symmetric ? '⇋' : '⛓';
      box.appendChild(link);
    }
    for (const side of ['left', 'right']) { const g = document.createElement('div'); g.className = `grip ${side}`; g.dataset.grip = side; box.appendChild(g); }
    box.addEventListener('pointerdown', (e) => timelineDrag(e, action, box));
    row.appendChild(box);
    timeline.appendChild(row);
  }
  const head = document.createElement('div');
  head.className = 'playhead';
  timeline.appendChild(head);
  drawPlayhead();
}
function timelineDrag(event, action, box) {
  event.stopPropagation();
  studio.selected = action.stroke;
  $('delete').disabled = false;
  const grip = /** @type {HTMLElement} */ (event.target).dataset.grip;
  const x0 = event.clientX;
  const start = action.start_frame, duration = action.end_frame - action.start_frame;
  box.setPointerCapture(event.pointerId);
  let edit = null;
  box.onpointermove = (e) => {
    const df = (e.clientX - x0) / PX;
    if (grip === 'left') { const s = Math.min(start + duration - 1, Math.max(0, start + df)); edit = { start_frame: s, duration: start + duration - s }; }
    else if (grip === 'right') edit = { start_frame: start, duration: Math.max(1, duration + df) };
    else edit = { start_frame: Math.max(0, start + df) };
    box.style.left = `${frameX(edit.start_frame)}px`;
    box.style.width = `${(edit.duration ?? duration) * PX}px`;
  };
  box.onpointerup = async () => {
    box.onpointermove = null; box.onpointerup = null;
    if (edit) await run('PATCH', `api/strokes/${action.stroke}`, edit);
    else { drawOverlays(); drawTimeline(); }
  };
}

// ---------- settings ----------
const numberFields = ['stroke_thickness', 'candidate_radius', 'pen_distance', 'edit_radius', 'hook_radius'];
function fillSettings(state) {
  const s = state.settings;
  /** @type {HTMLInputElement} */ ($('symmetry')).checked = !!s.symmetry;
  /** @type {HTMLSelectElement} */ ($('falloff')).value = s.falloff;
  /** @type {HTMLSelectElement} */ ($('mode')).value = s.mode;
  /** @type {HTMLSelectElement} */ ($('selection')).value = s.selection;
  /** @type {HTMLInputElement} */ ($('subsample')).value = s.subsample;
  for (const f of numberFields) {
    const input = /** @type {HTMLInputElement} */ ($(f));
    if (document.activeElement !== input) { input.value = s[f] ?? ''; input.placeholder = state.resolved[f].toPrecision(3); }
  }
  $('resolved').textContent = `In use: candidate radius ${state.resolved.candidate_radius.toPrecision(3)}, pen ${state.resolved.pen_distance.toPrecision(3)}, editing ${state.resolved.edit_radius.toPrecision(3)}, hook ${state.resolved.hook_radius.toPrecision(3)}`;
}
function settingsFromPanel() {
  const s = { ...studio.state.settings };
  s.symmetry = /** @type {HTMLInputElement} */ ($('symmetry')).checked;
  s.falloff = /** @type {HTMLSelectElement} */ ($('falloff')).value;
  s.mode = /** @type {HTMLSelectElement} */ ($('mode')).value;
  s.selection = /** @type {HTMLSelectElement} */ ($('selection')).value;
  s.subsample = Math.max(1, Math.round(Number(/** @type {HTMLInputElement} */ ($('subsample')).value) || 1));
  for (const f of numberFields) { const v = /** @type {HTMLInputElement} */ ($(f)).value; s[f] = v === '' ? null : Number(v); }
  return s;
}
for (const id of ['symmetry', 'falloff', 'mode', 'selection', 'subsample', ...numberFields]) {
  $(id).addEventListener('change', () => run('PUT', 'api/settings', settingsFromPanel()));
}
$('fps').addEventListener('change', () => run('PUT', 'api/fps', { fps: Number(/** @type {HTMLInputElement} */ ($('fps')).value) }));

// ---------- commands ----------
const commands = {
  undo: () => run('POST', 'api/undo'),
  redo: () => run('POST', 'api/redo'),
  delete: () => { if (studio.selected !== null) { const s = studio.selected; studio.selected = null; return run('DELETE', `api/strokes/${s}`); } },
  save: async () => { try { const r = await api('POST', 'api/project/save'); showError(''); $('status').textContent = `Saved ${r.saved}`; } catch (e) { showError(String(e.message || e)); } },
  reopen: () => run('POST', 'api/project/reopen'),
  new: () => run('POST', 'api/project/new'),
  play: () => { studio.direction = 1; studio.playing = !studio.playing; $('play').textContent = studio.playing ? 'Pause' : 'Play'; studio.lastFrameTime = performance.now(); },
  playBackwards: () => { studio.direction = -1; studio.playing = true; $('play').textContent = 'Pause'; studio.lastFrameTime = performance.now(); },
  pause: () => { studio.playing = false; $('play').textContent = 'Play'; },
  step: (by) => { commands.pause(); setFrame(Math.round(studio.frame) + by); },
};
$('undo').onclick = commands.undo; $('redo').onclick = commands.redo; $('delete').onclick = commands.delete;
$('save').onclick = commands.save; $('reopen').onclick = commands.reopen; $('new').onclick = commands.new;
$('play').onclick = commands.play;
$('open').onclick = () => $('project-file').click();
$('project-file').addEventListener('change', async (e) => {
  const file = /** @type {HTMLInputElement} */ (e.target).files?.[0];
  if (!file) return;
  try { applyState(await api('PUT', 'api/project', await file.arrayBuffer()), true); showError(''); }
  catch (err) { showError(`${file.name}: ${err.message || err}`); }
});
async function uploadCharacter(file) {
  showError('');
  $('status').textContent = `Opening ${file.name}…`;
  try {
    const result = await api('POST', 'api/character/upload', await file.arrayBuffer(), { 'x-filename': file.name.replace(/[^\x20-\x7e]/g, '_') });
    studio.character = await api('GET', 'api/character');
    $('character-name').textContent = studio.character.name;
    frameCamera();
    applyState(result.state, true);
    if (result.warnings.length) showError(result.warnings.join('\n'));
  } catch (err) { showError(String(err.message || err)); $('status').textContent = `Could not open ${file.name}; still on ${studio.character.name}.`; }
}
$('open-character').onclick = () => $('character-file').click();
$('character-file').addEventListener('change', (e) => { const f = /** @type {HTMLInputElement} */ (e.target).files?.[0]; if (f) uploadCharacter(f); });
viewport.addEventListener('dragover', (e) => { e.preventDefault(); viewport.classList.add('dragover'); });
viewport.addEventListener('dragleave', () => viewport.classList.remove('dragover'));
viewport.addEventListener('drop', (e) => { e.preventDefault(); viewport.classList.remove('dragover'); const f = e.dataTransfer?.files?.[0]; if (f) uploadCharacter(f); });
$('help-button').onclick = () => { $('help').hidden = !$('help').hidden; };
$('help-close').onclick = () => { $('help').hidden = true; };
window.addEventListener('keydown', (e) => {
  if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
  const ctrl = e.ctrlKey || e.metaKey;
  if (ctrl && e.key.toLowerCase() === 'z') { e.preventDefault(); (e.shiftKey ? commands.redo : commands.undo)(); }
  else if (ctrl && e.key.toLowerCase() === 'y') { e.preventDefault(); commands.redo(); }
  else if (ctrl && e.key.toLowerCase() === 's') { e.preventDefault(); commands.save(); }
  else if (e.key === 'Delete' || e.key === 'Backspace') commands.delete();
  else if (e.key === ' ') { e.preventDefault(); commands.play(); }
  else if (e.key === 'ArrowRight') commands.step(1);
  else if (e.key === 'ArrowLeft') commands.step(-1);
  else if (e.key === 'j') commands.playBackwards();
  else if (e.key === 'k') commands.pause();
  else if (e.key === 'l') { commands.pause(); commands.play(); }
  else if (e.key === 'Home') setFrame(0);
  else if (e.key === 'End') setFrame(lastFrame());
  else if (e.key === '?') $('help').hidden = !$('help').hidden;
  else if (e.key === 'Escape') $('help').hidden = true;
});

// ---------- loop ----------
// Draw only when something changed: an idle studio leaves the CPU to capture and training
// (and a laptop's battery alone). Pointer input and playback always redraw.
let dirty = true;
studio.invalidate = () => { dirty = true; };
controls.addEventListener('change', studio.invalidate);
for (const type of ['pointerdown', 'pointermove', 'pointerup', 'wheel', 'keydown']) viewport.addEventListener(type, studio.invalidate, { passive: true });
window.addEventListener('keydown', studio.invalidate);
renderer.setAnimationLoop((now) => {
  if (studio.playing && studio.state) {
    const fps = studio.state.fps;
    const last = Math.max(1, lastFrame());
    const loop = /** @type {HTMLInputElement} */ ($('loop')).checked;
    let f = studio.frame + studio.direction * (now - studio.lastFrameTime) / 1000 * fps;
    if (f > last) { if (loop) f = f % last; else { f = last; commands.pause(); } }
    if (f < 0) { if (loop) f = last + (f % last); else { f = 0; commands.pause(); } }
    setFrame(f);
  }
  studio.lastFrameTime = now;
  if (!dirty && !studio.playing) return;
  dirty = false;
  if (FAST) for (const mesh of studio.meshes) blendNow(mesh);
  renderer.render(scene, camera);
  for (const f of studio.onRender) f();
  studio.drawCalls = renderer.info.render.calls;
  studio.frameCount++;
});

// What capture.js (capture mode) uses of the sketch page.
Object.assign(studio, { api, showError, setFrame, applyLayer, lastFrame, run, commands, drawTimeline });

// ---------- start ----------
(async () => {
  try {
    studio.character = await api('GET', 'api/character');
    $('character-name').textContent = studio.character.name;
    resize();
    frameCamera();
    applyState(await api('GET', 'api/state'), true);
  } catch (e) { showError(String(e.message || e)); }
})();
