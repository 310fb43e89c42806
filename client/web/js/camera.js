// The camera as the thin client's renderer uses it (core/camera.h CameraRays,
// render/passes/gbuffer_pass.cpp clipFromWorldOf and gbufferPushOf), in WebGL's conventions.
import { cross, dot, normalize, radians, radicalInverse, sub, scale, set } from './math.js';

/// A pinhole camera: eye, target, up (metres; up a hint), vertical field of view in degrees.
export class Camera {
  constructor(eye, target, up = [0, 1, 0], fovyDegrees = 60) {
    this.eye = eye;
    this.target = target;
    this.up = up;
    this.fovyDegrees = fovyDegrees;
  }

  /// "ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy", as picclient's --camera; throws naming the value.
  static parse(text) {
    const v = text.split(',').map(Number);
    if (v.length !== 10 || v.some((x) => !Number.isFinite(x)))
      throw new Error(`camera "${text}": expected ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy (10 numbers)`);
    const camera = new Camera(v.slice(0, 3), v.slice(3, 6), v.slice(6, 9), v[9]);
    camera.check();
    return camera;
  }

  toString() {
    const r = (x) => Number(x.toPrecision(6));
    return [...this.eye, ...this.target, ...this.up, this.fovyDegrees].map(r).join(',');
  }

  /// core/camera.cpp checkCamera's conditions: a direction, an up not along it, 0 < fovy < 180.
  check() {
    const forward = sub(this.target, this.eye);
    if (!(dot(forward, forward) > 0)) throw new Error('camera: the eye is at the target');
    const right = cross(forward, this.up);
    if (!(dot(right, right) > 0)) throw new Error('camera: up is along the view direction');
    if (!(this.fovyDegrees > 0 && this.fovyDegrees < 180))
      throw new Error(`camera: field of view ${this.fovyDegrees}° is not in (0, 180)`);
  }

  /// CameraRays' orthonormal basis.
  basis() {
    const forward = normalize(sub(this.target, this.eye));
    const right = normalize(cross(forward, this.up));
    const up = cross(right, forward);
    return { forward, right, up };
  }
}

/// core/camera.cpp subsampleOffset: subsample s of n inside a pixel, in [0, 1)².
export function subsampleOffset(s, n) {
  const shifted = radicalInverse(2, s) + 0.5 / n;
  return [(s + 0.5) / n, shifted - Math.floor(shifted)];
}

/// What the G-buffer pass draws one subsample with: clip (WebGL's clip-from-world, the image's
/// top row at the targets' row 0), forward, and the ray direction's change per pixel scaled by
/// footprintScale (texture footprints). With depth.zeroToOne (EXT_clip_control's 0..1 depth)
/// the stored depth is near/w, the Vulkan renderer's reversed depth (test GREATER, clear 0);
/// without it, a conventional −1..1 depth between depth.near and depth.far (test LESS, clear 1).
export function gbufferView(camera, width, height, near, offset, footprintScale, depth) {
  const { forward, right, up } = camera.basis();
  const tanHalf = Math.tan(radians(camera.fovyDegrees) * 0.5);
  const aspect = width / height;
  // gbufferPushOf's rows, Vulkan's: x = right·(p − eye)/(aspect·tan), y = −up·(p − eye)/tan,
  // w = forward·(p − eye), each of x and y plus shift·w, the shift moving the subsample onto
  // the pixel centre the rasteriser samples.
  const rowX = scale(right, 1 / (aspect * tanHalf));
  const rowY = scale(up, -1 / tanHalf);
  const shiftX = 2 * (0.5 - offset[0]) / width;
  const shiftY = 2 * (0.5 - offset[1]) / height;
  const rowW = [...forward, -dot(forward, camera.eye)];
  const rows = [[...rowX, -dot(rowX, camera.eye)], [...rowY, -dot(rowY, camera.eye)], null, rowW];
  for (let c = 0; c < 4; ++c) {
    rows[0][c] += shiftX * rowW[c];
    rows[1][c] += shiftY * rowW[c];
  }
  // Not flipped for WebGL's upward window y: the targets hold the image top row first, as
  // the Vulkan renderer's do, so that an edge through a pixel centre (SwiftShader snaps
  // vertices to 1/16 pixel, which puts many there) goes to the side lavapipe gives it; the
  // display pass flips.
  if (depth.zeroToOne) {
    rows[2] = [0, 0, 0, near];
  } else {
    const a = (depth.far + depth.near) / (depth.far - depth.near);
    const b = -2 * depth.far * depth.near / (depth.far - depth.near);
    rows[2] = rowW.map((x, c) => a * x + (c === 3 ? b : 0));
  }
  const clip = new Float32Array(16);
  for (let r = 0; r < 4; ++r)
    for (let c = 0; c < 4; ++c) set(clip, c, r, rows[r][c]);
  const perPixel = 2 * tanHalf / height * footprintScale;
  return {
    clip,
    forward,
    directionPerPixelX: scale(right, perPixel),
    directionPerPixelY: scale(up, -perPixel),
  };
}
