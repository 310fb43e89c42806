// The session's HTTP routes (docs/stream.md#browsers' HTTP routes) for the page: errors thrown
// with the server's message, and the delay a rate limit asks for.

export class SessionApi {
  constructor(session, token) {
    this.query = `session=${encodeURIComponent(session)}&token=${encodeURIComponent(token)}`;
  }

  async call(method, path, { body, params = '' } = {}) {
    const response = await fetch(`${path}?${this.query}${params}`, {
      method, body, headers: body ? { 'Content-Type': 'application/json' } : {} });
    let json = null;
    try { json = await response.json(); } catch (_) { /* not JSON */ }
    if (!response.ok) {
      const error = new Error((json && json.error) || `${method} ${path}: ${response.status} ${response.statusText}`);
      error.status = response.status;
      error.retryAfterS = Number(response.headers.get('Retry-After') || 0);
      throw error;
    }
    return json;
  }

  /// {session, role, bake_id, version, lights, presets}.
  session() { return this.call('GET', '/v1/session'); }
  /// {version}: the version the stream carries the set in.
  setLights(json) { return this.call('POST', '/v1/lights', { body: json }); }
  savePreset(name, json) {
    return this.call('PUT', '/v1/presets', { body: json, params: `&name=${encodeURIComponent(name)}` });
  }
  deletePreset(name) { return this.call('DELETE', '/v1/presets', { params: `&name=${encodeURIComponent(name)}` }); }
  presets() { return this.call('GET', '/v1/presets'); }
}
