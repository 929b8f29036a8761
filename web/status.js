// The page's messages: the error banner and the status line under the settings.

const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

/** Shows `message` in the error banner, or hides it when empty. */
export function showError(message) {
  const box = $('error');
  box.textContent = message;
  box.hidden = !message;
}

/** The error banner for a failed call. */
export function showFailure(error) {
  showError(String((error && error.message) || error));
}

/** Sets the status line. */
export function showStatus(text) {
  $('status').textContent = text;
}
