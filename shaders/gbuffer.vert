#version 460
// G-buffer (render/passes/gbuffer_pass.h): scene triangles, 3 unshared corners each, seen by the
// camera. Attributes are interpolated perspective-correctly, so that the fragment at a pixel
// centre gets them at the point its camera ray hits: b0·a0 + b1·a1 + b2·a2 as the CPU twin
// computes them from the hit's barycentrics.
#extension GL_GOOGLE_include_directive : require
#include "shared/gbuffer.h"

layout(location = 0) in vec3 position;  // metres, world space
layout(location = 1) in vec4 color;
layout(location = 2) in vec2 uv0;
layout(location = 3) in vec2 uv1;
layout(location = 4) in vec2 lightmapUv;
layout(push_constant) uniform Push { GbufferPush pc; };

layout(location = 0) out vec3 outPosition;
layout(location = 1) out vec4 outColor;
layout(location = 2) out vec2 outUv0;
layout(location = 3) out vec2 outUv1;
layout(location = 4) out vec2 outLightmapUv;
layout(location = 5) flat out uint outTriangle;

void main() {
    outPosition = position;
    outColor = color;
    outUv0 = uv0;
    outUv1 = uv1;
    outLightmapUv = lightmapUv;
    outTriangle = uint(gl_VertexIndex) / 3u;
    gl_Position = pc.clipFromWorld * vec4(position, 1.0);
}
