// Marking a face by hand in a real browser (Debian's chromium, driven by playwright-core): the
// studio holds a head the face model cannot read, so making its map says so and the Capture
// tab asks for the ten marks; each is clicked on the character where the page shows it (the
// page's own projection of the point), the prompt names the next, the last sends them, and the
// map is made from them. Two photos picked then are read through that map, against a neutral
// face the page lets the user choose.
// Usage: node face-marks-e2e.mjs URL OUTPUT_DIR POINTS_JSON PHOTOS_JSON
// POINTS_JSON: {"right_eye_outer": [x, y, z], …} in the character's space; PHOTOS_JSON: paths.
// Prints one JSON line of measurements; exits non-zero with a message on the first failure.
import { checker, launch } from './browser.mjs';
import fs from 'node:fs';
import path from 'node:path';

const [url, out, pointsJson, photosJson] = process.argv.slice(2);
const points = JSON.parse(pointsJson), photos = JSON.parse(photosJson);
fs.mkdirSync(out, { recursive: true });
const check = checker('face-marks-e2e');

const browser = await launch();
try {
  const page = await browser.newPage({ viewport: { width: 1200, height: 800 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`${url}?fast#capture`);
  await page.waitForFunction(() => window.studio && window.studio.character && window.studio.meshes.length > 0 && window.studio.bakedReady, null, { timeout: 60000 });
  await page.click('#retarget-section > summary');
  // The map cannot be made: the page says why and offers the marks.
  await page.click('#retarget-make');
  await page.waitForFunction(() => document.getElementById('face-marks-prompt').textContent.includes('found no face'), null, { timeout: 60000, polling: 250 });
  check(await page.isVisible('#face-marks-start'), 'no button to mark the face');
  await page.screenshot({ path: path.join(out, '01-no-face.png') });

  await page.click('#face-marks-start');
  const asked = await page.evaluate(() => fetch('api/capture/state').then((r) => r.json()).then((s) => s.retarget.marks.map((m) => m.point)));
  check(asked.length === 10, `the server asks for ${asked.length} marks`);
  for (const [k, name] of asked.entries()) {
    const prompt = await page.textContent('#face-marks-prompt');
    check(prompt.startsWith(`Mark ${k + 1} of 10`), `mark ${k + 1}: the prompt says ${prompt}`);
    const [x, y] = await page.evaluate((p) => window.studio.project(p), points[name]);
    await page.mouse.click(x, y);
    if (k === 4) {
      // A slip: undone, and placed again.
      await page.mouse.click(x + 40, y + 40);
      await page.click('#face-marks-undo');
    }
  }
  // The map is made from the marks, or the job says why not.
  const captureState = () => page.evaluate(() => fetch('api/capture/state').then((r) => r.json()));
  for (const start = Date.now(); ; await new Promise((r) => setTimeout(r, 250))) {
    const s = await captureState();
    if (s.retarget.face_points && (s.retarget.loaded || (s.job && !s.job.running))) break;
    check(Date.now() - start < 120000, `the map from the marks was not made in 2 minutes: ${JSON.stringify(s.job)}`);
  }
  await page.waitForFunction(() => document.getElementById('face-marks-prompt').textContent.includes('points you marked'), null, { timeout: 30000, polling: 250 });
  const state = await captureState();
  check(state.retarget.loaded, `no map was made from the marks: ${JSON.stringify(state.job)}`);
  const geometry = state.retarget.rows.filter((r) => r.from === 'geometry' && r.shapes.length).length;
  await page.screenshot({ path: path.join(out, '02-marked.png') });

  // Photos read through the map: it reads each face against the take's neutral one, so the
  // page offers to choose that frame and says what reads against it.
  await page.setInputFiles('#capture-file', photos);
  for (const start = Date.now(); ; await new Promise((r) => setTimeout(r, 250))) {
    const s = await captureState();
    if (s.take && s.take.frames === photos.length && !(s.job && s.job.running)) break;
    check(Date.now() - start < 60000, `the photos were not read in a minute: ${JSON.stringify(s.job)}`);
  }
  const take = (await captureState()).take;
  check(take.estimator === 'retarget' && take.reads_neutral && take.neutral, `the photos' take: ${take.estimator} ${take.reads_neutral} ${JSON.stringify(take.neutral)}`);
  await page.waitForFunction(() => document.getElementById('neutral-info').textContent.includes('the retarget map reads every frame relative to it'), null, { timeout: 30000, polling: 250 });
  check(!(await page.isDisabled('#neutral-frame')) && !(await page.isDisabled('#neutral-auto')), 'the neutral frame cannot be chosen for a take read through the map');
  await page.screenshot({ path: path.join(out, '03-photos-through-the-map.png') });
  check(!errors.length, `page errors: ${errors.join('; ')}`);
  console.log(JSON.stringify({ marked: state.retarget.face_points, geometry_rows: geometry }));
} finally {
  await browser.close();
}
