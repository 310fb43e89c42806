#version 460
// Copy probe: copies one buffer into another, 16 bytes per invocation and step, striding
// over the grid. No CPU twin: its result is checked against the data it was given.
#extension GL_GOOGLE_include_directive : require
#include "shared/copy_probe.h"

layout(local_size_x = kCopyProbeGroup) in;
layout(std430, binding = 0) readonly buffer Source { uvec4 source[]; };
layout(std430, binding = 1) writeonly buffer Target { uvec4 target[]; };
layout(push_constant) uniform Push { CopyProbePush pc; };

void main() {
    const uint stride = gl_NumWorkGroups.x * kCopyProbeGroup;
    for (uint i = gl_GlobalInvocationID.x; i < pc.words; i += stride) target[i] = source[i];
}
