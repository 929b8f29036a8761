// A lip-sync take's sound: plays with the animation (while it plays forwards, the picture
// follows the sound's own clock, so the two cannot drift), and sounds a short slice when the
// frame is scrubbed by hand, so the animator hears where the mouth is. Owns the <audio>
// element; capture.js says which sound the open take has.

import { currentFrame, isPlaying, onFrame, onPlaying, setClock } from './playback.js';

const audio = new Audio();
audio.preload = 'auto';
/** @type {string|null} */
let source = null;
/** Slices of sound while scrubbing last this long, ms. */
const SLICE_MS = 90;
let sliceTimer = 0;

const seconds = () => currentFrame() / rate;

/** @type {number[]|null} Per frame, the sound's peak (0..1), once decoded. */
let peaks = null;

/** The take's frames per second (its frames are the timeline's). */
let rate = 30;

/** The sound's loudness per frame of the take, for the timeline; null without one. */
export function waveform() { return peaks; }

/** @type {Array<() => void>} Called when the waveform is measured. */
const measuredListeners = [];
/** Calls `fn` whenever a sound's waveform has been measured (the timeline redraws). */
export function onWaveform(fn) { measuredListeners.push(fn); }

/** Decodes `url` and measures its peak per frame. */
async function measure(url) {
  const bytes = await fetch(url).then((r) => r.arrayBuffer());
  const decoded = await new OfflineAudioContext(1, 1, 44100).decodeAudioData(bytes);
  if (url !== source) return;
  const data = decoded.getChannelData(0);
  const per = decoded.sampleRate / rate;
  const frames = Math.ceil(data.length / per);
  peaks = Array.from({ length: frames }, (_, f) => {
    let most = 0;
    for (let i = Math.floor(f * per); i < Math.min(data.length, Math.floor((f + 1) * per)); i++) most = Math.max(most, Math.abs(data[i]));
    return most;
  });
  for (const fn of measuredListeners) fn();
}

/** Plays `url` with the take, whose frames run at `fps` (null: no sound). */
export function setSound(url, fps = 30) {
  if (url === source) return;
  source = url;
  rate = fps;
  peaks = null;
  if (url) measure(url).catch(() => {});
  audio.pause();
  if (url) audio.src = url; else audio.removeAttribute('src');
  setClock(url ? heard : null);
}

/** The sound's time while it is really playing (not paused, not waiting for data). */
function heard() {
  return !audio.paused && !audio.seeking && audio.readyState >= 3 ? audio.currentTime : null;
}

/** The sound as scripts and tests see it. */
export const sound = {
  get source() { return source; },
  get playing() { return !audio.paused; },
  get time() { return audio.currentTime; },
  /** Frames whose loudness the timeline draws (0 before the sound is decoded). */
  get waveformFrames() { return peaks ? peaks.length : 0; },
};

onPlaying((playing) => {
  if (!source) return;
  window.clearTimeout(sliceTimer);
  if (playing) {
    audio.currentTime = seconds();
    audio.play().catch(() => {});
  } else {
    audio.pause();
  }
});

onFrame(() => {
  if (!source) return;
  const t = seconds();
  if (isPlaying()) {
    // While the sound plays the picture follows it (playback's clock); before it starts
    // (loading, seeking) the picture leads and the sound joins it.
    if (heard() === null && Math.abs(audio.currentTime - t) > 0.1 && !audio.seeking) audio.currentTime = t;
    return;
  }
  // Scrubbing: a slice of sound at the frame.
  audio.currentTime = Math.min(t, Number.isFinite(audio.duration) ? audio.duration : t);
  audio.play().catch(() => {});
  window.clearTimeout(sliceTimer);
  sliceTimer = window.setTimeout(() => { if (!isPlaying()) audio.pause(); }, SLICE_MS);
});
