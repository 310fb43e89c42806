// A session's stream over the browser transport (docs/stream.md#browsers):
// ws(s)://HOST/v1/stream?session=ID&token=T, one serialised v1::Frame per binary message, the
// end or a refusal in the close frame as 4000 + the gRPC status code. A dropped connection is
// opened again (the server starts every connection with a key frame); a refusal is final.
import { FrameDecoder } from './frames.js';

/// Close codes after which connecting again cannot help: a bad token (UNAUTHENTICATED), no
/// such session (NOT_FOUND), a viewer where an editor is needed (PERMISSION_DENIED), a
/// request the server refuses (INVALID_ARGUMENT, FAILED_PRECONDITION).
const kFinal = new Set([4003, 4005, 4007, 4009, 4016]);

/// Frames whose size Stream.received keeps (tests/latency.mjs reads them).
const kReceived = 10000;

export class Stream {
  /// Streams session `session` with `token` from `url` (the page's origin); FrameType is the
  /// protobufjs type pic.v1.Frame. onState(decoder, frame) after each decoded frame,
  /// onStatus(text, final) on connection changes.
  constructor({ url, session, token, FrameType, scene, onState, onStatus }) {
    this.url = url;
    this.session = session;
    this.token = token;
    this.FrameType = FrameType;
    this.decoder = new FrameDecoder(scene.caches, scene.bands_y, scene.bands_c);
    this.onState = onState;
    this.onStatus = onStatus;
    this.connections = 0;
    this.frames = 0;
    this.bytes = 0;
    this.received = [];  // {bytes, key} of each decoded frame, the last kReceived
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
    socket.onopen = () => {
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
        this.decoder.apply(frame);
      } catch (error) {
        // A delta against another state or a corrupt frame: a new connection starts with a
        // key frame.
        this.onStatus(`frame refused (${error.message}); connecting again`, false);
        socket.close();
        return;
      }
      ++this.frames;
      this.bytes += bytes.byteLength;
      this.received.push({ bytes: bytes.byteLength, key: Number(frame.base_version || 0) === 0 });
      if (this.received.length > kReceived) this.received.shift();
      this.onState(this.decoder, frame, { received, bytes: bytes.byteLength });
    };
    socket.onclose = (event) => {
      if (this.closed) return;
      if (kFinal.has(event.code)) {
        this.onStatus(`stream refused: ${event.reason || `close code ${event.code}`}`, true);
        return;
      }
      const why = event.reason || (event.code === 1006 ? 'connection lost' : `close code ${event.code}`);
      this.onStatus(`${why}; connecting again in ${this.retryMs} ms`, false);
      setTimeout(() => this.connect(), this.retryMs);
      this.retryMs = Math.min(5000, this.retryMs * 2);
    };
  }

  close() {
    this.closed = true;
    this.socket.close();
  }
}
