#include "render/runtime.h"

#include <cmath>

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

Result<void> checkRuntimeLights(const LightSet& lights, const Scene& scene) {
    PIC_TRY(checkLightSet(lights, scene));
    // The numbers the passes multiply with: a light set that did not come through
    // parseLightSet (which checks all of this) must not turn every cache into NaN.
    const auto finite = [](const glm::vec3& v) {
        return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    for (const Light& light : lights.lights) {
        if (!finite(light.position) || !finite(light.direction) || !finite(light.color) ||
            !std::isfinite(light.intensity) || light.intensity < 0.0f ||
            glm::any(glm::lessThan(light.color, glm::vec3(0.0f))))
            return fail(ErrorCode::InvalidInput,
                        "light \"{}\" has a non-finite or negative position, direction, colour "
                        "or intensity (intensity {})",
                        light.id, light.intensity);
    }
    for (const auto& [material, scale] : lights.emissiveScale)
        if (!std::isfinite(scale) || scale < 0.0f)
            return fail(ErrorCode::InvalidInput,
                        "emissiveScale of material \"{}\" is {}; it must be finite and ≥ 0",
                        material, scale);
    return {};
}

}  // namespace pic
