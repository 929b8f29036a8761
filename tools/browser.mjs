// Debian's chromium as every browser script here launches it (playwright-core): headless, drawn
// by SwiftShader (software GL, as on a machine without a GPU), nothing fetched or synced.
import { chromium } from 'playwright-core';

const FLAGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--no-first-run', '--use-angle=swiftshader',
  '--enable-unsafe-swiftshader'];

/** Launches chromium (`$CHROMIUM`, else /usr/bin/chromium) with the common flags and `extra`
 * ones (a fake camera or microphone). */
export function launch(extra = []) {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: [...FLAGS, ...extra],
  });
}

/** A check for the script `name`: throws `name: message` when `ok` is false, so the script's
 * `finally` closes the browser and node exits non-zero with the message. */
export const checker = (name) => (ok, message) => { if (!ok) throw new Error(`${name}: ${message}`); };
