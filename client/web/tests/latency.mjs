// N browser tabs on one session: how long each takes to load, then how long a light change
// takes to reach each tab's drawn frame while something else (bench/run_browser.sh: picclient
// load) changes the lights:
//   node latency.mjs --url URL --tabs N --duration-s D [--out FILE.json] [--open-concurrency K]
//                    [--load-timeout-s S] [--drain-s S] [--timeout-s S] [--chromium PATH]
// URL is the page (…/?session=ID&token=T&size=WxH&samples=N&ui=0); one headless chromium opens
// N tabs of it, each in a browser context of its own (its own cache and connections: a cold
// load, as N people would), K at a time (default 1: a tab loads beside the idle ones already
// open). Once every tab has drawn it prints `ready`, collects for D seconds, waits up to
// --drain-s (default 30) for every tab to draw the newest version any tab received, and prints
// one JSON line (also written, indented, to --out). SIGUSR2 (the light changes are over) ends
// the collection before D s.
//   load: per tab ms from navigation start to the first drawn frame (performance.now() in the
//     page when window.pic.state became 'ready', read by a probe this script puts on
//     window.pic before the page runs) and bytes over HTTP (transferSize of the navigation and
//     resource entries: the page, scripts, libraries, /v1/scene; the WebSocket's first key
//     frame is first_frame_bytes);
//   latency_ms: per tab and per version accepted after the tab's `ready` (the server
//     accepting its light set, lights_set_unix_ns, as any tab received it) → the tab drawing
//     the final state (part 0) of that version or a newer one (window.pic.latencies' `at`):
//     a version the tab skipped counts until it drew a newer one, as picclient load counts
//     it; received_latency_ms the same until the frame reached the page's socket handler
//     (window.pic.stream.received's `at`);
//   versions: pushed (newest version any tab received − each tab's version at `ready`), drawn,
//     received (frames), skipped = pushed − drawn;
//   frame_bytes: key and delta frames as the WebSocket carried them (serialised v1::Frame,
//     window.pic.stream.received).
// Exit status 1 with the reason on stderr (a tab that fails, a timeout); chromium is closed on
// every path.
import { writeFileSync } from 'node:fs';
import puppeteer from 'puppeteer-core';
import { launchOptions, parseArgs } from './browser.mjs';
import { acceptedTimes, bytesStats, latencyStats, mean, percentile, round, untilFirst } from './stats.mjs';

const args = parseArgs(process.argv.slice(2), {
  tabs: '1', 'duration-s': '10', 'open-concurrency': '1', 'load-timeout-s': '120',
  'drain-s': '30',
});
const known = new Set(['url', 'tabs', 'duration-s', 'out', 'open-concurrency', 'load-timeout-s',
                       'drain-s', 'timeout-s', 'chromium']);
const unknown = Object.keys(args).filter((k) => !known.has(k));
const tabs = Number(args.tabs), durationS = Number(args['duration-s']);
const concurrency = Number(args['open-concurrency']);
const loadTimeoutMs = Number(args['load-timeout-s']) * 1000;
const drainMs = Number(args['drain-s']) * 1000;
if (!args.url || unknown.length || !(Number.isInteger(tabs) && tabs >= 1 && tabs <= 1000) ||
    !(durationS >= 0) || !(Number.isInteger(concurrency) && concurrency >= 1) ||
    !(loadTimeoutMs > 0) || !(drainMs >= 0)) {
  if (unknown.length) console.error(`unknown option --${unknown.join(', --')}`);
  console.error('usage: node latency.mjs --url URL --tabs N --duration-s D [--out FILE.json] ' +
                '[--open-concurrency K] [--load-timeout-s S] [--drain-s S] [--timeout-s S]');
  process.exit(2);
}
// The whole run's limit: every tab's load, the collection and the drain, with a margin.
const timeoutS = Number(args['timeout-s'] ||
                        60 + Math.ceil(tabs / concurrency) * loadTimeoutMs / 1000 + durationS +
                        drainMs / 1000);
const sizeMatch = /[?&]size=(\d+)x(\d+)/.exec(args.url);
const viewport = { width: sizeMatch ? Number(sizeMatch[1]) : 800,
                   height: sizeMatch ? Number(sizeMatch[2]) : 600, deviceScaleFactor: 1 };

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

let phase = 'starting chromium';
let browser = null;
let closing = null;

/// Closes chromium (killing it when it does not close within 10 s); once.
function closeBrowser() {
  if (!closing) {
    closing = (async () => {
      if (!browser) return;
      const process_ = browser.process();
      await Promise.race([browser.close().catch(() => {}), sleep(10000)]);
      if (process_ && process_.exitCode === null && process_.signalCode === null)
        process_.kill('SIGKILL');
    })();
  }
  return closing;
}

async function die(message) {
  console.error(`latency.mjs: ${message}`);
  await closeBrowser();
  process.exit(1);
}

const watchdog = setTimeout(() => die(`timed out after ${timeoutS} s while ${phase}`),
                            timeoutS * 1000);
for (const signal of ['SIGINT', 'SIGTERM', 'SIGHUP'])
  process.on(signal, () => die(`stopped by ${signal} while ${phase}`));
// SIGUSR2: whatever pushes the light changes is done; the collection ends early.
let endCollection = null, pushesDone = false;
process.on('SIGUSR2', () => {
  pushesDone = true;
  if (endCollection) endCollection();
});

/// Put on window.pic before the page runs: performance.now() when its state first became
/// 'ready' (the page sets it right after drawing its first version) goes to window.__picReadyMs.
function readyProbe() {
  let pic;
  Object.defineProperty(window, 'pic', {
    configurable: true, enumerable: true,
    get() { return pic; },
    set(value) {
      pic = value;
      if (!value || typeof value !== 'object') return;
      let state = value.state;
      Object.defineProperty(value, 'state', {
        configurable: true, enumerable: true,
        get() { return state; },
        set(next) {
          if (next === 'ready' && window.__picReadyMs === undefined)
            window.__picReadyMs = performance.now();
          state = next;
        },
      });
    },
  });
}

/// Opens tab `index` in a browser context of its own and waits until it has drawn.
async function openTab(index) {
  const context = await browser.createBrowserContext();
  const page = await context.newPage();
  const tab = { index, page, logs: [], contextLost: 0 };
  page.on('console', (m) => {
    if (/context lost|CONTEXT_LOST/i.test(m.text())) ++tab.contextLost;
    if (m.type() === 'error' || m.type() === 'warn') tab.logs.push(`${m.type()}: ${m.text()}`);
  });
  page.on('pageerror', (e) => tab.logs.push(`page error: ${e.message}`));
  page.on('error', (e) => tab.logs.push(`tab crashed: ${e.message}`));
  await page.setViewport(viewport);
  await page.evaluateOnNewDocument(readyProbe);
  await page.goto(args.url, { timeout: loadTimeoutMs });
  try {
    await page.waitForFunction(() => window.pic && window.pic.state !== 'loading',
                               { timeout: loadTimeoutMs, polling: 50 });
  } catch (error) {
    throw new Error(`tab ${index} did not draw within ${loadTimeoutMs / 1000} s ` +
                    `(${error.message})\n${tab.logs.join('\n')}`);
  }
  const load = await page.evaluate(() => {
    const entries = [...performance.getEntriesByType('navigation'),
                     ...performance.getEntriesByType('resource')];
    const nav = performance.getEntriesByType('navigation')[0];
    const first = (window.pic.latencies || [])[0];
    const received = window.pic.stream && window.pic.stream.received;
    return {
      state: window.pic.state, error: window.pic.error,
      // The probe's time; without it (window.pic replaced), now: an upper bound.
      ms: window.__picReadyMs !== undefined ? window.__picReadyMs : performance.now(),
      probe: window.__picReadyMs !== undefined,
      http_bytes: entries.reduce((sum, e) => sum + (e.transferSize || 0), 0),
      http_body_bytes: entries.reduce((sum, e) => sum + (e.encodedBodySize || 0), 0),
      requests: entries.length,
      dom_content_loaded_ms: nav ? nav.domContentLoadedEventEnd : null,
      scene_ms: window.pic.sceneMs,
      scene_bytes: window.pic.sceneBytes,
      first_frame_bytes: received && received.length ? received[0].bytes
                                                     : (first ? first.bytes : null),
      first_decode_to_drawn_ms: first ? first.decodeToDrawnMs : null,
    };
  });
  if (load.state === 'error')
    throw new Error(`tab ${index} failed to load: ${load.error}\n${tab.logs.join('\n')}`);
  tab.load = load;
  return tab;
}

/// What a tab holds now (the stream object stays in the page).
function snapshot(page) {
  return page.evaluate(() => {
    const p = window.pic;
    const s = p.stream || {};
    const stats = document.getElementById('stats');
    return { state: p.state, error: p.error, version: p.version, drawnVersion: p.drawnVersion,
             stats: stats ? stats.textContent : null,
             drawnPart: p.drawnPart, draws: p.draws, frames: s.frames || 0, bytes: s.bytes || 0,
             connections: s.connections || 0 };
  });
}

let status = 0;
try {
  browser = await puppeteer.launch(launchOptions(args));
  browser.on('disconnected', () => {
    if (!closing) die(`chromium went away while ${phase}`);
  });

  // Load: K tabs at a time, each cold.
  const opened = [];
  const started = performance.now();
  for (let next = 0; next < tabs;) {
    const batch = [];
    for (; next < tabs && batch.length < concurrency; ++next) batch.push(next);
    phase = `loading tabs ${batch[0]}..${batch[batch.length - 1]} of ${tabs}`;
    opened.push(...(await Promise.all(batch.map(openTab))));
  }
  const openS = (performance.now() - started) / 1000;

  // Each tab's state at `ready`: versions above it are the ones pushed while collecting.
  phase = 'reading the tabs at ready';
  for (const tab of opened) tab.atReady = await snapshot(tab.page);
  process.stdout.write('ready\n');

  phase = `collecting for ${durationS} s`;
  const collectStart = performance.now();
  // Tab 0 once a second meanwhile: when its frames came and were drawn.
  const timeline = [];
  const sample = setInterval(() => {
    const at = round((performance.now() - collectStart) / 1000);
    snapshot(opened[0].page).then((s) => timeline.push([at, s.version, s.drawnVersion, s.frames]))
      .catch(() => {});
  }, 1000);
  if (!pushesDone)
    await new Promise((resolve) => {
      endCollection = resolve;
      setTimeout(resolve, durationS * 1000);
    });
  clearInterval(sample);
  const collectS = (performance.now() - collectStart) / 1000;

  // Drain: every tab draws the newest version any tab holds, or --drain-s passes.
  phase = 'waiting for every tab to draw the newest version';
  const drainStart = performance.now();
  let now;
  for (;;) {
    now = await Promise.all(opened.map((t) => snapshot(t.page)));
    const newest = Math.max(...now.map((s) => s.version));
    if (now.every((s) => s.drawnVersion >= newest && s.drawnPart === 0)) break;
    if (performance.now() - drainStart > drainMs) break;
    await sleep(250);
  }
  const drainS = (performance.now() - drainStart) / 1000;
  const newest = Math.max(...now.map((s) => s.version));

  phase = 'reading the tabs';
  const read = await Promise.all(opened.map((tab) => tab.page.evaluate(() => ({
    latencies: window.pic.latencies || [],
    received: window.pic.stream ? window.pic.stream.received : [],
  }))));
  const accepted = acceptedTimes(read.map((r) => r.received));
  const perTab = [];
  const pooledMs = [], pooledReceivedMs = [], keyBytes = [], deltaBytes = [];
  const failed = [];
  for (const [i, tab] of opened.entries()) {
    const end = now[i];
    const { latencies, received } = read[i];
    const base = tab.atReady.drawnVersion;
    const finals = latencies.filter((l) => l.version > base && l.part === 0);
    const { ms, missed } = untilFirst(accepted, finals, base, newest);
    const receivedMs = untilFirst(accepted, received.filter((f) => f.part === 0), base, newest).ms;
    pooledMs.push(...ms);
    pooledReceivedMs.push(...receivedMs);
    // Frame sizes: every frame the socket brought (the load's key frame included).
    const key = received.filter((f) => f.key).map((f) => f.bytes);
    const delta = received.filter((f) => !f.key).map((f) => f.bytes);
    keyBytes.push(...key);
    deltaBytes.push(...delta);
    const pushed = newest - base;
    const drawn = new Set(finals.map((l) => l.version)).size;
    if (end.state === 'error') failed.push(`tab ${i}: ${end.error}`);
    perTab.push({
      tab: i,
      load: { ...tab.load, ms: round(tab.load.ms), scene_ms: round(tab.load.scene_ms),
              first_decode_to_drawn_ms: round(tab.load.first_decode_to_drawn_ms) },
      latency_ms: latencyStats(ms),
      received_latency_ms: latencyStats(receivedMs),
      versions: { at_ready: base, newest_received: end.version, last_drawn: end.drawnVersion,
                  pushed, drawn, skipped: pushed - drawn, never_drawn: missed,
                  frames_received: end.frames - tab.atReady.frames,
                  draws: end.draws - tab.atReady.draws },
      frame_bytes: { key: bytesStats(key), delta: bytesStats(delta) },
      connections: end.connections,
      state: end.state,
      stats: end.stats,  // the page's last draw: version, fps, ms per frame
      context_lost: tab.contextLost,
      logs: tab.logs.slice(0, 10),
    });
  }
  const loads = perTab.map((t) => t.load.ms), http = perTab.map((t) => t.load.http_bytes);
  const drawnPerTab = perTab.map((t) => t.versions.drawn);
  const receivedPerTab = perTab.map((t) => t.versions.frames_received);
  const report = {
    url: args.url, tabs, duration_s: durationS, viewport: [viewport.width, viewport.height],
    open_concurrency: concurrency, open_s: round(openS), collect_s: round(collectS),
    drain_s: round(drainS),
    load: {
      ms: { median: round(percentile(loads, 0.5)), max: round(Math.max(...loads)),
            min: round(Math.min(...loads)) },
      http_bytes: { median: percentile(http, 0.5), max: Math.max(...http) },
      first_frame_bytes: percentile(perTab.map((t) => t.load.first_frame_bytes || 0), 0.5),
      probe: perTab.every((t) => t.load.probe),
    },
    latency_ms: latencyStats(pooledMs),
    received_latency_ms: latencyStats(pooledReceivedMs),
    versions: {
      newest: newest,
      pushed_max: Math.max(...perTab.map((t) => t.versions.pushed)),
      drawn: { mean: round(mean(drawnPerTab), 2), min: Math.min(...drawnPerTab),
               max: Math.max(...drawnPerTab) },
      received: { mean: round(mean(receivedPerTab), 2), min: Math.min(...receivedPerTab),
                  max: Math.max(...receivedPerTab) },
      skipped_total: perTab.reduce((s, t) => s + t.versions.skipped, 0),
      frames_received_total: perTab.reduce((s, t) => s + t.versions.frames_received, 0),
      tabs_without_newest: perTab.filter((t) => t.versions.last_drawn < newest).length,
      never_drawn_total: perTab.reduce((s, t) => s + t.versions.never_drawn, 0),
    },
    frame_bytes: { key: bytesStats(keyBytes), delta: bytesStats(deltaBytes) },
    reconnects: perTab.reduce((s, t) => s + Math.max(0, t.connections - 1), 0),
    context_lost: perTab.reduce((s, t) => s + t.context_lost, 0),
    // [s after ready, version received, version drawn, frames] of tab 0, each second.
    timeline_tab0: timeline,
    per_tab: perTab,
  };
  if (args.out) writeFileSync(args.out, JSON.stringify(report, null, 2) + '\n');
  process.stdout.write(JSON.stringify(report) + '\n');
  if (failed.length) {
    console.error(`latency.mjs: ${failed.length} of ${tabs} tabs failed:\n${failed.join('\n')}`);
    status = 1;
  }
} catch (error) {
  console.error(`latency.mjs: ${phase}: ${error.message}`);
  status = 1;
} finally {
  clearTimeout(watchdog);
  await closeBrowser();
}
process.exit(status);
