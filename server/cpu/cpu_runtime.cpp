#include "server/cpu/cpu_runtime.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>
#include <vector>

#include "core/color.h"
#include "core/sh.h"
#include "server/cpu/cache_lighting.h"
#include "server/cpu/pull.h"
#include "server/cpu/surfel_lighting.h"

namespace pic {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// Luminance of the summed flux (W); summed in double so that 10⁵ small terms keep their
/// digits, and in index order so that the result does not depend on threads.
double totalLuminance(std::span<const glm::vec3> flux) {
    double sum[3] = {0.0, 0.0, 0.0};
    for (const glm::vec3& f : flux)
        for (int c = 0; c < 3; ++c) sum[c] += f[c];
    return luminance(glm::vec3(float(sum[0]), float(sum[1]), float(sum[2])));
}

/// What the passes rely on beyond the bake file's own validation: the bake belongs to this
/// scene, and the hierarchy is ordered so that a level-by-level pull reads only finished nodes.
Result<void> checkBake(const Scene& scene, const BakeData& bake) {
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

/// The numbers the passes multiply with: a light set that did not come through parseLightSet
/// (which checks all of this) must not turn every cache into NaN.
Result<void> checkLightValues(const LightSet& lights) {
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

/// The CPU backend: every pass of paper 000 Figure 2 but shadow maps (visibility comes from
/// Embree rays). Not thread-safe: one update at a time.
class CpuRuntime final : public Runtime {
public:
    CpuRuntime(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
               const BounceParams& bounces)
        : mScene(scene),
          mRays(rays),
          mBake(bake),
          mBounces(bounces),
          mDirectFlux(bake.surfels.size()),
          mNodeFlux(bake.nodes.size()),
          mValues(CacheValues::zeros(bake.caches.size(), bake.params.bandsY, bake.params.bandsC)) {
        // RTP links' directions and cone factors do not depend on the lights: unpacked once.
        if (bake.links.mode == LinkMode::Rtp) mRtp = unpackRtpLinks(bake.links, bake.params.bandsY);
    }

    Result<const CacheValues*> setLights(const LightSet& lights, UpdateStats* stats) override;
    const char* name() const override { return "cpu"; }

private:
    const Scene& mScene;
    const EmbreeScene& mRays;
    const BakeData& mBake;
    BounceParams mBounces;
    RtpLinkTable mRtp;                  ///< RTP bakes only
    std::vector<glm::vec3> mDirectFlux; ///< nS: flux from lights and emission, per update
    std::vector<glm::vec3> mNodeFlux;   ///< 2nS − 1: leaves hold the current bounce's surfel flux
    CacheValues mValues;
};

Result<const CacheValues*> CpuRuntime::setLights(const LightSet& lights, UpdateStats* stats) {
    if (auto ok = checkLightSet(lights, mScene); !ok) return std::unexpected(ok.error());
    if (auto ok = checkLightValues(lights); !ok) return std::unexpected(ok.error());

    const Clock::time_point start = Clock::now();
    UpdateStats local;
    UpdateStats& s = stats ? *stats : local;
    s = UpdateStats{};
    double& surfelMs = s.passMs["surfel_lighting"];
    double& pullMs = s.passMs["pull"];
    double& cacheMs = s.passMs["cache_lighting"];

    const bool progressive = mBounces.bounces < 0;
    const int passes = progressive ? mBounces.maxBounces : mBounces.bounces;
    if (passes == 0) {
        // No cache pass: the caches hold no light and no surfel needs lighting.
        mValues = CacheValues::zeros(mBake.caches.size(), mValues.bandsY, mValues.bandsC);
        s.totalMs = millisecondsSince(start);
        return &mValues;
    }

    const std::span<glm::vec3> leaves(mNodeFlux.data(), mBake.surfels.size());
    Clock::time_point t = Clock::now();
    directSurfelFlux(mScene, mRays, mBake, lights, mDirectFlux);
    std::copy(mDirectFlux.begin(), mDirectFlux.end(), leaves.begin());
    double total = totalLuminance(leaves);
    surfelMs += millisecondsSince(t);

    for (int bounce = 1;; ++bounce) {
        t = Clock::now();
        pullFlux(mBake, mNodeFlux);
        pullMs += millisecondsSince(t);

        t = Clock::now();
        lightCaches(mBake, mNodeFlux, mRtp, mValues);
        cacheMs += millisecondsSince(t);
        s.bounces = bounce;
        s.surfelFlux = total;
        if (bounce == passes) break;

        // The next bounce: direct flux plus what the surfels receive from these caches.
        t = Clock::now();
        bounceSurfelFlux(mScene, mBake, mDirectFlux, mValues, leaves);
        const double next = totalLuminance(leaves);
        surfelMs += millisecondsSince(t);
        // Progressive: a bounce that adds less than `convergence` of the flux is not worth
        // its cache pass (`<=` also stops a scene without light at once).
        if (progressive && next - total <= double(mBounces.convergence) * next) break;
        total = next;
    }
    s.totalMs = millisecondsSince(start);
    return &mValues;
}

}  // namespace

Result<std::unique_ptr<Runtime>> createCpuRuntime(const Scene& scene, const EmbreeScene& rays,
                                                  const BakeData& bake,
                                                  const BounceParams& bounces) {
    if (auto ok = checkBake(scene, bake); !ok) return std::unexpected(ok.error());
    if (auto ok = checkBounceParams(bounces); !ok) return std::unexpected(ok.error());
    return std::unique_ptr<Runtime>(new CpuRuntime(scene, rays, bake, bounces));
}

}  // namespace pic
