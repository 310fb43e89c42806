// What latency.mjs and sockets.mjs compute alike: percentiles and the latency of each version.

/// The nearest-rank percentile (as picclient load computes it), 0 without values.
export function percentile(values, p) {
  if (values.length === 0) return 0;
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.min(sorted.length - 1, Math.max(0, Math.ceil(p * sorted.length) - 1))];
}
export const mean = (values) => (values.length ? values.reduce((a, b) => a + b, 0) / values.length : 0);
export const round = (x, digits = 1) => Math.round(x * 10 ** digits) / 10 ** digits;
export const latencyStats = (ms) => ({
  p50: round(percentile(ms, 0.5)), p90: round(percentile(ms, 0.9)),
  p99: round(percentile(ms, 0.99)), max: round(ms.length ? Math.max(...ms) : 0),
  mean: round(mean(ms)), samples: ms.length,
});
export const bytesStats = (bytes) => ({ frames: bytes.length, median: percentile(bytes, 0.5),
                                        mean: Math.round(mean(bytes)) });

/// When the server accepted each version's light set (Unix ms), from the frames clients
/// received (Stream.received entries: {version, lightsSetNs}).
export function acceptedTimes(receivedLists) {
  const accepted = new Map();
  for (const received of receivedLists)
    for (const f of received)
      if (f.lightsSetNs > 0) accepted.set(f.version, f.lightsSetNs / 1e6);
  return accepted;
}

/// Per version in (base, newest] of `accepted`: ms from its acceptance until the first of
/// `entries` ({version, at: Unix ms}, in arrival order) holding it or a newer one, so that a
/// version a client skipped counts until a newer one arrived (as picclient load counts it);
/// `missed` counts the versions no entry reached.
export function untilFirst(accepted, entries, base, newest) {
  const ms = [];
  let missed = 0;
  for (const [version, at] of accepted) {
    if (version <= base || version > newest) continue;
    const first = entries.find((e) => e.version >= version);
    if (first) ms.push(first.at - at);
    else ++missed;
  }
  return { ms, missed };
}
