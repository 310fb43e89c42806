#version 460
// Pull (paper 000 Figure 2 step 3, §4.1): every node of one level gets the sum of its two
// children's flux, and its radiance Φ / (π·A) as RGBE8 for cache lighting (§4.7). Dispatched
// level by level, lowest first, then the small upper levels in one workgroup
// (shared/pull.h). CPU twin: render/cpu/pull.cpp.
#extension GL_GOOGLE_include_directive : require
#include "shared/pull.h"
#include "lib/rgbe8.glsl"

layout(local_size_x = 64) in;
layout(constant_id = 0) const uint kMode = kPullModeLevel;
// The tail reads children its own workgroup wrote: coherent storage, not texels.
layout(std430, binding = 0) coherent buffer NodeFlux { vec4 nodeFlux[]; };  // W, RGB
layout(binding = 1) uniform usamplerBuffer pullNodes;  // PullNode per inner node
layout(std430, binding = 2) writeonly buffer NodeRadiance { uint nodeRadiance[]; };  // RGBE8
layout(binding = 3) uniform samplerBuffer childFlux;  // nodeFlux as RGBA32F texels (level mode)
layout(std430, binding = 4) readonly buffer LevelOffsets { uint levelOffsets[]; };
layout(push_constant) uniform Push { PullPush pc; };

/// Writes inner node `node`'s flux, the sum of its children's, and its radiance.
void writeNode(uint node, PullNode inner, vec3 flux) {
    nodeFlux[node] = vec4(flux, 0.0);
    nodeRadiance[node] = packRgbe8(flux * inner.radianceScale);
}

void main() {
    if (kMode == kPullModeLevel) {
        const uint node = pc.first + gl_GlobalInvocationID.x;
        if (node >= pc.end) return;
        const PullNode inner = fetchPullNode(pullNodes, node - pc.surfelCount);
        writeNode(node, inner, texelFetch(childFlux, int(inner.left)).xyz +
                                   texelFetch(childFlux, int(inner.right)).xyz);
    } else {
        // One workgroup: its invocations share each level's nodes, then wait for each other.
        for (uint level = pc.first; level < pc.end; ++level) {
            for (uint node = levelOffsets[level - 1u] + gl_LocalInvocationID.x;
                 node < levelOffsets[level]; node += gl_WorkGroupSize.x) {
                const PullNode inner = fetchPullNode(pullNodes, node - pc.surfelCount);
                writeNode(node, inner, nodeFlux[inner.left].xyz + nodeFlux[inner.right].xyz);
            }
            memoryBarrierBuffer();
            barrier();
        }
    }
}
