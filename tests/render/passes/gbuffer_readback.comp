#version 460
// Test only (gbuffer_pass_test.cpp): copies the four G-buffer targets into one buffer the host
// reads, since the targets are images that shaders sample and the host cannot read.
// Target-major: texels[t·width·height + y·width + x], row 0 at the top.

layout(local_size_x = 64) in;

layout(binding = 0) uniform sampler2D target0;
layout(binding = 1) uniform sampler2D target1;
layout(binding = 2) uniform sampler2D target2;
layout(binding = 3) uniform sampler2D target3;
layout(std430, binding = 4) writeonly buffer Texels { vec4 texels[]; };
layout(push_constant) uniform Push { uint width; uint height; };

void main() {
    const uint i = gl_GlobalInvocationID.x;
    const uint pixels = width * height;
    if (i >= pixels) return;
    const ivec2 p = ivec2(i % width, i / width);
    texels[i] = texelFetch(target0, p, 0);
    texels[pixels + i] = texelFetch(target1, p, 0);
    texels[2u * pixels + i] = texelFetch(target2, p, 0);
    texels[3u * pixels + i] = texelFetch(target3, p, 0);
}
