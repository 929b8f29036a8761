// Live mode: the webcam drives the character in real time. Camera frames go to the server one
// at a time (the newest waiting), in the camera's own pixel format where the browser gives it;
// the weights that come back go on the character, and Record makes a take of them. Measures
// frames per second and camera-to-screen latency.

import { api } from './api.js';
import { turnHead } from './head-turn.js';
import { apply, currentView, post, showTakeFrame } from './take.js';
import { pushMedian } from './medians.js';
import { applyLayer, pause } from './playback.js';
import { onRender } from './scene.js';
import { showError } from './status.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

/** Live webcam measurements: frames per second and camera-to-screen latency (ms); scripts
 * read them as `window.studio.capture.live` (and may set `maxInFlight`). */
export const live = {
  running: false, fps: 0, latency_ms: 0, server_ms: 0, frames: 0,
  /** Where the latency goes (ms, last frame): reading the camera frame, the round trip to
   * the server, and drawing the character. */
  stages: { grab_ms: 0, round_trip_ms: 0, draw_ms: 0 },
  /** The pixel format frames are sent in (the camera's own YUV when the browser gives it). */
  format: '',
  /** @type {number|null} frames recorded so far */ recorded: null,
  /** Who chose the neutral face frames are read against: 'user' (Calibrate), 'automatic'
   * (held still) or null (none yet). */
  neutral: /** @type {string|null} */ (null),
  /** @type {number[]|null} */ weights: null,
  latencies: /** @type {number[]} */ ([]),
  /** Frames sent to the server and not yet answered, at most: a newer camera frame waits
   * for a free slot and is dropped if another comes first, so a slow server costs frames,
   * not latency. One: the server tracks one frame at a time, so a second one only queues
   * behind it. Without a GPU (tools/live-bench.mjs) two gave 24 % more frames per second for
   * 14 % more median latency and 27 % more at the 90th percentile; with a GPU the server is
   * the limit and a queued frame adds latency only. */
  maxInFlight: 1,
  /** Camera frames the page has received and not closed yet (a frame left unclosed stalls
   * the camera): at most the waiting one and those being read. */
  get open_frames() { return open.size; },
};

/** The camera frames received and not yet released. */
const open = new Set();
/** Closes a camera frame the page received, once. */
function release(/** @type {any} */ frame) {
  if (!open.delete(frame)) return;
  frame.close();
}

const video = /** @type {HTMLVideoElement} */ ($('capture-video'));
const grab = document.createElement('canvas');
let stream = /** @type {MediaStream|null} */ (null);
let inFlight = 0;
/** Timings of the frame whose weights are on the character but not yet drawn. */
let pendingShown = /** @type {{captured: number, sent: number, received: number}|null} */ (null);
let fpsWindow = { start: 0, count: 0 };

async function startLive() {
  showError('');
  try {
    stream = await navigator.mediaDevices.getUserMedia({ video: { width: { ideal: 640 }, height: { ideal: 480 }, frameRate: { ideal: 30 } }, audio: false });
  } catch (e) { showError(`The webcam could not be opened: ${e.message || e}`); return; }
  try { apply(await api('POST', 'api/capture/live/start')); }
  catch (e) { showError(String(e.message || e)); stopLive(); return; }
  $('capture-frame').hidden = true;
  Object.assign(live, { running: true, fps: 0, latency_ms: 0, frames: 0, weights: null, latencies: [] });
  fpsWindow = { start: performance.now(), count: 0 };
  $('live').textContent = 'Stop webcam';
  /** @type {HTMLButtonElement} */ ($('record')).disabled = false;
  /** @type {HTMLButtonElement} */ ($('calibrate')).disabled = false;
  live.neutral = null;
  calibrating = false;
  showNeutral();
  pause();
  const track = stream.getVideoTracks()[0];
  const Processor = /** @type {any} */ (window).MediaStreamTrackProcessor;
  if (Processor && typeof VideoFrame !== 'undefined') {
    // Frames straight from the camera track: independent of how fast the page is drawn, which
    // matters on machines that draw in software.
    shownCanvas.hidden = false;
    readTrack(new Processor({ track }).readable.getReader());
  } else {
    video.srcObject = stream;
    video.hidden = false;
    await video.play();
    nextVideoFrame();
  }
}

/** The input frame shown beside the character in live mode: the frame last sent. */
const shownCanvas = document.createElement('canvas');
shownCanvas.id = 'capture-live';
shownCanvas.hidden = true;
$('capture-input').appendChild(shownCanvas);

/** The newest camera frame not yet sent, with the time it arrived: a frame that arrives while
 * the server is busy waits here (replacing an older one), so that the next is sent the moment
 * an answer comes back instead of when the camera next delivers. */
let waiting = /** @type {{frame: any, captured: number}|null} */ (null);

async function readTrack(reader) {
  // Read until the track ends (stopLive stops it), closing what comes after Stop: a frame left
  // in the stream unread is garbage collected unclosed, which stalls the camera.
  try {
    for (;;) {
      const { value: frame, done } = await reader.read();
      if (done || !frame) break;
      open.add(frame);
      if (!live.running) { release(frame); continue; }
      if (waiting) release(waiting.frame);
      waiting = { frame, captured: performance.now() };
      sendWaiting();
    }
  } catch { /* the stream failed with its track: nothing more will come */ } finally {
    if (waiting) { release(waiting.frame); waiting = null; }
    reader.releaseLock();
  }
}

// Leaving or reloading the page with the webcam on: let the camera go, and close the frames
// the page holds (their reads would never finish, and unclosed frames stall the camera).
window.addEventListener('pagehide', () => {
  live.running = false;
  waiting = null;
  for (const frame of [...open]) release(frame);
  if (stream) for (const t of stream.getTracks()) t.stop();
});

/** Sends the waiting frame if a slot with the server is free. */
async function sendWaiting() {
  if (!waiting || !live.running || inFlight >= live.maxInFlight) return;
  const { frame, captured } = waiting;
  waiting = null;
  inFlight++; // the slot is taken while the frame is read, too
  try {
    const { pixels, width, height, format } = await frameBytes(frame);
    if (shownCanvas.width !== width) { shownCanvas.width = width; shownCanvas.height = height; }
    shownCanvas.getContext('2d')?.drawImage(frame, 0, 0, width, height);
    send(pixels, width, height, format, captured, performance.now());
  } catch (e) {
    inFlight--;
    if (live.running) showError(`The webcam frame could not be read: ${e.message || e}`);
  } finally { release(frame); }
}

/** Pixel-format headers of a frame the page converted to RGBA itself. */
const RGBA = { 'x-pixel-format': 'RGBA' };

/** A camera frame's bytes as the server reads them: the camera's own 4:2:0 planes when it
 * gives them (no conversion in the page, and 3/8 of the bytes of RGBA), else RGBA. */
async function frameBytes(/** @type {any} */ frame) {
  const { width, height } = frame.visibleRect;
  const cw = Math.ceil(width / 2), ch = Math.ceil(height / 2);
  if (frame.format === 'I420' || frame.format === 'NV12') {
    // Tightly packed planes, whatever the camera's own strides.
    const layout = frame.format === 'I420'
      ? [{ offset: 0, stride: width }, { offset: width * height, stride: cw }, { offset: width * height + cw * ch, stride: cw }]
      : [{ offset: 0, stride: width }, { offset: width * height, stride: 2 * cw }];
    try {
      const pixels = new Uint8Array(width * height + 2 * cw * ch);
      await frame.copyTo(pixels, { layout });
      const space = frame.colorSpace || {};
      const format = {
        'x-pixel-format': frame.format,
        // BT.709 for HD cameras (and BT.2020, nearer to it than to BT.601); BT.601 otherwise.
        'x-yuv-matrix': space.matrix === 'bt709' || space.matrix === 'bt2020-ncl' ? 'bt709' : 'bt601',
        'x-yuv-range': space.fullRange ? 'full' : 'limited',
      };
      return { pixels, width, height, format };
    } catch { /* fall through to RGBA */ }
  }
  try {
    const pixels = new Uint8Array(frame.allocationSize({ format: 'RGBA' }));
    await frame.copyTo(pixels, { format: 'RGBA' });
    return { pixels, width, height, format: RGBA };
  } catch {
    grab.width = width; grab.height = height;
    const g = /** @type {CanvasRenderingContext2D} */ (grab.getContext('2d', { willReadFrequently: true }));
    g.drawImage(frame, 0, 0, width, height);
    return { pixels: g.getImageData(0, 0, width, height).data, width, height, format: RGBA };
  }
}

function nextVideoFrame() {
  if (!live.running) return;
  if ('requestVideoFrameCallback' in video) video.requestVideoFrameCallback((_now, meta) => onVideoFrame(meta.captureTime || meta.presentationTime || performance.now()));
  else requestAnimationFrame(() => onVideoFrame(performance.now()));
}

/** Sends the newest camera frame when a slot is free (a slow server drops frames instead of
 * falling behind). */
function onVideoFrame(captured) {
  nextVideoFrame();
  if (inFlight >= live.maxInFlight || !video.videoWidth) return;
  const scale = Math.min(1, 640 / video.videoWidth);
  const width = Math.round(video.videoWidth * scale), height = Math.round(video.videoHeight * scale);
  grab.width = width; grab.height = height;
  const g = grab.getContext('2d', { willReadFrequently: true });
  if (!g) return;
  g.drawImage(video, 0, 0, width, height);
  inFlight++;
  send(g.getImageData(0, 0, width, height).data, width, height, RGBA, captured, performance.now());
}

/** Sends one frame (`format`: its pixel-format headers) in a slot already taken; its weights
 * go on the character when they come back, and the slot goes to the waiting frame. */
function send(pixels, width, height, format, captured, sent) {
  live.format = format['x-pixel-format'];
  // A Blob, not the array itself: Chromium hands a Blob to its network process without copying
  // it through a pipe, which took ~70 ms of the round trip for a 480×480 frame here.
  const headers = { 'x-width': String(width), 'x-height': String(height), ...format };
  fetch('api/capture/live/frame', { method: 'POST', headers, body: new Blob([pixels]) })
    .then(async (response) => {
      const result = await response.json();
      if (!response.ok) throw new Error(result.error || response.statusText);
      if (!live.running || !result.live) return;
      live.weights = result.weights;
      if (result.head || result.bones) turnHead(result.head, result.bones);
      live.server_ms = result.server_ms;
      live.frames++;
      fpsWindow.count++;
      pendingShown = { captured, sent, received: performance.now() };
      applyLayer();
      live.recorded = result.recorded ?? null;
      live.neutral = result.neutral ?? null;
      if (live.neutral === 'user') calibrating = false;
      showNeutral();
      if (result.recorded !== null && result.recorded !== undefined) $('record').textContent = `Stop (${result.recorded})`;
    })
    .catch((e) => { if (live.running) showError(String(e.message || e)); })
    .finally(() => { inFlight--; sendWaiting(); });
}

// Latency is measured when the character showing the frame's weights has been drawn.
onRender(() => {
  if (pendingShown === null) return;
  const drawn = performance.now();
  const { captured, sent, received } = pendingShown;
  const latency = drawn - captured;
  live.stages = { grab_ms: sent - captured, round_trip_ms: received - sent, draw_ms: drawn - received };
  pendingShown = null;
  live.latency_ms = pushMedian(live.latencies, latency, 120);
  const now = performance.now();
  if (now - fpsWindow.start >= 1000) {
    live.fps = fpsWindow.count * 1000 / (now - fpsWindow.start);
    fpsWindow = { start: now, count: 0 };
    $('live-stats').textContent = `Live: ${live.fps.toFixed(1)} fps, ${live.latency_ms.toFixed(0)} ms camera → screen (server ${live.server_ms.toFixed(0)} ms)`;
  }
});

async function stopLive() {
  live.running = false;
  // Let frames already on their way come back before the server stops tracking.
  for (let i = 0; i < 100 && inFlight > 0; i++) await new Promise((r) => setTimeout(r, 20));
  if (stream) for (const t of stream.getTracks()) t.stop();
  stream = null;
  video.hidden = true;
  video.srcObject = null;
  shownCanvas.hidden = true;
  $('live').textContent = 'Webcam (live)';
  $('record').textContent = 'Record';
  /** @type {HTMLButtonElement} */ ($('record')).disabled = true;
  /** @type {HTMLButtonElement} */ ($('calibrate')).disabled = true;
  $('live-neutral').textContent = '';
  try { apply(await api('POST', 'api/capture/live/stop')); } catch { /* the server may be gone */ }
  showTakeFrame();
}
$('live').onclick = () => (live.running ? stopLive() : startLive());

const NEUTRAL_TEXT = {
  user: 'Neutral: calibrated.',
  automatic: 'Neutral: taken while you held still (Calibrate to choose it).',
};
/** Calibrate was pressed and no frame has come back since. */
let calibrating = false;
/** Says which neutral face the live frames are read against. */
function showNeutral() {
  if (!live.running) return;
  $('live-neutral').textContent = calibrating ? 'Calibrating: relax your face…'
    : live.neutral ? NEUTRAL_TEXT[live.neutral] || ''
      : 'No neutral yet: relax and hold still, or press Calibrate.';
}
$('calibrate').onclick = async () => {
  if (await post('api/capture/live/calibrate', {})) { calibrating = true; showNeutral(); }
};
$('record').onclick = async () => {
  const view = currentView();
  const recording = view && view.live && view.live.recording !== null && view.live.recording !== undefined;
  if (!recording) {
    if (await post('api/capture/live/record', { on: true })) $('record').textContent = 'Stop (0)';
  } else if (await post('api/capture/live/record', { on: false })) {
    await stopLive();
  }
};
