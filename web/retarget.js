// The character's retarget map in the Capture tab: which of its own shapes answer to each of
// ARKit's 52 channels (by name, by geometry, or as the user set them), made on the server in
// the background, and edited a row at a time: `shape:0.8, other` in a row's field, or nothing
// for a channel that should move nothing. The server checks every name and weight.

import { api } from './api.js';
import { showError } from './status.js';
import { showMarks } from './face-marks.js';

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

const FROM = { by_name: 'by name', geometry: 'geometry', user: 'set by you' };

/** Where answers go: the Capture tab's state (given by `showMap`). */
let applyState = (/** @type {any} */ _view) => {};

/** Whether the last map said that no face was found (the section opens once when it does). */
let noFace = false;

/** A row's shapes as the field shows them. */
const written = (/** @type {[string, number][]} */ shapes) =>
  shapes.map(([s, w]) => (Math.abs(w - 1) < 5e-3 ? s : `${s}:${w.toFixed(2)}`)).join(', ');

/** The field's text as the row's shapes, or an error naming the item that is wrong. */
export function parseRow(/** @type {string} */ text) {
  /** @type {Record<string, number>} */
  const shapes = {};
  for (const item of text.split(',').map((s) => s.trim()).filter(Boolean)) {
    const at = item.lastIndexOf(':');
    const name = at < 0 ? item : item.slice(0, at).trim();
    const weight = at < 0 ? 1 : Number(item.slice(at + 1));
    if (!name || !Number.isFinite(weight)) throw new Error(`'${item}': write SHAPE or SHAPE:WEIGHT`);
    shapes[name] = weight;
  }
  return shapes;
}

async function send(/** @type {string} */ method, /** @type {string} */ path, /** @type {any} */ body) {
  try { showError(''); applyState(await api(method, path, body)); }
  catch (e) { showError(String(/** @type {any} */ (e).message || e)); }
}

/** Shows `map` (the state's `retarget`); `apply` takes the state the server answers with. */
export function showMap(/** @type {any} */ map, /** @type {(view: any) => void} */ apply, /** @type {boolean} */ busy) {
  applyState = apply;
  const use = map.in_use ? 'it reads capture' : map.loaded ? 'the adapter reads capture instead' : '';
  $('retarget-info').textContent = map.loaded
    ? `Map: ${map.path}${map.seconds ? ` (made in ${map.seconds.toFixed(1)} s)` : ''}; ${use}.`
    : `${map.note ? `${map.note} ` : ''}${map.needed
      ? (map.note ? '' : 'No map yet: it is made (in seconds) when a capture, a clip, speech or a live input needs it, or now.')
      : 'Every channel is driven by its ARKit name; a map is not needed.'}`;
  const make = /** @type {HTMLButtonElement} */ ($('retarget-make'));
  make.textContent = map.loaded ? 'Make again' : 'Make map';
  make.disabled = busy;
  showMarks(map, apply, busy);
  if (map.no_face && !noFace) /** @type {HTMLDetailsElement} */ ($('retarget-section')).open = true;
  noFace = map.no_face;
  const table = $('retarget-rows');
  if (document.activeElement && table.contains(document.activeElement)) return;
  table.replaceChildren(...map.rows.map((/** @type {any} */ row) => {
    const tr = document.createElement('tr');
    const channel = document.createElement('td');
    channel.textContent = row.channel;
    const cell = document.createElement('td');
    const field = document.createElement('input');
    field.value = written(row.shapes);
    field.setAttribute('aria-label', `shapes answering to ${row.channel}`);
    field.onchange = () => {
      let shapes;
      try { shapes = parseRow(field.value); } catch (e) { showError(`${row.channel}: ${/** @type {any} */ (e).message}`); return; }
      send('PUT', 'api/capture/retarget/row', { channel: row.channel, shapes });
    };
    cell.append(field);
    // Where the row comes from, under the channel's name: the field keeps the row's width.
    const from = document.createElement('div');
    from.className = 'note';
    const percent = row.explained != null ? `${Math.round(100 * row.explained)}%` : '';
    if (row.from === 'none') {
      from.textContent = percent ? `no shape (the best fit: ${percent})` : 'no shape';
    } else {
      const twin = row.with_twin ? ` with ${row.with_twin}` : '';
      const share = percent ? ` ${percent}${row.with_twin ? ' of both' : ''}` : '';
      from.textContent = `${FROM[row.from] ?? row.from}${twin}${share}${row.calibrated ? ', calibrated' : ''}`;
    }
    channel.append(from);
    tr.append(channel, cell);
    return tr;
  }));
}

$('retarget-make').onclick = () => {
  const remake = $('retarget-make').textContent !== 'Make map';
  send('POST', 'api/capture/retarget', { remake });
};
