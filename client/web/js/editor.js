// The session panel: light gizmos over the view, each light's switch, colour and intensity,
// the session's named presets, the cameras and "share this view". Editors change lights
// (dragging a gizmo moves a point or spot light in the plane facing the camera, or turns a
// directional light, whose gizmo sits up-light of the scene's centre); viewers see the same
// gizmos move and cannot change them. Changes are previewed at once (direct light and shadows
// drawn here) and sent to the server, one request at a time, the newest edit winning; the
// stream's frames then bring the caches, and the lights other editors set.
import { lightSetJson, lightSetFromJson } from './lights.js';
import { add, dot, length, normalize, scale, sub } from './math.js';

const clone = (set) => JSON.parse(JSON.stringify(set, (k, v) => (v === Infinity ? 'Infinity' : v)),
                                  (k, v) => (v === 'Infinity' ? Infinity : v));

/// Linear colour factor ↔ "#rrggbb" (sRGB-encoded, as colour inputs show it).
const toHex = (c) => '#' + c.map((v) => {
  const x = Math.min(1, Math.max(0, v));
  const s = x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055;
  return Math.round(255 * s).toString(16).padStart(2, '0');
}).join('');
const fromHex = (hex) => [1, 3, 5].map((i) => {
  const s = parseInt(hex.slice(i, i + 2), 16) / 255;
  return s <= 0.04045 ? s / 12.92 : Math.pow((s + 0.055) / 1.055, 2.4);
});

export class SessionPanel {
  /// `role` "editor" or "viewer"; viewerToken the session's viewer token when the page knows
  /// it (else null); onPreview() when the lights to draw changed locally.
  constructor({ root, canvas, scene, camera, controls, api, role, session, token, viewerToken,
                onPreview }) {
    Object.assign(this, { root, canvas, scene, camera, controls, api, role, session, token,
                          viewerToken, onPreview });
    this.editor = role === 'editor';
    this.streamSet = null;     // the newest frame's light set
    this.streamVersion = 0;
    this.local = null;         // the editor's working copy while its edits are on their way
    this.awaited = 0;          // the version the last accepted edit produces
    this.inFlight = false;
    this.pending = false;
    this.offIntensity = new Map();  // a switched-off light's intensity, to switch it on again
    this.presets = [];
    const b = scene.bounds;
    this.centre = scale(add(b.min, b.max), 0.5);
    this.diagonal = length(sub(b.max, b.min));
    this.gizmos = document.createElement('div');
    this.gizmos.id = 'gizmos';
    document.body.appendChild(this.gizmos);
    this.build();
  }

  /// The lights to draw: the editor's own while its edits are on their way, else the stream's.
  lights() { return this.local || this.streamSet; }

  /// A frame brought `set` (lightSetOf) at `version`.
  streamed(set, version) {
    const changed = set !== this.streamSet;
    this.streamSet = set;
    this.streamVersion = version;
    if (this.local && !this.inFlight && !this.pending && version >= this.awaited) {
      this.local = null;
      this.refresh();
    } else if (changed && !this.local) {
      this.refresh();
    }
  }

  // ---- the panel ----

  build() {
    const panel = document.createElement('div');
    panel.id = 'panel';
    panel.innerHTML = `
      <div class="role">${this.editor ? 'editor' : 'viewer: lights are read-only'}</div>
      <h3>View</h3>
      <div class="row"><select id="cameras"></select><button id="mode" title="F">orbit</button></div>
      <div class="row"><button id="share">${this.shareLabel()}</button>
        ${this.editor && this.viewerToken ? '<button id="share-edit">Share for editing</button>' : ''}</div>
      <h3>Lights</h3>
      <div id="lights"></div>
      <h3>Presets</h3>
      <div class="row"><select id="presets"></select><button id="apply">Apply</button></div>
      <div class="row editor-only"><button id="save">Save as…</button><button id="delete">Delete</button></div>
      <div id="message"></div>`;
    this.root.appendChild(panel);
    this.panel = panel;
    const $ = (id) => panel.querySelector(`#${id}`);
    if (!this.editor) panel.querySelectorAll('.editor-only, #apply').forEach((e) => { e.disabled = true; });
    const cameras = $('cameras');
    cameras.innerHTML = '<option value="">camera…</option>' + (this.scene.cameras || []).map(
      (c, i) => `<option value="${i}">${i + 1}: ${c.name || `camera ${i}`}</option>`).join('');
    cameras.onchange = () => {
      if (cameras.value !== '') this.controls.set(this.controls.sceneCameras[Number(cameras.value)]);
      cameras.value = '';
    };
    $('mode').onclick = () => { this.controls.mode = this.controls.mode === 'walk' ? 'orbit' : 'walk'; this.refreshMode(); };
    $('share').onclick = () => this.share(false);
    if ($('share-edit')) $('share-edit').onclick = () => this.share(true);
    $('apply').onclick = () => this.applyPreset($('presets').value);
    $('save').onclick = () => this.savePreset();
    $('delete').onclick = () => this.deletePreset($('presets').value);
  }

  refreshMode() { this.panel.querySelector('#mode').textContent = this.controls.mode; }

  say(text, error = false) {
    const m = this.panel.querySelector('#message');
    m.textContent = text;
    m.classList.toggle('error', error);
  }

  /// Rows of the lights panel and the gizmos, from lights().
  refresh() {
    const set = this.lights();
    if (!set) return;
    const list = this.panel.querySelector('#lights');
    list.innerHTML = '';
    for (const light of set.lights) {
      const row = document.createElement('div');
      row.className = 'light';
      row.dataset.lightId = light.id;
      const on = light.intensity > 0;
      const remembered = this.offIntensity.get(light.id) || 1;
      row.innerHTML = `
        <label><input type="checkbox" class="switch" ${on ? 'checked' : ''}> ${light.id}</label>
        <span class="type">${light.type}</span>
        <input type="color" class="color" value="${toHex(light.color)}">
        <input type="number" class="intensity" min="0" step="any" value="${Number((on ? light.intensity : 0).toPrecision(4))}">
        <input type="range" class="dim" min="-6" max="3" step="0.1" value="0" title="dim or brighten (stops)">`;
      row.querySelectorAll('input').forEach((i) => { i.disabled = !this.editor; });
      row.querySelector('.switch').onchange = (e) => this.edit(light.id, (l) => {
        if (e.target.checked) l.intensity = remembered;
        else { this.offIntensity.set(l.id, l.intensity); l.intensity = 0; }
      });
      row.querySelector('.color').oninput = (e) => this.edit(light.id, (l) => { l.color = fromHex(e.target.value); });
      row.querySelector('.intensity').onchange = (e) => this.edit(light.id, (l) => {
        const v = Number(e.target.value);
        if (Number.isFinite(v) && v >= 0) l.intensity = v;
      });
      const dim = row.querySelector('.dim');
      let base = null;
      dim.onpointerdown = () => { base = this.find(light.id).intensity; };
      dim.oninput = () => {
        if (base === null) base = this.find(light.id).intensity;
        this.edit(light.id, (l) => { l.intensity = base * Math.pow(2, Number(dim.value)); }, false);
      };
      dim.onchange = () => { base = null; dim.value = 0; this.refresh(); };
      list.appendChild(row);
    }
    this.placeGizmos();
  }

  find(id) { return this.lights().lights.find((l) => l.id === id); }

  /// Applies `change` to light `id` of the working copy, previews it and sends it.
  edit(id, change, refresh = true) {
    if (!this.editor) return;
    // A new object per edit: the renderer takes a set it has not drawn as new lights.
    this.local = clone(this.local || this.streamSet);
    const light = this.local.lights.find((l) => l.id === id);
    if (!light) return;
    change(light);
    this.onPreview();
    if (refresh) this.refresh();
    else this.placeGizmos();
    this.push();
  }

  /// Sends the working copy: one request at a time, the newest copy when it returns.
  async push() {
    if (this.inFlight) {
      this.pending = true;
      return;
    }
    this.inFlight = true;
    this.pending = false;
    try {
      const reply = await this.api.setLights(lightSetJson(this.local));
      this.awaited = reply.version;
      this.say(`version ${reply.version} set`);
    } catch (error) {
      if (error.status === 429 && error.retryAfterS > 0) {
        this.say(error.message, true);
        await new Promise((r) => setTimeout(r, 1000 * error.retryAfterS));
        this.pending = true;
      } else {
        // Refused: the stream's lights stand.
        this.say(error.message, true);
        this.local = null;
        this.pending = false;
        this.onPreview();
        this.refresh();
      }
    } finally {
      this.inFlight = false;
    }
    if (this.pending && this.local) this.push();
  }

  // ---- gizmos ----

  /// Where a point appears on the canvas (CSS pixels from its top left), or null behind the eye.
  project(p) {
    const c = this.camera;
    const { forward, right, up } = c.basis();
    const d = sub(p, c.eye);
    const depth = dot(d, forward);
    if (!(depth > 0)) return null;
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    const tanHalf = Math.tan(c.fovyDegrees * Math.PI / 360);
    const x = dot(d, right) / (depth * tanHalf * (w / h));
    const y = dot(d, up) / (depth * tanHalf);
    return [(x + 1) * w / 2, (1 - y) * h / 2];
  }

  /// The camera ray through a canvas point: {origin, direction}.
  ray(px, py) {
    const c = this.camera;
    const { forward, right, up } = c.basis();
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    const tanHalf = Math.tan(c.fovyDegrees * Math.PI / 360);
    const x = (2 * px / w - 1) * tanHalf * (w / h), y = (1 - 2 * py / h) * tanHalf;
    return { origin: c.eye, direction: normalize(add(forward, add(scale(right, x), scale(up, y)))) };
  }

  /// Where a light's gizmo sits: its position, or for a directional light the point up-light
  /// of the scene's centre.
  anchor(light) {
    return light.type === 'directional' ? sub(this.centre, scale(light.direction, 0.6 * this.diagonal))
                                        : light.position;
  }

  placeGizmos() {
    const set = this.lights();
    if (!set) return;
    const rect = this.canvas.getBoundingClientRect();
    const ids = new Set(set.lights.map((l) => l.id));
    for (const g of [...this.gizmos.children]) if (!ids.has(g.dataset.lightId)) g.remove();
    for (const light of set.lights) {
      let g = this.gizmos.querySelector(`[data-light-id="${CSS.escape(light.id)}"]`);
      if (!g) {
        g = document.createElement('div');
        g.className = `gizmo ${light.type}`;
        g.dataset.lightId = light.id;
        g.title = light.id;
        if (this.editor) this.draggable(g, light.id);
        this.gizmos.appendChild(g);
      }
      const at = this.project(this.anchor(light));
      g.style.display = at ? '' : 'none';
      if (!at) continue;
      g.style.left = `${rect.left + at[0]}px`;
      g.style.top = `${rect.top + at[1]}px`;
      g.style.background = light.intensity > 0 ? toHex(light.color) : 'transparent';
      g.classList.toggle('off', !(light.intensity > 0));
    }
  }

  draggable(g, id) {
    g.addEventListener('pointerdown', (e) => {
      e.stopPropagation();
      g.setPointerCapture(e.pointerId);
      const light = this.find(id);
      // The plane through the gizmo facing the camera.
      const anchor = this.anchor(light);
      const normal = this.camera.basis().forward;
      const rect = this.canvas.getBoundingClientRect();
      const move = (ev) => {
        const { origin, direction } = this.ray(ev.clientX - rect.left, ev.clientY - rect.top);
        const along = dot(direction, normal);
        if (!(Math.abs(along) > 1e-6)) return;
        const t = dot(sub(anchor, origin), normal) / along;
        if (!(t > 0)) return;
        const p = add(origin, scale(direction, t));
        this.edit(id, (l) => {
          if (l.type === 'directional') l.direction = normalize(sub(this.centre, p));
          else l.position = p;
        }, false);
      };
      const up = () => {
        g.removeEventListener('pointermove', move);
        g.removeEventListener('pointerup', up);
        this.refresh();
      };
      g.addEventListener('pointermove', move);
      g.addEventListener('pointerup', up);
    });
  }

  // ---- presets and sharing ----

  setPresets(presets) {
    this.presets = presets;
    const select = this.panel.querySelector('#presets');
    const current = select.value;
    select.innerHTML = presets.length ? presets.map((p) => `<option>${p.name}</option>`).join('')
                                      : '<option value="">no presets</option>';
    if (presets.some((p) => p.name === current)) select.value = current;
  }

  async applyPreset(name) {
    const preset = this.presets.find((p) => p.name === name);
    if (!preset || !this.editor) return;
    this.local = lightSetFromJson(preset.lights);
    this.onPreview();
    this.refresh();
    this.push();
  }

  async savePreset() {
    const name = prompt('Save the current lights as preset:');
    if (!name) return;
    try {
      await this.api.savePreset(name, lightSetJson(this.lights()));
      this.setPresets((await this.api.presets()).presets);
      this.panel.querySelector('#presets').value = name;
      this.say(`preset "${name}" saved`);
    } catch (error) {
      this.say(error.message, true);
    }
  }

  async deletePreset(name) {
    if (!name) return;
    try {
      await this.api.deletePreset(name);
      this.setPresets((await this.api.presets()).presets);
      this.say(`preset "${name}" deleted`);
    } catch (error) {
      this.say(error.message, true);
    }
  }

  /// "Share this view" says what the link grants when that is more than viewing.
  shareLabel() {
    return this.editor && !this.viewerToken ? 'Share this view (lets its reader edit)' : 'Share this view';
  }

  /// A link to this session and view: with the viewer token where the page knows it, unless
  /// `editing` (then, and without one, this page's token: an editor's lets its reader edit).
  shareUrl(editing = false) {
    const token = !editing && this.viewerToken ? this.viewerToken : this.token;
    const q = new URLSearchParams({ session: this.session, token });
    if (editing && this.viewerToken) q.set('viewer', this.viewerToken);
    q.set('camera', this.camera.toString());
    return `${location.origin}/?${q}`;
  }

  async share(editing) {
    const url = this.shareUrl(editing);
    try {
      await navigator.clipboard.writeText(url);
      this.say(editing ? 'link for editing copied' : 'link to this view copied');
    } catch (_) {
      prompt('Link to this view:', url);
    }
  }
}
