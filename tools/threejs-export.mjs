// Re-writes a .glb/.vrm as three.js writes it: loaded by its GLTFLoader and written by its
// GLTFExporter (binary, with the file's animations), in headless Chromium — what web-based
// avatar editors and viewers save. A test fixture from a producer that is not us: one mesh and
// one skin per primitive, morph target names in each mesh's `extras.targetNames`, the
// animations' weight tracks per mesh node.
// Usage: node tools/threejs-export.mjs IN.glb OUT.glb
import { readFile, writeFile } from 'node:fs/promises';
import { IMPORT_MAP, withThreePage } from './three-page.mjs';

const [input, output] = process.argv.slice(2);
if (!input || !output) {
  console.error('usage: node tools/threejs-export.mjs IN.glb OUT.glb');
  process.exit(2);
}
const html = `<!doctype html><html><head>${IMPORT_MAP}</head><body><script type="module">
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { GLTFExporter } from '/GLTFExporter.js';
window.exported = (async () => {
  const gltf = await new GLTFLoader().loadAsync('/model.glb');
  const bytes = new Uint8Array(await new GLTFExporter().parseAsync(gltf.scene, { binary: true, animations: gltf.animations }));
  let text = '';
  for (let i = 0; i < bytes.length; i += 0x8000) text += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(text);
})();
</script></body></html>`;
const written = await withThreePage({ html, model: await readFile(input), width: 64, height: 64 }, async (page, errors) => {
  const base64 = await page.evaluate(() => window.exported);
  if (errors.length) throw new Error(`three.js: ${errors.join('; ')}`);
  return Buffer.from(base64, 'base64');
});
await writeFile(output, written);
