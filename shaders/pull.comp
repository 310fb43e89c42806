#version 460
// Pull (paper 000 Figure 2 step 3, §4.1): every node of one level gets the sum of its two
// children's flux and the flux's first moment about its centroid, and writes its light for
// cache lighting: its flux's limited linear spread, the radiance at its box centre as RGBE8
// (§4.7) and the slopes along the box's axes (shared/pull.h). Dispatched level by level, lowest first, then the small upper
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

/// render/cpu/pull.cpp limitedSpread: the fitted spread's gradient in the node's axes, scaled
/// so the spread stays ≥ 0 over the surfels' box; returns the flux at the box centre and sets
/// the slopes along the axes per half extent, relative to it.
float limitedSpread(PullNode inner, float flux, vec3 moment, out vec3 slopes) {
    slopes = vec3(0.0);
    if (!(flux > 0.0)) return 0.0;
    const vec3 low = vec3(inner.low0, inner.low1, inner.low2);
    const vec3 centre = 0.5 * (low + inner.high);
    const vec3 halfExtent = 0.5 * (inner.high - low);
    vec3 g = (moment * mat3(inner.axis0, inner.axis1, inner.axis2)) * inner.inverseVariance;
    float atCentre = flux + dot(g, centre);
    vec3 change = abs(g * halfExtent);
    const float swing = change.x + change.y + change.z;
    if (swing > atCentre) {
        g *= flux / (swing - dot(g, centre));
        atCentre = flux + dot(g, centre);
    }
    if (!(atCentre > 0.0)) return 0.0;
    slopes = g * halfExtent * (1.0 / atCentre);
    change = abs(slopes);
    const float sum = change.x + change.y + change.z;
    if (sum > 1.0) slopes *= 1.0 / sum;
    return atCentre;
}

/// snorm8 of v ∈ [−1, 1] rounded towards zero (shared/pull.h), in the low byte.
uint snorm8TowardsZero(float v) {
    return uint(int(trunc(clamp(v, -1.0, 1.0) * 127.0))) & 0xFFu;
}

/// The nine slopes as shared/pull.h packs them.
uvec3 packSlopes(vec3 r, vec3 g, vec3 b) {
    return uvec3(snorm8TowardsZero(r.x) | snorm8TowardsZero(r.y) << 8 | snorm8TowardsZero(r.z) << 16 |
                     snorm8TowardsZero(g.x) << 24,
                 snorm8TowardsZero(g.y) | snorm8TowardsZero(g.z) << 8 | snorm8TowardsZero(b.x) << 16 |
                     snorm8TowardsZero(b.y) << 24,
                 snorm8TowardsZero(b.z));
}

/// Writes inner node `node` from its children's flux and moments.
void writeNode(uint node, PullNode inner, vec3 leftFlux, vec3 rightFlux, vec3 leftMoment[3],
               vec3 rightMoment[3]) {
    const vec3 flux = leftFlux + rightFlux;
    nodeFlux[node] = vec4(flux, 0.0);
    vec3 centre, slopes[3];
    for (int c = 0; c < 3; ++c) {
        vec3 m = leftMoment[c] + rightMoment[c];
        m += leftFlux[c] * inner.leftOffset;
        m += rightFlux[c] * inner.rightOffset;
        nodeMoment[3u * node + uint(c)] = vec4(m, 0.0);
        centre[c] = limitedSpread(inner, flux[c], m, slopes[c]);
    }
    nodeLight[node] =
        uvec4(packSlopes(slopes[0], slopes[1], slopes[2]), packRgbe8(centre * inner.radianceScale));
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
