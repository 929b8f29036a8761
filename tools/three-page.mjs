// A page of ours in headless Chromium with three.js (the copy the studio ships,
// web/vendor/three) and one model, for the tools that render with three.js
// (threejs-render.mjs, heldout-stills.mjs) or write with it (threejs-export.mjs). Nothing is
// fetched from the network: the page, the model, three.js, its glTF exporter
// (/GLTFExporter.js) and meshoptimizer's decoder (/meshopt_decoder.mjs) are answered from here.
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { launch } from './browser.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const three = path.join(here, '../web/vendor/three');

/** The import map a page puts in its head to load three.js and its addons. */
export const IMPORT_MAP = '<script type="importmap">{ "imports": { "three": "/three/three.module.min.js", "three/addons/": "/three/addons/" } }</script>';

/**
 * Opens `html` (served as http://three.test/, with `model` at /model.glb and each of `files`,
 * `{ '/path': { body, contentType } }`, at its path) in a `width`×`height`
 * page, runs `work(page, errors)` and closes the browser; `errors` collects the page's uncaught
 * errors. Resolves to what `work` returns.
 */
export async function withThreePage({ html, model, width, height, files = {} }, work) {
  const browser = await launch();
  try {
    const page = await browser.newPage({ viewport: { width, height } });
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    await page.route('http://three.test/**', async (route) => {
      const url = new URL(route.request().url());
      if (url.pathname === '/') return route.fulfill({ body: html, contentType: 'text/html' });
      if (url.pathname === '/model.glb') return route.fulfill({ body: model, contentType: 'model/gltf-binary' });
      if (Object.hasOwn(files, url.pathname)) {
        const { body, contentType } = files[url.pathname];
        return route.fulfill({ body, contentType });
      }
      // meshoptimizer's own decoder (npm `meshoptimizer`), for files with EXT_meshopt_compression.
      if (url.pathname === '/meshopt_decoder.mjs') {
        return route.fulfill({ body: await readFile(path.join(here, 'node_modules/meshoptimizer/meshopt_decoder.mjs')), contentType: 'text/javascript' });
      }
      // three.js's own glTF exporter (npm `three`, the vendored copy's version), for the
      // files a web editor writes.
      if (url.pathname === '/GLTFExporter.js') {
        return route.fulfill({ body: await readFile(path.join(here, 'node_modules/three/examples/jsm/exporters/GLTFExporter.js')), contentType: 'text/javascript' });
      }
      if (url.pathname.startsWith('/three/')) {
        const local = path.join(three, url.pathname.slice('/three/'.length));
        if (!local.startsWith(three)) return route.fulfill({ status: 404 });
        try { return route.fulfill({ body: await readFile(local), contentType: 'text/javascript' }); } catch { return route.fulfill({ status: 404 }); }
      }
      return route.fulfill({ status: 404 });
    });
    await page.goto('http://three.test/');
    return await work(page, errors);
  } finally {
    await browser.close();
  }
}
