// Plays a VRM Animation (.vrma) on a VRM avatar with pixiv's three-vrm and
// three-vrm-animation (npm, the reference implementation VRM apps on the web use), in headless
// Chromium, and prints what the avatar does at each key of the animation as JSON:
//   { times, expressions: {name: [weight…]}, morphs: {mesh: {target: [influence…]}} (the
//     targets that moved),
//     head: [[x, y, z, w]…] (the head bone's turn from its rest, in the scene),
//     lookAt: [[yaw, pitch]…] (degrees; null for an avatar without lookAt), humanBones: [names], warnings: [console warnings] }
// Usage: node tools/vrma-play.mjs AVATAR.vrm ANIMATION.vrma
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { IMPORT_MAP, withThreePage } from './three-page.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const [avatarPath, animationPath] = process.argv.slice(2);
if (!avatarPath || !animationPath) {
  console.error('usage: node vrma-play.mjs AVATAR.vrm ANIMATION.vrma');
  process.exit(2);
}

const script = `
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { VRMLoaderPlugin } from '/three-vrm.js';
import { VRMAnimationLoaderPlugin, VRMLookAtQuaternionProxy, createVRMAnimationClip } from '/three-vrm-animation.js';
window.warnings = [];
const warn = console.warn;
console.warn = (...a) => { window.warnings.push(a.join(' ')); warn(...a); };
try {
  const loader = new GLTFLoader();
  loader.register((parser) => new VRMLoaderPlugin(parser));
  loader.register((parser) => new VRMAnimationLoaderPlugin(parser));
  const vrm = (await loader.loadAsync('/model.glb')).userData.vrm;
  const vrmAnimation = (await loader.loadAsync('/animation.vrma')).userData.vrmAnimations[0];
  const proxy = new VRMLookAtQuaternionProxy(vrm.lookAt);
  proxy.name = 'VRMLookAtQuaternionProxy';
  vrm.scene.add(proxy);
  const clip = createVRMAnimationClip(vrmAnimation, vrm);
  const mixer = new THREE.AnimationMixer(vrm.scene);
  // Played once and held at its end, so that the last key is sampled, not the loop's start.
  const action = mixer.clipAction(clip);
  action.setLoop(THREE.LoopOnce, 1);
  action.clampWhenFinished = true;
  action.play();
  const head = vrm.humanoid.getRawBoneNode('head');
  vrm.scene.updateMatrixWorld(true);
  const rest = head.getWorldQuaternion(new THREE.Quaternion()).invert();
  const times = Array.from(clip.tracks[0].times);
  const names = [...vrmAnimation.expressionTracks.preset.keys(), ...vrmAnimation.expressionTracks.custom.keys()];
  const meshes = [];
  vrm.scene.traverse((o) => { if (o.isMesh && o.morphTargetDictionary) meshes.push(o); });
  const out = { times, expressions: {}, morphs: {}, head: [], lookAt: [],
    humanBones: [...vrmAnimation.humanoidTracks.rotation.keys()] };
  for (const n of names) out.expressions[n] = [];
  for (const t of times) {
    mixer.setTime(t);
    vrm.update(0);
    vrm.scene.updateMatrixWorld(true);
    for (const n of names) out.expressions[n].push(vrm.expressionManager.getValue(n));
    for (const m of meshes) {
      const into = (out.morphs[m.name] ??= {});
      for (const [target, i] of Object.entries(m.morphTargetDictionary)) (into[target] ??= []).push(m.morphTargetInfluences[i]);
    }
    out.head.push(head.getWorldQuaternion(new THREE.Quaternion()).multiply(rest).toArray());
    out.lookAt.push(vrm.lookAt ? [vrm.lookAt.yaw, vrm.lookAt.pitch] : null);
  }
  window.result = out;
} catch (e) {
  window.result = { error: String(e && e.stack || e) };
}
`;
const html = `<!doctype html><html><head>${IMPORT_MAP}</head><body><script type="module">${script}</script></body></html>`;
const js = (file) => readFile(path.join(here, 'node_modules/@pixiv', file)).then((body) => ({ body, contentType: 'text/javascript' }));
const result = await withThreePage({
  html,
  model: await readFile(avatarPath),
  width: 64,
  height: 64,
  files: {
    '/animation.vrma': { body: await readFile(animationPath), contentType: 'model/gltf-binary' },
    '/three-vrm.js': await js('three-vrm/lib/three-vrm.module.js'),
    '/three-vrm-animation.js': await js('three-vrm-animation/lib/three-vrm-animation.module.js'),
  },
}, async (page, errors) => {
  await page.waitForFunction(() => window.result !== undefined, null, { timeout: 60000 });
  const out = await page.evaluate(() => ({ ...window.result, warnings: window.warnings }));
  if (errors.length) out.pageErrors = errors;
  return out;
});
// Only the targets that moved.
for (const targets of Object.values(result.morphs ?? {})) {
  for (const [name, values] of Object.entries(targets)) if (values.every((v) => v === 0)) delete targets[name];
}
console.log(JSON.stringify(result));
// Not process.exit: it would cut a long report short on a pipe.
process.exitCode = result.error || result.pageErrors ? 1 : 0;
