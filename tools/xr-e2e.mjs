// Immersive sketching in an emulated Meta Quest 3 (npm iwer) in headless Chromium: enters VR,
// draws strokes in the air with the right controller's trigger, frame by frame (each move waits
// for the next XR frame, so timing is the XRFrame clock's, however slow software rendering is),
// grabs and moves the arrow, slides the sphere, flicks the left thumbstick four ways, navigates
// with Y and the squeeze, and checks that a second, desktop page of the same studio sees the
// strokes. Prints one JSON line of measurements last.
// Usage: node tools/xr-e2e.mjs URL OUT_DIR NAME[,NAME…]   (blendshapes to draw, by name)
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { launch } from './browser.mjs';

const [url, out, namesArg] = process.argv.slice(2);
const names = (namesArg || 'jawOpen').split(',');
const here = path.dirname(fileURLToPath(import.meta.url));
const iwer = await readFile(path.join(here, 'node_modules/iwer/build/iwer.js'), 'utf8');

const browser = await launch();
const fail = (message) => { throw new Error(message); };
const measured = {};
const errors = [];
let vrPage = null;
try {
  const context = await browser.newContext({ viewport: { width: 1100, height: 760 } });
  const vr = await context.newPage();
  vrPage = vr;
  vr.on('console', (m) => { if (m.type() === 'error') errors.push(`vr: ${m.text()}`); });
  vr.on('pageerror', (e) => errors.push(`vr: ${e}`));
  await vr.addInitScript({ content: `${iwer}\nwindow.__xrDevice = new IWER.XRDevice(IWER.metaQuest3);\nwindow.__xrDevice.installRuntime({ forceInstall: true });` });
  await vr.goto(url);
  await vr.waitForFunction(() => window.studio && window.studio.bakedReady && window.studio.state, null, { timeout: 120000 });
  // A second page, the desktop view of the same studio.
  const desk = await context.newPage();
  desk.on('console', (m) => { if (m.type() === 'error') errors.push(`desktop: ${m.text()}`); });
  await desk.goto(url);
  await desk.waitForFunction(() => window.studio && window.studio.bakedReady && window.studio.state, null, { timeout: 120000 });
  // The headset's page in front, as the one a user wears is: Chromium runs a page behind
  // another at one frame a second (the desktop page behind it still hears the studio's events).
  await vr.bringToFront();

  const enter = vr.getByRole('button', { name: 'Enter VR' });
  await enter.waitFor({ state: 'visible', timeout: 30000 });
  await enter.click();
  await vr.waitForFunction(() => window.studio.xr.session !== null && window.studio.xr.frames > 2, null, { timeout: 120000 });
  measured.entered = true;

  /** Waits until `n` more XR frames were drawn. */
  const frames = (n = 1) => vr.evaluate(async (n) => {
    const start = window.studio.xr.frames;
    while (window.studio.xr.frames < start + n) await new Promise((r) => setTimeout(r, 5));
  }, n);
  /** Puts hand's pen tip at a point of the character's own space. */
  const tipAt = (hand, p) => vr.evaluate(([hand, p]) => {
    const d = window.__xrDevice.controllers[hand];
    const tip = window.studio.xr.tip(hand);
    const want = window.studio.xr.toWorld(p);
    d.position.set(d.position.x + want[0] - tip[0], d.position.y + want[1] - tip[1], d.position.z + want[2] - tip[2]);
  }, [hand, p]);
  const button = (hand, name, value) => vr.evaluate(([hand, name, value]) => window.__xrDevice.controllers[hand].updateButtonValue(name, value), [hand, name, value]);
  const stick = (x, y) => vr.evaluate(([x, y]) => window.__xrDevice.controllers.left.updateAxes('thumbstick', x, y), [x, y]);
  const state = () => vr.evaluate(() => window.studio.state);
  const now = () => vr.evaluate(() => performance.now());
  const lerp = (a, b, s) => a.map((v, i) => v + (b[i] - v) * s);
  /** Points the left controller's ray at a panel point (`{point, normal, along, quaternion}`
   * from the xr hook) from 0.2 m in front of it, moved `shift` metres along the panel. */
  const pointLeftAt = (aim, shift = 0) => vr.evaluate(([aim, shift]) => {
    const c = window.__xrDevice.controllers.left;
    const p = aim.point.map((v, i) => v + 0.2 * aim.normal[i] + shift * aim.along[i]);
    c.position.set(p[0], p[1], p[2]);
    c.quaternion.set(aim.quaternion[0], aim.quaternion[1], aim.quaternion[2], aim.quaternion[3]);
  }, [aim, shift]);
  // The pen tip's first placement moves the controller; let a frame pass so tip() follows.
  const anchors = await vr.evaluate(() => fetch('api/character/anchors').then((r) => r.json()));

  /** Draws from `a` to `b` (character space) in `steps` XR frames; returns the drawing time (s):
   * the tip's moves (`inner`) and from the trigger's press to its release (`outer`: the stroke
   * may take the frames on either side, which a loaded machine draws slowly). */
  async function draw(a, b, steps = 8) {
    await tipAt('right', a); await frames(1); await tipAt('right', a); await frames(1);
    const before = (await state()).actions.length;
    const pressed = await now();
    await button('right', 'trigger', 1);
    await frames(1);
    const t0 = await now();
    for (let i = 1; i <= steps; i++) { await tipAt('right', lerp(a, b, i / steps)); await frames(1); }
    const t1 = await now();
    await button('right', 'trigger', 0);
    await frames(1);
    const released = await now();
    await vr.waitForFunction((n) => window.studio.state.actions.length > n, before, { timeout: 30000 });
    return { inner: (t1 - t0) / 1000, outer: (released - pressed) / 1000 };
  }

  // 1. Strokes from the vertex each blendshape moves most to where weight 1 takes it.
  measured.strokes = [];
  for (const name of names) {
    const anchor = anchors.find((x) => x.name === name) || fail(`no anchor for ${name}`);
    const { inner: seconds, outer } = await draw(anchor.rest, anchor.target);
    const s = await state();
    const action = s.actions[s.actions.length - 1];
    const duration = (action.end_frame - action.start_frame) / s.fps;
    measured.strokes.push({ name, target: action.sides[0].target, weight: action.sides[0].weight, seconds, outer, duration });
    if (action.sides[0].target !== name) fail(`${name}: the VR stroke picked ${action.sides[0].target}`);
    if (action.sides[0].weight < 0.8) fail(`${name}: weight ${action.sides[0].weight}`);
    if (duration < 0.5 * seconds || duration > 1.5 * outer) fail(`${name}: lasts ${duration} s for ${seconds} s of drawing (${outer} s from press to release)`);
  }
  await vr.screenshot({ path: path.join(out, 'xr-strokes.png') });

  // 2. The desktop page sees the VR strokes.
  const count = (await state()).actions.length;
  await desk.waitForFunction((n) => window.studio.state.actions.length === n, count, { timeout: 15000, polling: 250 });
  measured.desktopSees = count;

  // 3. The four flicks of the left thumbstick: left takes the stroke just drawn away (undo),
  // right brings it back (redo), down toggles symmetry twice, up enters and leaves the timeline.
  const flick = async (x, y) => { await stick(x, y); await frames(2); await stick(0, 0); await frames(2); };
  {
    const before = (await state()).actions.length;
    await flick(-1, 0);
    await vr.waitForFunction((n) => window.studio.state.actions.length === n - 1, before, { timeout: 15000 });
    await flick(1, 0);
    await vr.waitForFunction((n) => window.studio.state.actions.length === n, before, { timeout: 15000 });
    const symmetry = (await state()).settings.symmetry;
    await flick(0, 1);
    await vr.waitForFunction((on) => window.studio.state.settings.symmetry === !on, symmetry, { timeout: 15000 });
    await flick(0, 1);
    await vr.waitForFunction((on) => window.studio.state.settings.symmetry === on, symmetry, { timeout: 15000 });
    await flick(0, -1);
    if (await vr.evaluate(() => window.studio.xr.mode) !== 'timeline') fail('thumbstick up did not enter the timeline');
    await flick(0, -1);
    if (await vr.evaluate(() => window.studio.xr.mode) !== 'waiting') fail('thumbstick up again did not leave the timeline');
    measured.flicks = true;
  }

  // 4. Squeeze near the last action's arrow and move it: its end moves.
  {
    const s = await state();
    const action = s.actions[s.actions.length - 1];
    const end = action.sides[0].end;
    await tipAt('right', end); await frames(1); await tipAt('right', end); await frames(1);
    await button('right', 'squeeze', 1);
    await frames(1);
    const to = [end[0], end[1] - 0.4 * (end[1] - action.sides[0].start[1]), end[2]];
    for (let i = 1; i <= 4; i++) { await tipAt('right', lerp(end, to, i / 4)); await frames(2); }
    await button('right', 'squeeze', 0);
    await frames(3);
    await vr.waitForFunction(([stroke, y]) => { const a = window.studio.state.actions.find((x) => x.stroke === stroke); return a && Math.abs(a.sides[0].end[1] - y) > 1e-4; }, [action.stroke, end[1]], { timeout: 15000 });
    measured.arrowMoved = true;
  }

  // 5. Trigger on the sphere and slide it along the stroke: the easing changes.
  {
    const s = await state();
    const action = s.actions[s.actions.length - 1];
    const mid = action.sides[0].mid;
    const path = action.sides[0].path;
    const ease = action.ease;
    await tipAt('right', mid); await frames(1); await tipAt('right', mid); await frames(1);
    await button('right', 'trigger', 1);
    await frames(1);
    const near = path[Math.max(1, Math.floor(path.length * 0.15))];
    for (let i = 1; i <= 4; i++) { await tipAt('right', lerp(mid, near, i / 4)); await frames(2); }
    await button('right', 'trigger', 0);
    await frames(3);
    await vr.waitForFunction(([stroke, ease]) => { const a = window.studio.state.actions.find((x) => x.stroke === stroke); return a && Math.abs(a.ease - ease) > 0.05; }, [action.stroke, ease], { timeout: 15000 });
    measured.sphereSlid = true;
  }

  // 6. Navigation: Y, then squeeze the left hand and move it: the character follows; strokes
  // still land.
  {
    await button('left', 'y-button', 1); await frames(2); await button('left', 'y-button', 0); await frames(1);
    if (await vr.evaluate(() => window.studio.xr.mode) !== 'navigation') fail('Y did not enter navigation');
    const probe = anchors[0].rest;
    const before = await vr.evaluate((p) => window.studio.xr.toWorld(p), probe);
    await button('left', 'squeeze', 1); await frames(2);
    const start = await vr.evaluate(() => window.__xrDevice.controllers.left.position.x);
    for (let i = 1; i <= 5; i++) { await vr.evaluate(([x]) => { window.__xrDevice.controllers.left.position.x = x; }, [start + 0.02 * i]); await frames(1); }
    await button('left', 'squeeze', 0); await frames(2);
    const after = await vr.evaluate((p) => window.studio.xr.toWorld(p), probe);
    measured.navigated = after[0] - before[0];
    if (Math.abs(after[0] - before[0] - 0.1) > 0.02) fail(`navigation moved the character by ${after[0] - before[0]} m, not 0.1`);
    await button('left', 'y-button', 1); await frames(2); await button('left', 'y-button', 0); await frames(1);
    if (await vr.evaluate(() => window.studio.xr.mode) !== 'waiting') fail('Y again did not leave navigation');
    // A blendshape no stroke has drawn yet: the trigger pressed at an earlier stroke's start
    // takes that stroke's sphere when its middle is within the hook radius, as it should (and
    // where the middle lies depends on how the frames fell while it was drawn).
    const drawn = new Set((await state()).actions.flatMap((a) => a.sides.map((x) => x.target)));
    const fresh = ['browInnerUp', 'cheekPuff', 'mouthFunnel', 'jawForward', ...anchors.map((x) => x.name)]
      .find((n) => !drawn.has(n) && anchors.some((x) => x.name === n)) || fail('no blendshape left to draw after navigating');
    const anchor = anchors.find((x) => x.name === fresh);
    await draw(anchor.rest, anchor.target);
    const s = await state();
    const action = s.actions[s.actions.length - 1];
    if (action.sides[0].target !== fresh || action.sides[0].weight < 0.8) fail(`after navigating, the stroke for ${fresh} made ${action.sides[0].target} at ${action.sides[0].weight}`);
    measured.strokeAfterNavigation = action.sides[0].weight;
  }

  // 7. The timeline panel: point the left hand's ray at the first action's orange start handle,
  // press the trigger and move the ray along the panel: the action starts later.
  {
    const s = await state();
    const action = s.actions[0];
    const aim = await vr.evaluate((stroke) => window.studio.xr.panelHandle(stroke, 'start'), action.stroke);
    if (!aim) fail('the timeline panel does not show the first action');
    const pose = (shift) => pointLeftAt(aim, shift);
    await pose(0); await frames(2);
    await button('left', 'trigger', 1); await frames(2);
    for (let i = 1; i <= 4; i++) { await pose(0.02 * i); await frames(1); }
    await button('left', 'trigger', 0); await frames(2);
    await vr.waitForFunction(([stroke, start]) => { const a = window.studio.state.actions.find((x) => x.stroke === stroke); return a && a.start_frame > start; }, [action.stroke, action.start_frame], { timeout: 15000 });
    const after = (await state()).actions.find((x) => x.stroke === action.stroke);
    measured.timelineStart = [action.start_frame, after.start_frame];
    await vr.screenshot({ path: path.join(out, 'xr-timeline.png') });
  }

  // 8. The settings panel: slide the pen distance, then press Save.
  {
    const aimAt = (where) => vr.evaluate(([key, at]) => window.studio.xr.settingsPoint(key, at), where);
    const pose = (aim) => pointLeftAt(aim);
    const before = (await state()).settings.pen_distance;
    await pose(await aimAt(['pen_distance', 0.5])); await frames(2);
    await button('left', 'trigger', 1); await frames(2);
    for (const s of [0.55, 0.6, 0.65]) { await pose(await aimAt(['pen_distance', s])); await frames(1); }
    await button('left', 'trigger', 0); await frames(2);
    await vr.waitForFunction((before) => window.studio.state.settings.pen_distance !== null && window.studio.state.settings.pen_distance !== before, before, { timeout: 15000 });
    measured.penDistance = [before, (await state()).settings.pen_distance];
    await pose(await aimAt(['save'])); await frames(2);
    await button('left', 'trigger', 1); await frames(2); await button('left', 'trigger', 0); await frames(2);
    await vr.waitForFunction(() => /Saved/.test(document.getElementById('status').textContent), null, { timeout: 15000 });
    measured.saved = true;
    await vr.screenshot({ path: path.join(out, 'xr-settings.png') });
  }

  measured.frames = await vr.evaluate(() => window.studio.xr.frames);
  measured.frameMs = await vr.evaluate(() => window.studio.xr.frameMs);
  await vr.screenshot({ path: path.join(out, 'xr-view.png') });
  // Leaving VR (the headset's own exit ends the session) returns to the desktop view with the
  // strokes.
  await vr.evaluate(() => window.studio.xr.session.end());
  await vr.waitForFunction(() => window.studio.xr.session === null, null, { timeout: 30000 });
  await vr.screenshot({ path: path.join(out, 'xr-left.png') });
  measured.errors = errors;
  if (errors.length) fail(`console errors: ${errors.join(' | ')}`);
} catch (e) {
  const banner = vrPage ? await vrPage.evaluate(() => ({ banner: document.getElementById('error').textContent, mode: window.studio.xr.mode, actions: window.studio.state.actions.length })).catch(() => null) : null;
  console.error(`failed: ${e.message}\npage: ${JSON.stringify(banner)}\nso far: ${JSON.stringify(measured)}\nconsole errors: ${errors.join(' | ')}`);
  process.exitCode = 1;
} finally {
  await browser.close();
}
if (!process.exitCode) console.log(JSON.stringify(measured));
