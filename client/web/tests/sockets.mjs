// N subscribers of the browser transport without a browser: the page's own Stream
// (js/stream.js) in node, each on a WebSocket of its own, parsing every frame's message but
// neither decompressing its planes (--decode 1 does, with the page's FrameDecoder) nor
// drawing. What the server's browser transport delivers to N clients, apart from what N tabs
// cost the one machine that runs them all (tests/latency.mjs):
//   node --experimental-websocket sockets.mjs --url URL --sockets N --duration-s D
//        [--decode 0|1] [--out FILE.json] [--drain-s S] [--timeout-s S]
// URL is the page's (…/?session=ID&token=T…). Once every socket holds its key frame it prints
// `ready`, collects for D seconds (SIGUSR2 ends it sooner), waits up to --drain-s (default 30)
// for every socket to hold the newest version any socket received, and prints one JSON line
// (also written, indented, to --out):
//   received_latency_ms: per socket and per version accepted after `ready` (the server
//     accepting its light set, lights_set_unix_ns) → the socket decoding the final state
//     (part 0) of that version or a newer one;
//   versions: pushed, received (frames), skipped = pushed − versions received (final states);
//   frame_bytes: key and delta frames as the WebSocket carried them (serialised v1::Frame).
// Needs node's WebSocket (node ≥ 22, or node 20 with --experimental-websocket).
// Exit status 1 with the reason on stderr; 2 for bad arguments.
import { writeFileSync } from 'node:fs';
import protobuf from 'protobufjs';
import { parseScene } from '../js/scene.js';
import { Stream } from '../js/stream.js';
import { parseArgs } from './browser.mjs';
import { acceptedTimes, bytesStats, latencyStats, mean, round, untilFirst } from './stats.mjs';

const args = parseArgs(process.argv.slice(2), { 'duration-s': '10', 'drain-s': '30', decode: '0' });
const known = new Set(['url', 'sockets', 'duration-s', 'decode', 'out', 'drain-s', 'timeout-s']);
const unknown = Object.keys(args).filter((k) => !known.has(k));
const sockets = Number(args.sockets), durationS = Number(args['duration-s']);
const drainMs = Number(args['drain-s']) * 1000;
if (!args.url || unknown.length || !(Number.isInteger(sockets) && sockets >= 1 && sockets <= 10000) ||
    !(durationS >= 0) || !(drainMs >= 0) || !['0', '1'].includes(args.decode)) {
  if (unknown.length) console.error(`unknown option --${unknown.join(', --')}`);
  console.error('usage: node --experimental-websocket sockets.mjs --url URL --sockets N ' +
                '--duration-s D [--decode 0|1] [--out FILE.json] [--drain-s S] [--timeout-s S]');
  process.exit(2);
}
if (typeof WebSocket !== 'function') {
  console.error(`sockets.mjs: node ${process.version} has no WebSocket ` +
                '(node ≥ 22, or node 20 with --experimental-websocket)');
  process.exit(1);
}
const timeoutS = Number(args['timeout-s'] || 120 + durationS + drainMs / 1000);
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

const url = new URL(args.url);
const session = url.searchParams.get('session'), token = url.searchParams.get('token');
const streams = [];
let phase = 'starting';

function stop(message, code) {
  for (const s of streams) s.close();
  if (message) console.error(`sockets.mjs: ${message}`);
  process.exit(code);
}
setTimeout(() => stop(`timed out after ${timeoutS} s while ${phase}`, 1), timeoutS * 1000).unref();
for (const signal of ['SIGINT', 'SIGTERM', 'SIGHUP'])
  process.on(signal, () => stop(`stopped by ${signal} while ${phase}`, 1));
let endCollection = null, pushesDone = false;
process.on('SIGUSR2', () => {
  pushesDone = true;
  if (endCollection) endCollection();
});

async function fetchOk(path, what) {
  const response = await fetch(new URL(path, url.origin));
  if (!response.ok) throw new Error(`${what}: HTTP ${response.status} ${await response.text()}`);
  return response;
}

try {
  phase = 'loading the scene and the wire schema';
  const query = `session=${encodeURIComponent(session)}&token=${encodeURIComponent(token)}`;
  const [sceneBytes, protoText] = await Promise.all([
    fetchOk(`/v1/scene?${query}`, 'scene').then((r) => r.arrayBuffer()),
    fetchOk('/v1/pic.proto', 'wire schema').then((r) => r.text()),
  ]);
  const scene = parseScene(new Uint8Array(sceneBytes));
  const FrameType = protobuf.parse(protoText, { keepCase: true }).root.lookupType('pic.v1.Frame');

  phase = `opening ${sockets} sockets`;
  let refused = null;
  for (let i = 0; i < sockets; ++i)
    streams.push(new Stream({
      url: url.origin, session, token, FrameType, scene, decode: args.decode === '1',
      onState: () => {},
      onStatus: (text, final) => { if (final) refused = text; },
    }));
  while (streams.some((s) => s.frames === 0)) {
    if (refused) throw new Error(refused);
    await sleep(50);
  }
  // The state a socket holds: its newest frame's.
  const held = (s) => s.received[s.received.length - 1];
  const atReady = streams.map((s) => ({ version: held(s).version, frames: s.frames }));
  process.stdout.write('ready\n');

  phase = `collecting for ${durationS} s`;
  const collectStart = performance.now();
  if (!pushesDone)
    await new Promise((resolve) => {
      endCollection = resolve;
      setTimeout(resolve, durationS * 1000);
    });
  const collectS = (performance.now() - collectStart) / 1000;

  phase = 'waiting for every socket to hold the newest version';
  const drainStart = performance.now();
  const newestNow = () => Math.max(...streams.map((s) => held(s).version));
  while (!streams.every((s) => held(s).version >= newestNow() && held(s).part === 0) &&
         performance.now() - drainStart < drainMs)
    await sleep(100);
  const drainS = (performance.now() - drainStart) / 1000;
  if (refused) throw new Error(refused);

  const newest = newestNow();
  const accepted = acceptedTimes(streams.map((s) => s.received));
  const pooledMs = [], keyBytes = [], deltaBytes = [], perSocket = [];
  for (const [i, s] of streams.entries()) {
    const base = atReady[i].version;
    const finals = s.received.filter((f) => f.part === 0);
    const { ms, missed } = untilFirst(accepted, finals, base, newest);
    pooledMs.push(...ms);
    keyBytes.push(...s.received.filter((f) => f.key).map((f) => f.bytes));
    deltaBytes.push(...s.received.filter((f) => !f.key).map((f) => f.bytes));
    const got = new Set(finals.filter((f) => f.version > base).map((f) => f.version)).size;
    perSocket.push({ base, newest: held(s).version, got, missed,
                     frames: s.frames - atReady[i].frames, connections: s.connections });
  }
  const received = perSocket.map((p) => p.frames);
  const report = {
    url: args.url, sockets, decode: args.decode === '1', duration_s: durationS,
    collect_s: round(collectS),
    drain_s: round(drainS),
    received_latency_ms: latencyStats(pooledMs),
    versions: {
      newest,
      pushed_max: Math.max(...perSocket.map((p) => newest - p.base)),
      received: { mean: round(mean(received), 2), min: Math.min(...received),
                  max: Math.max(...received) },
      skipped_total: perSocket.reduce((sum, p) => sum + (newest - p.base - p.got), 0),
      never_received_total: perSocket.reduce((sum, p) => sum + p.missed, 0),
      sockets_without_newest: perSocket.filter((p) => p.newest < newest).length,
    },
    frame_bytes: { key: bytesStats(keyBytes), delta: bytesStats(deltaBytes) },
    reconnects: perSocket.reduce((sum, p) => sum + Math.max(0, p.connections - 1), 0),
  };
  if (args.out) writeFileSync(args.out, JSON.stringify(report, null, 2) + '\n');
  process.stdout.write(JSON.stringify(report) + '\n');
  stop(null, 0);
} catch (error) {
  stop(`${phase}: ${error.message}`, 1);
}
