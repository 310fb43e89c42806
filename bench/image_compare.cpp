#include "bench/image_compare.h"

#include <cstdio>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bench/bench_common.h"
#include "core/image.h"

namespace pic {

int runImageCompare(const ImageCompareParams& params) {
    auto image = readImage(params.imagePath);
    if (!image) return reportError(image.error());
    auto reference = readImage(params.referencePath);
    if (!reference) return reportError(reference.error());
    // Sizes before any averaging, so that the message names the files' own sizes.
    if (image->width != reference->width || image->height != reference->height)
        return reportError(Error{
            ErrorCode::InvalidInput,
            fmt::format("{} is {}x{} but the reference {} is {}x{}", params.imagePath, image->width,
                        image->height, params.referencePath, reference->width, reference->height)});

    nlohmann::ordered_json json;
    json["image"] = params.imagePath;
    json["reference"] = params.referencePath;
    json["width"] = image->width;
    json["height"] = image->height;
    nlohmann::ordered_json rows = nlohmann::ordered_json::array();
    std::printf("%8s  %13s  %10s  %12s\n", "block", "relative RMSE", "mean ratio", "mean-matched");
    for (const uint32_t block : params.blocks) {
        auto averaged = blockAverage(*image, block);
        if (!averaged) return reportError(averaged.error());
        auto averagedReference = blockAverage(*reference, block);
        if (!averagedReference) return reportError(averagedReference.error());
        auto error = compareImages(*averaged, *averagedReference);
        if (!error) return reportError(error.error());
        // The same after scaling the image to the reference's mean (at 4 × 4 blocks, the
        // accuracy benchmark's blotch index): what remains is disagreement in shape.
        auto matched = blotchIndex(*image, *reference, block);
        if (!matched) return reportError(matched.error());
        std::printf("%3ux%-4u  %13.4f  %10.4f  %12.4f\n", block, block, error->relativeRmse,
                    error->meanRatio, *matched);
        rows.push_back({{"block", block},
                        {"relative_rmse", error->relativeRmse},
                        {"rmse", error->rmse},
                        {"mean_ratio", error->meanRatio},
                        {"mean_matched_relative_rmse", *matched}});
    }
    json["blocks"] = rows;
    if (params.jsonPath.empty()) return 0;
    return writeJson(json, params.jsonPath);
}

}  // namespace pic
