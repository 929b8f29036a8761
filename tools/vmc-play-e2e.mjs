// The studio's page playing its animation while the studio sends VMC (`--vmc-send`): each
// frame the viewport shows goes out. Draws nothing itself: the caller posted the strokes, or
// (with `take`) the studio opened a take, which plays in the Capture tab.
// Usage: node vmc-play-e2e.mjs URL OUTPUT_DIR [strokes|take] [FRAMES_SENT]
// Prints one JSON line of measurements; exits non-zero with a message on the first failure.
import { launch } from './browser.mjs';
import fs from 'node:fs';
import path from 'node:path';

const [url, out, what = 'strokes', wanted = '6'] = process.argv.slice(2);
fs.mkdirSync(out, { recursive: true });
const fail = (message) => { console.error(`vmc-play-e2e: ${message}`); process.exit(1); };

const browser = await launch();
try {
  const page = await browser.newPage({ viewport: { width: 1200, height: 800 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  if (what === 'take') {
    await page.goto(`${url}?fast#capture`);
    await page.waitForFunction(() => window.studio && window.studio.bakedReady && window.studio.capture.view && window.studio.capture.view.take, null, { timeout: 60000 });
  } else {
    await page.goto(`${url}?fast`);
    await page.waitForFunction(() => window.studio && window.studio.bakedReady && window.studio.state && window.studio.state.actions.length > 0, null, { timeout: 60000 });
  }
  // Play until the studio has sent the frames asked for.
  await page.click('#play');
  const sentSoFar = () => page.evaluate(() => fetch('api/capture/vmc').then((r) => r.json()).then((s) => s.sending.frames));
  // Each check waits for the viewport's next drawn frame (bounded), not for a clock.
  for (let k = 0; k < 600 && (await sentSoFar()) < Number(wanted); k++) {
    const drawn = await page.evaluate(() => window.studio.frameCount);
    await page.waitForFunction((f) => window.studio.frameCount > f, drawn, { timeout: 10000 });
  }
  await page.click('#play');
  const sent = await page.evaluate(() => fetch('api/capture/vmc').then((r) => r.json()));
  // What the transport bar says while frames go out.
  const shown = await page.evaluate(() => { const e = document.getElementById('vmc-out'); return e.hidden ? null : e.textContent; });
  await page.screenshot({ path: path.join(out, 'playing-out.png') });
  if (errors.length) fail(`page errors: ${errors.join('; ')}`);
  console.log(JSON.stringify({ frames_sent: sent.sending.frames, dropped: sent.sending.dropped, shown }));
} finally {
  await browser.close();
}
