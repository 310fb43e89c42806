// A session's stream over the browser transport (docs/stream.md#browsers):
// ws(s)://HOST/v1/stream?session=ID&token=T, one serialised v1::Frame per binary message, the
// end or a refusal in the close frame as 4000 + the gRPC status code. A dropped connection is
// opened again (the server starts every connection with a key frame); a refusal is final.
import { FrameDecoder } from './frames.js';

/// Close codes after which connecting again cannot help: a bad token (UNAUTHENTICATED), no
/// such session (NOT_FOUND), a viewer where an editor is needed (PERMISSION_DENIED), a
/// request the server refuses (INVALID_ARGUMENT, FAILED_PRECONDITION).
const kFinal = new Set([4003, 4005, 4007, 4009, 4016]);

/// Frames Stream.received keeps (tests/latency.mjs reads them).
const kReceived = 10000;

export class Stream {
  /// Streams session `session` with `token` from `url` (the page's origin); FrameType is the
  /// protobufjs type pic.v1.Frame. onState(decoder, frame) after each decoded frame,
  /// onStatus(text, final) on connection changes. decode = false only parses each frame's
  /// message (tests/sockets.mjs: the transport without the client's work).
  constructor({ url, session, token, FrameType, scene, onState, onStatus, decode = true }) {
    this.url = url;
    this.session = session;
    this.token = token;
    this.FrameType = FrameType;
    this.decoder = decode ? new FrameDecoder(scene.caches, scene.bands_y, scene.bands_c) : null;
    this.onState = onState;
    this.onStatus = onStatus;
    this.connections = 0;
    this.frames = 0;
    this.bytes = 0;
    // Each decoded frame, the last kReceived: {version, part, bytes, key, lightsSetNs (the
    // server accepting its light set, Unix ns), at (its arrival, Unix ms)}.
    this.received = [];
    this.retryMs = 250;
    this.closed = false;
    this.connect();
  }

  connect() {
    const query = `session=${encodeURIComponent(this.session)}&token=${encodeURIComponent(this.token)}`;
    const base = this.url.replace(/^http/, 'ws');
    const socket = new WebSocket(`${base}/v1/stream?${query}`);
    socket.binaryType = 'arraybuffer';
    this.socket = socket;
    // A socket whose handshake fails: browsers fire error then close, node's WebSocket
    // (tests/sockets.mjs) error alone. Either way, once per socket; after the open, close
    // alone decides (an unclean close fires error before the close that carries the code).
    let opened = false, ended = false;
    socket.onopen = () => {
      opened = true;
      ++this.connections;
      this.retryMs = 250;
      this.onStatus(`streaming session ${this.session}`, false);
    };
    socket.onmessage = (event) => {
      const bytes = new Uint8Array(event.data);
      const received = performance.now();
      let frame;
      try {
        frame = this.FrameType.decode(bytes);
        if (this.decoder) this.decoder.apply(frame);
      } catch (error) {
        // A delta against another state or a corrupt frame: a new connection starts with a
        // key frame.
        this.onStatus(`frame refused (${error.message}); connecting again`, false);
        socket.close();
        return;
      }
      ++this.frames;
      this.bytes += bytes.byteLength;
      this.received.push({ version: Number(frame.version), part: frame.part || 0,
                           bytes: bytes.byteLength, key: Number(frame.base_version || 0) === 0,
                           lightsSetNs: Number(frame.lights_set_unix_ns || 0), at: Date.now() });
      if (this.received.length > kReceived) this.received.shift();
      this.onState(this.decoder, frame, { received, bytes: bytes.byteLength });
    };
    const end = (code, reason) => {
      if (ended || this.closed) return;
      ended = true;
      if (kFinal.has(code)) {
        this.onStatus(`stream refused: ${reason || `close code ${code}`}`, true);
        return;
      }
      const why = reason || (code === 1006 ? 'connection lost' : `close code ${code}`);
      this.onStatus(`${why}; connecting again in ${this.retryMs} ms`, false);
      setTimeout(() => this.connect(), this.retryMs);
      this.retryMs = Math.min(5000, this.retryMs * 2);
    };
    socket.onerror = () => {
      if (!opened) end(1006, 'connection failed');
    };
    socket.onclose = (event) => end(event.code, event.reason);
  }

  close() {
    this.closed = true;
    this.socket.close();
  }
}
