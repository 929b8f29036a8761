// Re-packs a glTF binary with its textures as KTX2 (`KHR_texture_basisu`, required), encoded
// by Binomial's Basis Universal encoder (WebAssembly, npm `ktx2-encoder`) through glTF
// Transform, as asset pipelines ship them: a test fixture from a producer that is not us.
//
// etc1s: ETC1S with BasisLZ (gltfpack's and toktx's default); uastc: UASTC with Zstandard
// supercompression (glTF Transform's `uastc` default).
//
// Usage: node tools/ktx2.mjs IN.glb OUT.glb etc1s|uastc
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import { ktx2 } from 'ktx2-encoder/gltf-transform';
import sharp from 'sharp';

const [input, output, mode] = process.argv.slice(2);
if (!input || !output || !['etc1s', 'uastc'].includes(mode)) {
  console.error('usage: node tools/ktx2.mjs IN.glb OUT.glb etc1s|uastc');
  process.exit(2);
}
const imageDecoder = async (buffer) => {
  const { data, info } = await sharp(buffer).ensureAlpha().raw().toBuffer({ resolveWithObject: true });
  return { data: new Uint8Array(data), width: info.width, height: info.height };
};
const io = new NodeIO().registerExtensions(ALL_EXTENSIONS);
const document = await io.read(input);
const uastc = mode === 'uastc';
await document.transform(
  ktx2({ isUASTC: uastc, needSupercompression: uastc, generateMipmap: true, enableDebug: false, imageDecoder }),
);
const textures = document.getRoot().listTextures();
if (!textures.length || textures.some((t) => t.getMimeType() !== 'image/ktx2')) {
  console.error(`${input}: not every texture became KTX2`);
  process.exit(1);
}
await io.write(output, document);
