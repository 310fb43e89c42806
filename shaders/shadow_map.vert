#version 460
// Shadow maps (paper 000 Figure 2 step 1): scene triangles into one depth layer of a light.
#extension GL_GOOGLE_include_directive : require
#include "shared/shadow_map.h"
#include "lib/subpixel.glsl"

layout(location = 0) in vec3 position;  // metres, world space
layout(push_constant) uniform Push { ShadowMapPush pc; };

void main() {
    gl_Position = snapToSubpixels(pc.clipFromWorld * vec4(position, 1.0), pc.viewport);
}
