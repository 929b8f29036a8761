// The studio in a real browser (Debian's chromium, driven by playwright-core), as an animator
// uses it: draw a stroke with pointer events, drag the end arrow, undo/redo, symmetry, save,
// reload and reopen, a broken upload; screenshots of each step; the viewport's frame rate.
// Usage: node studio-e2e.mjs URL OUTPUT_DIR   (the studio must be running on ICT-FaceKit's head)
// Prints one JSON line of measurements; exits non-zero with a message on the first failure.
import { launch } from './browser.mjs';
import fs from 'node:fs';
import path from 'node:path';

const [url, out] = process.argv.slice(2);
fs.mkdirSync(out, { recursive: true });
const fail = (message) => { console.error(`studio-e2e: ${message}`); process.exit(1); };
const check = (condition, message) => { if (!condition) fail(message); };

const browser = await launch();
const measurements = {};
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 860 } });
  const consoleErrors = [];
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  const shot = (name) => page.screenshot({ path: path.join(out, `${name}.png`) });
  const state = () => page.evaluate(() => fetch('api/state').then((r) => r.json()));
  const clip = () => page.evaluate(() => fetch('api/export.json').then((r) => r.json()));
  const maxWeight = (c, name) => { const i = c.blendshapes.indexOf(name); return Math.max(...c.frames.map((f) => f[i])); };
  const ready = () => page.waitForFunction(() => window.studio && window.studio.bakedReady, null, { timeout: 60000 });

  await page.goto(url);
  await ready();
  await shot('01-opened');
  // The Sketch tab is the viewport and its settings, and nothing of capture mode.
  const layout = await page.evaluate(() => {
    const box = (id) => { const e = document.getElementById(id); const r = e.getBoundingClientRect(); return { visible: e.getClientRects().length > 0, width: r.width }; };
    return { viewport: box('viewport'), input: box('capture-input'), panel: box('capture-panel'), window: innerWidth };
  });
  check(!layout.input.visible && !layout.panel.visible, `capture mode's panels show in the Sketch tab: ${JSON.stringify(layout)}`);
  check(layout.viewport.width > layout.window * 0.6, `the viewport is squeezed in the Sketch tab: ${JSON.stringify(layout)}`);
  check(consoleErrors.length === 0, `page errors on open: ${consoleErrors.join('; ')}`);

  // 1. The current frame typed as 45, then a stroke from the left mouth corner towards the
  //    mouthSmile_L target: its action starts at frame 45, on whole frames.
  const anchors = await page.evaluate(() => fetch('api/character/anchors').then((r) => r.json()));
  // The character's own name for an ARKit shape (`mouthSmile_L` or `mouthSmileLeft`), so the
  // same session runs on any ARKit-named character; a one-sided name falls back to the shape
  // without sides (`browInnerUp`).
  const key = (n) => n.replace(/[_.]?L$/, 'Left').replace(/[_.]?R$/, 'Right').toLowerCase().replace(/[^a-z0-9]/g, '');
  const own = (arkit) => {
    const found = anchors.find((a) => key(a.name) === key(arkit)) || anchors.find((a) => key(a.name) === key(arkit).replace(/(left|right)$/, ''));
    check(found, `the character has no ${arkit}`);
    return found.name;
  };
  const SMILE_L = own('mouthSmileLeft'), SMILE_R = own('mouthSmileRight');
  await page.getByLabel('Current frame').fill('45');
  await page.getByLabel('Current frame').press('Enter');
  await page.waitForFunction(() => Math.round(window.studio.frame) === 45, null, { timeout: 10000 });
  /** Drags the mouse from where `name` moves most towards its target sphere, as a user aims. */
  const drawStroke = async (name) => {
    const anchor = anchors.find((a) => a.name === name);
    check(anchor && anchor.vertex !== null, `no ${name} anchor on this character`);
    const [ax, ay] = await page.evaluate((p) => window.studio.project(p), anchor.rest);
    const from = await page.evaluate(([x, y]) => window.studio.hit(x, y), [ax, ay]);
    check(from, `the ${name} vertex is not under the pointer`);
    const offered = await page.evaluate(([p, f]) => fetch('api/candidates', { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ point: p, frame: f }) }).then((r) => r.json()), [from, Math.round(await page.evaluate(() => window.studio.frame))]);
    const target = offered && offered.candidates.find((c) => c.name === name);
    check(target, `no ${name} target from its vertex: ${JSON.stringify(offered && offered.candidates.map((c) => c.name))}`);
    const [bx, by] = await page.evaluate((p) => window.studio.project(p), target.position);
    await page.mouse.move(ax, ay);
    await page.mouse.down();
    for (let i = 1; i <= 20; i++) {
      await page.mouse.move(ax + (bx - ax) * i / 20, ay + (by - ay) * i / 20);
      await page.waitForTimeout(25);
      if (i === 14) await shot(`aiming-${name}`);
    }
    return async () => page.mouse.up();
  };
  const release = await drawStroke(SMILE_L);
  // While drawing, the candidate under the cursor is named beside its sphere.
  const named = await page.evaluate(() => { const l = document.getElementById('candidate-label'); return l && !l.hidden ? l.textContent : ''; });
  check(named.startsWith(`${SMILE_L} `), `the candidate under the cursor is labelled '${named}'`);
  measurements.candidate_label = named;
  const released = Date.now();
  await release();
  await page.waitForSelector('#timeline .row', { timeout: 10000 });
  measurements.release_to_timeline_row_ms = Date.now() - released;
  measurements.release_to_action_drawn_ms = await page.evaluate(() => window.studio.lastStrokeMs);
  await ready();
  await page.waitForFunction(() => window.studio.state.actions.length === 1);
  await shot('02-stroke');
  let s = await state();
  check(s.actions.length === 1, `expected one action, got ${JSON.stringify(s.actions.map((a) => a.name))}`);
  check(s.actions[0].start_frame === 45 && Number.isInteger(s.actions[0].end_frame), `the stroke made frames ${s.actions[0].start_frame}–${s.actions[0].end_frame}, not from 45 on whole frames`);
  const drawnProject = await page.evaluate(() => fetch('api/project').then((r) => r.json()));
  check(drawnProject.strokes[0].symmetry === false, `the studio did not record the stroke's own mirror choice: ${JSON.stringify(drawnProject.strokes[0].symmetry)}`);
  const label = await page.textContent('#timeline .row .label');
  check(label.includes(SMILE_L), `timeline shows '${label}', not ${SMILE_L}`);
  let c = await clip();
  const smileWeight = maxWeight(c, SMILE_L);
  check(smileWeight > 0.5, `exported ${SMILE_L} reaches only ${smileWeight}`);
  measurements.smile_weight = smileWeight;
  const weightBefore = s.actions[0].sides[0].weight;

  // 2. Drag the end arrow halfway back: the weight changes, live.
  const end = s.actions[0].sides[0].end;
  const start = s.actions[0].sides[0].start;
  const [ex, ey] = await page.evaluate((p) => window.studio.project(p), end);
  const mid = end.map((v, i) => (v + start[i]) / 2);
  const [mx, my] = await page.evaluate((p) => window.studio.project(p), mid);
  await page.mouse.move(ex, ey);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) { await page.mouse.move(ex + (mx - ex) * i / 10, ey + (my - ey) * i / 10); await page.waitForTimeout(30); }
  await page.mouse.up();
  await page.waitForTimeout(300);
  await ready();
  s = await state();
  const weightDragged = s.actions[0].sides[0].weight;
  check(Math.abs(weightDragged - weightBefore) > 0.1, `dragging the arrow left the weight at ${weightDragged} (was ${weightBefore})`);
  check(s.actions.length === 1, 'pressing on the arrow started a new stroke');
  check(s.actions[0].sides[0].straight, 'moving the end of a straight stroke bent it');
  await shot('03-arrow-dragged');
  measurements.weight_before = weightBefore;
  measurements.weight_dragged = weightDragged;

  // 3. Undo and redo with the keyboard.
  await page.locator('#viewport').focus();
  const weightNow = async () => (await state()).actions[0]?.sides[0].weight;
  await page.keyboard.press('Control+z');
  await page.waitForTimeout(300);
  check(Math.abs((await weightNow()) - weightBefore) < 1e-4, 'undo did not restore the drawn weight');
  await page.keyboard.press('Control+Shift+z');
  await page.waitForTimeout(300);
  check(Math.abs((await weightNow()) - weightDragged) < 1e-4, 'redo did not bring back the dragged weight');
  await shot('04-undo-redo');

  // 3b. The Action inspector shows the selected action's numbers and edits them, each edit one
  //     step of undo: duration, start, ease, weight; then all four undone.
  await page.waitForSelector('#inspector-fields:not([hidden])', { timeout: 10000 });
  s = await state();
  const shownWeight = Number(await page.inputValue('#inspect-weight'));
  check(Math.abs(shownWeight - s.actions[0].sides[0].weight) < 0.006, `the inspector shows weight ${shownWeight}, the action has ${s.actions[0].sides[0].weight}`);
  check(Number(await page.inputValue('#inspect-start')) === s.actions[0].start_frame, 'the inspector does not show the start frame');
  const inspected = { ease: s.actions[0].ease, duration: s.actions[0].end_frame - s.actions[0].start_frame };
  const typeInto = async (label, value) => { const input = page.getByLabel(label, { exact: true }); await input.fill(String(value)); await input.press('Enter'); };
  await typeInto('Duration in frames', 30);
  await page.waitForFunction(() => { const a = window.studio.state.actions[0]; return a && a.end_frame - a.start_frame === 30; }, null, { timeout: 10000 });
  await typeInto('Start frame', 12);
  await page.waitForFunction(() => window.studio.state.actions[0]?.start_frame === 12, null, { timeout: 10000 });
  await typeInto('Ease', 0.8);
  await page.waitForFunction(() => Math.abs(window.studio.state.actions[0]?.ease - 0.8) < 1e-6, null, { timeout: 10000 });
  await typeInto('Weight', 0.5);
  await page.waitForFunction(() => Math.abs(window.studio.state.actions[0]?.sides[0].weight - 0.5) < 0.05, null, { timeout: 10000 });
  s = await state();
  check(s.actions.length === 1 && s.actions[0].start_frame === 12 && s.actions[0].end_frame === 42, `the inspector's edits gave ${JSON.stringify(s.actions.map((a) => [a.start_frame, a.end_frame]))}`);
  await shot('04b-inspector');
  await page.locator('#viewport').focus();
  const undoUntil = async (condition, argument) => {
    await page.keyboard.press('Control+z');
    await page.waitForFunction(condition, argument, { timeout: 10000 });
  };
  await undoUntil((w) => Math.abs(window.studio.state.actions[0].sides[0].weight - w) < 1e-4, weightDragged);
  await undoUntil((e) => Math.abs(window.studio.state.actions[0].ease - e) < 1e-6, inspected.ease);
  await undoUntil(() => window.studio.state.actions[0].start_frame === 45, null);
  await undoUntil((d) => window.studio.state.actions[0].end_frame - window.studio.state.actions[0].start_frame === d, inspected.duration);

  // 4. Mirroring as the seed has it: the switch mirrors the strokes drawn while it is on; the
  //    one-sided smile stays one-sided, a stroke drawn now is mirrored, and each action keeps
  //    its own choice (here turned on for the first one through its edit).
  await page.check('#symmetry');
  await page.waitForFunction(() => window.studio.state.settings.symmetry === true, null, { timeout: 10000 });
  s = await state();
  check(s.actions[0].symmetric === false, 'ticking the mirror switch re-edited the one-sided smile');
  const releaseMirrored = await drawStroke(SMILE_R);
  await releaseMirrored();
  await page.waitForFunction(() => window.studio.state.actions.length === 2, null, { timeout: 10000 });
  s = await state();
  const drawnAfter = s.actions.find((a) => a.stroke === 1);
  check(drawnAfter && drawnAfter.symmetric, `a stroke drawn with the switch on is not mirrored: ${JSON.stringify(drawnAfter && drawnAfter.name)}`);
  await shot('05-mirrored-stroke');
  await page.locator('#viewport').focus();
  await page.keyboard.press('Delete');
  await page.waitForFunction(() => window.studio.state.actions.length === 1, null, { timeout: 10000 });
  await page.evaluate(() => fetch('api/strokes/0', { method: 'PATCH', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ symmetry: true }) }));
  await page.reload();
  await ready();
  await page.waitForFunction(() => window.studio.state.actions[0]?.symmetric === true, null, { timeout: 10000 });
  await ready();
  s = await state();
  const mirrored = s.actions[0].sides.map((x) => x.target);
  check(mirrored.includes(SMILE_R), `the mirrored side targets ${mirrored}`);
  await page.waitForTimeout(500);
  await shot('05-symmetry');

  // 5. Save, reload the page, reopen the saved project: the same clip.
  const before = await clip();
  await page.click('#save');
  await page.waitForFunction(() => document.querySelector('#status').textContent.startsWith('Saved'));
  await page.click('#new');
  await page.waitForFunction(() => window.studio.state.actions.length === 0);
  await page.reload();
  await ready();
  await page.click('#reopen');
  await page.waitForFunction(() => window.studio.state.actions.length === 1);
  await ready();
  const after = await clip();
  check(JSON.stringify(after) === JSON.stringify(before), 'the reopened project bakes a different clip');
  await shot('06-reopened');

  // 5b. The page's downloads: a link saves the file under the server's name and says so; a
  //     refused one (a VRM Animation of a head that is no VRM: the link is hidden, clicked
  //     anyway) shows the server's reason in the banner and saves nothing.
  const [csv] = await Promise.all([page.waitForEvent('download'), page.click('#export-csv')]);
  check(csv.suggestedFilename().endsWith('.csv'), `the CSV downloads as ${csv.suggestedFilename()}`);
  const csvPath = path.join(out, 'download.csv');
  await csv.saveAs(csvPath);
  check(fs.readFileSync(csvPath, 'utf8').startsWith('Timecode,'), 'the downloaded CSV is not Live Link Face');
  await page.waitForFunction(() => document.querySelector('#status').textContent.startsWith('Downloaded '));
  let downloads = 0;
  const counted = () => { downloads += 1; };
  page.on('download', counted);
  const errorsBefore = consoleErrors.length;
  await page.evaluate(() => document.getElementById('export-vrma').click());
  await page.waitForFunction(() => !document.getElementById('error').hidden);
  const refusal = await page.textContent('#error');
  // The browser logs the refusal's 400 itself; any other error stays to fail the run.
  const logged = consoleErrors.splice(errorsBefore);
  consoleErrors.push(...logged.filter((e) => !e.includes('status of 400')));
  check(refusal.includes('is no VRM avatar'), `the refused download says: ${refusal}`);
  page.off('download', counted);
  check(downloads === 0, 'a refused download saved a file');
  // The next download that works clears the banner.
  await Promise.all([page.waitForEvent('download'), page.click('#export-json')]);
  await page.waitForFunction(() => document.getElementById('error').hidden);

  // 6. Playback of a 10-action animation: frames per second of the viewport (software GL here),
  // with draw calls and morph targets. Nine more strokes, each from a blendshape's most-moved
  // vertex to its target, drawn over half a second, one after the other.
  // The drawn stroke lasts as long as the page took to handle the mouse (longer where the page
  // draws slowly), and the nine strokes below start on the face it poses: its length is pinned
  // so that they meet the same animation on any machine.
  await page.evaluate(() => fetch('api/strokes/0', { method: 'PATCH', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ start_frame: 0, duration: 270 }) }).then((r) => { if (!r.ok) throw new Error(`PATCH: ${r.status}`); }));
  const names = ['jawOpen', 'mouthSmileRight', 'eyeBlinkLeft', 'eyeBlinkRight', 'browInnerUpLeft', 'mouthFunnel', 'cheekPuffLeft', 'browOuterUpLeft', 'mouthPucker'].map(own);
  for (const [k, name] of names.entries()) {
    const a = anchors.find((x) => x.name === name);
    check(a && a.vertex !== null, `no anchor for ${name}`);
    const samples = Array.from({ length: 11 }, (_, i) => ({ t: i * 0.05, p: a.rest.map((v, j) => v + (a.target[j] - v) * i / 10) }));
    await page.evaluate((stroke) => fetch('api/strokes', { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify(stroke) }), { samples, start_frame: 20 + 15 * k });
  }
  await page.reload();
  await ready();
  s = await state();
  check(s.actions.length === 10, `expected 10 actions, got ${s.actions.length}: ${JSON.stringify(s.rejected)}`);
  const timing = await page.evaluate(async () => {
    const st = window.studio;
    const info = { meshes: st.meshes.length, morphTargets: st.meshes[0]?.morphTargetInfluences?.length ?? 0, drawCalls: st.drawCalls };
    if (!st.playing) document.getElementById('play').click();
    const f0 = st.frameCount, t0 = performance.now();
    await new Promise((r) => setTimeout(r, 3000));
    info.fps = (st.frameCount - f0) / ((performance.now() - t0) / 1000);
    document.getElementById('play').click();
    return info;
  });
  Object.assign(measurements, { viewport_fps_10_actions: timing.fps, draw_calls: timing.drawCalls, meshes: timing.meshes, morph_targets: timing.morphTargets });
  await shot('08-ten-actions');

  // 6b. Two actions selected with Shift+click move together by a drag on one of them, whole
  //     frames, and one undo takes both back.
  const startOf = async (k) => (await state()).actions.find((a) => a.stroke === k).start_frame;
  const [s1, s2] = [await startOf(1), await startOf(2)];
  await page.click('#timeline .row[data-stroke="1"] .box', { position: { x: 12, y: 8 } });
  await page.click('#timeline .row[data-stroke="2"] .box', { modifiers: ['Shift'], position: { x: 12, y: 8 } });
  const grab = await page.locator('#timeline .row[data-stroke="1"] .box').boundingBox();
  await page.mouse.move(grab.x + 12, grab.y + 8);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) await page.mouse.move(grab.x + 12 + 8 * i, grab.y + 8);
  await page.mouse.up();
  await page.waitForFunction(([a, b]) => { const f = (k) => window.studio.state.actions.find((x) => x.stroke === k).start_frame; return f(1) === a + 10 && f(2) === b + 10; }, [s1, s2], { timeout: 10000 });
  await shot('08b-two-moved');
  await page.locator('#viewport').focus();
  await page.keyboard.press('Control+z');
  await page.waitForFunction(([a, b]) => { const f = (k) => window.studio.state.actions.find((x) => x.stroke === k).start_frame; return f(1) === a && f(2) === b; }, [s1, s2], { timeout: 10000 });

  // 7. A broken character upload shows the importer's error in the page (the browser logs the
  // refused request itself; that one is expected).
  check(consoleErrors.length === 0, `page errors: ${consoleErrors.join('; ')}`);
  await page.setInputFiles('#character-file', { name: 'broken.glb', mimeType: 'model/gltf-binary', buffer: Buffer.from('glTF but not really a binary glTF file') });
  await page.waitForSelector('#error:not([hidden])', { timeout: 10000 });
  const error = await page.textContent('#error');
  check(error.includes('broken.glb'), `the error does not name the file: ${error}`);
  await shot('07-broken-upload');
  // 8. The blendshape list: at frame 100, a click on jawOpen adds its action there.
  await page.click('#error');
  const actionsBefore = (await state()).actions.length;
  await page.getByLabel('Current frame').fill('100');
  await page.getByLabel('Current frame').press('Enter');
  await page.fill('#shape-search', 'jawOp');
  await page.click('#shape-list li:has-text("jawOpen")');
  await page.waitForFunction((n) => window.studio.state.actions.length === n + 1, actionsBefore, { timeout: 10000 });
  s = await state();
  const listed = s.actions[s.actions.length - 1];
  check(listed.name.startsWith('jawOpen') && listed.start_frame === 100, `the list's jawOpen made ${listed.name} at frame ${listed.start_frame}`);
  await shot('09-blendshape-list');
  const unexpected = consoleErrors.filter((e) => !e.includes('status of 400'));
  check(unexpected.length === 0, `page errors: ${unexpected.join('; ')}`);
  // Whether the page told this display about `?fast` (slow frames while drawing), and where.
  measurements.slow_hint = await page.evaluate(() => ({
    shown: !document.getElementById('slow-hint').hidden,
    href: document.getElementById('slow-hint-link').href,
  }));
  console.log(JSON.stringify(measurements));
} finally {
  await browser.close();
}
