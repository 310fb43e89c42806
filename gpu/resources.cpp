#include "gpu/resources.h"

#include <algorithm>
#include <bit>
#include <cstring>

#include "gpu/device.h"
#include "gpu/vk_error.h"

namespace pic::gpu {
namespace {

/// The first memory type among `allowed` with the `required` flags and the `preferred` ones,
/// else the first with the `required` flags.
Result<uint32_t> memoryType(const Context& context, uint32_t allowed,
                            VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) {
    const VkPhysicalDeviceMemoryProperties& memory = context.memoryProperties();
    int best = -1;
    for (uint32_t t = 0; t < memory.memoryTypeCount; ++t) {
        const VkMemoryPropertyFlags flags = memory.memoryTypes[t].propertyFlags;
        if (!(allowed & (1u << t)) || (flags & required) != required) continue;
        if ((flags & preferred) == preferred) return t;
        if (best < 0) best = int(t);
    }
    if (best < 0)
        return fail(ErrorCode::Unsupported,
                    "Vulkan device \"{}\" has no memory type with flags {:#x}",
                    context.deviceName(), uint32_t(required));
    return uint32_t(best);
}

/// Memory for `requirements` of a type memoryType() picks; `flags` (when given) receives the
/// type's flags. Out-of-memory failures say so and name `what`.
Result<DeviceMemory> allocate(const Context& context, const VkMemoryRequirements& requirements,
                              VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred,
                              const char* what, VkMemoryPropertyFlags* flags = nullptr) {
    PIC_TRY_ASSIGN(const uint32_t type,
                   memoryType(context, requirements.memoryTypeBits, required, preferred));
    const VkPhysicalDeviceMemoryProperties& memory = context.memoryProperties();
    if (flags) *flags = memory.memoryTypes[type].propertyFlags;
    const VkDeviceSize heap = memory.memoryHeaps[memory.memoryTypes[type].heapIndex].size;
    if (requirements.size > heap)
        return fail(ErrorCode::Internal,
                    "{} needs {:.1f} MiB, more than the {:.1f} MiB memory heap of \"{}\" (out of "
                    "memory)",
                    what, double(requirements.size) / (1 << 20), double(heap) / (1 << 20),
                    context.deviceName());
    VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    info.allocationSize = requirements.size;
    info.memoryTypeIndex = type;
    VkDeviceMemory allocated = VK_NULL_HANDLE;
    if (VkResult r = vkAllocateMemory(context.device(), &info, nullptr, &allocated);
        r != VK_SUCCESS)
        return fail(ErrorCode::Internal, "allocating {:.1f} MiB for {} failed: {} (out of memory)",
                    double(requirements.size) / (1 << 20), what, vkResultName(r));
    return DeviceMemory(context.device(), allocated);
}

/// A 2D image of `layers` layers of `extent` texels of `format` for `usage` (optimal tiling,
/// one sample, one mip level, layout UNDEFINED) in device-local memory of its own; returns the
/// memory's size.
Result<VkDeviceSize> createImage(const Context& context, VkFormat format, VkExtent2D extent,
                                 uint32_t layers, VkImageUsageFlags usage, const char* what,
                                 DeviceMemory& memory, Image& image) {
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {extent.width, extent.height, 1};
    info.mipLevels = 1;
    info.arrayLayers = layers;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    const VkDevice device = context.device();
    VkImage created = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreateImage(device, &info, nullptr, &created));
    image = Image(device, created);
    VkMemoryRequirements requirements;
    vkGetImageMemoryRequirements(device, created, &requirements);
    PIC_TRY_ASSIGN(memory,
                   allocate(context, requirements, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0, what));
    PIC_VK_TRY(vkBindImageMemory(device, created, memory.get(), 0));
    return requirements.size;
}

/// A view of `range` of `image` as `format`.
Result<ImageView> createImageView(VkDevice device, VkImage image, VkImageViewType type,
                                  VkFormat format, const VkImageSubresourceRange& range) {
    VkImageViewCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    info.image = image;
    info.viewType = type;
    info.format = format;
    info.subresourceRange = range;
    VkImageView view = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreateImageView(device, &info, nullptr, &view));
    return ImageView(device, view);
}

/// Bytes per texel of the formats texel views take (0 for any other).
VkDeviceSize texelSize(VkFormat format) {
    switch (format) {
    case VK_FORMAT_R16_SFLOAT:
        return 2;
    case VK_FORMAT_R32_UINT:
    case VK_FORMAT_R32_SFLOAT:
        return 4;
    case VK_FORMAT_R32G32_UINT:
        return 8;
    case VK_FORMAT_R32G32B32_UINT:
        return 12;
    case VK_FORMAT_R32G32B32A32_UINT:
    case VK_FORMAT_R32G32B32A32_SFLOAT:
        return 16;
    default:
        return 0;
    }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Buffer, TexelView

Result<Buffer> Buffer::create(Context& context, VkDeviceSize bytes, VkBufferUsageFlags usage,
                              MemoryUse use, const char* what) {
    PIC_TRY(context.checkAlive());
    const VkDevice device = context.device();
    Buffer buffer;
    buffer.mSize = std::max<VkDeviceSize>(bytes, 4);
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = buffer.mSize;
    info.usage = usage | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                 VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    VkBuffer created = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreateBuffer(device, &info, nullptr, &created));
    buffer.mBuffer = {device, created};
    VkMemoryRequirements requirements;
    vkGetBufferMemoryRequirements(device, created, &requirements);
    VkMemoryPropertyFlags flags = 0;
    if (use == MemoryUse::Device) {
        PIC_TRY_ASSIGN(
            buffer.mMemory,
            allocate(context, requirements, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0, what, &flags));
    } else {
        PIC_TRY_ASSIGN(buffer.mMemory, allocate(context, requirements,
                                                VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                                    VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                                VK_MEMORY_PROPERTY_HOST_CACHED_BIT, what, &flags));
    }
    PIC_VK_TRY(vkBindBufferMemory(device, created, buffer.mMemory.get(), 0));
    // Memory the host sees coherently is mapped once for its whole life.
    const VkMemoryPropertyFlags mappable =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    if ((flags & mappable) == mappable && (use != MemoryUse::Device || context.mapsDeviceMemory()))
        PIC_VK_TRY(vkMapMemory(device, buffer.mMemory.get(), 0, VK_WHOLE_SIZE, 0, &buffer.mMapped));
    return buffer;
}

Result<Buffer> Buffer::createWith(Context& context, const void* data, VkDeviceSize bytes,
                                  VkBufferUsageFlags usage, const char* what) {
    PIC_TRY_ASSIGN(Buffer buffer, create(context, bytes, usage, MemoryUse::Device, what));
    if (bytes > 0) PIC_TRY(context.upload(buffer, data, bytes));
    return buffer;
}

Result<TexelView> TexelView::create(Context& context, const Buffer& buffer, VkFormat format,
                                    const char* what) {
    const VkDeviceSize texelBytes = texelSize(format);
    return create(context, buffer, format, 0, texelBytes ? buffer.size() / texelBytes : 0, what);
}

Result<TexelView> TexelView::create(Context& context, const Buffer& buffer, VkFormat format,
                                    VkDeviceSize offset, VkDeviceSize texels, const char* what) {
    const VkDeviceSize texelBytes = texelSize(format);
    if (texelBytes == 0)
        return fail(ErrorCode::InvalidInput, "{}: texel format {} is not one texel views take",
                    what, int(format));
    if (!context.canReadTexels(format))
        return fail(ErrorCode::Unsupported, "{}: {} cannot read format {} as a texel buffer", what,
                    context.deviceName(), int(format));
    const VkPhysicalDeviceLimits& limits = context.properties().limits;
    if (texels == 0 || texels > limits.maxTexelBufferElements)
        return fail(ErrorCode::Unsupported, "{}: a texel view of {} elements (1 to {} on {})", what,
                    texels, limits.maxTexelBufferElements, context.deviceName());
    if (offset % limits.minTexelBufferOffsetAlignment != 0 ||
        offset + texels * texelBytes > buffer.size())
        return fail(ErrorCode::InvalidInput,
                    "{}: texels [{}, {}) of {} bytes do not lie aligned within a buffer of {} "
                    "bytes (offset alignment {})",
                    what, offset, offset + texels * texelBytes, texelBytes, buffer.size(),
                    limits.minTexelBufferOffsetAlignment);
    VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    info.buffer = buffer.handle();
    info.format = format;
    info.offset = offset;
    info.range = texels * texelBytes;
    VkBufferView created = VK_NULL_HANDLE;
    PIC_VK_TRY(vkCreateBufferView(context.device(), &info, nullptr, &created));
    TexelView view;
    view.mView = {context.device(), created};
    return view;
}

// ---------------------------------------------------------------------------------------------
// DepthArray, RenderTarget

Result<DepthArray> DepthArray::create(Context& context, uint32_t size, uint32_t layers) {
    PIC_TRY(context.checkAlive());
    const VkPhysicalDeviceLimits& limits = context.properties().limits;
    if (size == 0 || layers == 0 || size > limits.maxImageDimension2D ||
        layers > limits.maxImageArrayLayers)
        return fail(ErrorCode::InvalidInput,
                    "shadow maps of {}² × {} layers exceed the device's limits ({}², {} layers)",
                    size, layers, limits.maxImageDimension2D, limits.maxImageArrayLayers);
    DepthArray depth;
    depth.mSize = size;
    // Cleared once at creation; read back by Context::downloadDepthLayer.
    const VkImageUsageFlags usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT |
                                    VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                                    VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    PIC_TRY(createImage(context, VK_FORMAT_D32_SFLOAT, {size, size}, layers, usage, "shadow maps",
                        depth.mMemory, depth.mImage));

    const VkDevice device = context.device();
    PIC_TRY_ASSIGN(
        depth.mArrayView,
        createImageView(device, depth.image(), VK_IMAGE_VIEW_TYPE_2D_ARRAY, VK_FORMAT_D32_SFLOAT,
                        {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, layers}));
    for (uint32_t layer = 0; layer < layers; ++layer) {
        PIC_TRY_ASSIGN(
            ImageView view,
            createImageView(device, depth.image(), VK_IMAGE_VIEW_TYPE_2D, VK_FORMAT_D32_SFLOAT,
                            {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, layer, 1}));
        depth.mLayerViews.push_back(std::move(view));
    }
    // Every layer starts readable (cleared to the far plane) so that a pass may sample layers
    // that no light rendered yet.
    PIC_TRY(context.submit([&](VkCommandBuffer cmd) {
        VkImageMemoryBarrier toClear{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        toClear.srcAccessMask = 0;
        toClear.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        toClear.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        toClear.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        toClear.srcQueueFamilyIndex = toClear.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        toClear.image = depth.image();
        toClear.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, layers};
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             0, 0, nullptr, 0, nullptr, 1, &toClear);
        const VkClearDepthStencilValue far{1.0f, 0};
        vkCmdClearDepthStencilImage(cmd, depth.image(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &far,
                                    1, &toClear.subresourceRange);
        // The clear before any shader read of the layers.
        VkImageMemoryBarrier toRead = toClear;
        toRead.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        toRead.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
        toRead.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        toRead.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 0, nullptr, 1,
                             &toRead);
    }));
    return depth;
}

Result<RenderTarget> RenderTarget::create(Context& context, uint32_t width, uint32_t height,
                                          VkFormat format, const char* what) {
    PIC_TRY(context.checkAlive());
    const uint32_t limit = context.properties().limits.maxImageDimension2D;
    if (width == 0 || height == 0 || width > limit || height > limit)
        return fail(ErrorCode::InvalidInput, "{} of {}x{} is outside the device's 1..{} per side",
                    what, width, height, limit);
    const bool depth = format == VK_FORMAT_D32_SFLOAT;
    RenderTarget target;
    target.mFormat = format;
    target.mWidth = width;
    target.mHeight = height;
    const VkImageUsageFlags usage =
        depth ? VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
              : VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
    PIC_TRY_ASSIGN(target.mBytes, createImage(context, format, {width, height}, 1, usage, what,
                                              target.mMemory, target.mImage));
    const VkImageAspectFlags aspect = depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
    PIC_TRY_ASSIGN(target.mView,
                   createImageView(context.device(), target.image(), VK_IMAGE_VIEW_TYPE_2D, format,
                                   {aspect, 0, 1, 0, 1}));
    return target;
}

// ---------------------------------------------------------------------------------------------
// Context's transfers

Result<Buffer*> Context::staging(VkDeviceSize bytes) {
    if (mStaging.size() < bytes) {
        mStaging = {};
        PIC_TRY_ASSIGN(mStaging, Buffer::create(*this, std::bit_ceil(bytes), 0, MemoryUse::Readback,
                                                "staging"));
    }
    return &mStaging;
}

Result<void> Context::upload(Buffer& buffer, const void* data, VkDeviceSize bytes,
                             VkDeviceSize offset) {
    PIC_CHECK(offset + bytes <= buffer.size());
    if (buffer.mapped()) {
        std::memcpy(static_cast<char*>(buffer.mapped()) + offset, data, bytes);
        return {};
    }
    PIC_TRY_ASSIGN(Buffer* staging, this->staging(bytes));
    std::memcpy(staging->mapped(), data, bytes);
    return submit([&](VkCommandBuffer cmd) {
        const VkBufferCopy region{0, offset, bytes};
        vkCmdCopyBuffer(cmd, staging->handle(), buffer.handle(), 1, &region);
    });
}

Result<void> Context::uploadWithNextSubmit(Buffer& buffer, const void* data, VkDeviceSize bytes,
                                           VkDeviceSize offset) {
    PIC_CHECK(offset + bytes <= buffer.size());
    if (buffer.mapped()) return upload(buffer, data, bytes, offset);  // at once, no submission
    VkDeviceSize start = (mPendingBytes + 15) / 16 * 16;
    if (start + bytes > mPendingStaging.size()) {
        // Grow only with nothing pending: an empty submission records what is.
        if (!mPending.empty()) PIC_TRY(submit([](VkCommandBuffer) {}));
        if (bytes > mPendingStaging.size()) {
            mPendingStaging = {};
            const VkDeviceSize size = std::bit_ceil(std::max<VkDeviceSize>(bytes, 4096));
            PIC_TRY_ASSIGN(mPendingStaging,
                           Buffer::create(*this, size, 0, MemoryUse::Readback, "pending uploads"));
        }
        start = 0;
    }
    std::memcpy(static_cast<char*>(mPendingStaging.mapped()) + start, data, bytes);
    mPending.push_back({buffer.handle(), start, offset, bytes});
    mPendingBytes = start + bytes;
    return {};
}

void Context::recordPendingUploads(VkCommandBuffer cmd) {
    if (mPending.empty()) return;
    for (const PendingUpload& u : mPending) {
        const VkBufferCopy region{u.stagingOffset, u.targetOffset, u.bytes};
        vkCmdCopyBuffer(cmd, mPendingStaging.handle(), u.target, 1, &region);
    }
    // The uploads land before any later command reads them.
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0,
                         1, &barrier, 0, nullptr, 0, nullptr);
    // Recorded: the staging bytes stay untouched until this submission has waited.
    mPending.clear();
    mPendingBytes = 0;
}

Result<void> Context::download(const Buffer& buffer, void* data, VkDeviceSize bytes,
                               VkDeviceSize offset) {
    PIC_CHECK(offset + bytes <= buffer.size());
    if (buffer.mapped()) {
        std::memcpy(data, static_cast<const char*>(buffer.mapped()) + offset, bytes);
        return {};
    }
    PIC_TRY_ASSIGN(Buffer* staging, this->staging(bytes));
    PIC_TRY(submit([&](VkCommandBuffer cmd) {
        const VkBufferCopy region{offset, 0, bytes};
        vkCmdCopyBuffer(cmd, buffer.handle(), staging->handle(), 1, &region);
    }));
    std::memcpy(data, staging->mapped(), bytes);
    return {};
}

Result<std::vector<float>> Context::downloadDepthLayer(const DepthArray& depth, uint32_t layer) {
    PIC_CHECK(layer < depth.layers());
    const VkDeviceSize bytes = VkDeviceSize{depth.size()} * depth.size() * sizeof(float);
    PIC_TRY_ASSIGN(Buffer staging,
                   Buffer::create(*this, bytes, 0, MemoryUse::Readback, "depth download"));
    PIC_TRY(submit([&](VkCommandBuffer cmd) {
        // Earlier depth writes and shader reads finish before the copy reads the layer.
        VkImageMemoryBarrier toCopy{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        toCopy.srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        toCopy.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        toCopy.oldLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        toCopy.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        toCopy.srcQueueFamilyIndex = toCopy.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        toCopy.image = depth.image();
        toCopy.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, layer, 1};
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                             VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &toCopy);
        VkBufferImageCopy region{};
        region.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, layer, 1};
        region.imageExtent = {depth.size(), depth.size(), 1};
        vkCmdCopyImageToBuffer(cmd, depth.image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                               staging.handle(), 1, &region);
        // The copy finishes before the layer is sampled or rendered again.
        VkImageMemoryBarrier back = toCopy;
        back.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        back.dstAccessMask = 0;
        back.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        back.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0, nullptr, 0, nullptr, 1,
                             &back);
    }));
    std::vector<float> texels(size_t(depth.size()) * depth.size());
    std::memcpy(texels.data(), staging.mapped(), bytes);
    return texels;
}

}  // namespace pic::gpu
