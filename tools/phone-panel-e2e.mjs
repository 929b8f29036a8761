// The Capture tab's phone panel in a real browser (Debian's chromium, driven by playwright-core)
// while the studio listens to a phone tracker (`--phone live-link-face`): the panel says what it
// listens to and where the phone should send; live, PyPI's pylivelinkface (not faceanim's
// packet code) plays a Live Link Face phone to the studio, and the panel counts its packets per
// second and the age of the last one while the character's mouth opens and shuts with the
// phone's JawOpen; Neutral is taken and marked; Stop ends the live view.
// Usage: node phone-panel-e2e.mjs URL OUTPUT_DIR PHONE_PORT SENDER_SCRIPT
// Prints one JSON line of measurements; exits non-zero with a message on the first failure.
import { checker, launch } from './browser.mjs';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

const [url, out, phonePort, sender] = process.argv.slice(2);
fs.mkdirSync(out, { recursive: true });
// A failure throws, so that the phone is stopped and the browser closed before node exits with
// the message.
const check = checker('phone-panel-e2e');

const browser = await launch();
let phone = null;
try {
  const page = await browser.newPage({ viewport: { width: 1200, height: 800 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`${url}?fast`);
  await page.waitForFunction(() => window.studio && window.studio.character && window.studio.meshes.length > 0, null, { timeout: 60000 });
  await page.click('#tab-capture');
  await page.waitForSelector('#vmc-row:not([hidden])', { timeout: 30000 });
  const listening = await page.textContent('#vmc-stats');
  check(listening.includes(`Live Link Face on 0.0.0.0:${phonePort}`), `the panel does not say what it listens to: ${listening}`);
  // Where the phone should send: this machine's LAN addresses (none on a machine with
  // loopback alone).
  const lan = await page.evaluate(() => fetch('api/capture/vmc').then((r) => r.json()).then((s) => s.this_machine));
  for (const address of lan) check(listening.includes(`${address}:${phonePort}`), `the panel does not say to send to ${address}: ${listening}`);
  check(await page.isHidden('#vmc-neutral') === false, 'a phone source has no Neutral button');
  await page.screenshot({ path: path.join(out, '01-listening.png') });

  // Live, then the phone: 20 s at 60 fps at most; stopped once the panel has shown enough.
  await page.click('#vmc-live');
  const sent = path.join(out, 'sent.json');
  phone = spawn('python3', [sender, '--to', phonePort, '--frames', '1200', '--fps', '60', '--out', sent], { stdio: 'inherit' });
  await page.waitForFunction(() => /\d+ frames/.test(document.getElementById('vmc-stats').textContent)
    && !document.getElementById('vmc-stats').textContent.includes(' 0 frames'), null, { timeout: 30000 });
  // The mouth follows the phone's JawOpen (a cosine, three times open and shut over the run):
  // the viewport's jaw influence, read each drawn frame for four seconds.
  const seen = await page.evaluate(async () => {
    const s = window.studio;
    const jaw = s.character.blendshapes.indexOf('jawOpen');
    let max = 0, min = 1, last = '';
    const start = performance.now();
    while (performance.now() - start < 4000) {
      const w = s.meshes[0].morphTargetInfluences[jaw];
      max = Math.max(max, w); min = Math.min(min, w);
      last = document.getElementById('vmc-stats').textContent;
      await new Promise((r) => requestAnimationFrame(r));
    }
    return { max, min, last, jaw };
  });
  check(seen.jaw >= 0, 'the built-in head has no jawOpen');
  check(seen.max - seen.min > 0.3, `the mouth did not follow the phone: jawOpen ${seen.min.toFixed(2)}..${seen.max.toFixed(2)}`);
  const rate = Number((seen.last.match(/: (\d+) packets\/s/) || [])[1]);
  check(rate >= 30 && rate <= 90, `the panel shows ${rate} packets/s for a phone sending 60: ${seen.last}`);
  const age = Number((seen.last.match(/last (\d+) ms ago/) || [])[1]);
  check(Number.isFinite(age) && age < 1000, `the panel does not show a fresh last packet: ${seen.last}`);
  check(seen.last.includes(' from 127.0.0.1'), `the panel does not say which phone sends: ${seen.last}`);
  await page.screenshot({ path: path.join(out, '02-live.png') });

  // Neutral: the phone's face now is the relaxed one, kept and marked.
  await page.click('#vmc-neutral');
  await page.waitForFunction(() => document.getElementById('vmc-neutral').textContent.includes('✓'), null, { timeout: 10000 });
  await page.click('#vmc-live');
  await page.waitForFunction(() => !document.getElementById('vmc-stats').textContent.includes('packets/s'), null, { timeout: 10000 });
  const stopped = await page.textContent('#vmc-stats');
  check(stopped.startsWith('Listening for Live Link Face'), `Stop did not end the live view: ${stopped}`);
  check(!errors.length, `page errors: ${errors.join('; ')}`);
  console.log(JSON.stringify({ packets_per_second: rate, last_packet_ms: age, jaw_open_min: seen.min, jaw_open_max: seen.max }));
} finally {
  if (phone && phone.exitCode === null) phone.kill();
  await browser.close();
}
