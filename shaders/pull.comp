#version 460
// Pull (paper 000 Figure 2 step 3, §4.1): every node of one level gets the sum of its two
// children's flux. Dispatched level by level, lowest first. CPU twin: server/cpu/pull.cpp.
#extension GL_GOOGLE_include_directive : require
#include "shared/pull.h"

layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer NodeFlux { vec4 nodeFlux[]; };           // W, RGB
layout(std430, binding = 1) readonly buffer Children { uvec2 children[]; };  // inner nodes
layout(push_constant) uniform Push { PullPush pc; };

void main() {
    const uint node = pc.firstNode + gl_GlobalInvocationID.x;
    if (node >= pc.endNode) return;
    const uvec2 child = children[node - pc.surfelCount];
    nodeFlux[node] = vec4(nodeFlux[child.x].xyz + nodeFlux[child.y].xyz, 0.0);
}
