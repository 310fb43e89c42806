// The browser client's page: /?session=ID&token=T[&viewer=VIEWER_TOKEN]
// [&camera=ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy][&scene_camera=N][&size=WxH][&samples=N]
// [&exposure=X][&shadow_map_size=N][&ui=0]. Fetches the scene and the
// wire schema, streams the session's caches and draws them as `picclient render` does.
// window.pic reports progress to tests and scripts.
import { SessionApi } from './api.js';
import { Camera } from './camera.js';
import { Controls } from './controls.js';
import { SessionPanel } from './editor.js';
import { lightSetJson, lightSetOf } from './lights.js';
import { Renderer } from './renderer.js';
import { parseScene } from './scene.js';
import { Stream } from './stream.js';
import { add, length, normalize, scale, sub } from './math.js';

const status = document.getElementById('status');
const stats = document.getElementById('stats');
const state = (window.pic = { state: 'loading', error: null, version: 0, part: 0,
                              drawnVersion: 0, drawnPart: -1, draws: 0, frames: 0, latencies: [] });

function report(text, error = false) {
  status.textContent = text;
  status.classList.toggle('error', error);
}

function fail(message) {
  state.state = 'error';
  state.error = message;
  report(message, true);
  console.error(message);
}

/// The URL's parameters, checked; throws naming the bad one.
function viewParams() {
  const q = new URLSearchParams(location.search);
  const session = q.get('session'), token = q.get('token');
  if (!session) throw new Error('the URL names no session (?session=ID&token=T)');
  if (!token) throw new Error('the URL carries no token (?session=ID&token=T)');
  let size = null;
  if (q.has('size')) {
    const m = /^(\d+)x(\d+)$/.exec(q.get('size'));
    if (!m || +m[1] < 1 || +m[2] < 1 || +m[1] > 16384 || +m[2] > 16384)
      throw new Error(`size "${q.get('size')}": expected WxH, each 1..16384`);
    size = [+m[1], +m[2]];
  }
  const number = (name, fallback, ok) => {
    if (!q.has(name)) return fallback;
    const v = Number(q.get(name));
    if (!ok(v)) throw new Error(`${name} "${q.get(name)}" is out of range`);
    return v;
  };
  return {
    session, token, size,
    // An editor's page may carry the session's viewer token too: its share link then grants
    // viewing only (the server keeps digests, not tokens, so it cannot say it).
    viewer: q.get('viewer') || null,
    camera: q.has('camera') ? Camera.parse(q.get('camera')) : null,
    sceneCamera: number('scene_camera', 0, (v) => Number.isInteger(v) && v >= 0),
    samples: number('samples', 4, (v) => Number.isInteger(v) && v >= 1 && v <= 64),
    exposure: number('exposure', 1, (v) => Number.isFinite(v) && v > 0),
    shadowMapSize: number('shadow_map_size', 1024, (v) => Number.isInteger(v) && v >= 16 && v <= 8192),
    ui: q.get('ui') !== '0',
  };
}

const sceneCameras = (scene) =>
  (scene.cameras || []).map((c) => new Camera(c.eye, c.target, c.up, c.fovy_degrees));

/// The scene's camera `index`, or a view of its bounds when it has none.
function startCamera(scene, params) {
  if (params.camera) return params.camera;
  const cameras = sceneCameras(scene);
  if (cameras.length > 0) {
    if (params.sceneCamera >= cameras.length)
      throw new Error(`scene_camera ${params.sceneCamera}: the scene has ${cameras.length} cameras`);
    const c = cameras[params.sceneCamera];
    return new Camera([...c.eye], [...c.target], [...c.up], c.fovyDegrees);
  }
  const centre = scale(add(scene.bounds.min, scene.bounds.max), 0.5);
  const diagonal = length(sub(scene.bounds.max, scene.bounds.min));
  return new Camera(add(centre, scale(normalize([1, 0.6, 1.4]), 0.9 * diagonal)), centre, [0, 1, 0], 50);
}

async function fetchOk(url, what) {
  const response = await fetch(url);
  if (!response.ok) {
    let message = `${response.status} ${response.statusText}`;
    try { message = (await response.json()).error || message; } catch (_) { /* not JSON */ }
    throw new Error(`${what}: ${message}`);
  }
  return response;
}

async function main() {
  const params = viewParams();
  document.body.classList.toggle('noui', !params.ui);
  document.body.classList.toggle('fill', !params.size);
  const started = performance.now();
  const query = `session=${encodeURIComponent(params.session)}&token=${encodeURIComponent(params.token)}`;
  report('loading the scene…');
  const [sceneBytes, protoText, shBasis] = await Promise.all([
    fetchOk(`/v1/scene?${query}`, 'scene').then((r) => r.arrayBuffer()),
    fetchOk('/v1/pic.proto', 'wire schema').then((r) => r.text()),
    fetchOk('/v1/sh_basis.glsl', 'SH basis').then((r) => r.text()),
  ]);
  const scene = parseScene(new Uint8Array(sceneBytes));
  const FrameType = protobuf.parse(protoText, { keepCase: true }).root.lookupType('pic.v1.Frame');
  const canvas = document.getElementById('view');
  const renderer = new Renderer(canvas, scene, shBasis, { shadowMapSize: params.shadowMapSize });
  const camera = startCamera(scene, params);
  state.sceneBytes = scene.bytes;
  state.sceneMs = performance.now() - started;
  report(`scene ${scene.scene_name} (${(scene.bytes / 1048576).toFixed(1)} MiB); waiting for the stream…`);

  // Drawing: at once after a change; while the view moves, one sample per pixel, and the
  // full count once it has been still for a moment.
  // A frame is requested only when something changed, so that an idle tab costs nothing.
  let dirty = false, moving = 0, drawnLights = null, scheduled = false;
  let pending = null;  // what the newest frame brought: {version, part, lightsSetNs, received}
  const schedule = () => {
    if (scheduled) return;
    scheduled = true;
    requestAnimationFrame(frame);
  };
  const redraw = () => {
    dirty = true;
    schedule();
  };

  // The session UI: cameras, light gizmos and panel, presets (not with ui=0).
  let panel = null, controls = null;
  if (params.ui) {
    const api = new SessionApi(params.session, params.token);
    const info = await api.session();
    // A viewer token the session does not call a viewer's would make "Share this view" grant
    // more than it says.
    if (params.viewer) {
      const viewer = await new SessionApi(params.session, params.viewer).session()
        .catch((error) => ({ role: error.message }));
      if (viewer.role !== 'viewer')
        throw new Error(`the URL's viewer token is not the session's viewer token (${viewer.role})`);
    }
    document.body.classList.toggle('viewer', info.role !== 'editor');
    controls = new Controls(canvas, camera, length(sub(scene.bounds.max, scene.bounds.min)), () => {
      moving = performance.now();
      redraw();
      if (panel) {
        panel.refreshMode();
        panel.placeGizmos();
      }
    });
    controls.sceneCameras = sceneCameras(scene);
    panel = new SessionPanel({ root: document.body, canvas, scene, camera, controls, api,
                               role: info.role, session: params.session, token: params.token,
                               viewerToken: params.viewer, onPreview: redraw });
    panel.setPresets(info.presets || []);
    state.role = info.role;
    state.panel = panel;
    // Presets other editors save show up within a few seconds.
    setInterval(() => api.presets().then((p) => panel.setPresets(p.presets)).catch(() => {}), 5000);
  }

  let streamSet = null, lightsProto = null;
  const stream = new Stream({
    url: location.origin, session: params.session, token: params.token, FrameType, scene,
    onState: (decoder, frame, arrival) => {
      renderer.setCaches(decoder.planes);
      if (decoder.lights && decoder.lights !== lightsProto) {
        lightsProto = decoder.lights;
        // Most versions keep the lights of the one before (parts of a budgeted update, other
        // clients' sets of equal lights): the same set keeps its object, and the panel its rows.
        const set = lightSetOf(lightsProto);
        if (!streamSet || lightSetJson(set) !== lightSetJson(streamSet)) streamSet = set;
      }
      if (panel) panel.streamed(streamSet, decoder.version);
      state.version = decoder.version;
      state.part = decoder.part;
      state.frames = stream.frames;
      state.lights = streamSet;
      pending = { version: decoder.version, part: decoder.part, received: arrival.received,
                  lightsSetNs: Number(frame.lights_set_unix_ns || 0), bytes: arrival.bytes,
                  key: Number(frame.base_version || 0) === 0 };
      redraw();
    },
    onStatus: (text, final) => {
      state.connections = stream ? stream.connections : 0;
      if (final) fail(text);
      else report(text);
    },
  });
  state.stream = stream;

  const drawTimes = [];
  let drawMs = 0;
  const size = () => params.size || [Math.max(1, innerWidth), Math.max(1, innerHeight)];
  addEventListener('resize', () => {
    redraw();
    if (panel) panel.placeGizmos();
  });
  function frame(now) {
    scheduled = false;
    if (controls) controls.tick(now);
    const still = now - moving > 150;
    if (state.state === 'error' || !streamSet) return;
    if (!dirty && !(still && moving && state.lastSamples !== params.samples)) return;
    dirty = false;
    const lights = panel ? panel.lights() : streamSet;
    if (lights !== drawnLights) {
      renderer.setLights(lights);
      drawnLights = lights;
    }
    const samples = still ? params.samples : 1;
    const [width, height] = size();
    const t0 = performance.now();
    renderer.render(camera, width, height, { samples, exposure: params.exposure });
    renderer.gl.finish();
    const done = performance.now();
    drawMs = done - t0;
    // The gizmos follow the view (and the canvas, which the first draw sizes).
    if (panel) panel.placeGizmos();
    state.lastSamples = samples;
    drawTimes.push(done);
    while (drawTimes[0] < done - 1000) drawTimes.shift();
    ++state.draws;
    if (pending && samples === params.samples) {
      state.drawnVersion = pending.version;
      state.drawnPart = pending.part;
      if (state.latencies.length >= 10000) state.latencies.shift();
      if (pending.lightsSetNs > 0) {
        const at = Date.now();
        state.latencies.push({ version: pending.version, part: pending.part, key: pending.key,
                               bytes: pending.bytes, at, ms: at - pending.lightsSetNs / 1e6,
                               decodeToDrawnMs: done - pending.received });
      }
      pending = null;
      state.state = 'ready';
    }
    stats.textContent = `version ${state.version}${state.part ? ` (part ${state.part})` : ''} · ` +
                        `${drawTimes.length} fps · ${drawMs.toFixed(0)} ms per frame · ` +
                        `${width}×${height} · ${samples} spp`;
    // A moving view was drawn with one sample: all of them once it has been still a moment.
    if (samples !== params.samples) setTimeout(schedule, 160);
  }
}

main().catch((error) => fail(error.message));
