// The studio's HTTP/JSON API (crates/studio/API.md): one fetch wrapper that sends JSON or bytes
// and turns the server's `{"error": …}` answers into thrown Errors with its message.

/** Calls the API; resolves with the parsed JSON answer (or null), rejects with the error. */
export async function api(method, path, body, headers = {}) {
  const init = { method, headers: { ...headers } };
  if (body !== undefined) {
    if (body instanceof ArrayBuffer || body instanceof Blob) { init.body = body; }
    else { init.body = JSON.stringify(body); init.headers['content-type'] = 'application/json'; }
  }
  const response = await fetch(path, init);
  const text = await response.text();
  let json = null;
  try { json = text ? JSON.parse(text) : null; } catch { json = null; }
  if (!response.ok) throw new Error(json && json.error ? json.error : text || response.statusText);
  return json;
}
