#version 460
// Pull (paper 000 Figure 2 step 3, §4.1): every node of one level gets the sum of its two
// children's flux and the flux's first moment about its centroid, and writes its light for
// cache lighting: its radiance Φ / (π·A) as RGBE8 (§4.7) and its limited relative flux
// gradients (shared/pull.h). Dispatched level by level, lowest first, then the small upper
// levels in one workgroup. CPU twin: render/cpu/pull.cpp.
#extension GL_GOOGLE_include_directive : require
#include "shared/pull.h"
#include "lib/rgbe8.glsl"

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint kMode = kPullModeLevel;
// The tail reads children its own workgroup wrote: coherent storage, not texels.
layout(std430, binding = 0) coherent buffer NodeFlux { vec4 nodeFlux[]; };  // W, RGB
layout(binding = 1) uniform usamplerBuffer pullNodes;  // PullNode per inner node
layout(std430, binding = 2) writeonly buffer NodeLight { uvec4 nodeLight[]; };
layout(binding = 3) uniform samplerBuffer childFlux;  // nodeFlux as RGBA32F texels (level mode)
layout(std430, binding = 4) readonly buffer LevelOffsets { uint levelOffsets[]; };
// M_R, M_G, M_B per node (W·m), the leaves' zero.
layout(std430, binding = 5) coherent buffer NodeMoment { vec4 nodeMoment[]; };
layout(binding = 6) uniform samplerBuffer childMoment;  // nodeMoment as RGBA32F (level mode)
layout(push_constant) uniform Push { PullPush pc; };

/// render/cpu/pull.cpp limitedGradient: the gradient of the fitted spread in the node's axes,
/// scaled so the spread stays ≥ 0 over the surfels' extent, over Φ.
vec3 limitedGradient(PullNode inner, float flux, vec3 moment) {
    if (!(flux > 0.0)) return vec3(0.0);
    const mat3 axes = mat3(inner.axis0, inner.axis1, inner.axis2);
    const vec3 g = (moment * axes) * inner.inverseVariance;
    const vec3 lowest = min(g * vec3(inner.low0, inner.low1, inner.low2), g * inner.high);
    const float drop = -(lowest.x + lowest.y + lowest.z);
    const float limit = drop > flux ? flux / drop : 1.0;
    return axes * (g * (limit / flux));
}

float maxAbs(vec3 v) {
    const vec3 a = abs(v);
    return max(a.x, max(a.y, a.z));
}

/// Nine gradient components as snorm8 of a shared binary16 scale (shared/pull.h).
uvec3 packGradients(vec3 r, vec3 g, vec3 b) {
    const float largest = min(max(maxAbs(r), max(maxAbs(g), maxAbs(b))), 65504.0);
    if (!(largest > 0.0)) return uvec3(0u);
    // The scale rounds up, so that every component / scale lies in [−1, 1].
    uint scaleBits = packHalf2x16(vec2(largest, 0.0)) & 0xFFFFu;
    if (unpackHalf2x16(scaleBits).x < largest) ++scaleBits;
    const float inverse = 1.0 / unpackHalf2x16(scaleBits).x;
    r *= inverse;
    g *= inverse;
    b *= inverse;
    return uvec3(packSnorm4x8(vec4(r, g.x)), packSnorm4x8(vec4(g.yz, b.xy)),
                 (packSnorm4x8(vec4(b.z, 0.0, 0.0, 0.0)) & 0xFFu) | (scaleBits << 16));
}

/// Writes inner node `node` from its children's flux and moments.
void writeNode(uint node, PullNode inner, vec3 leftFlux, vec3 rightFlux, vec3 leftMoment[3],
               vec3 rightMoment[3]) {
    const vec3 flux = leftFlux + rightFlux;
    nodeFlux[node] = vec4(flux, 0.0);
    vec3 r[3];
    for (int c = 0; c < 3; ++c) {
        vec3 m = leftMoment[c] + rightMoment[c];
        m += leftFlux[c] * inner.leftOffset;
        m += rightFlux[c] * inner.rightOffset;
        nodeMoment[3u * node + uint(c)] = vec4(m, 0.0);
        r[c] = limitedGradient(inner, flux[c], m);
    }
    nodeLight[node] = uvec4(packGradients(r[0], r[1], r[2]), packRgbe8(flux * inner.radianceScale));
}

void main() {
    vec3 leftMoment[3], rightMoment[3];
    if (kMode == kPullModeLevel) {
        const uint node = pc.first + gl_GlobalInvocationID.x;
        if (node >= pc.end) return;
        const PullNode inner = fetchPullNode(pullNodes, node - pc.surfelCount);
        for (int c = 0; c < 3; ++c) {
            leftMoment[c] = texelFetch(childMoment, int(3u * inner.left) + c).xyz;
            rightMoment[c] = texelFetch(childMoment, int(3u * inner.right) + c).xyz;
        }
        writeNode(node, inner, texelFetch(childFlux, int(inner.left)).xyz,
                  texelFetch(childFlux, int(inner.right)).xyz, leftMoment, rightMoment);
    } else {
        // One workgroup: its invocations share each level's nodes, then wait for each other.
        for (uint level = pc.first; level < pc.end; ++level) {
            for (uint node = levelOffsets[level - 1u] + gl_LocalInvocationID.x;
                 node < levelOffsets[level]; node += gl_WorkGroupSize.x) {
                const PullNode inner = fetchPullNode(pullNodes, node - pc.surfelCount);
                for (int c = 0; c < 3; ++c) {
                    leftMoment[c] = nodeMoment[3u * inner.left + uint(c)].xyz;
                    rightMoment[c] = nodeMoment[3u * inner.right + uint(c)].xyz;
                }
                writeNode(node, inner, nodeFlux[inner.left].xyz, nodeFlux[inner.right].xyz,
                          leftMoment, rightMoment);
            }
            memoryBarrierBuffer();
            barrier();
        }
    }
}
