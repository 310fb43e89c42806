// A frame's light set (v1::LightSet, decoded by protobufjs with the proto's field names) as the
// shaders read it: core/light_set.h's defaults for absent fields, directions normalised, and
// GpuLight records (shaders/shared/shadow_map.h) packed five RGBA32UI texels each.
import { normalize } from './math.js';

const kType = { 1: 'point', 2: 'spot', 3: 'directional', 4: 'sky' };
export const kLightPoint = 0, kLightSpot = 1, kLightDirectional = 2;
export const kShadowCube = 0, kShadowPerspective = 1, kShadowOrthographic = 2;

const has = (message, field) => Object.prototype.hasOwnProperty.call(message, field) &&
                                message[field] !== null && message[field] !== undefined;
const vec = (v) => [v.x || 0, v.y || 0, v.z || 0];

/// The light set's punctual lights with core/scene.h Light's defaults, the sky (null without;
/// the caches' light alone: it has no direct term in the thin client's shading), the emissive
/// scales by material name and the indirect scales.
export function lightSetOf(proto) {
  const lights = [];
  let sky = null;
  for (const [index, l] of (proto.lights || []).entries()) {
    const type = kType[l.type];
    if (type === undefined) continue;
    if (type === 'sky') {
      sky = { id: l.id || `light_${index}`, type, color: has(l, 'color') ? vec(l.color) : [1, 1, 1],
              intensity: has(l, 'intensity') ? l.intensity : 1, environment: l.environment || '',
              rotation: has(l, 'rotation') ? l.rotation : 0 };
      continue;
    }
    lights.push({
      id: l.id || `light_${index}`,
      type,
      position: has(l, 'position') ? vec(l.position) : [0, 0, 0],
      direction: normalize(has(l, 'direction') ? vec(l.direction) : [0, 0, -1]),
      color: has(l, 'color') ? vec(l.color) : [1, 1, 1],
      intensity: has(l, 'intensity') ? l.intensity : 1,
      innerConeAngle: has(l, 'inner_cone_angle') ? l.inner_cone_angle : 0,
      outerConeAngle: has(l, 'outer_cone_angle') ? l.outer_cone_angle : Math.PI / 4,
      range: has(l, 'range') ? l.range : Infinity,
    });
  }
  const indirect = proto.indirect_scale || {};
  return {
    lights,
    sky,
    emissiveScale: proto.emissive_scale || {},
    indirectScale: {
      y: has(indirect, 'y') ? indirect.y : 1,
      cocg: has(indirect, 'cocg') ? indirect.cocg : 1,
    },
  };
}

/// The light set in the JSON of the light-set files (core/light_set.h toJson's fields), which
/// POST /v1/lights and the presets take.
export function lightSetJson(set) {
  const lights = set.lights.map((l) => {
    const o = { id: l.id, type: l.type };
    if (l.type !== 'directional') o.position = l.position;
    if (l.type !== 'point') o.direction = l.direction;
    o.color = l.color;
    o.intensity = l.intensity;
    if (l.type === 'spot') {
      o.innerConeAngle = l.innerConeAngle;
      o.outerConeAngle = l.outerConeAngle;
    }
    if (l.type !== 'directional' && Number.isFinite(l.range)) o.range = l.range;
    return o;
  });
  if (set.sky) {
    const o = { id: set.sky.id, type: 'sky', color: set.sky.color, intensity: set.sky.intensity };
    if (set.sky.environment) o.environment = set.sky.environment;
    if (set.sky.rotation) o.rotation = set.sky.rotation;
    lights.push(o);
  }
  return JSON.stringify({ lights, emissiveScale: set.emissiveScale, indirectScale: set.indirectScale });
}

/// A light set from the JSON of the light-set files (what GET /v1/session and the presets
/// give), with lightSetOf's shape and defaults.
export function lightSetFromJson(json) {
  const lights = [];
  let sky = null;
  for (const [index, l] of (json.lights || []).entries()) {
    const id = l.id || `light_${index}`;
    if (l.type === 'sky') {
      sky = { id, type: 'sky', color: l.color || [1, 1, 1], intensity: l.intensity ?? 1,
              environment: l.environment || '', rotation: l.rotation || 0 };
      continue;
    }
    lights.push({
      id, type: l.type, position: l.position || [0, 0, 0],
      direction: normalize(l.direction || [0, 0, -1]), color: l.color || [1, 1, 1],
      intensity: l.intensity ?? 1, innerConeAngle: l.innerConeAngle ?? 0,
      outerConeAngle: l.outerConeAngle ?? Math.PI / 4, range: l.range ?? Infinity,
    });
  }
  const indirect = json.indirectScale || {};
  return { lights, sky, emissiveScale: json.emissiveScale || {},
           indirectScale: { y: indirect.y ?? 1, cocg: indirect.cocg ?? 1 } };
}

/// render/passes/shadow_map_pass.cpp gpuLightRecord plus the shadow fields of `shadow`
/// ({kind, firstLayer, depthNear, depthFar}), written at record k of `out` (Uint32Array view,
/// 20 words per light).
export function writeLightRecord(out, k, light, shadow) {
  const f = new Float32Array(out.buffer, out.byteOffset, out.length);
  const o = k * 20;
  const type = light.type === 'point' ? kLightPoint : light.type === 'spot' ? kLightSpot
                                                                            : kLightDirectional;
  f.set(light.position, o);
  out[o + 3] = type;
  f.set(light.direction, o + 4);
  f[o + 7] = Number.isFinite(light.range) ? light.range : 0;
  f.set(light.color.map((c) => c * light.intensity), o + 8);
  f[o + 11] = Math.cos(light.outerConeAngle);
  f[o + 12] = Math.cos(light.innerConeAngle);
  out[o + 13] = shadow.kind;
  out[o + 14] = shadow.firstLayer;
  f[o + 15] = shadow.depthNear;
  f[o + 16] = shadow.depthFar;
  out[o + 17] = light.innerConeAngle >= light.outerConeAngle ? 1 : 0;
  out[o + 18] = 0;
  out[o + 19] = 0;
}
