#version 460
// Pull (paper 000 Figure 2 step 3, §4.1): every node of one level gets the sum of its two
// children's flux and the flux's first moment about its centroid, and writes its light for
// cache lighting: its flux's limited linear spread (or, for a flat node whose flux the line
// cannot hold, its exponential spread), the radiance at its box centre as RGBE8 (§4.7) and the
// slopes along the box's axes (shared/pull.h). Dispatched level by level, lowest first, then the small upper
// levels in one workgroup. CPU twin: render/cpu/pull.cpp.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
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
float limitedSpread(PullNode inner, float flux, vec3 moment, out vec3 slopes,
                    inout bool concentrated) {
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
        const float kept = flux / (swing - dot(g, centre));
        concentrated = concentrated || kept < kExponentialLimit;
        g *= kept;
        atCentre = flux + dot(g, centre);
    }
    if (!(atCentre > 0.0)) return 0.0;
    slopes = g * halfExtent * (1.0 / atCentre);
    change = abs(slopes);
    const float sum = change.x + change.y + change.z;
    if (sum > 1.0) slopes *= 1.0 / sum;
    return atCentre;
}

/// render/cpu/pull.cpp inverseLangevin: x with coth x − 1/x = r (Jedynak's approximation).
float inverseLangevin(float r) {
    const float a = min(abs(r), 0.99);
    const float x = a * (3.0 - 2.6 * a + 0.7 * a * a) / ((1.0 - a) * (1.0 + 0.1 * a));
    return r < 0.0 ? -x : x;
}

/// render/cpu/pull.cpp exponentialSpread: returns the flux at the box centre and sets the
/// slopes β·halfExtent and ln Z. `a` holds the node's box model, √3·σ_k per axis and 0 on flat
/// axes (the same for every channel: writeNode computes it once).
float exponentialSpread(PullNode inner, vec3 a, float flux, vec3 moment, out vec3 slopes,
                        out float concentration) {
    slopes = vec3(0.0);
    concentration = 0.0;
    if (!(flux > 0.0)) return 0.0;
    const vec3 low = vec3(inner.low0, inner.low1, inner.low2);
    const vec3 centre = 0.5 * (low + inner.high);
    const vec3 halfExtent = 0.5 * (inner.high - low);
    const vec3 mean = (moment * mat3(inner.axis0, inner.axis1, inner.axis2)) * (1.0 / flux);
    vec3 beta = vec3(0.0);
    [[unroll]] for (int k = 0; k < 3; ++k)
        if (a[k] > 0.0) beta[k] = inverseLangevin(mean[k] / a[k]) / a[k];
    const float sum = dot(abs(beta), halfExtent);
    if (sum > kExponentialSpreadCap) beta *= kExponentialSpreadCap / sum;
    [[unroll]] for (int k = 0; k < 3; ++k) {
        const float x = abs(beta[k] * a[k]);
        concentration += x > 1e-2 ? log(sinh(x) / x) : x * x * (1.0 / 6.0);
    }
    slopes = beta * halfExtent;
    return flux * exp(dot(beta, centre));
}

/// snorm8 of v ∈ [−1, 1] (shared/pull.h) in the low byte, rounded towards zero (linear
/// spreads) or to nearest (exponential ones).
uint snorm8(float v, bool towardsZero) {
    const float scaled = clamp(v, -1.0, 1.0) * 127.0;
    return uint(int(towardsZero ? trunc(scaled) : round(scaled))) & 0xFFu;
}

/// The nine slopes and, for an exponential spread, ln Z per channel as shared/pull.h packs them.
uvec3 packSpread(vec3 r, vec3 g, vec3 b, vec3 concentration, bool exponential) {
    const float scale = exponential ? 1.0 / kExponentialSpreadCap : 1.0;
    const bool t = !exponential;
    r *= scale, g *= scale, b *= scale;
    uvec3 packed = uvec3(snorm8(r.x, t) | snorm8(r.y, t) << 8 | snorm8(r.z, t) << 16 | snorm8(g.x, t) << 24,
                         snorm8(g.y, t) | snorm8(g.z, t) << 8 | snorm8(b.x, t) << 16 | snorm8(b.y, t) << 24,
                         snorm8(b.z, t));
    if (exponential) {
        const uvec3 bits =
            uvec3(round(clamp(concentration / kConcentrationRange, 0.0, 1.0) * 127.0));
        packed.z |= bits.r << 8 | bits.g << 15 | bits.b << 22 | kNodeLightExponentialBit;
    }
    return packed;
}

/// Writes inner node `node` from its children's flux and moments.
void writeNode(uint node, PullNode inner, vec3 leftFlux, vec3 rightFlux, vec3 leftMoment[3],
               vec3 rightMoment[3]) {
    const vec3 flux = leftFlux + rightFlux;
    nodeFlux[node] = vec4(flux, 0.0);
    vec3 centre, slopes[3], moments[3], concentration = vec3(0.0);
    bool concentrated = false;
    for (int c = 0; c < 3; ++c) {
        vec3 m = leftMoment[c] + rightMoment[c];
        m += leftFlux[c] * inner.leftOffset;
        m += rightFlux[c] * inner.rightOffset;
        nodeMoment[3u * node + uint(c)] = vec4(m, 0.0);
        moments[c] = m;
        centre[c] = limitedSpread(inner, flux[c], m, slopes[c], concentrated);
    }
    // Where the limiter keeps less than kExponentialLimit of the gradient in any channel of a
    // flat node whose flux centroids lie within kExponentialReach of its box model, its
    // spread is exponential in all three (render/cpu/pull.cpp isFlat, fitsBoxModel).
    vec3 variance = vec3(0.0);
    [[unroll]] for (int k = 0; k < 3; ++k)
        if (inner.inverseVariance[k] > 0.0) variance[k] = 1.0 / inner.inverseVariance[k];
    const float total = variance.x + variance.y + variance.z;
    bool exponential =
        concentrated && min(variance.x, min(variance.y, variance.z)) <= kFlatVariance * total;
    vec3 a = vec3(0.0);
    if (exponential) {
        [[unroll]] for (int k = 0; k < 3; ++k)
            if (variance[k] > kFlatVariance * total) a[k] = sqrt(3.0 * variance[k]);
        const mat3 axes = mat3(inner.axis0, inner.axis1, inner.axis2);
        for (int c = 0; c < 3; ++c) {
            if (!(flux[c] > 0.0)) continue;
            const vec3 mean = (moments[c] * axes) * (1.0 / flux[c]);
            [[unroll]] for (int k = 0; k < 3; ++k)
                if (a[k] > 0.0 && abs(mean[k]) > kExponentialReach * a[k]) exponential = false;
        }
    }
    if (exponential) {
        for (int c = 0; c < 3; ++c)
            centre[c] =
                exponentialSpread(inner, a, flux[c], moments[c], slopes[c], concentration[c]);
    }
    nodeLight[node] = uvec4(packSpread(slopes[0], slopes[1], slopes[2], concentration, exponential),
                            packRgbe8(centre * inner.radianceScale));
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
