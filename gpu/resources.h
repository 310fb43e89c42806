#pragma once
/// GPU resources: buffers with their memory, texel views of buffers, depth arrays and render
/// targets. Each is made by its static create() on a Context and holds Handles (handle.h), so it
/// is move-only and frees itself; it must not outlive its context. Transfers between the host
/// and buffers are the Context's (device.h): they share its staging buffers and its queue.

#include <cstdint>
#include <span>
#include <vector>

#include <vulkan/vulkan.h>

#include "core/error.h"
#include "gpu/handle.h"

namespace pic::gpu {

class Context;

/// Where a buffer lives.
enum class MemoryUse {
    Device,    ///< device-local; mapped too when the device shares memory with the host
    Readback,  ///< host-visible, coherent (cached when available): results read by the CPU
};

/// A buffer and its memory. Moved from, it is empty: null handle, size 0, not mapped.
class Buffer {
public:
    /// A buffer of `bytes` (> 0) for `usage` (storage and transfer usage are always added).
    static Result<Buffer> create(Context& context, VkDeviceSize bytes, VkBufferUsageFlags usage,
                                 MemoryUse use, const char* what);
    /// A device buffer holding `bytes` of `data` (uploaded through a staging buffer when the
    /// device memory is not mapped).
    static Result<Buffer> createWith(Context& context, const void* data, VkDeviceSize bytes,
                                     VkBufferUsageFlags usage, const char* what);
    /// A device buffer holding the elements of `data`.
    template <class T>
    static Result<Buffer> createWith(Context& context, std::span<const T> data,
                                     VkBufferUsageFlags usage, const char* what) {
        return createWith(context, data.data(), data.size_bytes(), usage, what);
    }

    VkBuffer handle() const { return mBuffer.get(); }
    VkDeviceSize size() const { return mBuffer ? mSize : 0; }
    /// Host pointer of a mapped buffer, null when the memory is not host-visible.
    void* mapped() const { return mBuffer ? mMapped : nullptr; }

private:
    DeviceMemory mMemory;  // before mBuffer: freed after it
    Handle<VkBuffer, vkDestroyBuffer> mBuffer;
    VkDeviceSize mSize = 0;
    void* mMapped = nullptr;
};

/// A typed view of a buffer range that shaders read as a uniform texel buffer
/// (`usamplerBuffer`, `samplerBuffer`). Texel fetches are gathers without branches on
/// lavapipe, where a storage-buffer load at an index that differs per lane is a branch per lane.
class TexelView {
public:
    /// A view of `texels` elements of `format` (32-bit components: R32, R32G32, R32G32B32 or
    /// R32G32B32A32 UINT; R16, R32 or R32G32B32A32 SFLOAT) in `buffer` from byte `offset`, which
    /// the buffer's usage must allow (VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT). Unsupported when
    /// `texels` exceeds maxTexelBufferElements or the format cannot be a uniform texel buffer.
    static Result<TexelView> create(Context& context, const Buffer& buffer, VkFormat format,
                                    VkDeviceSize offset, VkDeviceSize texels, const char* what);
    /// A view of all of `buffer` as texels of `format` (as many as fit).
    static Result<TexelView> create(Context& context, const Buffer& buffer, VkFormat format,
                                    const char* what);

    VkBufferView handle() const { return mView.get(); }

private:
    BufferView mView;
};

/// A 2D-array depth image (shadow maps): one view of all layers for sampling and one view per
/// layer for rendering.
class DepthArray {
public:
    /// A D32 depth array of `layers` square layers of `size`², sampled and rendered to, in
    /// SHADER_READ_ONLY layout once created (cleared to the far plane).
    static Result<DepthArray> create(Context& context, uint32_t size, uint32_t layers);

    VkImage image() const { return mImage.get(); }
    VkImageView arrayView() const { return mArrayView.get(); }
    VkImageView layerView(uint32_t layer) const { return mLayerViews[layer].get(); }
    uint32_t size() const { return mSize; }
    uint32_t layers() const { return uint32_t(mLayerViews.size()); }
    VkDeviceSize bytes() const { return VkDeviceSize{mSize} * mSize * layers() * 4; }

private:
    DeviceMemory mMemory;  // memory, image, views: destroyed views first
    Image mImage;
    ImageView mArrayView;
    std::vector<ImageView> mLayerViews;
    uint32_t mSize = 0;
};

/// A 2D image with one view over its single layer: a colour or depth target that a raster
/// pass renders and later passes sample. Its layout is UNDEFINED once created; the pass that
/// renders it transitions it.
class RenderTarget {
public:
    /// A width × height render target of `format`: a depth attachment for depth formats
    /// (VK_FORMAT_D32_SFLOAT), else a colour attachment that shaders may sample. InvalidInput
    /// when a side is 0 or beyond the device's 2D image limit.
    static Result<RenderTarget> create(Context& context, uint32_t width, uint32_t height,
                                       VkFormat format, const char* what);

    VkImage image() const { return mImage.get(); }
    VkImageView view() const { return mView.get(); }
    VkFormat format() const { return mFormat; }
    uint32_t width() const { return mWidth; }
    uint32_t height() const { return mHeight; }
    VkDeviceSize bytes() const { return mBytes; }

private:
    DeviceMemory mMemory;  // memory, image, view: destroyed view first
    Image mImage;
    ImageView mView;
    VkFormat mFormat = VK_FORMAT_UNDEFINED;
    uint32_t mWidth = 0;
    uint32_t mHeight = 0;
    VkDeviceSize mBytes = 0;
};

}  // namespace pic::gpu
