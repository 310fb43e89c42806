#include "render/runtime.h"

#include <algorithm>
#include <cmath>

#include "core/color.h"
#include "core/sh.h"

namespace pic {

Result<void> checkRuntimeBake(const Scene& scene, const BakeData& bake) {
    if (bake.sceneHash != scene.hash)
        return fail(ErrorCode::InvalidInput,
                    "bake was made for scene hash {:016x}, but scene {} has hash {:016x}",
                    bake.sceneHash, scene.sourcePath, scene.hash);
    const size_t nS = bake.surfels.size();
    if (nS == 0 || bake.nodes.size() != 2 * nS - 1)
        return fail(ErrorCode::InvalidInput, "bake has {} nodes for {} surfels, expected 2·nS − 1",
                    bake.nodes.size(), nS);
    const uint32_t bandsY = bake.params.bandsY, bandsC = bake.params.bandsC;
    if (bandsY < 1 || bandsY > uint32_t(kMaxShBands) || bandsC < 1 || bandsC > bandsY)
        return fail(ErrorCode::InvalidInput, "bake has lY = {}, lC = {}; need 1 ≤ lC ≤ lY ≤ {}",
                    bandsY, bandsC, kMaxShBands);
    if (bake.links.mode == LinkMode::Sh && bake.links.bands != bandsY)
        return fail(ErrorCode::InvalidInput, "bake's SH links hold {} bands but lY is {}",
                    bake.links.bands, bandsY);
    const size_t nLinks = bake.caches.size() * bake.links.linksPerCache;
    const size_t stored =
        bake.links.mode == LinkMode::Rtp ? bake.links.rtp.size() : bake.links.shNodes.size();
    if (stored != nLinks)
        return fail(ErrorCode::InvalidInput, "bake has {} links for {} caches × {} links",
                    stored, bake.caches.size(), bake.links.linksPerCache);

    for (size_t i = 0; i < nS; ++i) {
        const Surfel& s = bake.surfels[i];
        if (s.triangle >= scene.triangles.size() || s.material >= scene.materials.size())
            return fail(ErrorCode::InvalidInput,
                        "surfel {} lies on triangle {} with material {}, but the scene has {} "
                        "triangles and {} materials",
                        i, s.triangle, s.material, scene.triangles.size(), scene.materials.size());
    }
    const std::vector<uint32_t>& offsets = bake.levelOffsets;
    if (offsets.empty() || offsets.front() != nS || offsets.back() != bake.nodes.size())
        return fail(ErrorCode::InvalidInput,
                    "bake's level offsets must run from nS = {} to the node count {}", nS,
                    bake.nodes.size());
    for (size_t level = 1; level < offsets.size(); ++level) {
        for (uint32_t n = offsets[level - 1]; n < offsets[level]; ++n) {
            const Node& node = bake.nodes[n];
            if (node.left >= offsets[level - 1] || node.right >= offsets[level - 1])
                return fail(ErrorCode::InvalidInput,
                            "node {} on level {} has children {} and {} that are not on lower "
                            "levels (< {})",
                            n, level, node.left, node.right, offsets[level - 1]);
        }
    }
    return {};
}

Result<void> checkBounceParams(const BounceParams& p) {
    if (p.bounces < -1)
        return fail(ErrorCode::InvalidInput, "bounces must be ≥ 0, or −1 for progressive, got {}",
                    p.bounces);
    if (!std::isfinite(p.convergence) || p.convergence < 0.0f)
        return fail(ErrorCode::InvalidInput, "convergence must be finite and ≥ 0, got {}",
                    p.convergence);
    if (p.maxBounces < 0)
        return fail(ErrorCode::InvalidInput, "maxBounces must be ≥ 0, got {}", p.maxBounces);
    return {};
}

namespace {
/// Luminance of a flux sum: differences are taken in double first, so float is enough here.
double luminanceOf(const glm::dvec3& flux) { return luminance(glm::vec3(flux)); }
}  // namespace

BounceSchedule::BounceSchedule(const BounceParams& params, glm::vec3 ratioBound)
    : mParams(params),
      mRatioBound(ratioBound),
      mPasses(params.bounces < 0 ? params.maxBounces : params.bounces) {}

bool BounceSchedule::record(const glm::dvec3& total) {
    mTotals.push_back(total);
    if (mTotals.size() == 1 || mParams.bounces >= 0 || mLastPlanned) return true;
    // `<=` also stops a scene without light at once.
    const double added = luminanceOf(total - mTotals[mTotals.size() - 2]);
    return added > double(mParams.convergence) * luminanceOf(total);
}

BounceStep BounceSchedule::afterBounce(int bounce) {
    BounceStep step;
    if (bounce >= mPasses || mLastPlanned) return step;
    step.another = true;
    step.last = bounce + 1 == mPasses;
    if (mParams.bounces < 0 && bounce >= 2) {
        PIC_CHECK(mTotals.size() >= size_t(bounce));
        const glm::dvec3 before = bounce >= 3 ? mTotals[bounce - 3] : glm::dvec3(0.0);
        const glm::dvec3 previous = mTotals[bounce - 2] - before;  // ΔS_{b−1} (S_0 = 0)
        const glm::dvec3 latest = mTotals[bounce - 1] - mTotals[bounce - 2];  // ΔS_b
        glm::dvec3 q(0.0);
        for (int c = 0; c < 3; ++c)
            if (previous[c] > 0.0 && latest[c] > 0.0)
                q[c] = std::min(latest[c] / previous[c], mRatioBound[c]);
        const double qLuminance = std::min(
            luminanceOf(previous) > 0.0 ? std::max(luminanceOf(latest), 0.0) / luminanceOf(previous) : 0.0,
            std::max({mRatioBound.x, mRatioBound.y, mRatioBound.z}));
        // The first ratio, bounced over direct light, says little about later ones (a sunlit
        // patch spreads into the room first: the living room stopped after 3 bounces at 0.84
        // of the light on it): only ratios of bounces plan the end.
        step.last = step.last ||
                    (bounce >= 3 && qLuminance * qLuminance * luminanceOf(latest) <=
                                        double(mParams.convergence) * luminanceOf(mTotals[bounce - 1]));
        if (step.last) step.tail = glm::vec3(q / (1.0 - q));
    }
    mLastPlanned = step.last;
    return step;
}

glm::vec3 bounceRatioBound(const BakeData& bake) {
    glm::vec3 bound(0.0f);
    for (const Surfel& s : bake.surfels) bound = glm::max(bound, s.albedo);
    return glm::min(bound, glm::vec3(0.95f));
}

Result<void> checkRuntimeLights(const LightSet& lights, const Scene& scene) {
    PIC_TRY(checkLightSet(lights, scene));
    // The numbers the passes multiply with: a light set that did not come through
    // parseLightSet (which checks all of this) must not turn every cache into NaN.
    const auto finite = [](const glm::vec3& v) {
        return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    if (lights.lights.size() > kMaxLights)
        return fail(ErrorCode::InvalidInput, "the light set holds {} lights, at most {} are allowed",
                    lights.lights.size(), kMaxLights);
    for (const Light& light : lights.lights) {
        if (!isLightId(light.id))
            return fail(ErrorCode::InvalidInput,
                        "light id \"{}\" ({} bytes) is empty, longer than {} bytes or holds a "
                        "control character",
                        clipped(light.id), light.id.size(), kMaxLightIdBytes);
        const float peak = light.intensity * std::max({light.color.x, light.color.y, light.color.z});
        if (!finite(light.position) || !finite(light.direction) || !finite(light.color) ||
            !std::isfinite(light.intensity) || light.intensity < 0.0f ||
            glm::any(glm::lessThan(light.color, glm::vec3(0.0f))) ||
            light.intensity > kMaxLightIntensity || !(peak <= kMaxLightIntensity))
            return fail(ErrorCode::InvalidInput,
                        "light \"{}\" has a non-finite or negative position, direction, colour "
                        "or intensity, or an intensity × colour above {:g} (intensity {})",
                        clipped(light.id), kMaxLightIntensity, light.intensity);
    }
    for (const auto& [material, scale] : lights.emissiveScale)
        if (!std::isfinite(scale) || scale < 0.0f || scale > kMaxEmissiveScale)
            return fail(ErrorCode::InvalidInput,
                        "emissiveScale of material \"{}\" is {}; it must be finite and in [0, {:g}]",
                        clipped(material), scale, kMaxEmissiveScale);
    return {};
}

}  // namespace pic
