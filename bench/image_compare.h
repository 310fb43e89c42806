#pragma once
/// `picbench compare`: the error of an image against a reference at several scales. For each
/// block size b, both images are averaged over b × b pixel blocks (core/image.h
/// blockAverage) and compared (compareImages): b = 1 is the per-pixel error, larger blocks
/// show how much of it is detail at the pixel scale (texture aliasing, noise) rather than
/// error in the lighting. Each block size also reports the error after scaling the image to
/// the reference's mean luminance (core/image.h blotchIndex; at 4 × 4 blocks the accuracy
/// benchmark's blotch index, so that a linked image can be held against ideal caches of any
/// sample count). Prints one line per block size; optionally writes JSON.

#include <cstdint>
#include <string>
#include <vector>

namespace pic {

struct ImageCompareParams {
    std::string imagePath;
    std::string referencePath;
    std::vector<uint32_t> blocks{1, 4, 16};  ///< block sides in pixels
    std::string jsonPath;                    ///< empty: no JSON
};

/// Exit code 0, 1 (a file could not be read or written) or 2 (images of different sizes,
/// a reference or image of mean 0, non-finite pixels, a block of size 0).
int runImageCompare(const ImageCompareParams& params);

}  // namespace pic
