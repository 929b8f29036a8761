// Benchmark of live mode: Debian's chromium (playwright-core) opens a running studio, its fake
// camera plays FILE.y4m, and live mode runs for SECONDS. Prints one JSON line: frames per
// second reaching the screen, camera-to-screen latency (median and 90th percentile, as the page
// measures it: from the camera frame's capture to the drawn character wearing its weights), the
// server's time per frame, and the CPU each of Chromium's processes and the studio spent.
// Usage: node live-bench.mjs URL WEBCAM.y4m [SECONDS] [--studio-pid PID] [--query QUERY]
//   [--chromium-args "FLAGS"] [--in-flight N]
// (QUERY defaults to `fast`, the page's software-GL viewport; FLAGS are added to Chromium's;
// N frames at most are with the server at once, by default the page's own choice).
import { launch } from './browser.mjs';
import fs from 'node:fs';

const args = process.argv.slice(2);
const option = (name, fallback) => {
  const i = args.indexOf(name);
  if (i < 0) return fallback;
  const [, value] = args.splice(i, 2);
  return value;
};
const studioPid = option('--studio-pid', null);
const query = option('--query', 'fast');
const maxInFlight = option('--in-flight', null);
const extraArgs = (option('--chromium-args', '') || '').split(' ').filter(Boolean);
const [url, y4m, secondsArg] = args;
if (!url || !y4m) {
  console.error('usage: node live-bench.mjs URL WEBCAM.y4m [SECONDS] [--studio-pid PID] [--query QUERY]');
  process.exit(2);
}
const seconds = Number(secondsArg || 10);
const ticksPerSecond = 100; // USER_HZ on Linux

/** CPU seconds (user + system) of one process, or 0 when it is gone. */
function cpuSeconds(pid) {
  try {
    const stat = fs.readFileSync(`/proc/${pid}/stat`, 'utf8');
    const fields = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
    return (Number(fields[11]) + Number(fields[12])) / ticksPerSecond;
  } catch { return 0; }
}

/** Chromium's processes under `root`, each named by its --type (the browser has none). */
function processTree(root) {
  const children = new Map();
  for (const entry of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(entry)) continue;
    try {
      const stat = fs.readFileSync(`/proc/${entry}/stat`, 'utf8');
      const ppid = Number(stat.slice(stat.lastIndexOf(')') + 2).split(' ')[1]);
      if (!children.has(ppid)) children.set(ppid, []);
      children.get(ppid).push(Number(entry));
    } catch { /* gone */ }
  }
  const named = [];
  const walk = (pid) => {
    let name = 'browser';
    try {
      // Chromium rewrites its children's titles into one line, so no split on NULs here.
      const cmdline = fs.readFileSync(`/proc/${pid}/cmdline`, 'utf8');
      const type = /--type=(\S+)/.exec(cmdline);
      const service = /--utility-sub-type=(\S+)/.exec(cmdline);
      if (type) name = type[1] + (service ? `:${service[1].split('.').pop()}` : '');
      else if (!/chromium\/chromium/.test(cmdline)) name = 'launcher';
    } catch { /* gone */ }
    named.push({ pid, name });
    for (const child of children.get(pid) || []) walk(child);
  };
  walk(root);
  return named;
}

const browser = await launch(['--use-fake-device-for-media-stream', `--use-file-for-fake-video-capture=${y4m}`, '--use-fake-ui-for-media-stream', ...extraArgs]);
try {
  const page = await (await browser.newContext({ viewport: { width: 1400, height: 900 } })).newPage();
  await page.goto(query ? `${url}?${query}` : url);
  await page.waitForFunction(() => window.studio && window.studio.bakedReady && window.studio.capture, null, { timeout: 60000 });
  await page.click('#tab-capture');
  if (maxInFlight) await page.evaluate((n) => { window.studio.capture.live.maxInFlight = n; }, Number(maxInFlight));
  await page.click('#live');
  await page.waitForFunction(() => window.studio.capture.live.frames > 10, null, { timeout: 60000 });

  // The browser process: the one started with our camera file and no --type.
  const browserPid = fs.readdirSync('/proc').filter((e) => /^\d+$/.test(e)).map(Number).find((pid) => {
    try {
      const cmdline = fs.readFileSync(`/proc/${pid}/cmdline`, 'utf8').split('\0');
      return cmdline.includes(`--use-file-for-fake-video-capture=${y4m}`) && !cmdline.some((a) => a.startsWith('--type='));
    } catch { return false; }
  });
  const processes = browserPid ? processTree(browserPid) : [];
  const cpuBefore = processes.map((p) => cpuSeconds(p.pid));
  const studioBefore = studioPid ? cpuSeconds(studioPid) : 0;
  const result = await page.evaluate(async (ms) => {
    const live = window.studio.capture.live;
    const frames0 = live.frames;
    const latencies = [], server = [], grab = [], trip = [], draw = [];
    let last = live.frames;
    const start = performance.now();
    while (performance.now() - start < ms) {
      // Polled by a timer, not requestAnimationFrame, so as not to ask for frames itself.
      await new Promise((r) => setTimeout(r, 4));
      if (live.frames !== last) {
        last = live.frames;
        latencies.push(live.latencies[live.latencies.length - 1]);
        server.push(live.server_ms);
        grab.push(live.stages.grab_ms); trip.push(live.stages.round_trip_ms); draw.push(live.stages.draw_ms);
      }
    }
    const elapsed = (performance.now() - start) / 1000;
    const q = (xs, p) => { const s = xs.filter((x) => x !== undefined).sort((a, b) => a - b); return s[Math.min(s.length - 1, Math.floor(p * s.length))]; };
    const canvas = document.querySelector('#viewport canvas');
    return {
      fps: (live.frames - frames0) / elapsed,
      latency_ms_median: q(latencies, 0.5),
      latency_ms_p90: q(latencies, 0.9),
      server_ms_median: q(server, 0.5),
      stages_ms_median: { grab: q(grab, 0.5), round_trip: q(trip, 0.5), draw: q(draw, 0.5) },
      viewport_px: canvas ? [canvas.width, canvas.height] : null,
      pixel_format: live.format,
      elapsed_s: elapsed,
    };
  }, seconds * 1000);
  const elapsed = result.elapsed_s;
  const cpu = {};
  processes.forEach((p, i) => {
    const share = (cpuSeconds(p.pid) - cpuBefore[i]) / elapsed;
    if (share > 0.005) cpu[p.name] = Math.round(((cpu[p.name] || 0) + share) * 100) / 100;
  });
  if (studioPid) cpu.studio = Math.round(((cpuSeconds(studioPid) - studioBefore) / elapsed) * 100) / 100;
  console.log(JSON.stringify({ ...result, cpu_cores: cpu }));
} finally {
  await browser.close();
}
