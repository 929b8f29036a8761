// Held-out stills of a character by a renderer faceanim's adapter never trained on: three.js
// (the copy the studio ships, web/vendor/three) in headless Chromium, with its own camera,
// lens, lights and physically based materials. The adapter is then measured on them
// (`faceanim adapt --eval-dir OUT`).
//
// Usage: node tools/heldout-stills.mjs MODEL.glb POSES.json OUTDIR
// POSES.json: {"frames": [{"image": "0000.png", "weights": {"name": 0.5, ...}}, ...],
//              "neutral": "neutral.png" (optional), "view": {...} (optional, below)}
// view: {"yaw": deg, "pitch": deg, "fov": deg, "width": px, "height": px, "fill": fraction of
//        the height the head takes, "background": "#rrggbb", "key": [x, y, z],
//        "keyColour": "#rrggbb", "keyIntensity": n, "ambient": n}
// Writes OUTDIR/<image> for every frame (and the neutral), and OUTDIR/truth.json (the poses).
import { mkdir, readFile, writeFile } from 'node:fs/promises';
import path from 'node:path';
import { IMPORT_MAP, withThreePage } from './three-page.mjs';

const [modelPath, posesPath, outDir] = process.argv.slice(2);
if (!modelPath || !posesPath || !outDir) {
  console.error('usage: node heldout-stills.mjs MODEL.glb POSES.json OUTDIR');
  process.exit(2);
}
const model = await readFile(modelPath);
const poses = JSON.parse(await readFile(posesPath, 'utf8'));
const view = {
  yaw: 12, pitch: -6, fov: 45, width: 640, height: 480, fill: 0.62,
  background: '#8a9bb0', key: [2, 2.5, 3], keyColour: '#fff1dc', keyIntensity: 2.2, ambient: 0.9,
  ...(poses.view || {}),
};

const pageHtml = `<!doctype html><html><head><style>body{margin:0}</style>
${IMPORT_MAP}
</head><body><script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
const view = ${JSON.stringify(view)};
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setSize(view.width, view.height);
renderer.setClearColor(new THREE.Color(view.background));
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.add(new THREE.HemisphereLight(0xffffff, 0x303030, view.ambient));
const key = new THREE.DirectionalLight(new THREE.Color(view.keyColour), view.keyIntensity);
key.position.set(...view.key);
scene.add(key);
const rim = new THREE.DirectionalLight(0xbfd4ff, 0.6);
rim.position.set(-3, 1, -2);
scene.add(rim);
try {
  const gltf = await new GLTFLoader().loadAsync('/model.glb');
  scene.add(gltf.scene);
  gltf.scene.updateMatrixWorld(true);
  const meshes = [];
  gltf.scene.traverse((o) => { if (o.isMesh && o.morphTargetDictionary) meshes.push(o); });
  const box = new THREE.Box3().setFromObject(gltf.scene);
  const size = box.getSize(new THREE.Vector3()), centre = box.getCenter(new THREE.Vector3());
  const camera = new THREE.PerspectiveCamera(view.fov, view.width / view.height, size.length() / 100, size.length() * 10);
  const distance = (0.5 * size.y / view.fill) / Math.tan(THREE.MathUtils.degToRad(view.fov / 2)) + size.z / 2;
  const yaw = THREE.MathUtils.degToRad(view.yaw), pitch = THREE.MathUtils.degToRad(view.pitch);
  const target = new THREE.Vector3(centre.x, centre.y + 0.05 * size.y, centre.z);
  camera.position.set(
    target.x + distance * Math.sin(yaw) * Math.cos(pitch),
    target.y + distance * Math.sin(pitch),
    target.z + distance * Math.cos(yaw) * Math.cos(pitch));
  camera.lookAt(target);
  window.pose = (weights) => {
    for (const mesh of meshes) {
      mesh.morphTargetInfluences.fill(0);
      for (const [name, w] of Object.entries(weights)) {
        const i = mesh.morphTargetDictionary[name];
        if (i !== undefined) mesh.morphTargetInfluences[i] = w;
      }
    }
    renderer.render(scene, camera);
    return renderer.domElement.toDataURL('image/png');
  };
  window.ready = { meshes: meshes.length };
} catch (e) { window.ready = { error: String(e && e.stack || e) }; }
</script></body></html>`;

let status = 0;
try {
  await withThreePage({ html: pageHtml, model, width: view.width, height: view.height }, async (page, errors) => {
    await page.waitForFunction(() => window.ready !== undefined, null, { timeout: 120000 });
    const ready = await page.evaluate(() => window.ready);
    if (ready.error || !ready.meshes) throw new Error(ready.error || 'the model has no morph targets');
    await mkdir(outDir, { recursive: true });
    const shots = poses.frames.map((f) => [f.image, f.weights]);
    if (poses.neutral) shots.push([poses.neutral, {}]);
    for (const [image, weights] of shots) {
      const url = await page.evaluate((w) => window.pose(w), weights);
      await writeFile(path.join(outDir, image), Buffer.from(url.split(',')[1], 'base64'));
    }
    await writeFile(path.join(outDir, 'truth.json'),
      JSON.stringify({ neutral: poses.neutral, frames: poses.frames }, null, 1));
    if (errors.length) throw new Error(errors.join('\n'));
    console.log(JSON.stringify({ stills: poses.frames.length, meshes: ready.meshes }));
  });
} catch (e) {
  console.error(String(e && e.stack || e));
  status = 1;
}
process.exit(status);
