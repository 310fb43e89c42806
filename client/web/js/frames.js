// The session's frames (v1::Frame) decoded as client/connection.h FrameDecoder decodes them:
// planes of half floats, coefficient-major (coefficient k of cache c at k·nC + c), coded by
// core/frame_codec.h (float-order ranks, differences from the previous value or the base
// version, zigzag, low then high byte planes, zstd; zstd by the fzstd package).
import { decompress } from 'fzstd';

const kPlaneNames = ['cache_y', 'cache_co', 'cache_cg'];
const KEY = 1, DELTA = 2;

/// A half's rank in float order and back (core/frame_codec.cpp orderOf, halfOfOrder).
const orderOf = (h) => ((h & 0x8000) ? (~h & 0xffff) : (h | 0x8000));
const halfOfOrder = (o) => ((o & 0x8000) ? (o & 0x7fff) : (~o & 0xffff));

/// core/frame_codec.cpp untransform: `bytes` (low bytes then high bytes) over `plane`, which
/// holds the base for a delta.
function untransform(bytes, delta, plane) {
  const n = plane.length;
  let previous = orderOf(0);
  for (let i = 0; i < n; ++i) {
    const z = bytes[i] | (bytes[n + i] << 8);
    const reference = delta ? orderOf(plane[i]) : previous;
    const o = (reference + ((z >>> 1) ^ -(z & 1))) & 0xffff;
    plane[i] = halfOfOrder(o);
    previous = o;
  }
}

export class FrameDecoder {
  /// For a bake of `caches` caches with bandsY luma and bandsC chroma bands.
  constructor(caches, bandsY, bandsC) {
    this.expected = [caches * bandsY * bandsY, caches * bandsC * bandsC, caches * bandsC * bandsC];
    this.planes = null;  // Uint16Array ×3 once a key frame arrived
    this.version = 0;
    this.part = 0;
    this.lights = null;  // the v1::LightSet of the newest frame that carried one
  }

  /// Whether what is held is at least `version`'s final state.
  holds(version) { return this.version > version || (this.version === version && this.part === 0); }

  /// Decodes `frame`; throws naming the problem and keeps the held state when it is a delta
  /// against another state or does not decode.
  apply(frame) {
    const version = Number(frame.version), part = frame.part || 0;
    const baseVersion = Number(frame.base_version || 0), basePart = frame.base_part || 0;
    if (baseVersion !== 0 && (baseVersion !== this.version || basePart !== this.part))
      throw new Error(`frame of version ${version} part ${part} is a delta against version ` +
                      `${baseVersion} part ${basePart}, but version ${this.version} part ` +
                      `${this.part} is held`);
    if (!frame.planes || frame.planes.length !== 3)
      throw new Error(`frame of version ${version} has ${frame.planes ? frame.planes.length : 0} planes, not 3`);
    const raw = frame.planes.map((plane, t) => {
      const name = kPlaneNames[t];
      if (plane.encoding !== KEY && plane.encoding !== DELTA)
        throw new Error(`frame plane ${name}: unknown encoding ${plane.encoding}`);
      if ((plane.encoding === DELTA) !== (baseVersion !== 0))
        throw new Error(`frame plane ${name}: encoding ${plane.encoding} in a frame with base version ${baseVersion}`);
      if (plane.values !== this.expected[t])
        throw new Error(`frame of version ${version}: plane ${name} holds ${plane.values} values, ` +
                        `the scene's caches ${this.expected[t]}`);
      const bytes = decompress(plane.data);
      if (bytes.length !== 2 * plane.values)
        throw new Error(`frame plane ${name}: decompressed ${bytes.length} bytes, expected ${2 * plane.values}`);
      return bytes;
    });
    if (baseVersion === 0) {
      const planes = this.expected.map((n) => new Uint16Array(n));
      planes.forEach((plane, t) => untransform(raw[t], false, plane));
      this.planes = planes;
    } else {
      this.planes.forEach((plane, t) => untransform(raw[t], true, plane));
    }
    this.version = version;
    this.part = part;
    if (frame.lights) this.lights = frame.lights;
  }
}
