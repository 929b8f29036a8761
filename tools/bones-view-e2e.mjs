// The face's bones in the studio's view, in a real browser (Debian's chromium, driven by
// playwright-core): on a full-body avatar whose take turns the head, looks aside and opens the
// jaw, the view is skinned to the face's bones (spine, neck, head, eyes, jaw), each joint turns
// as the server's rotations for the frame say (the export's turns: crates/export/tests/
// view_bones.rs ties them to the file), the head's vertices move and the hips' do not; with
// "Turn the head as captured" unchecked the head rests. Once on the GPU path, once with ?fast.
// The sketch's own jawOpen stroke turns the jaw joint in the Sketch tab, where no take is shown.
// Usage: node bones-view-e2e.mjs URL OUTPUT_DIR FRAME SKETCH_FRAME
// Prints one JSON line of measurements; exits non-zero with a message on the first failure.
import { checker, launch } from './browser.mjs';
import fs from 'node:fs';
import path from 'node:path';

const [url, out, frameArg, sketchFrameArg] = process.argv.slice(2);
const frame = Number(frameArg);
const sketchFrame = Number(sketchFrameArg);
fs.mkdirSync(out, { recursive: true });
const check = checker('bones-view-e2e');

const browser = await launch();
const measured = {};
try {
  for (const mode of ['gpu', 'fast']) {
    const page = await browser.newPage({ viewport: { width: 900, height: 700 } });
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
    await page.goto(`${url}${mode === 'fast' ? '?fast' : ''}#capture`);
    await page.waitForFunction(() => window.studio && window.studio.bakedReady && window.studio.capture.view && window.studio.capture.view.take, null, { timeout: 60000 });
    await page.$eval('#current-frame', (e, f) => { e.value = String(f); e.dispatchEvent(new Event('change')); }, frame);
    const seen = await page.evaluate(async (f) => {
      const s = window.studio;
      const take = s.capture.view.take;
      const skinned = s.meshes.filter((m) => m.isSkinnedMesh);
      const mesh = skinned[0];
      if (!mesh) return { skinned: 0 };
      mesh.updateMatrixWorld(true);
      mesh.skeleton.update();
      const bones = mesh.skeleton.bones;
      const asked = take.bones[Math.min(f, take.bones.length - 1)];
      const off = Math.max(...bones.map((b, k) => Math.max(...b.quaternion.toArray().map((v, i) => Math.abs(v - asked[k][i])))));
      // Each vertex where the view puts it, against where it rests.
      const position = mesh.geometry.attributes.position;
      const moved = (v) => {
        const rest = new mesh.position.constructor().fromBufferAttribute(position, v);
        const now = rest.clone();
        mesh.applyBoneTransform(v, now);
        return now.distanceTo(rest);
      };
      // The highest vertex wholly on the head joint, and the lowest vertex (the feet).
      const head = bones.findIndex((b) => b.name === 'faceanim_head');
      const joints = mesh.geometry.attributes.skinIndex, weights = mesh.geometry.attributes.skinWeight;
      let top = -1, bottom = 0;
      for (let v = 0; v < position.count; v++) {
        const onHead = joints.getX(v) === head && weights.getX(v) > 0.999;
        if (onHead && (top < 0 || position.getY(v) > position.getY(top))) top = v;
        if (position.getY(v) < position.getY(bottom)) bottom = v;
      }
      if (top < 0) return { skinned: skinned.length, meshes: s.meshes.length, names: bones.map((b) => b.name), off, top: 0, bottom: 0, rootTurned: 0, noHeadVertex: true };
      return { skinned: skinned.length, meshes: s.meshes.length, names: bones.map((b) => b.name), off, top: moved(top), bottom: moved(bottom), rootTurned: Math.abs(s.root.quaternion.w - 1) };
    }, frame);
    check(seen.skinned > 0 && seen.skinned === seen.meshes, `${mode}: the view is not skinned to the face's bones (${seen.skinned} of ${seen.meshes} meshes)`);
    for (const name of ['faceanim_rest', 'faceanim_head', 'faceanim_neck', 'faceanim_upper_spine', 'faceanim_left_eye', 'faceanim_right_eye', 'faceanim_jaw']) {
      check(seen.names.includes(name), `${mode}: no joint ${name} in ${seen.names}`);
    }
    check(seen.off < 1e-5, `${mode}: the joints are ${seen.off} from the server's rotations`);
    check(seen.top > 0.01, `${mode}: the top of the head did not move (${seen.top})`);
    check(seen.bottom < 1e-6, `${mode}: the feet moved (${seen.bottom})`);
    check(seen.rootTurned < 1e-6, `${mode}: the whole character turned as well`);
    await page.screenshot({ path: path.join(out, `${mode}-turned.png`) });
    // Unchecked, the head rests (the eyes and jaw still follow).
    await page.click('#head-turn');
    const rested = await page.evaluate(() => {
      const bones = window.studio.meshes[0].skeleton.bones;
      const turn = (name) => 1 - Math.abs(bones.find((b) => b.name === name).quaternion.w);
      return { head: turn('faceanim_head'), neck: turn('faceanim_neck') };
    });
    check(rested.head < 1e-6 && rested.neck < 1e-6, `${mode}: unchecked, the head still turns ${JSON.stringify(rested)}`);
    await page.screenshot({ path: path.join(out, `${mode}-rest.png`) });
    // The Sketch tab shows no take: the sketch's jawOpen stroke opens the jaw joint, the head rests.
    await page.click('#tab-sketch');
    await page.$eval('#current-frame', (e, f) => { e.value = String(f); e.dispatchEvent(new Event('change')); }, sketchFrame);
    const sketched = await page.evaluate(() => {
      const bones = window.studio.meshes[0].skeleton.bones;
      const turn = (name) => 2 * Math.acos(Math.min(1, Math.abs(bones.find((b) => b.name === name).quaternion.w))) * 180 / Math.PI;
      return { jaw: turn('faceanim_jaw'), head: turn('faceanim_head') };
    });
    check(sketched.jaw > 1 && sketched.head < 1e-3, `${mode}: in the Sketch tab the joints turn ${JSON.stringify(sketched)}`);
    // Strokes pick the skinned face: the tip of the nose (the foremost vertex on the head joint)
    // is hit where the page draws it.
    const nose = await page.evaluate(() => {
      const mesh = window.studio.meshes[0];
      const head = mesh.skeleton.bones.findIndex((b) => b.name === 'faceanim_head');
      const position = mesh.geometry.attributes.position;
      const joints = mesh.geometry.attributes.skinIndex, weights = mesh.geometry.attributes.skinWeight;
      let front = -1;
      for (let v = 0; v < position.count; v++) {
        if (joints.getX(v) === head && weights.getX(v) > 0.999 && (front < 0 || position.getZ(v) > position.getZ(front))) front = v;
      }
      const p = [position.getX(front), position.getY(front), position.getZ(front)];
      const [x, y] = window.studio.project(p);
      const hit = window.studio.hit(x, y);
      return { p, hit };
    });
    check(nose.hit && Math.hypot(...nose.hit.map((v, i) => v - nose.p[i])) < 0.01, `${mode}: the nose at ${nose.p} is hit at ${nose.hit}`);
    await page.screenshot({ path: path.join(out, `${mode}-sketch.png`) });
    check(errors.length === 0, `${mode}: the page failed: ${errors.join('; ')}`);
    measured[mode] = { top_moved: seen.top, joints_off: seen.off, sketch_jaw_degrees: sketched.jaw };
    await page.close();
  }
} finally {
  await browser.close();
}
console.log(JSON.stringify(measured));
