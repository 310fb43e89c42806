#include "render/passes/gbuffer_pass.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/camera.h"
#include "gpu/pipelines.h"
#include "gpu/vk_error.h"
#include "render/gbuffer_geometry.h"
#include "spirv/gbuffer_frag.h"
#include "spirv/gbuffer_vert.h"

namespace pic::gpu {
namespace {

/// Storage buffers the fragment shader reads: triangles, materials, textures, texels,
/// emissive scales, mip levels (shaders/gbuffer.frag bindings 0–5).
constexpr uint32_t kBindingCount = 6;

static_assert(kGbufferMaxAnisotropy == kMaxAnisotropy, "the shader filters as core/texture.h");

/// The colour targets' names, for allocation messages.
constexpr const char* kTargetNames[kGbufferTargets] = {"G-buffer positions", "G-buffer normals",
                                                       "G-buffer albedo", "G-buffer emission"};

}  // namespace

glm::mat4 clipFromWorldOf(const Camera& camera, uint32_t width, uint32_t height, float near) {
    // The basis of core/camera.cpp CameraRays: right = forward × up, up re-orthogonalised.
    const glm::vec3 forward = glm::normalize(camera.target - camera.eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, camera.up));
    const glm::vec3 up = glm::cross(right, forward);
    const float tanHalfFovy = std::tan(glm::radians(camera.fovyDegrees) * 0.5f);
    const float aspect = float(width) / float(height);
    // A direction forward + a·aspect·tan·right + b·tan·up is CameraRays' at ndc (a, b) with b
    // growing upward; Vulkan's ndc y grows downward, hence the sign of row 1. Rows of the
    // matrix applied to (p, 1): x = right·(p − eye)/(aspect·tan), y = −up·(p − eye)/tan,
    // z = near (reversed depth near/w), w = forward·(p − eye).
    const glm::vec3 rowX = right / (aspect * tanHalfFovy);
    const glm::vec3 rowY = -up / tanHalfFovy;
    glm::mat4 m(0.0f);  // m[column][row]
    for (int c = 0; c < 3; ++c) {
        m[c][0] = rowX[c];
        m[c][1] = rowY[c];
        m[c][3] = forward[c];
    }
    m[3][0] = -glm::dot(rowX, camera.eye);
    m[3][1] = -glm::dot(rowY, camera.eye);
    m[3][2] = near;
    m[3][3] = -glm::dot(forward, camera.eye);
    return m;
}

GbufferPush gbufferPushOf(const Camera& camera, uint32_t width, uint32_t height, float near,
                          glm::vec2 offset, float footprintScale) {
    GbufferPush push{};
    push.clipFromWorld = clipFromWorldOf(camera, width, height, near);
    // Framebuffer x is (ndc x + 1)·width/2, as CameraRays' image x, and likewise y: adding
    // 2·(½ − offset)/size to ndc (times w in clip space) moves the point on the ray through
    // x + offset onto the pixel centre x + ½.
    const glm::vec2 shift = 2.0f * (glm::vec2(0.5f) - offset) / glm::vec2(width, height);
    for (int c = 0; c < 4; ++c) {
        push.clipFromWorld[c][0] += shift.x * push.clipFromWorld[c][3];
        push.clipFromWorld[c][1] += shift.y * push.clipFromWorld[c][3];
    }
    push.eye = camera.eye;
    const CameraRays rays(camera, width, height);
    push.directionPerPixelX = glm::vec4(footprintScale * rays.directionPerPixelX(), 0.0f);
    push.directionPerPixelY = glm::vec4(footprintScale * rays.directionPerPixelY(), 0.0f);
    return push;
}

Result<std::unique_ptr<Pass>> GbufferPass::create(Context& context, const PassConfig& config) {
    PIC_CHECK(config.scene != nullptr);
    const Scene& scene = *config.scene;
    const std::span<const glm::vec2> triangleUvs = config.triangleUvs;
    PIC_CHECK_EQ(triangleUvs.size(), 3 * scene.triangles.size());
    // The arrays the shaders read, built on the CPU (render/gbuffer_geometry.h), uploaded below.
    PIC_TRY_ASSIGN(GbufferGeometry geometry, gbufferGeometryOf(scene, triangleUvs));
    const auto& [vertices, triangles, materials, textures, levels, texels] = geometry;
    std::unique_ptr<GbufferPass> pass(new GbufferPass(context, scene));
    pass->mVertexCount = uint32_t(vertices.size());

    // Each array the fragment shader reads is one storage-buffer binding.
    const VkDeviceSize range = context.properties().limits.maxStorageBufferRange;
    const std::pair<VkDeviceSize, const char*> arrays[] = {
        {texels.size() * sizeof(glm::vec4), "the textures as float RGBA"},
        {triangles.size() * sizeof(GbufferTriangle), "the triangle records"},
        {materials.size() * sizeof(GbufferMaterial), "the materials"}};
    for (const auto& [bytes, what] : arrays)
        if (bytes > range)
            return fail(ErrorCode::Unsupported,
                        "{} of scene {} take {:.1f} MiB, more than the {:.1f} MiB one storage "
                        "buffer of \"{}\" holds",
                        what, scene.sourcePath, double(bytes) / (1 << 20),
                        double(range) / (1 << 20), context.deviceName());

    PIC_TRY_ASSIGN(pass->mVertices,
                   Buffer::createWith(context, std::span<const GbufferVertex>(vertices),
                                      VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, "G-buffer vertices"));
    PIC_TRY_ASSIGN(pass->mTriangles,
                   Buffer::createWith(context, std::span<const GbufferTriangle>(triangles), 0,
                                      "G-buffer triangles"));
    PIC_TRY_ASSIGN(
        pass->mMaterials,
        Buffer::createWith(context, std::span<const GbufferMaterial>(materials), 0, "materials"));
    PIC_TRY_ASSIGN(pass->mTextures,
                   Buffer::createWith(context, std::span<const GbufferTexture>(textures), 0,
                                      "texture records"));
    PIC_TRY_ASSIGN(pass->mTexels,
                   Buffer::createWith(context, std::span<const glm::vec4>(texels), 0, "texels"));
    PIC_TRY_ASSIGN(pass->mLevels,
                   Buffer::createWith(context, std::span<const GbufferTextureLevel>(levels), 0,
                                      "texture mip levels"));
    PIC_TRY_ASSIGN(
        pass->mEmissiveScale,
        Buffer::create(context, std::max<size_t>(scene.materials.size(), 1) * sizeof(float), 0,
                       MemoryUse::Device, "emissive scales"));
    PIC_TRY(pass->createPipeline());
    return pass;
}

Result<void> GbufferPass::createPipeline() {
    VkDevice device = mContext.device();

    // One set of storage buffers for the fragment shader; it never changes.
    std::array<VkDescriptorType, kBindingCount> bindings;
    bindings.fill(VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    PIC_TRY_ASSIGN(mSetLayout,
                   createDescriptorSetLayout(mContext, bindings, VK_SHADER_STAGE_FRAGMENT_BIT));
    PIC_TRY_ASSIGN(mPool, createDescriptorPool(mContext, bindings, 1));
    VkDescriptorSetAllocateInfo allocInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    allocInfo.descriptorPool = mPool.get();
    allocInfo.descriptorSetCount = 1;
    const VkDescriptorSetLayout setLayout = mSetLayout.get();
    allocInfo.pSetLayouts = &setLayout;
    PIC_VK_TRY(vkAllocateDescriptorSets(device, &allocInfo, &mSet));
    const Buffer* buffers[kBindingCount] = {&mTriangles, &mMaterials,     &mTextures,
                                            &mTexels,    &mEmissiveScale, &mLevels};
    std::array<VkDescriptorBufferInfo, kBindingCount> infos;
    std::array<VkWriteDescriptorSet, kBindingCount> writes;
    for (uint32_t b = 0; b < kBindingCount; ++b) {
        infos[b] = {buffers[b]->handle(), 0, VK_WHOLE_SIZE};
        writes[b] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        writes[b].dstSet = mSet;
        writes[b].dstBinding = b;
        writes[b].descriptorCount = 1;
        writes[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        writes[b].pBufferInfo = &infos[b];
    }
    vkUpdateDescriptorSets(device, kBindingCount, writes.data(), 0, nullptr);

    PIC_TRY_ASSIGN(mPipelineLayout,
                   createPipelineLayout(mContext, setLayout,
                                        {VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
                                         0, sizeof(GbufferPush)}));

    const VkVertexInputAttributeDescription attributes[] = {
        {0, 0, VK_FORMAT_R32G32B32_SFLOAT, uint32_t(offsetof(GbufferVertex, position))},
        {1, 0, VK_FORMAT_R32G32B32A32_SFLOAT, uint32_t(offsetof(GbufferVertex, color))},
        {2, 0, VK_FORMAT_R32G32_SFLOAT, uint32_t(offsetof(GbufferVertex, uv0))},
        {3, 0, VK_FORMAT_R32G32_SFLOAT, uint32_t(offsetof(GbufferVertex, uv1))},
        {4, 0, VK_FORMAT_R32G32_SFLOAT, uint32_t(offsetof(GbufferVertex, lightmapUv))},
    };
    std::array<VkFormat, kGbufferTargets> formats;
    formats.fill(kGbufferFormat);
    RasterPipelineDesc desc;
    desc.vertexSpirv = kSpirvGbufferVert;
    desc.vertexName = "gbuffer.vert";
    desc.fragmentSpirv = kSpirvGbufferFrag;
    desc.fragmentName = "gbuffer.frag";
    desc.binding = {0, sizeof(GbufferVertex), VK_VERTEX_INPUT_RATE_VERTEX};
    desc.attributes = attributes;
    desc.depthCompare = VK_COMPARE_OP_GREATER;  // reversed depth: nearer is larger
    desc.colorFormats = formats;
    desc.layout = mPipelineLayout.get();
    PIC_TRY_ASSIGN(mPipeline, createRasterPipeline(mContext, desc));
    return {};
}

Result<void> GbufferPass::prepare(uint32_t width, uint32_t height, const LightSet& lights,
                                  bool& reallocated) {
    reallocated = false;
    if (width != mWidth || height != mHeight) {
        // Forget the old size first, so that a failed allocation leaves no half-sized set.
        mWidth = mHeight = 0;
        for (uint32_t i = 0; i < kGbufferTargets; ++i) {
            PIC_TRY_ASSIGN(mTargets[i], RenderTarget::create(mContext, width, height,
                                                             kGbufferFormat, kTargetNames[i]));
        }
        PIC_TRY_ASSIGN(mDepth, RenderTarget::create(mContext, width, height, VK_FORMAT_D32_SFLOAT,
                                                    "G-buffer depth"));
        mWidth = width;
        mHeight = height;
        reallocated = true;
    }
    std::vector<float> scales(std::max<size_t>(mScene.materials.size(), 1), 1.0f);
    for (size_t m = 0; m < mScene.materials.size(); ++m)
        scales[m] = lights.emissiveScaleOf(mScene.materials[m].name);
    return mContext.upload(mEmissiveScale, scales.data(), scales.size() * sizeof(float));
}

void GbufferPass::record(VkCommandBuffer cmd, const FrameResources& frame) {
    const GbufferPush& push = frame.gbuffer;
    PIC_CHECK(mWidth > 0 && mHeight > 0);
    // Earlier compute reads of the targets finish before they are cleared and drawn over
    // (their old contents are discarded: UNDEFINED).
    std::array<VkImageMemoryBarrier, kGbufferTargets + 1> toRender{};
    for (uint32_t i = 0; i <= kGbufferTargets; ++i) {
        const bool depth = i == kGbufferTargets;
        VkImageMemoryBarrier& b = toRender[i];
        b = {VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        b.srcAccessMask = 0;
        b.dstAccessMask = depth ? VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT |
                                      VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
                                : VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        b.newLayout = depth ? VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL
                            : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
        b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        b.image = depth ? mDepth.image() : mTargets[i].image();
        b.subresourceRange = {depth ? VkImageAspectFlags(VK_IMAGE_ASPECT_DEPTH_BIT)
                                    : VkImageAspectFlags(VK_IMAGE_ASPECT_COLOR_BIT),
                              0, 1, 0, 1};
    }
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                         VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                             VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                             VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                         0, 0, nullptr, 0, nullptr, uint32_t(toRender.size()), toRender.data());

    // Cleared to zero: a pixel no triangle covers has hit flag 0, and reversed depth 0 is
    // infinitely far.
    std::array<VkRenderingAttachmentInfo, kGbufferTargets> colors{};
    for (uint32_t i = 0; i < kGbufferTargets; ++i) {
        colors[i] = {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
        colors[i].imageView = mTargets[i].view();
        colors[i].imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
        colors[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        colors[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        colors[i].clearValue.color = {{0.0f, 0.0f, 0.0f, 0.0f}};
    }
    VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    depth.imageView = mDepth.view();
    depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    depth.clearValue.depthStencil = {0.0f, 0};
    VkRenderingInfo rendering{VK_STRUCTURE_TYPE_RENDERING_INFO};
    rendering.renderArea = {{0, 0}, {mWidth, mHeight}};
    rendering.layerCount = 1;
    rendering.colorAttachmentCount = kGbufferTargets;
    rendering.pColorAttachments = colors.data();
    rendering.pDepthAttachment = &depth;
    vkCmdBeginRendering(cmd, &rendering);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, mPipeline.get());
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, mPipelineLayout.get(), 0, 1,
                            &mSet, 0, nullptr);
    const VkViewport viewport{0.0f, 0.0f, float(mWidth), float(mHeight), 0.0f, 1.0f};
    const VkRect2D scissor{{0, 0}, {mWidth, mHeight}};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
    vkCmdPushConstants(cmd, mPipelineLayout.get(),
                       VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(push),
                       &push);
    const VkBuffer vertices = mVertices.handle();
    const VkDeviceSize zero = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &vertices, &zero);
    vkCmdDraw(cmd, mVertexCount, 1, 0, 0);
    vkCmdEndRendering(cmd);

    // The colour writes finish before the shading pass reads the targets.
    std::array<VkImageMemoryBarrier, kGbufferTargets> toRead{};
    for (uint32_t i = 0; i < kGbufferTargets; ++i) {
        toRead[i] = toRender[i];
        toRead[i].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        toRead[i].dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
        toRead[i].oldLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
        toRead[i].newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    }
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 0, nullptr,
                         kGbufferTargets, toRead.data());
}

VkDeviceSize GbufferPass::bytes() const {
    VkDeviceSize total = mVertices.size() + mTriangles.size() + mMaterials.size() +
                         mTextures.size() + mLevels.size() + mTexels.size() +
                         mEmissiveScale.size() + mDepth.bytes();
    for (const RenderTarget& target : mTargets) total += target.bytes();
    return total;
}

}  // namespace pic::gpu
