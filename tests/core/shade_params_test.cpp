// Shading parameters: one check for the CPU shading and the client's renderer.

#include <gtest/gtest.h>

#include <limits>

#include "core/image.h"
#include "core/shade_params.h"

namespace pic {
namespace {

ShadeParams valid() {
    ShadeParams params;
    params.width = 64;
    params.height = 32;
    return params;
}

/// The message of a refused `params`, "" when they are accepted.
std::string refusal(const ShadeParams& params) {
    auto checked = checkShadeParams(params);
    if (checked) return "";
    EXPECT_EQ(checked.error().code, ErrorCode::InvalidInput);
    return checked.error().message;
}

TEST(ShadeParams, InRangeParametersAreAccepted) {
    EXPECT_EQ(refusal(valid()), "");
    ShadeParams edge = valid();
    edge.width = kMaxImageSide;
    edge.height = 1;
    edge.samplesPerPixel = kMaxSamplesPerPixel;
    edge.glossyExponent = 200.0f;
    edge.glossyWeight = 0.5f;
    EXPECT_EQ(refusal(edge), "");
}

TEST(ShadeParams, EachOutOfRangeFieldIsRefusedByName) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    struct Case {
        ShadeParams params;
        const char* names;
    };
    std::vector<Case> cases;
    auto with = [](auto change) { ShadeParams p = valid(); change(p); return p; };
    cases.push_back({with([](ShadeParams& p) { p.width = 0; }), "image size 0x32"});
    cases.push_back({with([](ShadeParams& p) { p.height = kMaxImageSide + 1; }), "image size 64x16385"});
    cases.push_back({with([](ShadeParams& p) { p.samplesPerPixel = 0; }), "samples per pixel 0"});
    cases.push_back({with([](ShadeParams& p) { p.samplesPerPixel = kMaxSamplesPerPixel + 1; }),
                     "samples per pixel 4097"});
    cases.push_back({with([&](ShadeParams& p) { p.glossyExponent = nan; }), "glossy exponent"});
    cases.push_back({with([](ShadeParams& p) { p.glossyExponent = -1.0f; }), "glossy exponent -1"});
    cases.push_back({with([&](ShadeParams& p) { p.glossyWeight = inf; }), "glossy weight inf"});
    cases.push_back({with([](ShadeParams& p) { p.glossyWeight = -0.5f; }), "glossy weight -0.5"});
    cases.push_back({with([](ShadeParams& p) { p.component = ShadeComponent::Glossy; }),
                     "the glossy component needs a lobe"});
    cases.push_back({with([](ShadeParams& p) {
                         p.component = ShadeComponent::Glossy;
                         p.glossyExponent = 10.0f;
                     }),
                     "weight 0 must be > 0"});
    for (const Case& c : cases) {
        const std::string message = refusal(c.params);
        EXPECT_NE(message.find(c.names), std::string::npos) << message << " / " << c.names;
    }
}

}  // namespace
}  // namespace pic
