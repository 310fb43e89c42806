#include "render/passes/shadow_map_pass.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "core/sampling.h"
#include "gpu/pipelines.h"

#include "spirv/shadow_map_vert.h"

namespace pic::gpu {
namespace {

/// Layers of a light's shadow map.
uint32_t layersOf(const Light& light) {
    if (light.type == LightType::Point) return 6;
    if (light.type == LightType::Spot && light.outerConeAngle > kMaxPerspectiveSpot) return 6;
    return 1;
}

/// The cube face (+x, −x, +y, −y, +z, −z: 0–5) that holds the direction `v` from the light:
/// its major axis, ties to x then y, as shaders/lib/lights.glsl picks it.
uint32_t cubeFace(const glm::vec3& v) {
    const glm::vec3 a = glm::abs(v);
    if (a.x >= a.y && a.x >= a.z) return v.x >= 0.0f ? 0 : 1;
    if (a.y >= a.z) return v.y >= 0.0f ? 2 : 3;
    return v.z >= 0.0f ? 4 : 5;
}

/// `count` points spread over the scene's surfaces by area: stratified along the triangles'
/// cumulative area, at Halton barycentrics within each triangle.
std::vector<glm::vec3> surfaceSamples(const Scene& scene, uint32_t count) {
    std::vector<double> cumulative(scene.triangles.size());
    double total = 0.0;
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        total += double(scene.triangleArea(t));
        cumulative[t] = total;
    }
    std::vector<glm::vec3> samples;
    if (!(total > 0.0)) return samples;
    samples.reserve(count);
    for (uint32_t k = 0; k < count; ++k) {
        const double at = (double(k) + 0.5) / double(count) * total;
        const size_t t = std::min<size_t>(
            size_t(std::lower_bound(cumulative.begin(), cumulative.end(), at) - cumulative.begin()),
            cumulative.size() - 1);
        const Triangle& tri = scene.triangles[t];
        const float r1 = std::sqrt(float(radicalInverse(2, k)));
        const float r2 = float(radicalInverse(3, k));
        samples.push_back((1.0f - r1) * scene.vertices[tri.v[0]].position +
                          r1 * (1.0f - r2) * scene.vertices[tri.v[1]].position +
                          r1 * r2 * scene.vertices[tri.v[2]].position);
    }
    return samples;
}

/// An up vector not parallel to `forward`.
glm::vec3 upFor(const glm::vec3& forward) {
    return std::abs(forward.y) > 0.9f ? glm::vec3(0.0f, 0.0f, 1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
}

}  // namespace

uint32_t footprintSide(float slopeAtOneTexel, float distance, float footprint, uint32_t maxSide) {
    const uint32_t top = std::max(maxSide, kMinShadowSide);
    const float texels = slopeAtOneTexel * distance / footprint;
    if (!(texels < float(top))) return top;  // also NaN
    if (!(texels > float(kMinShadowSide))) return kMinShadowSide;
    const uint32_t side = (uint32_t(std::ceil(texels)) + kMinShadowSide - 1) / kMinShadowSide * kMinShadowSide;
    return std::min(side, top);
}

Result<std::unique_ptr<Pass>> ShadowMapPass::create(Context& context, const PassConfig& config) {
    PIC_CHECK(config.scene != nullptr);
    const Scene& scene = *config.scene;
    const uint32_t size = config.shadowMapSize;
    const ShadowMapOptions& options = config.shadowMap;
    if (size < kMinShadowMapSize || size > kMaxShadowMapSize)
        return fail(ErrorCode::InvalidInput, "shadow-map size must be in [{}, {}], got {}",
                    kMinShadowMapSize, kMaxShadowMapSize, size);
    if (scene.triangles.empty() || scene.bounds.empty())
        return fail(ErrorCode::InvalidInput, "scene {} has no triangles to cast shadows",
                    scene.sourcePath);
    std::unique_ptr<ShadowMapPass> pass(new ShadowMapPass(context));
    pass->mSize = size;
    pass->mBounds = scene.bounds;
    if (options.equalFootprint) pass->mSurfaceSamples = surfaceSamples(scene, kFootprintSamples);

    // The casters: the scene's triangles, coplanar runs merged (level 0), then coarser
    // levels of detail for layers whose texels are wide. The coarsest error is the one an
    // orthographic layer over the scene allows; finer ones a quarter of the previous each.
    const Scene merged = options.mergeCoplanar ? mergeShadowCasters(scene) : Scene{};
    const Scene& finest = options.mergeCoplanar ? merged : scene;
    std::vector<std::pair<float, Scene>> levels;
    // Level 0's own distance from the scene's surfaces (float rounding where coplanar
    // triangles merged; more where meshoptimizer's estimate let a curved facet go).
    const float finestError =
        options.mergeCoplanar ? surfaceDeviation(scene, finest, 1e-3f * scene.bounds.diagonal()) : 0.0f;
    levels.emplace_back(finestError, Scene{});
    if (options.levelsOfDetail && std::isfinite(finestError)) {
        const float coarsest = kCasterErrorPerTexel * scene.bounds.diagonal() / float(size);
        size_t kept = finest.triangles.size();
        for (float error : {coarsest / 64.0f, coarsest / 16.0f, coarsest / 4.0f, coarsest}) {
            if (error <= finestError) continue;
            // meshoptimizer's error is an estimate that can fall short of the true distance
            // (2.4× on a cylinder in the tests): aim at half, measure, and aim lower while the
            // measured distance exceeds what the level may have.
            for (float target = 0.5f * error; target > 0.05f * error; target *= 0.5f) {
                Scene level = simplifyShadowCasters(finest, target);
                if (float(level.triangles.size()) > kCasterLevelReduction * float(kept)) break;
                const float measured = finestError + surfaceDeviation(finest, level, error);
                if (!(measured <= error)) continue;
                kept = level.triangles.size();
                levels.emplace_back(measured, std::move(level));
                break;
            }
        }
    }

    // Each level's triangles in cluster order, so that each cluster is one run of the index
    // buffer, and each cluster's vertices (positions only: depth needs nothing else) stored
    // together, so that a draw of a few clusters spans a short vertex range (lavapipe shades
    // the whole range an indexed draw spans). Solids are wound counter-clockwise seen from
    // outside (glTF's front faces), inverted ones reversed here, so that one cull mode keeps
    // the faces that look at the light.
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    for (const auto& [error, simplified] : levels) {
        const Scene& casters = pass->mLevels.empty() ? finest : simplified;
        const Solids solids = options.oneSidedSolids ? findSolids(casters) : Solids{};
        std::vector<uint32_t> order;
        std::vector<TriangleCluster> clusters = buildTriangleClusters(
            casters, kShadowClusterTriangles, order, options.oneSidedSolids ? &solids : nullptr);
        CasterLevel level{error, uint32_t(pass->mClusters.size()), uint32_t(clusters.size()),
                          uint32_t(casters.triangles.size())};
        std::vector<uint32_t> local(casters.vertices.size(), UINT32_MAX);
        for (TriangleCluster& cluster : clusters) {
            const uint32_t firstVertex = uint32_t(positions.size() / 3);
            const uint32_t first = cluster.firstTriangle;
            cluster.firstTriangle = uint32_t(indices.size() / 3);
            for (uint32_t i = first; i < first + cluster.triangleCount; ++i) {
                const uint32_t t = order[i];
                uint32_t corners[3] = {casters.triangles[t].v[0], casters.triangles[t].v[1],
                                       casters.triangles[t].v[2]};
                if (!solids.solidOf.empty() && solids.solidOf[t] != Solids::kOpen) {
                    if (pass->mLevels.empty()) ++pass->mSolidTriangles;
                    if (solids.inverted[solids.solidOf[t]]) std::swap(corners[1], corners[2]);
                }
                for (uint32_t v : corners) {
                    if (local[v] == UINT32_MAX || local[v] < firstVertex) {
                        local[v] = uint32_t(positions.size() / 3);
                        const glm::vec3& p = casters.vertices[v].position;
                        positions.insert(positions.end(), {p.x, p.y, p.z});
                    }
                    indices.push_back(local[v]);
                }
            }
            pass->mClusters.push_back(cluster);
        }
        pass->mLevels.push_back(level);
    }
    PIC_TRY_ASSIGN(pass->mVertices,
                   Buffer::createWith(context, std::span<const float>(positions),
                                      VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, "shadow vertices"));
    PIC_TRY_ASSIGN(pass->mIndices,
                   Buffer::createWith(context, std::span<const uint32_t>(indices),
                                      VK_BUFFER_USAGE_INDEX_BUFFER_BIT, "shadow indices"));
    PIC_TRY_ASSIGN(pass->mLights, Buffer::create(context, sizeof(GpuLight) * kMaxLights,
                                                 VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT,
                                                 MemoryUse::Device, "lights"));
    PIC_TRY_ASSIGN(pass->mLayerBuffer,
                   Buffer::create(context, sizeof(GpuShadowLayer) * 6 * kMaxLights, 0,
                                  MemoryUse::Device, "shadow layers"));
    // A one-layer placeholder keeps descriptor sets valid before the first light arrives.
    PIC_TRY_ASSIGN(pass->mDepth, DepthArray::create(context, size, 1));

    // Depth-only pipelines: no fragment shader, viewport and scissor set per layer. Open
    // triangles are drawn from both sides (surfels sit on both sides of single-sided
    // geometry); solids seen from outside only from the side that looks at the light.
    PIC_TRY_ASSIGN(pass->mPipelineLayout,
                   createPipelineLayout(context, VK_NULL_HANDLE,
                                        {VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(ShadowMapPush)}));

    RasterPipelineDesc desc;
    desc.vertexSpirv = kSpirvShadowMapVert;
    desc.vertexName = "shadow_map.vert";
    desc.binding = {0, 3 * sizeof(float), VK_VERTEX_INPUT_RATE_VERTEX};
    const VkVertexInputAttributeDescription position{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0};
    desc.attributes = std::span(&position, 1);
    desc.depthCompare = VK_COMPARE_OP_LESS;
    desc.layout = pass->mPipelineLayout.get();
    PIC_TRY_ASSIGN(pass->mPipeline, createRasterPipeline(context, desc));
    desc.cullMode = kCullAwayFromLight;
    PIC_TRY_ASSIGN(pass->mOneSidedPipeline, createRasterPipeline(context, desc));
    return pass;
}

uint32_t ShadowMapPass::levelFor(const LightSlot& slot, uint32_t layer) const {
    // The allowed error where the layer's texels are finest: an orthographic layer's texels
    // are one size; a perspective layer's grow with depth from the nearest caster it sees
    // (level 0's clusters, whose bounds are exact).
    const GpuLight& g = slot.gpu;
    float texel = mLayers[layer].texelSlope;
    if (g.shadowKind != kShadowOrthographic) {
        const float nearest = nearestClusterDepth(clustersOf(0), mLayers[layer].clipFromWorld);
        texel *= std::max(nearest, g.depthNear);
    }
    const float allowed = kCasterErrorPerTexel * texel;
    uint32_t level = 0;
    for (uint32_t l = 1; l < mLevels.size(); ++l)  // level 0 is drawn wherever no other may
        if (mLevels[l].error <= allowed) level = l;
    return level;
}

std::vector<GpuLight> ShadowMapPass::lightRecords() const {
    std::vector<GpuLight> records;
    for (const LightSlot& slot : mCurrent) records.push_back(slot.gpu);
    return records;
}

VkDeviceSize ShadowMapPass::bytes() const {
    return mVertices.size() + mIndices.size() + mLights.size() + mLayerBuffer.size() + mDepth.bytes();
}

GpuLight gpuLightRecord(const Light& light) {
    GpuLight g{};
    g.position = light.position;
    g.type = light.type == LightType::Point  ? kLightPoint
             : light.type == LightType::Spot ? kLightSpot
                                             : kLightDirectional;
    g.direction = light.direction;
    g.range = std::isfinite(light.range) ? light.range : 0.0f;
    g.radiant = light.intensity * light.color;
    g.cosOuter = std::cos(light.outerConeAngle);
    g.cosInner = std::cos(light.innerConeAngle);
    g.hardCone = light.innerConeAngle >= light.outerConeAngle ? 1u : 0u;
    return g;
}

ShadowMapPass::LightSlot ShadowMapPass::describe(const Light& light, uint32_t firstLayer,
                                                 std::vector<GpuShadowLayer>& layers) const {
    LightSlot slot;
    slot.id = light.id;
    slot.position = light.position;
    slot.direction = light.direction;
    slot.outerConeAngle = light.outerConeAngle;
    slot.type = light.type;
    slot.layers = layersOf(light);

    slot.gpu = gpuLightRecord(light);
    GpuLight& g = slot.gpu;
    g.firstLayer = firstLayer;

    const float diagonal = std::max(mBounds.diagonal(), 1e-3f);
    const auto addLayer = [&](const glm::mat4& clipFromWorld, float texelSlope, uint32_t side) {
        slot.sides[layers.size() - firstLayer] = side;
        GpuShadowLayer record{};
        record.clipFromWorld = clipFromWorld;
        record.texelSlope = texelSlope;
        record.side = side;
        layers.push_back(record);
    };
    if (light.type == LightType::Directional) {
        // An orthographic box around the scene's bounding sphere, looking along the light.
        const glm::vec3 centre = mBounds.center();
        const float radius = 0.5f * float(mSize) * orthographicTexel();
        const glm::vec3 eye = centre - light.direction * (radius * 1.01f);
        const glm::mat4 view = glm::lookAtRH(eye, centre, upFor(light.direction));
        g.shadowKind = kShadowOrthographic;
        g.depthNear = 0.0f;
        g.depthFar = 2.02f * radius * 1.01f;
        slot.eye = ShadowEye{};
        addLayer(glm::orthoRH_ZO(-radius, radius, -radius, radius, g.depthNear, g.depthFar) * view,
                 orthographicTexel(), mSize);
        return slot;
    }

    // Perspective: near plane a thousandth of the scene, far plane past its farthest corner.
    float farthest = 0.0f;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 c((corner & 1) ? mBounds.max.x : mBounds.min.x,
                          (corner & 2) ? mBounds.max.y : mBounds.min.y,
                          (corner & 4) ? mBounds.max.z : mBounds.min.z);
        farthest = std::max(farthest, glm::length(c - light.position));
    }
    g.depthNear = 1e-3f * diagonal;
    g.depthFar = std::max(farthest * 1.01f, 2.0f * g.depthNear);
    // The near plane's corners lie within 3 near-plane distances of the light for every
    // field of view used here (≤ 2 × 61°: √(1 + 2 tan² 61°) = 2.7).
    slot.eye = ShadowEye{false, light.position, 3.0f * g.depthNear};
    if (slot.layers == 1) {
        // A spot's cone plus a margin of one degree.
        const float fov = 2.0f * light.outerConeAngle + 0.035f;
        g.shadowKind = kShadowPerspective;
        const float slope = 2.0f * std::tan(0.5f * fov);
        const uint32_t side = perspectiveSides(light, slope)[0];
        const glm::mat4 view = glm::lookAtRH(light.position, light.position + light.direction,
                                             upFor(light.direction));
        addLayer(glm::perspectiveRH_ZO(fov, 1.0f, g.depthNear, g.depthFar) * view, slope / float(side), side);
        return slot;
    }
    // Cube faces +x, −x, +y, −y, +z, −z: 90° frusta whose union is every direction; the
    // surfel-lighting pass picks the face by the major axis of (p − light).
    g.shadowKind = kShadowCube;
    const std::array<uint32_t, 6> sides = perspectiveSides(light, 2.0f);
    const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    const glm::mat4 projection = glm::perspectiveRH_ZO(glm::radians(90.0f), 1.0f, g.depthNear, g.depthFar);
    for (uint32_t face = 0; face < 6; ++face)
        addLayer(projection * glm::lookAtRH(light.position, light.position + axes[face], upFor(axes[face])),
                 2.0f / float(sides[face]), sides[face]);
    return slot;
}

std::array<uint32_t, 6> ShadowMapPass::perspectiveSides(const Light& light, float slopeAtOneTexel) const {
    std::array<uint32_t, 6> sides;
    sides.fill(mSize);
    if (mSurfaceSamples.empty()) return sides;
    // The samples the light can reach (occlusion aside), within its range and, for spots,
    // its outer cone, each on the layer that holds it: a cube's face by the major axis of
    // (p − light), as surfel lighting picks it; a narrow spot's only layer.
    const bool cube = layersOf(light) == 6;
    const float cosOuter = std::cos(light.outerConeAngle);
    std::array<std::vector<float>, 6> distances;
    for (const glm::vec3& p : mSurfaceSamples) {
        const glm::vec3 offset = p - light.position;
        const float distance = glm::length(offset);
        if (!(distance > 0.0f)) continue;
        if (std::isfinite(light.range) && light.range > 0.0f && distance >= light.range) continue;
        if (light.type == LightType::Spot && glm::dot(offset, light.direction) < cosOuter * distance)
            continue;
        distances[cube ? cubeFace(offset) : 0].push_back(distance);
    }
    for (uint32_t layer = 0; layer < (cube ? 6u : 1u); ++layer) {
        std::vector<float>& d = distances[layer];
        if (d.empty()) {  // the layer is never sampled where lit
            sides[layer] = kMinShadowSide;
            continue;
        }
        const auto median = d.begin() + d.size() / 2;
        std::nth_element(d.begin(), median, d.end());
        sides[layer] = footprintSide(slopeAtOneTexel, *median, orthographicTexel(), mSize);
    }
    return sides;
}

Result<void> ShadowMapPass::prepare(const LightSet& lights, bool& reallocated) {
    reallocated = false;
    std::vector<LightSlot> next;
    std::vector<GpuShadowLayer> layerRecords;
    uint32_t layer = 0;
    for (const Light& light : lights.lights) {
        LightSlot slot = describe(light, layer, layerRecords);
        layer += slot.layers;
        next.push_back(std::move(slot));
    }
    // The image grows when the lights need more layers (every map is then re-rendered); it
    // never shrinks, so that toggling a light does not reallocate.
    if (layer > mDepth.layers()) {
        PIC_TRY_ASSIGN(mDepth, DepthArray::create(mContext, mSize, layer));
        reallocated = true;
    }
    // A light keeps its maps when the same light sat on the same layers with the same
    // geometry; colour, intensity, range and inner cone do not change its depth.
    for (size_t i = 0; i < next.size(); ++i) {
        LightSlot& slot = next[i];
        slot.dirty = true;
        if (reallocated || i >= mCurrent.size()) continue;
        const LightSlot& old = mCurrent[i];
        slot.dirty = !(old.id == slot.id && old.type == slot.type &&
                       old.gpu.firstLayer == slot.gpu.firstLayer && old.layers == slot.layers &&
                       old.sides == slot.sides &&
                       old.position == slot.position && old.direction == slot.direction &&
                       old.outerConeAngle == slot.outerConeAngle && !old.dirty);
    }
    mCurrent = std::move(next);
    mLayers = std::move(layerRecords);
    mLayerLevels.resize(mLayers.size(), 0);

    const std::vector<GpuLight> records = lightRecords();
    if (!records.empty()) {
        PIC_TRY(mContext.uploadWithNextSubmit(mLights, records.data(),
                                              records.size() * sizeof(GpuLight)));
        PIC_TRY(mContext.uploadWithNextSubmit(mLayerBuffer, mLayers.data(),
                                              mLayers.size() * sizeof(GpuShadowLayer)));
    }
    return {};
}

void ShadowMapPass::bindPipeline(VkCommandBuffer cmd, VkPipeline pipeline, uint32_t layer,
                                 uint32_t side) const {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
    const VkViewport viewport{0.0f, 0.0f, float(side), float(side), 0.0f, 1.0f};
    const VkRect2D scissor{{0, 0}, {side, side}};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
    const ShadowMapPush push{.clipFromWorld = mLayers[layer].clipFromWorld,
                             .viewport = glm::vec2(float(side))};
    vkCmdPushConstants(cmd, mPipelineLayout.get(), VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(push),
                       &push);
    const VkBuffer vertices = mVertices.handle();
    const VkDeviceSize zero = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &vertices, &zero);
    vkCmdBindIndexBuffer(cmd, mIndices.handle(), 0, VK_INDEX_TYPE_UINT32);
}

void ShadowMapPass::record(VkCommandBuffer cmd, const FrameResources&) {
    mRenderedLights = 0;
    mDrawnTriangles = 0;
    mRenderedTexels = 0;
    mOneSidedTriangles = 0;
    // The layers to render: every layer of each light that changed. One barrier before and one
    // after all of them (layers are separate subresources, so no layer waits for another, and
    // the rasteriser can bin one layer while it fills the previous).
    std::vector<VkImageMemoryBarrier> toDepth;
    for (const LightSlot& slot : mCurrent) {
        if (!slot.dirty) continue;
        // Earlier compute reads of these layers finish before they are rendered over.
        VkImageMemoryBarrier barrier{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        barrier.srcAccessMask = VK_ACCESS_SHADER_READ_BIT;
        barrier.dstAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT |
                                VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        barrier.oldLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        barrier.newLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
        barrier.srcQueueFamilyIndex = barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        barrier.image = mDepth.image();
        barrier.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, slot.gpu.firstLayer, slot.layers};
        toDepth.push_back(barrier);
    }
    if (toDepth.empty()) return;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                         VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                             VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                         0, 0, nullptr, 0, nullptr, uint32_t(toDepth.size()), toDepth.data());

    for (LightSlot& slot : mCurrent) {
        if (!slot.dirty) continue;
        ++mRenderedLights;
        for (uint32_t l = 0; l < slot.layers; ++l) {
            const uint32_t layer = slot.gpu.firstLayer + l;
            VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
            depth.imageView = mDepth.layerView(layer);
            depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
            depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
            depth.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
            depth.clearValue.depthStencil = {1.0f, 0};
            VkRenderingInfo rendering{VK_STRUCTURE_TYPE_RENDERING_INFO};
            const uint32_t side = mLayers[layer].side;
            rendering.renderArea = {{0, 0}, {side, side}};
            rendering.layerCount = 1;
            rendering.pDepthAttachment = &depth;
            vkCmdBeginRendering(cmd, &rendering);
            mRenderedTexels += uint64_t(side) * side;
            const uint32_t level = levelFor(slot, layer);
            mLayerLevels[layer] = level;
            const auto ranges = visibleTriangleRanges(clustersOf(level), mLayers[layer].clipFromWorld, slot.eye);
            for (const bool oneSided : {true, false}) {
                bool bound = false;
                for (const TriangleRange& range : ranges) {
                    if (range.oneSided != oneSided) continue;
                    if (!bound) {
                        bindPipeline(cmd, (oneSided ? mOneSidedPipeline : mPipeline).get(), layer,
                                     side);
                        bound = true;
                    }
                    vkCmdDrawIndexed(cmd, 3 * range.triangleCount, 1, 3 * range.firstTriangle, 0, 0);
                    mDrawnTriangles += range.triangleCount;
                    if (oneSided) mOneSidedTriangles += range.triangleCount;
                }
            }
            vkCmdEndRendering(cmd);
        }
        slot.dirty = false;
    }

    // The depth writes finish before surfel lighting samples the layers.
    std::vector<VkImageMemoryBarrier> toRead = toDepth;
    for (VkImageMemoryBarrier& barrier : toRead) {
        barrier.srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
        barrier.oldLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
        barrier.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    }
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 0, nullptr,
                         uint32_t(toRead.size()), toRead.data());
}

}  // namespace pic::gpu
