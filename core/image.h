#pragma once
/// Linear RGB images and their files: OpenEXR (half or float, linear) for measurement and
/// PNG (sRGB, clamped) for people, written with OpenImageIO.

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/error.h"

namespace pic {

/// Largest image side any program renders or accepts, texels.
inline constexpr uint32_t kMaxImageSide = 16384;

/// A linear RGB float image, row 0 at the top.
struct Image {
    uint32_t width = 0;
    uint32_t height = 0;
    std::vector<glm::vec3> pixels;  ///< width·height, row-major

    Image() = default;
    Image(uint32_t w, uint32_t h) : width(w), height(h), pixels(size_t{w} * h, glm::vec3(0.0f)) {}
    glm::vec3& at(uint32_t x, uint32_t y) { return pixels[size_t{y} * width + x]; }
    const glm::vec3& at(uint32_t x, uint32_t y) const { return pixels[size_t{y} * width + x]; }
};

/// Writes by extension: .exr as 32-bit float linear RGB; .png as 8-bit sRGB of
/// exposure·pixel clamped to [0,1]; .hdr/.tif via OpenImageIO as float. Atomic (temp + rename).
Result<void> writeImage(const std::string& path, const Image& image, float exposure = 1.0f);

/// Reads an image as linear RGB (PNG/JPEG are converted from sRGB).
Result<Image> readImage(const std::string& path);

/// Parses "WxH" (e.g. "640x480"); InvalidInput naming the text otherwise, sizes 1..kMaxImageSide.
Result<glm::uvec2> parseImageSize(const std::string& text);

/// Image comparison metrics against a reference (same size required).
struct ImageError {
    double rmse = 0.0;          ///< root mean square error over all pixels and channels
    double relativeRmse = 0.0;  ///< rmse / mean of the reference
    double meanRatio = 0.0;     ///< mean luminance of image / mean luminance of reference
    glm::dvec3 channelRatio{0.0};  ///< mean of each channel of image / of reference (0 where
                                   ///< the reference channel is black)
};
Result<ImageError> compareImages(const Image& image, const Image& reference);

/// The image averaged over block × block pixel blocks, ⌈width/block⌉ × ⌈height/block⌉ pixels
/// (blocks cut by the right or bottom edge average the pixels they hold): compared with a
/// reference averaged the same way, it gives the error at a coarser scale. InvalidInput for
/// block 0 or an empty image.
Result<Image> blockAverage(const Image& image, uint32_t block);

/// Blotch index: the relative RMSE of `image` against `reference` over block × block tiles
/// after scaling `image` to the reference's mean luminance, so that a global bias does not
/// count, only disagreement between neighbouring regions (issue 23: linked against ideal
/// caches, 4 × 4 blocks). Fails like compareImages, and when `image` is black.
Result<double> blotchIndex(const Image& image, const Image& reference, uint32_t block = 4);

}  // namespace pic
