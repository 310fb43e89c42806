// Small vector and matrix helpers with glm's conventions: matrices are Float32Array(16),
// column-major (element [column][row] at column·4 + row), as uniformMatrix4fv takes them.

export const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
export const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
export const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
export const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                a[0] * b[1] - a[1] * b[0]];
export const length = (a) => Math.sqrt(dot(a, a));
export const normalize = (a) => scale(a, 1 / length(a));
export const radians = (degrees) => degrees * Math.PI / 180;

/// m[column][row] = v.
export function set(m, column, row, v) { m[column * 4 + row] = v; }
export function get(m, column, row) { return m[column * 4 + row]; }

/// a · b.
export function multiply(a, b) {
  const m = new Float32Array(16);
  for (let c = 0; c < 4; ++c)
    for (let r = 0; r < 4; ++r) {
      let s = 0;
      for (let k = 0; k < 4; ++k) s += a[k * 4 + r] * b[c * 4 + k];
      m[c * 4 + r] = s;
    }
  return m;
}

/// glm::lookAtRH.
export function lookAt(eye, centre, up) {
  const f = normalize(sub(centre, eye));
  const s = normalize(cross(f, up));
  const u = cross(s, f);
  const m = new Float32Array(16);
  for (let c = 0; c < 3; ++c) {
    set(m, c, 0, s[c]);
    set(m, c, 1, u[c]);
    set(m, c, 2, -f[c]);
  }
  set(m, 3, 0, -dot(s, eye));
  set(m, 3, 1, -dot(u, eye));
  set(m, 3, 2, dot(f, eye));
  set(m, 3, 3, 1);
  return m;
}

/// glm::perspectiveRH_ZO: depth 0 at the near plane, 1 at the far one.
export function perspectiveZo(fovy, aspect, near, far) {
  const t = Math.tan(fovy / 2);
  const m = new Float32Array(16);
  set(m, 0, 0, 1 / (aspect * t));
  set(m, 1, 1, 1 / t);
  set(m, 2, 2, far / (near - far));
  set(m, 2, 3, -1);
  set(m, 3, 2, -(far * near) / (far - near));
  return m;
}

/// glm::orthoRH_ZO.
export function orthoZo(left, right, bottom, top, near, far) {
  const m = new Float32Array(16);
  set(m, 0, 0, 2 / (right - left));
  set(m, 1, 1, 2 / (top - bottom));
  set(m, 2, 2, -1 / (far - near));
  set(m, 3, 0, -(right + left) / (right - left));
  set(m, 3, 1, -(top + bottom) / (top - bottom));
  set(m, 3, 2, -near / (far - near));
  set(m, 3, 3, 1);
  return m;
}

/// A Vulkan clip matrix (depth 0..1) as WebGL's (depth −1..1): z' = 2z − w, so that the depth
/// WebGL stores, (z'/w + 1)/2, is Vulkan's z/w.
export function glDepthFromZo(m) {
  const out = new Float32Array(m);
  for (let c = 0; c < 4; ++c) set(out, c, 2, 2 * get(m, c, 2) - get(m, c, 3));
  return out;
}

/// core/sampling.h radicalInverse: the digits of k in `base` mirrored about the point.
export function radicalInverse(base, k) {
  let inverse = 1 / base, result = 0, factor = inverse;
  while (k > 0) {
    result += (k % base) * factor;
    k = Math.floor(k / base);
    factor *= inverse;
  }
  return result;
}
