// The character's blendshapes in the Sketch tab: search them, point at one to see the region it
// moves, click one to add its action at the playhead (a stroke from the vertex it moves most to
// where weight 1 takes it, drawn in half a second).

import { api } from './api.js';
import { showGhost } from './overlays.js';
import { currentFrame } from './playback.js';
import { showError, showFailure } from './status.js';
import * as store from './store.js';

const list = /** @type {HTMLElement} */ (document.getElementById('shape-list'));
const search = /** @type {HTMLInputElement} */ (document.getElementById('shape-search'));
/** @type {any[]} */
let anchors = [];
let loadedFor = '';

async function load(character) {
  loadedFor = character;
  try { anchors = await api('GET', 'api/character/anchors'); } catch (e) { anchors = []; showFailure(e); }
  draw();
}

function draw() {
  const query = search.value.trim().toLowerCase();
  list.innerHTML = '';
  for (const anchor of anchors) {
    if (anchor.vertex === null || (query && !anchor.name.toLowerCase().includes(query))) continue;
    const item = document.createElement('li');
    item.textContent = anchor.name;
    item.title = `${anchor.name}: click to add its action at the playhead`;
    item.onmouseenter = () => showGhost(anchor.name);
    item.onmouseleave = () => showGhost(null);
    item.onclick = () => add(anchor);
    list.appendChild(item);
  }
}

async function add(anchor) {
  const samples = Array.from({ length: 11 }, (_, i) => ({ t: i * 0.05, p: anchor.rest.map((v, j) => v + (anchor.target[j] - v) * i / 10) }));
  const settings = store.state().settings;
  try {
    const state = await api('POST', 'api/strokes', { samples, start_frame: Math.round(currentFrame()), symmetry: !!settings.symmetry });
    store.select(state.added);
    store.setState(state, true);
    const rejected = state.rejected.find((r) => r.stroke === state.added);
    showError(rejected ? `${anchor.name} made no action: ${rejected.reason}` : '');
  } catch (e) { showFailure(e); }
}

search.addEventListener('input', draw);
store.onState((state) => { if (state.character !== loadedFor) load(state.character); });
