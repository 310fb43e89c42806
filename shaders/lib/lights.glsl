// Punctual lights and their shadow maps (shaders/shared/shadow_map.h) on the GPU, shared by
// every pass that lights a surface point. The includer declares `GpuLight`'s header, the
// per-layer records as `GpuShadowLayer shadowLayers[]` and the depth array as `sampler2DArray shadowMaps`.

/// core/light_set.h lightIrradiance: irradiance on a surface at p with normal n, the unit
/// direction to the light and its distance (∞ for directional lights).
vec3 lightIrradiance(GpuLight light, vec3 p, vec3 n, out vec3 toLight, out float distance) {
    if (light.type == kLightDirectional) {
        toLight = -light.direction;
        distance = 1.0 / 0.0;
        return light.radiant * max(0.0, dot(n, toLight));
    }
    const vec3 offset = light.position - p;
    distance = length(offset);
    if (!(distance > 0.0)) {
        toLight = n;
        return vec3(0.0);
    }
    toLight = offset / distance;
    const float cosTheta = dot(n, toLight);
    if (cosTheta <= 0.0) return vec3(0.0);
    float attenuation = 1.0 / (distance * distance);
    if (light.range > 0.0) {
        const float ratio = distance / light.range;
        const float ratio2 = ratio * ratio;
        attenuation *= clamp(1.0 - ratio2 * ratio2, 0.0, 1.0);
    }
    if (light.type == kLightSpot) {
        const float cd = dot(light.direction, -toLight);
        if (light.hardCone != 0u) {
            attenuation *= cd >= light.cosOuter ? 1.0 : 0.0;
        } else {
            const float scale = 1.0 / max(0.001, light.cosInner - light.cosOuter);
            const float ramp = clamp(cd * scale - light.cosOuter * scale, 0.0, 1.0);
            attenuation *= ramp * ramp;
        }
    }
    return light.radiant * (cosTheta * attenuation);
}

/// Shadow-map visibility of the light from a surface point p with normal n (cosTheta the
/// cosine between n and the direction to the light; epsilon the CPU twin's ray offset in
/// metres). The point moves off the surface by the
/// ray offset plus one shadow texel's footprint along the normal (normal-offset shadows), and
/// the depth test allows half a texel plus a slope term, so that a lit plane never shadows
/// itself while contact shadows keep their place.
bool shadowVisible(GpuLight light, vec3 p, vec3 n, float cosTheta, float epsilon) {
    // Layer and depth along its view axis.
    uint layer = light.firstLayer;
    if (light.shadowKind == kShadowCube) {
        const vec3 v = p - light.position;
        const vec3 a = abs(v);
        uint face = a.x >= a.y && a.x >= a.z ? (v.x >= 0.0 ? 0u : 1u)
                  : a.y >= a.z             ? (v.y >= 0.0 ? 2u : 3u)
                                           : (v.z >= 0.0 ? 4u : 5u);
        layer += face;
    }
    const bool ortho = light.shadowKind == kShadowOrthographic;
    const GpuShadowLayer shadowLayer = shadowLayers[layer];
    const mat4 m = shadowLayer.clipFromWorld;
    const float depthP = ortho ? light.depthNear + (m * vec4(p, 1.0)).z * (light.depthFar - light.depthNear)
                               : (m * vec4(p, 1.0)).w;
    const float texel = ortho ? shadowLayer.texelSlope : shadowLayer.texelSlope * max(depthP, 0.0);
    const float tanTheta = sqrt(max(1.0 - cosTheta * cosTheta, 0.0)) / max(cosTheta, 1e-4);
    const vec3 q = p + n * (epsilon + texel);
    const vec4 clip = m * vec4(q, 1.0);
    if (!ortho && clip.w <= 0.0) return true;  // behind the light's near plane
    const vec3 ndc = clip.xyz / clip.w;
    const vec2 uv = ndc.xy * 0.5 + 0.5;
    const int size = int(shadowLayer.side);
    const ivec2 xy = clamp(ivec2(floor(uv * float(size))), ivec2(0), ivec2(size - 1));
    const float stored = texelFetch(shadowMaps, ivec3(xy, int(layer)), 0).r;
    if (stored >= 1.0) return true;  // nothing drawn there: the far plane
    const float n0 = light.depthNear, f0 = light.depthFar;
    const float depthStored = ortho ? n0 + stored * (f0 - n0) : n0 * f0 / (f0 - stored * (f0 - n0));
    const float depthQ = ortho ? n0 + ndc.z * (f0 - n0) : clip.w;
    const float bias = texel * (0.5 + 0.5 * min(tanTheta, 10.0));
    return depthQ <= depthStored + bias;
}
