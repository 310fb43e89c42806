// The browser client's page: /?session=ID&token=T[&camera=ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy]
// [&scene_camera=N][&size=WxH][&samples=N][&exposure=X][&ui=0]. Fetches the scene and the
// wire schema, streams the session's caches and draws them as `picclient render` does.
// window.pic reports progress to tests and scripts.
import { Camera } from './camera.js';
import { lightSetOf } from './lights.js';
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
    camera: q.has('camera') ? Camera.parse(q.get('camera')) : null,
    sceneCamera: number('scene_camera', 0, (v) => Number.isInteger(v) && v >= 0),
    samples: number('samples', 4, (v) => Number.isInteger(v) && v >= 1 && v <= 64),
    exposure: number('exposure', 1, (v) => Number.isFinite(v) && v > 0),
    ui: q.get('ui') !== '0',
  };
}

/// The scene's camera `index`, or a view of its bounds when it has none.
function startCamera(scene, params) {
  if (params.camera) return params.camera;
  const cameras = scene.cameras || [];
  if (cameras.length > 0) {
    if (params.sceneCamera >= cameras.length)
      throw new Error(`scene_camera ${params.sceneCamera}: the scene has ${cameras.length} cameras`);
    const c = cameras[params.sceneCamera];
    return new Camera(c.eye, c.target, c.up, c.fovy_degrees);
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
  const renderer = new Renderer(canvas, scene, shBasis);
  const camera = startCamera(scene, params);
  state.sceneBytes = scene.bytes;
  state.sceneMs = performance.now() - started;
  report(`scene ${scene.scene_name} (${(scene.bytes / 1048576).toFixed(1)} MiB); waiting for the stream…`);

  let dirty = false;
  let pending = null;  // what the newest frame brought: {version, part, lightsSetNs, received}
  let lightsProto = null;
  const stream = new Stream({
    url: location.origin, session: params.session, token: params.token, FrameType, scene,
    onState: (decoder, frame, arrival) => {
      renderer.setCaches(decoder.planes);
      if (decoder.lights && decoder.lights !== lightsProto) {
        lightsProto = decoder.lights;
        renderer.setLights(lightSetOf(lightsProto));
      }
      state.version = decoder.version;
      state.part = decoder.part;
      state.frames = stream.frames;
      pending = { version: decoder.version, part: decoder.part, received: arrival.received,
                  lightsSetNs: Number(frame.lights_set_unix_ns || 0), bytes: arrival.bytes,
                  key: Number(frame.base_version || 0) === 0 };
      dirty = true;
    },
    onStatus: (text, final) => {
      state.connections = stream ? stream.connections : 0;
      if (final) fail(text);
      else report(text);
    },
  });
  state.stream = stream;

  // Frames per second: draws in the last second.
  const drawTimes = [];
  const size = () => params.size || [Math.max(1, innerWidth), Math.max(1, innerHeight)];
  addEventListener('resize', () => { dirty = true; });
  const frame = () => {
    requestAnimationFrame(frame);
    if (!dirty || state.state === 'error') return;
    dirty = false;
    const [width, height] = size();
    renderer.render(camera, width, height, { samples: params.samples, exposure: params.exposure });
    renderer.gl.finish();
    const now = performance.now();
    drawTimes.push(now);
    while (drawTimes[0] < now - 1000) drawTimes.shift();
    ++state.draws;
    if (pending) {
      state.drawnVersion = pending.version;
      state.drawnPart = pending.part;
      if (pending.lightsSetNs > 0)
        state.latencies.push({ version: pending.version, part: pending.part, key: pending.key,
                               bytes: pending.bytes,
                               ms: Date.now() - pending.lightsSetNs / 1e6,
                               decodeToDrawnMs: now - pending.received });
      pending = null;
      state.state = 'ready';
    }
    stats.textContent = `version ${state.version}${state.part ? ` (part ${state.part})` : ''} · ` +
                        `${drawTimes.length} fps · ${width}×${height} · ${params.samples} spp`;
  };
  requestAnimationFrame(frame);
}

main().catch((error) => fail(error.message));
