#version 460
// Pull (paper 000 Figure 2 step 3, §4.1): every node of one level gets the sum of its two
// children's flux, and its radiance Φ / (π·A) as RGBE8 for cache lighting (§4.7). Dispatched
// level by level, lowest first. CPU twin: server/cpu/pull.cpp.
#extension GL_GOOGLE_include_directive : require
#include "shared/pull.h"
#include "lib/rgbe8.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) writeonly buffer NodeFlux { vec4 nodeFlux[]; };     // W, RGB
layout(binding = 1) uniform usamplerBuffer pullNodes;  // PullNode per inner node
layout(std430, binding = 2) writeonly buffer NodeRadiance { uint nodeRadiance[]; };  // RGBE8
layout(binding = 3) uniform samplerBuffer childFlux;  // nodeFlux, read as RGBA32F texels
layout(push_constant) uniform Push { PullPush pc; };

void main() {
    const uint node = pc.firstNode + gl_GlobalInvocationID.x;
    if (node >= pc.endNode) return;
    const uvec4 inner = texelFetch(pullNodes, int(node - pc.surfelCount));  // PullNode
    const vec3 flux = texelFetch(childFlux, int(inner.x)).xyz + texelFetch(childFlux, int(inner.y)).xyz;
    nodeFlux[node] = vec4(flux, 0.0);
    nodeRadiance[node] = packRgbe8(flux * uintBitsToFloat(inner.z));
}
