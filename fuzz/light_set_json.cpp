// Light-set files (picclient lights --set FILE, every tool's --lights FILE) and the light sets
// a session database holds.

#include <cmath>

#include "core/light_set.h"
#include "fuzz/fuzz.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace pic;
    const auto lights = parseLightSet(std::string(fuzz::text(data, size)));
    if (!lights) return 0;
    PIC_CHECK(lights->lights.size() <= kMaxLights);
    for (const Light& light : lights->lights) {
        PIC_CHECK(isLightId(light.id));
        PIC_CHECK(std::isfinite(light.intensity) && light.intensity >= 0.0f &&
                       light.intensity <= kMaxLightIntensity);
    }
    for (const auto& [material, scale] : lights->emissiveScale)
        PIC_CHECK(scale >= 0.0f && scale <= kMaxEmissiveScale);
    // What it accepted round-trips: the same set, the same text.
    const std::string json = toJson(*lights);
    const auto again = parseLightSet(json);
    PIC_CHECK(again);
    PIC_CHECK(toJson(*again) == json);
    return 0;
}
