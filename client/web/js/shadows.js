// Shadow-map layers of a light set as render/passes/shadow_map_pass.cpp lays them out for the
// thin client (every layer the full side: the client's pass has no per-layer footprint
// sides): six 90° cube faces for point lights and spots wider than 60°, one perspective
// layer for narrower spots, one orthographic layer over the scene for directional lights.
import { add, length, lookAt, multiply, orthoZo, perspectiveZo, radians, scale, sub } from './math.js';
import { kShadowCube, kShadowOrthographic, kShadowPerspective } from './lights.js';

const kMaxPerspectiveSpot = 1.0472;  // 60°, render/passes/shadow_map_pass.h

export function layersOf(light) {
  if (light.type === 'point') return 6;
  if (light.type === 'spot' && light.outerConeAngle > kMaxPerspectiveSpot) return 6;
  return 1;
}

const upFor = (forward) => (Math.abs(forward[1]) > 0.9 ? [0, 0, 1] : [0, 1, 0]);

/// The layers of `lights` for a scene with bounds {min, max} and layers `size` texels wide:
/// per light its shadow fields ({kind, firstLayer, depthNear, depthFar}) and a key of what
/// its depth depends on; per layer {clip (Vulkan's, depth 0..1), texelSlope, side}.
export function layoutShadows(lights, bounds, size) {
  const diagonal = Math.max(length(sub(bounds.max, bounds.min)), 1e-3);
  const centre = scale(add(bounds.min, bounds.max), 0.5);
  const orthographicTexel = 1.01 * diagonal / size;
  const shadows = [];
  const layers = [];
  for (const light of lights) {
    const firstLayer = layers.length;
    const key = JSON.stringify([light.type, light.position, light.direction,
                                light.outerConeAngle, firstLayer]);
    if (light.type === 'directional') {
      const radius = 0.5 * size * orthographicTexel;
      const eye = sub(centre, scale(light.direction, radius * 1.01));
      const view = lookAt(eye, centre, upFor(light.direction));
      const depthFar = 2.02 * radius * 1.01;
      shadows.push({ kind: kShadowOrthographic, firstLayer, depthNear: 0, depthFar, key });
      layers.push({ clip: multiply(orthoZo(-radius, radius, -radius, radius, 0, depthFar), view),
                    texelSlope: orthographicTexel, side: size });
      continue;
    }
    let farthest = 0;
    for (let corner = 0; corner < 8; ++corner) {
      const c = [corner & 1 ? bounds.max[0] : bounds.min[0], corner & 2 ? bounds.max[1] : bounds.min[1],
                 corner & 4 ? bounds.max[2] : bounds.min[2]];
      farthest = Math.max(farthest, length(sub(c, light.position)));
    }
    const depthNear = 1e-3 * diagonal;
    const depthFar = Math.max(farthest * 1.01, 2 * depthNear);
    if (layersOf(light) === 1) {
      const fov = 2 * light.outerConeAngle + 0.035;
      const slope = 2 * Math.tan(0.5 * fov);
      const view = lookAt(light.position, add(light.position, light.direction), upFor(light.direction));
      shadows.push({ kind: kShadowPerspective, firstLayer, depthNear, depthFar, key });
      layers.push({ clip: multiply(perspectiveZo(fov, 1, depthNear, depthFar), view),
                    texelSlope: slope / size, side: size });
      continue;
    }
    shadows.push({ kind: kShadowCube, firstLayer, depthNear, depthFar, key });
    const axes = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
    const projection = perspectiveZo(radians(90), 1, depthNear, depthFar);
    for (const axis of axes)
      layers.push({ clip: multiply(projection, lookAt(light.position, add(light.position, axis), upFor(axis))),
                    texelSlope: 2 / size, side: size });
  }
  return { shadows, layers };
}
