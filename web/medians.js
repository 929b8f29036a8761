// Running medians of the page's live measurements (latency, delays): the newest values kept,
// their median read. Used by live.js and voice.js.

/** Adds `value` to `list`, keeping the newest `keep`; returns their median. */
export function pushMedian(/** @type {number[]} */ list, /** @type {number} */ value, keep) {
  list.push(value);
  if (list.length > keep) list.shift();
  return list.slice().sort((a, b) => a - b)[Math.floor(list.length / 2)];
}
