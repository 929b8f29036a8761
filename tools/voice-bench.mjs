// Benchmark of live lip sync: Debian's chromium (playwright-core) opens a running studio, its
// fake microphone plays MICROPHONE.wav (the calibration passage read aloud, then lines with
// pauses, looping), the Capture tab's microphone runs, Calibrate voice learns the voice, and
// it listens until ONSETS voice onsets after a pause have been seen. Prints one JSON line, as
// the page measures on its own clock: voice → screen latency (median and 90th percentile: from
// the newest sample's arrival in the page to the character drawn with the mouth it gave, plus
// the analysis window and the microphone's input latency), the mouth's delay at the voice's
// onsets (each, and the median), where the latency goes, and the calibration.
// Usage: node voice-bench.mjs URL MICROPHONE.wav [ONSETS]
import { launch } from './browser.mjs';

const [url, microphone, onsetsArg] = process.argv.slice(2);
if (!url || !microphone) {
  console.error('usage: node voice-bench.mjs URL MICROPHONE.wav [ONSETS]');
  process.exit(2);
}
const wanted = Number(onsetsArg || 6);
const browser = await launch(['--use-fake-device-for-media-stream', '--use-fake-ui-for-media-stream', `--use-file-for-fake-audio-capture=${microphone}`]);
try {
  const page = await browser.newPage({ viewport: { width: 1200, height: 800 } });
  await page.goto(`${url}?fast#capture`);
  await page.waitForFunction(() => window.studio && window.studio.capture && window.studio.capture.view, null, { timeout: 60000 });
  await page.click('#voice-live');
  await page.waitForFunction(() => window.studio.capture.voice.chunks > 10, null, { timeout: 30000 });
  await page.click('#voice-calibrate');
  await page.waitForFunction(() => { const v = window.studio.capture.voice.view; return v && ['calibrated', 'failed'].includes(v.calibration.state); }, null, { timeout: 120000 });
  const result = await page.evaluate(async (n) => {
    const v = window.studio.capture.voice;
    v.onset_lags.length = 0;
    while (v.onset_lags.length < n) await new Promise((r) => setTimeout(r, 100));
    const sorted = v.latencies.slice().sort((a, b) => a - b);
    const lags = v.onset_lags.slice().sort((a, b) => a - b);
    return {
      latency_ms: sorted[Math.floor(sorted.length / 2)],
      latency_p90_ms: sorted[Math.floor(sorted.length * 0.9)],
      onset_lag_ms: lags[Math.floor(lags.length / 2)],
      onset_lags_ms: v.onset_lags.map(Math.round),
      onset_misses: v.onset_misses,
      stages: v.stages,
      calibration: v.view.calibration,
      learned: v.view.learned,
    };
  }, wanted);
  console.log(JSON.stringify(result));
} finally {
  await browser.close();
}
