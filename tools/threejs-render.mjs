// Opens a .glb/.vrm in three.js (the copy the studio ships, web/vendor/three) in headless
// Chromium, as a game or web developer's viewer would: plays its first animation to TIME
// seconds, frames the whole scene, saves a screenshot and prints a JSON report of what loaded.
// Usage: node tools/threejs-render.mjs FILE OUT.png TIME
// Report: {meshes, skinnedMeshes, bones, morphMeshes, maxInfluence, texturedMaterials,
//          animations, channels, pixels: {nonBackground}}; exit 1 on a load error.
import { readFile } from 'node:fs/promises';
import { IMPORT_MAP, withThreePage } from './three-page.mjs';

const [file, out, time] = process.argv.slice(2);
if (!file || !out) {
  console.error('usage: node threejs-render.mjs FILE OUT.png [TIME]');
  process.exit(2);
}
const model = await readFile(file);

const page_html = `<!doctype html><html><head><style>body{margin:0;background:#202428}</style>
${IMPORT_MAP}
</head><body><script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { MeshoptDecoder } from '/meshopt_decoder.mjs';
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setSize(480, 640);
renderer.setClearColor(0x202428);
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 2.5));
const sun = new THREE.DirectionalLight(0xffffff, 2); sun.position.set(1, 2, 3); scene.add(sun);
try {
  const gltf = await new GLTFLoader().setMeshoptDecoder(MeshoptDecoder).loadAsync('/model.glb');
  scene.add(gltf.scene);
  let channels = 0;
  if (gltf.animations.length) {
    const mixer = new THREE.AnimationMixer(gltf.scene);
    mixer.clipAction(gltf.animations[0]).play();
    mixer.setTime(${Number(time) || 0});
    channels = gltf.animations[0].tracks.length;
  }
  gltf.scene.updateMatrixWorld(true);
  const box = new THREE.Box3().setFromObject(gltf.scene);
  const size = box.getSize(new THREE.Vector3()), centre = box.getCenter(new THREE.Vector3());
  const camera = new THREE.PerspectiveCamera(30, 480 / 640, size.length() / 100, size.length() * 10);
  const distance = 0.55 * Math.max(size.y, size.x * 640 / 480) / Math.tan(THREE.MathUtils.degToRad(15));
  camera.position.set(centre.x, centre.y, box.max.z + distance);
  camera.lookAt(centre);
  renderer.render(scene, camera);
  const report = { meshes: 0, skinnedMeshes: 0, bones: 0, morphMeshes: 0, maxInfluence: 0, texturedMaterials: 0, animations: gltf.animations.length, channels };
  const materials = new Set();
  gltf.scene.traverse((o) => {
    if (o.isBone) report.bones++;
    if (!o.isMesh) return;
    report.meshes++;
    if (o.isSkinnedMesh) report.skinnedMeshes++;
    if (o.morphTargetInfluences) { report.morphMeshes++; report.maxInfluence = Math.max(report.maxInfluence, ...o.morphTargetInfluences); }
    for (const m of [].concat(o.material)) if (m.map && m.map.image) materials.add(m);
  });
  report.texturedMaterials = materials.size;
  const gl = renderer.getContext();
  const pixels = new Uint8Array(480 * 640 * 4);
  gl.readPixels(0, 0, 480, 640, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
  let nonBackground = 0;
  for (let i = 0; i < pixels.length; i += 4) if (Math.abs(pixels[i] - 0x20) + Math.abs(pixels[i + 1] - 0x24) + Math.abs(pixels[i + 2] - 0x28) > 24) nonBackground++;
  report.pixels = { nonBackground };
  window.report = report;
} catch (e) { window.report = { error: String(e && e.stack || e) }; }
</script></body></html>`;

let status = 0;
await withThreePage({ html: page_html, model, width: 480, height: 640 }, async (page, errors) => {
  await page.waitForFunction(() => window.report !== undefined, null, { timeout: 120000 });
  const report = await page.evaluate(() => window.report);
  await page.screenshot({ path: out });
  if (errors.length) report.pageErrors = errors;
  console.log(JSON.stringify(report));
  if (report.error) status = 1;
});
process.exit(status);
