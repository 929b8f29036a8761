// Tells a user on a slow display (software rendering, an old GPU) about the viewport for
// machines without a GPU, `?fast`, which sketching needs most: drawing a stroke waits on every
// frame. It watches the frames that draw and, when most of the recent ones took longer than
// SLOW_MS, shows a link to the same page with `?fast`, in a corner, over nothing one clicks on
// the character. Never in `?fast` itself or in a headset.

import { FAST, onRender, onTick, renderer } from './scene.js';

/** A frame longer than this, in milliseconds, is slow. */
const SLOW_MS = 120;
/** How many slow frames out of the last `WINDOW` drawn show the hint. */
const SLOW_FRAMES = 8;
const WINDOW = 12;

const hint = /** @type {HTMLElement} */ (document.getElementById('slow-hint'));
const link = /** @type {HTMLAnchorElement} */ (document.getElementById('slow-hint-link'));
/** @type {boolean[]} */
const recent = [];
let lastTick = 0;
let drew = false;

if (!FAST && hint && link) {
  const url = new URL(location.href);
  url.searchParams.set('fast', '');
  link.href = url.toString().replace('fast=', 'fast');
  // A frame's length is from its tick to the next one; only frames that drew count (an idle
  // page draws nothing and its frames say nothing about the display).
  onTick((now) => {
    if (drew && lastTick && hint.hidden && !renderer.xr.isPresenting) {
      recent.push(now - lastTick > SLOW_MS);
      if (recent.length > WINDOW) recent.shift();
      if (recent.filter(Boolean).length >= SLOW_FRAMES) hint.hidden = false;
    }
    drew = false;
    lastTick = now;
    return false;
  });
  onRender(() => { drew = true; });
}
