// The Capture tab's copy of the server's take state (/api/capture/state), and the one way to
// change it: send an edit and show the answer. capture.js draws each state it is told of; the
// live sources (live.js, vmc.js, voice.js) read the state and send edits through here, so none
// of them imports the module that draws it.

import { api } from './api.js';
import { showError } from './status.js';

/** @type {any} The last /api/capture/state. */
let view = null;
/** @type {Array<(v: any, previous: any) => void>} */
const viewListeners = [];
/** @type {Array<() => void>} */
const frameListeners = [];

/** The last capture state (null before the first). */
export const currentView = () => view;

/** Calls `fn(state, previous)` for every capture state the server answers with. */
export function onView(fn) { viewListeners.push(fn); }

/** Shows a capture state the server answered with. */
export function apply(v) {
  const previous = view;
  view = v;
  for (const fn of viewListeners) fn(v, previous);
}

/** Sends an edit to the take and shows the answer; false (with the error shown) on failure. */
export async function post(path, body) {
  try { showError(''); apply(await api('POST', path, body)); return true; }
  catch (e) { showError(String(e.message || e)); return false; }
}

/** Calls `fn` when a live source asks for the take's current frame to be shown again. */
export function onShowTakeFrame(fn) { frameListeners.push(fn); }

/** Shows the take's current frame again (after live mode, which drew over it). */
export function showTakeFrame() { for (const fn of frameListeners) fn(); }
