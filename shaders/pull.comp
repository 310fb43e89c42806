#version 460
// Pull (paper 000 Figure 2 step 3, §4.1): every node of one level gets the sum of its two
// children's flux, and its radiance Φ / (π·A) as RGBE8 for cache lighting (§4.7). Dispatched
// level by level, lowest first. CPU twin: server/cpu/pull.cpp.
#extension GL_GOOGLE_include_directive : require
#include "shared/pull.h"
#include "lib/rgbe8.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer NodeFlux { vec4 nodeFlux[]; };                 // W, RGB
layout(std430, binding = 1) readonly buffer PullNodes { PullNode pullNodes[]; };  // inner nodes
layout(std430, binding = 2) writeonly buffer NodeRadiance { uint nodeRadiance[]; };  // RGBE8
layout(push_constant) uniform Push { PullPush pc; };

void main() {
    const uint node = pc.firstNode + gl_GlobalInvocationID.x;
    if (node >= pc.endNode) return;
    const PullNode inner = pullNodes[node - pc.surfelCount];
    const vec3 flux = nodeFlux[inner.left].xyz + nodeFlux[inner.right].xyz;
    nodeFlux[node] = vec4(flux, 0.0);
    nodeRadiance[node] = packRgbe8(flux * inner.radianceScale);
}
