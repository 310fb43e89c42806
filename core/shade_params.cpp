#include "core/shade_params.h"

#include <cmath>

#include "core/image.h"

namespace pic {

Result<void> checkShadeParams(const ShadeParams& params) {
    if (params.width == 0 || params.height == 0 || params.width > kMaxImageSide ||
        params.height > kMaxImageSide)
        return fail(ErrorCode::InvalidInput, "image size {}x{} is outside 1..{} per side",
                    params.width, params.height, kMaxImageSide);
    if (params.samplesPerPixel == 0 || params.samplesPerPixel > kMaxSamplesPerPixel)
        return fail(ErrorCode::InvalidInput, "samples per pixel {} is outside 1..{}",
                    params.samplesPerPixel, kMaxSamplesPerPixel);
    if (!(std::isfinite(params.glossyExponent) && params.glossyExponent >= 0.0f))
        return fail(ErrorCode::InvalidInput, "glossy exponent {} is not a finite number ≥ 0",
                    params.glossyExponent);
    if (!(std::isfinite(params.glossyWeight) && params.glossyWeight >= 0.0f))
        return fail(ErrorCode::InvalidInput, "glossy weight {} is not a finite number ≥ 0",
                    params.glossyWeight);
    if (params.component == ShadeComponent::Glossy &&
        !(params.glossyExponent > 0.0f && params.glossyWeight > 0.0f))
        return fail(ErrorCode::InvalidInput,
                    "the glossy component needs a lobe: exponent {} and weight {} must be > 0",
                    params.glossyExponent, params.glossyWeight);
    return {};
}

}  // namespace pic
