#pragma once
/// What a view is shaded with: image size, which component of the outgoing radiance, the
/// glossy lobe and subsamples. Shared by the CPU shading (render/cpu/cache_shading.h), the
/// thin client's renderer (render/renderer.h) and the programs that drive them.

#include <cstdint>

#include "core/error.h"

namespace pic {

/// Which part of the outgoing radiance an image holds (the `--component` values).
enum class ShadeComponent {
    Full,      ///< directly visible emission + direct + indirect
    Direct,    ///< punctual lights reflected once, with exact visibility
    Indirect,  ///< the cache term (it holds the emitters' light too, paper 000 §4.4)
    Glossy,    ///< the glossy lobe's part of the cache term alone (needs a lobe)
};

/// What to shade and how.
struct ShadeParams {
    uint32_t width = 0;
    uint32_t height = 0;
    ShadeComponent component = ShadeComponent::Full;
    float glossyExponent = 0.0f;   ///< Phong exponent n of the glossy lobe; 0 = diffuse only
    float glossyWeight = 0.0f;     ///< factor on the glossy lobe's radiance
    uint32_t samplesPerPixel = 1;  ///< 1: pixel centre; more: fixed stratified subsamples, averaged
};

/// Most subsamples per pixel any shading accepts.
inline constexpr uint32_t kMaxSamplesPerPixel = 4096;

/// `params` in range: sides 1..kMaxImageSide (core/image.h), 1..kMaxSamplesPerPixel
/// subsamples, glossy exponent and weight finite and ≥ 0, both > 0 for the Glossy component.
/// InvalidInput naming the value.
Result<void> checkShadeParams(const ShadeParams& params);

}  // namespace pic
