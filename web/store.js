// The sketch's document as the server last described it (GET /api/state), the character's
// facts (GET /api/character) and the selected action. This module owns them; others read them
// here and change them only through the server (`run`) or `select`.

import { api } from './api.js';
import { showError, showFailure } from './status.js';

let current = /** @type {any} */ (null);
let characterView = /** @type {any} */ (null);
let selected = /** @type {number|null} */ (null);
/** Every selected action's stroke (the last one clicked is `selected`). */
let group = /** @type {Set<number>} */ (new Set());
/** @type {((state: any, rebake: boolean) => void)[]} */
const stateListeners = [];
/** @type {(() => void)[]} */
const selectionListeners = [];

/** The last state (`null` before the first). */
export const state = () => current;
/** The character (`name`, `vertices`, `blendshapes`, `bounds`, `head`, `diagonal`, `generated`, `vrm`). */
export const character = () => characterView;
/** The selected action's stroke index, or null. */
export const selection = () => selected;

/** Calls `listener(state, rebake)` after every new state; `rebake` when the animation changed. */
export function onState(listener) { stateListeners.push(listener); }

const characterListeners = [];
/** Calls `listener(character)` each time the character's facts are read (at start, and after
 * another character is opened). */
export function onCharacter(listener) { characterListeners.push(listener); }
/** Calls `listener()` when the selection changes. */
export function onSelection(listener) { selectionListeners.push(listener); }

/** Counts the states taken, so that a poll answered after a newer state is dropped. */
let taken = 0;

/** Takes a state the server answered with. */
export function setState(next, rebake) {
  taken++;
  current = next;
  // Strokes that no longer exist (deleted, undone) leave the selection.
  const count = next && next.actions ? Math.max(-1, ...next.actions.map((a) => a.stroke)) + 1 : 0;
  group = new Set([...group].filter((s) => s < count));
  if (selected !== null && selected >= count) selected = null;
  for (const listener of stateListeners) listener(next, rebake);
}

/** Reads the character's facts again (after an upload). */
export async function loadCharacter() {
  characterView = await api('GET', 'api/character');
  for (const listener of characterListeners) listener(characterView);
  return characterView;
}

/** The strokes of every selected action. */
export const selectedGroup = () => group;

/** Selects the action of stroke `index` (or none); with `add`, adds it to the selection (or
 * takes it out again). */
export function select(index, add = false) {
  if (add && index !== null) {
    if (group.has(index) && group.size > 1) { group.delete(index); selected = [...group][group.size - 1]; }
    else { group.add(index); selected = index; }
  } else {
    if (selected === index && group.size <= 1) return;
    selected = index;
    group = new Set(index === null ? [] : [index]);
  }
  for (const listener of selectionListeners) listener();
}

/** Sends a change; the answer becomes the state (and the animation is baked again). Errors go to
 * the banner; resolves with the state, or null. */
export async function run(method, path, body) {
  try { const next = await api(method, path, body); setState(next, true); showError(''); return next; }
  catch (e) { showFailure(e); return null; }
}

// Another page of the same studio (a headset, a second desktop) may change the project: look
// for a different state every second while this page is visible, and take it when it differs.
const FOLLOW_MS = 1000;
setInterval(async () => {
  if (document.hidden || !current) return;
  const before = taken;
  try {
    const next = await api('GET', 'api/state');
    if (before !== taken) return;
    const changed = JSON.stringify(next.actions) !== JSON.stringify(current.actions)
      || JSON.stringify(next.settings) !== JSON.stringify(current.settings)
      || next.fps !== current.fps || next.can_undo !== current.can_undo || next.can_redo !== current.can_redo;
    if (changed) setState(next, true);
  } catch { /* the server is away: the next poll tries again */ }
}, FOLLOW_MS);
