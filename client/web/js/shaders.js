// The thin client's shaders in GLSL ES 3.00, line for line the Vulkan ones (shaders/gbuffer.*,
// shaders/cache_shading.comp, shaders/lib/lights.glsl, shaders/lib/sh.glsl): storage buffers
// become data textures kDataWidth texels wide (element i at (i mod width, i / width)), the
// cache textures become the frame's planes plus the bake's index maps (a grid vertex or
// light-map texel reads the plane of the cache its map names; coverage is "names one").

export const kDataWidth = 4096;

const prelude = `#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp usampler2D;
precision highp sampler2DArray;
const int kDataWidth = ${kDataWidth};
ivec2 dataAt(int i) { return ivec2(i % kDataWidth, i / kDataWidth); }
`;

// shaders/lib/subpixel.glsl: framebuffer x, y on the 1/16-pixel grid every rasteriser shares
// (SwiftShader snaps to 1/16, lavapipe to 1/256), plus 1/1024 pixel.
const snapToSubpixels = `
uniform vec2 viewport;
vec4 snapToSubpixels(vec4 clip) {
  if (!(clip.w > 0.0)) return clip;
  vec2 pixels = (clip.xy / clip.w * 0.5 + 0.5) * viewport;
  vec2 snapped = (floor(pixels * 16.0 + 0.5) + 1.0 / 64.0) / 16.0;
  return vec4((snapped / viewport * 2.0 - 1.0) * clip.w, clip.zw);
}
`;

export const shadowVertex = `${prelude}${snapToSubpixels}
in vec3 position;
uniform mat4 clip;
void main() { gl_Position = snapToSubpixels(clip * vec4(position, 1.0)); }
`;

export const shadowFragment = `${prelude}
void main() {}
`;

export const gbufferVertex = `${prelude}
in vec3 position;
in vec4 color;
in vec2 uv0;
in vec2 uv1;
in vec2 lightmapUv;
uniform mat4 clip;
out vec3 vPosition;
out vec4 vColor;
out vec2 vUv0;
out vec2 vUv1;
out vec2 vLightmapUv;
flat out int vTriangle;
void main() {
  vPosition = position;
  vColor = color;
  vUv0 = uv0;
  vUv1 = uv1;
  vLightmapUv = lightmapUv;
  vTriangle = gl_VertexID / 3;
  gl_Position = clip * vec4(position, 1.0);
}
`;

export const gbufferFragment = `${prelude}
const float kNotLightmappedUv = -1.0;
const int kGbufferMaxAnisotropy = 16;
const uint kTextureRepeatS = 1u;
const uint kTextureRepeatT = 2u;

in vec3 vPosition;
in vec4 vColor;
in vec2 vUv0;
in vec2 vUv1;
in vec2 vLightmapUv;
flat in int vTriangle;

uniform usampler2D triangles;   // 3 texels per GbufferTriangle
uniform usampler2D materials;   // 3 texels per GbufferMaterial
uniform usampler2D textures;    // 1 texel per GbufferTexture
uniform usampler2D levels;      // 1 texel per GbufferTextureLevel
uniform sampler2D texels;       // RGBA32F
uniform sampler2D emissiveScale;  // R32F per material
uniform vec3 eye;
uniform vec3 forward;
uniform vec3 directionPerPixelX;
uniform vec3 directionPerPixelY;

layout(location = 0) out vec4 outPositionU;
layout(location = 1) out vec4 outNormalV;
layout(location = 2) out vec4 outAlbedo;
layout(location = 3) out vec4 outEmission;

struct Level { int firstTexel; int width; int height; };
struct Tex { int firstLevel; int levelCount; uint wrap; };

Level levelAt(int i) {
  uvec4 v = texelFetch(levels, dataAt(i), 0);
  return Level(int(v.x), int(v.y), int(v.z));
}
Tex textureAt(int i) {
  uvec4 v = texelFetch(textures, dataAt(i), 0);
  return Tex(int(v.x), int(v.y), v.z);
}
vec4 texelAt(int i) { return texelFetch(texels, dataAt(i), 0); }

void texelPair(float coord, int size, bool repeat, out int i0, out int i1, out float fraction) {
  if (isnan(coord) || isinf(coord)) coord = 0.0;
  coord = repeat ? coord - floor(coord) : min(max(coord, 0.0), 1.0);
  float x = coord * float(size) - 0.5;
  float base = floor(x);
  i0 = int(base);
  i1 = i0 + 1;
  if (repeat) {
    if (i0 < 0) i0 += size;
    if (i1 >= size) i1 -= size;
  } else {
    i0 = max(i0, 0);
    i1 = min(i1, size - 1);
  }
  fraction = x - base;
}

vec4 bilinear(Level l, bool repeatS, bool repeatT, vec2 uv) {
  int s0, s1, t0, t1;
  float fs, ft;
  texelPair(uv.x, l.width, repeatS, s0, s1, fs);
  texelPair(uv.y, l.height, repeatT, t0, t1, ft);
  int row0 = l.firstTexel + t0 * l.width;
  int row1 = l.firstTexel + t1 * l.width;
  vec4 top = mix(texelAt(row0 + s0), texelAt(row0 + s1), fs);
  vec4 bottom = mix(texelAt(row1 + s0), texelAt(row1 + s1), fs);
  return mix(top, bottom, ft);
}

vec4 sampleLevel(Tex t, int level, vec2 uv) {
  return bilinear(levelAt(t.firstLevel + clamp(level, 0, t.levelCount - 1)),
                  (t.wrap & kTextureRepeatS) != 0u, (t.wrap & kTextureRepeatT) != 0u, uv);
}

vec4 sampleFootprint(int index, vec2 uv, vec2 dUvdx, vec2 dUvdy) {
  Tex t = textureAt(index);
  Level level0 = levelAt(t.firstLevel);
  vec2 size = vec2(level0.width, level0.height);
  float lengthX = length(dUvdx * size);
  float lengthY = length(dUvdy * size);
  float last = float(t.levelCount - 1);
  float major = max(lengthX, lengthY);
  float minor = min(lengthX, lengthY);
  float lod = 0.0;
  float taps = 1.0;
  vec2 axis = vec2(0.0);
  if (isinf(lengthX) || isnan(lengthX) || isinf(lengthY) || isnan(lengthY)) {
    lod = last;
  } else if (major > 0.0) {
    float anisotropy = float(kGbufferMaxAnisotropy);
    float ratio = minor > 0.0 ? major / minor : anisotropy;
    taps = max(1.0, min(ceil(min(ratio, anisotropy)), ceil(major)));
    lod = clamp(log2(major / taps), 0.0, last);
    if (taps > 1.0) axis = lengthX >= lengthY ? dUvdx : dUvdy;
  }
  float base = min(floor(lod), last);
  float fraction = lod - base;
  Level fine = levelAt(t.firstLevel + int(base));
  Level coarse = levelAt(t.firstLevel + int(min(base + 1.0, last)));
  bool repeatS = (t.wrap & kTextureRepeatS) != 0u;
  bool repeatT = (t.wrap & kTextureRepeatT) != 0u;
  vec4 sumFine = vec4(0.0);
  vec4 sumCoarse = vec4(0.0);
  for (int i = 0; i < int(taps); ++i) {
    vec2 at = uv + axis * ((float(i) + 0.5) / taps - 0.5);
    sumFine += bilinear(fine, repeatS, repeatT, at);
    if (fraction > 0.0) sumCoarse += bilinear(coarse, repeatS, repeatT, at);
  }
  return mix(sumFine, sumCoarse, fraction) / taps;
}

void main() {
  uvec4 t0 = texelFetch(triangles, dataAt(3 * vTriangle), 0);
  uvec4 t1 = texelFetch(triangles, dataAt(3 * vTriangle + 1), 0);
  uvec4 t2 = texelFetch(triangles, dataAt(3 * vTriangle + 2), 0);
  vec3 triangleNormal = uintBitsToFloat(t0.xyz);
  int material = int(t0.w);
  vec3 uGradient = uintBitsToFloat(t1.xyz);
  bool lightmapped = t1.w != 0u;
  vec3 vGradient = uintBitsToFloat(t2.xyz);
  uvec4 m0 = texelFetch(materials, dataAt(3 * material), 0);
  uvec4 m1 = texelFetch(materials, dataAt(3 * material + 1), 0);
  uvec4 m2 = texelFetch(materials, dataAt(3 * material + 2), 0);
  vec4 baseColorFactor = uintBitsToFloat(m0);
  vec3 materialEmission = uintBitsToFloat(m1.xyz);
  int baseColorTexture = int(m1.w);
  int baseColorTexCoord = int(m2.x);
  int emissiveTexture = int(m2.y);

  bool backFace = dot(triangleNormal, vPosition - eye) > 0.0;
  vec3 normal = backFace ? -triangleNormal : triangleNormal;

  vec3 albedo = baseColorFactor.rgb * vColor.rgb;
  if (baseColorTexture >= 0) {
    vec3 toHit = vPosition - eye;
    float depth = dot(toHit, forward);
    float along = dot(triangleNormal, toHit);
    vec3 sx = depth * directionPerPixelX;
    vec3 sy = depth * directionPerPixelY;
    vec3 dPdx = sx - toHit * (dot(triangleNormal, sx) / along);
    vec3 dPdy = sy - toHit * (dot(triangleNormal, sy) / along);
    vec2 dUvdx = vec2(dot(uGradient, dPdx), dot(vGradient, dPdx));
    vec2 dUvdy = vec2(dot(uGradient, dPdy), dot(vGradient, dPdy));
    albedo *= sampleFootprint(baseColorTexture, baseColorTexCoord == 1 ? vUv1 : vUv0, dUvdx, dUvdy).rgb;
  }

  vec3 emission = vec3(0.0);
  if (!backFace) {
    emission = materialEmission;
    if (emissiveTexture >= 0) emission *= sampleLevel(textureAt(emissiveTexture), 0, vUv0).rgb;
    emission *= texelFetch(emissiveScale, dataAt(material), 0).r;
  }

  vec2 lightmapUv = lightmapped ? vLightmapUv : vec2(kNotLightmappedUv);
  outPositionU = vec4(vPosition, lightmapUv.x);
  outNormalV = vec4(normal, lightmapUv.y);
  outAlbedo = vec4(albedo, 1.0);
  outEmission = vec4(emission, 0.0);
}
`;

/// The shading pass for lY = bandsY, lC = bandsC; shBasis is shaders' generated sh_basis.glsl.
export function shadingFragment(bandsY, bandsC, shBasis) {
  return `${prelude}
const uint kBandsY = ${bandsY}u;
const uint kBandsC = ${bandsC}u;
const int kCountY = ${bandsY * bandsY};
const int kCountC = ${bandsC * bandsC};
const float kPi = 3.14159265358979;
const float kNotLightmappedUv = -1.0;
const uint kLightPoint = 0u, kLightSpot = 1u, kLightDirectional = 2u;
const uint kShadowCube = 0u, kShadowPerspective = 1u, kShadowOrthographic = 2u;

uniform sampler2D gbufferPositionU;
uniform sampler2D gbufferNormalV;
uniform sampler2D gbufferAlbedo;
uniform sampler2D gbufferEmission;
uniform sampler2D previous;          // the sum of the earlier subsamples
uniform usampler2D lights;           // 5 texels per GpuLight
uniform sampler2D shadowLayers;      // 5 texels per layer: clip's columns, (texelSlope, side)
uniform sampler2DArray shadowMaps;   // depth
uniform sampler2DArray planeY;       // coefficient k of cache c at (c mod W, c / W, k)
uniform sampler2DArray planeCo;
uniform sampler2DArray planeCg;
uniform usampler2D gridCaches;       // cache of grid vertex v, or noCache
uniform usampler2D lightmapCaches;   // cache of light-map texel t, or noCache
uniform uint noCache;
uniform vec3 eye;
uniform vec3 gridOrigin;
uniform float gridCellSize;
uniform ivec3 gridDims;
uniform int lightCount;
uniform ivec2 lightmapSize;
uniform float epsilon;
uniform bool accumulate;
uniform bool direct;
uniform float yScale;
uniform float cocgScale;
uniform float clampedCosine[8];

out vec4 outRadiance;

${shBasis}

vec3 yCoCgToRgb(vec3 ycocg) {
  float t = ycocg.x - ycocg.z;
  return vec3(t + ycocg.y, ycocg.x + ycocg.z, t - ycocg.y);
}

vec2 chromaPerLuma(vec3 ycocg) {
  if (!(ycocg.x > 0.0)) return vec2(0.0);
  return clamp(ycocg.yz / ycocg.x, vec2(-2.0, -1.0), vec2(2.0, 1.0));
}

struct GpuLight {
  vec3 position; uint type; vec3 direction; float range; vec3 radiant; float cosOuter;
  float cosInner; uint shadowKind; uint firstLayer; float depthNear; float depthFar; uint hardCone;
};

GpuLight fetchLight(int k) {
  uvec4 a = texelFetch(lights, dataAt(5 * k), 0);
  uvec4 b = texelFetch(lights, dataAt(5 * k + 1), 0);
  uvec4 c = texelFetch(lights, dataAt(5 * k + 2), 0);
  uvec4 d = texelFetch(lights, dataAt(5 * k + 3), 0);
  uvec4 e = texelFetch(lights, dataAt(5 * k + 4), 0);
  return GpuLight(uintBitsToFloat(a.xyz), a.w, uintBitsToFloat(b.xyz), uintBitsToFloat(b.w),
                  uintBitsToFloat(c.xyz), uintBitsToFloat(c.w), uintBitsToFloat(d.x), d.y, d.z,
                  uintBitsToFloat(d.w), uintBitsToFloat(e.x), e.y);
}

vec3 lightIrradiance(GpuLight light, vec3 p, vec3 n, out vec3 toLight) {
  if (light.type == kLightDirectional) {
    toLight = -light.direction;
    return light.radiant * max(0.0, dot(n, toLight));
  }
  vec3 offset = light.position - p;
  float distance = length(offset);
  if (!(distance > 0.0)) {
    toLight = n;
    return vec3(0.0);
  }
  toLight = offset / distance;
  float cosTheta = dot(n, toLight);
  if (cosTheta <= 0.0) return vec3(0.0);
  float attenuation = 1.0 / (distance * distance);
  if (light.range > 0.0) {
    float ratio = distance / light.range;
    float ratio2 = ratio * ratio;
    attenuation *= clamp(1.0 - ratio2 * ratio2, 0.0, 1.0);
  }
  if (light.type == kLightSpot) {
    float cd = dot(light.direction, -toLight);
    if (light.hardCone != 0u) {
      attenuation *= cd >= light.cosOuter ? 1.0 : 0.0;
    } else {
      float s = 1.0 / max(0.001, light.cosInner - light.cosOuter);
      float ramp = clamp(cd * s - light.cosOuter * s, 0.0, 1.0);
      attenuation *= ramp * ramp;
    }
  }
  return light.radiant * (cosTheta * attenuation);
}

bool shadowVisible(GpuLight light, vec3 p, vec3 n, float cosTheta) {
  int layer = int(light.firstLayer);
  if (light.shadowKind == kShadowCube) {
    vec3 v = p - light.position;
    vec3 a = abs(v);
    int face = a.x >= a.y && a.x >= a.z ? (v.x >= 0.0 ? 0 : 1)
             : a.y >= a.z               ? (v.y >= 0.0 ? 2 : 3)
                                        : (v.z >= 0.0 ? 4 : 5);
    layer += face;
  }
  bool ortho = light.shadowKind == kShadowOrthographic;
  mat4 m = mat4(texelFetch(shadowLayers, dataAt(5 * layer), 0),
                texelFetch(shadowLayers, dataAt(5 * layer + 1), 0),
                texelFetch(shadowLayers, dataAt(5 * layer + 2), 0),
                texelFetch(shadowLayers, dataAt(5 * layer + 3), 0));
  vec4 record = texelFetch(shadowLayers, dataAt(5 * layer + 4), 0);
  float texelSlope = record.x;
  int size = int(record.y);
  float depthP = ortho ? light.depthNear + (m * vec4(p, 1.0)).z * (light.depthFar - light.depthNear)
                       : (m * vec4(p, 1.0)).w;
  float texel = ortho ? texelSlope : texelSlope * max(depthP, 0.0);
  float tanTheta = sqrt(max(1.0 - cosTheta * cosTheta, 0.0)) / max(cosTheta, 1e-4);
  vec3 q = p + n * (epsilon + texel);
  vec4 clipQ = m * vec4(q, 1.0);
  if (!ortho && clipQ.w <= 0.0) return true;
  vec3 ndc = clipQ.xyz / clipQ.w;
  vec2 uv = ndc.xy * 0.5 + 0.5;
  ivec2 xy = clamp(ivec2(floor(uv * float(size))), ivec2(0), ivec2(size - 1));
  float stored = texelFetch(shadowMaps, ivec3(xy, layer), 0).r;
  if (stored >= 1.0) return true;
  float n0 = light.depthNear, f0 = light.depthFar;
  float depthStored = ortho ? n0 + stored * (f0 - n0) : n0 * f0 / (f0 - stored * (f0 - n0));
  float depthQ = ortho ? n0 + ndc.z * (f0 - n0) : clipQ.w;
  float bias = texel * (0.5 + 0.5 * min(tanTheta, 10.0));
  return depthQ <= depthStored + bias;
}

int sCache[8];
float sWeight[8];
int sCount;

void addNeighbour(uint cache, float w) {
  if (cache == noCache) return;
  sCache[sCount] = int(cache);
  sWeight[sCount] = w;
  ++sCount;
}

void finishStencil() {
  float total = 0.0;
  for (int k = 0; k < sCount; ++k) total += sWeight[k];
  for (int k = 0; k < sCount; ++k) sWeight[k] = total > 0.0 ? sWeight[k] / total : 1.0 / float(sCount);
}

void lightmapStencil(vec2 uv) {
  sCount = 0;
  vec2 size = vec2(lightmapSize);
  vec2 p = uv * size - 0.5;
  vec2 base = floor(p);
  vec2 f = p - base;
  for (int dy = 0; dy < 2; ++dy) {
    for (int dx = 0; dx < 2; ++dx) {
      float x = base.x + float(dx);
      float y = base.y + float(dy);
      if (!(x >= 0.0 && y >= 0.0 && x < size.x && y < size.y)) continue;
      float w = (dx != 0 ? f.x : 1.0 - f.x) * (dy != 0 ? f.y : 1.0 - f.y);
      int texel = int(x) + lightmapSize.x * int(y);
      addNeighbour(texelFetch(lightmapCaches, dataAt(texel), 0).r, w);
    }
  }
  finishStencil();
}

void gridAxis(float coordinate, int vertices, out int lower, out float fraction) {
  if (vertices < 2) {
    lower = 0;
    fraction = 0.0;
    return;
  }
  float c = !(coordinate > 0.0) ? 0.0 : min(coordinate, float(vertices - 1));
  lower = min(int(c), vertices - 2);
  fraction = c - float(lower);
}

void gridStencil(vec3 position) {
  sCount = 0;
  if (gridCellSize > 0.0 && gridDims.x * gridDims.y * gridDims.z > 0) {
    vec3 p = (position - gridOrigin) / gridCellSize;
    int lower[3];
    float fraction[3];
    for (int a = 0; a < 3; ++a) gridAxis(p[a], gridDims[a], lower[a], fraction[a]);
    for (int corner = 0; corner < 8; ++corner) {
      int v[3];
      float w = 1.0;
      bool exists = true;
      for (int a = 0; a < 3; ++a) {
        int upper = (corner >> a) & 1;
        exists = exists && !(upper != 0 && gridDims[a] < 2);
        v[a] = lower[a] + upper;
        w *= upper != 0 ? fraction[a] : 1.0 - fraction[a];
      }
      if (!exists) continue;
      int vertex = v[0] + gridDims.x * (v[1] + gridDims.y * v[2]);
      addNeighbour(texelFetch(gridCaches, dataAt(vertex), 0).r, w);
    }
  }
  finishStencil();
}

float planeValue(sampler2DArray plane, int cache, int k) {
  return texelFetch(plane, ivec3(dataAt(cache), k), 0).r;
}

void main() {
  ivec2 xy = ivec2(gl_FragCoord.xy);
  vec4 sum = accumulate ? texelFetch(previous, xy, 0) : vec4(0.0);
  vec4 positionU = texelFetch(gbufferPositionU, xy, 0);
  vec4 normalV = texelFetch(gbufferNormalV, xy, 0);
  vec4 albedoHit = texelFetch(gbufferAlbedo, xy, 0);
  if (albedoHit.w == 0.0) {
    outRadiance = sum;
    return;
  }
  vec3 position = positionU.xyz;
  vec3 normal = normalV.xyz;
  vec3 albedo = albedoHit.rgb;
  vec3 result = texelFetch(gbufferEmission, xy, 0).rgb;

  if (direct) {
    vec3 irradiance = vec3(0.0);
    for (int k = 0; k < lightCount; ++k) {
      GpuLight light = fetchLight(k);
      vec3 toLight;
      vec3 e = lightIrradiance(light, position, normal, toLight);
      if (!(e.r > 0.0 || e.g > 0.0 || e.b > 0.0)) continue;
      if (shadowVisible(light, position, normal, dot(normal, toLight))) irradiance += e;
    }
    result += albedo * (1.0 / kPi) * irradiance;
  }

  bool lightmapped = positionU.w != kNotLightmappedUv && lightmapSize.x > 0 && lightmapSize.y > 0;
  if (lightmapped) lightmapStencil(vec2(positionU.w, normalV.w));
  else gridStencil(position);
  float y[kCountY];
  float co[kCountC];
  float cg[kCountC];
  for (int c = 0; c < kCountY; ++c) y[c] = 0.0;
  for (int c = 0; c < kCountC; ++c) { co[c] = 0.0; cg[c] = 0.0; }
  for (int k = 0; k < sCount; ++k) {
    float w = sWeight[k];
    int cache = sCache[k];
    for (int c = 0; c < kCountY; ++c) y[c] += w * planeValue(planeY, cache, c);
    for (int c = 0; c < kCountC; ++c) {
      co[c] += w * planeValue(planeCo, cache, c);
      cg[c] += w * planeValue(planeCg, cache, c);
    }
  }
  vec2 chroma = chromaPerLuma(vec3(y[0], co[0], cg[0]));
  float basis[64];
  shEvaluate(normal, basis);
  vec3 e = vec3(0.0);
  for (int c = 0; c < kCountY; ++c) {
    float w = clampedCosine[int(kShBandOf[c])] * basis[c];
    e.x += y[c] * w;
    if (c < kCountC) {
      e.y += co[c] * w;
      e.z += cg[c] * w;
    } else {
      e.yz += chroma * (y[c] * w);
    }
  }
  vec3 indirectScale = vec3(yScale, cocgScale, cocgScale);
  result += albedo * (1.0 / kPi) * max(yCoCgToRgb(indirectScale * e), vec3(0.0));
  outRadiance = sum + vec4(result, 0.0);
}
`;
}

export const fullscreenVertex = `${prelude}
void main() {
  // One triangle over the viewport.
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
`;

/// core/image.cpp srgb8: the mean of the subsamples times the exposure, clamped to [0, 1],
/// sRGB-encoded.
export const displayFragment = `${prelude}
uniform sampler2D radianceSum;
uniform float samples;
uniform float exposure;
out vec4 outColor;
float srgb(float linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * pow(linear, 1.0 / 2.4) - 0.055;
}
void main() {
  // The sums hold the image top row first (camera.js gbufferView); the canvas's y grows upward.
  ivec2 xy = ivec2(gl_FragCoord.x, float(textureSize(radianceSum, 0).y) - gl_FragCoord.y);
  vec3 v = clamp(texelFetch(radianceSum, xy, 0).rgb / samples * exposure, 0.0, 1.0);
  outColor = vec4(srgb(v.r), srgb(v.g), srgb(v.b), 1.0);
}
`;
