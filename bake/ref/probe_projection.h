#pragma once
/// How incident radiance at a cache is sampled and projected to the bake's SH: stratified
/// uniform directions over the sphere (grid caches) or the hemisphere above Cache::normal
/// (light-map caches), and the running YCoCg SH sums of the samples. Shared by the ideal
/// caches (bake/ref/probes.h) and the ray-traced probes baseline (bench/traced_probes.h), so
/// that both estimate exactly the same quantity.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_values.h"

namespace pic {

/// Direction i of n stratified directions about the polar axis z: cosθ jittered by `jitter`
/// in [0, 1) within the i-th of n equal slices (equal solid angle), azimuth on the
/// golden-angle spiral turned by `phiOffset` turns; over the sphere or only its upper half.
/// With a uniform jitter every direction is uniformly distributed on its own, so estimates
/// stay unbiased.
glm::vec3 stratifiedDirection(uint32_t i, uint32_t n, float jitter, double phiOffset,
                              bool hemisphere);

/// The frame a cache's directions are drawn in: local z along `normal`, over the upper
/// hemisphere for light-map caches, over the whole sphere for grid caches.
struct ProbeFrame {
    glm::vec3 tangent{1.0f, 0.0f, 0.0f};
    glm::vec3 bitangent{0.0f, 1.0f, 0.0f};
    glm::vec3 normal{0.0f, 0.0f, 1.0f};
    bool hemisphere = false;

    /// The world axes over the sphere for a grid cache; for a light-map cache its unit
    /// normal and an orthonormal tangent frame about it over the hemisphere.
    static ProbeFrame of(const Cache& cache);
    /// A frame over the sphere or hemisphere about unit `axis`.
    static ProbeFrame about(const glm::vec3& axis, bool hemisphere);
    /// The world direction of a local one (normalised).
    glm::vec3 toWorld(const glm::vec3& local) const {
        return glm::normalize(local.x * tangent + local.y * bitangent + local.z * normal);
    }
    /// Ω of the sampled domain: 4π over the sphere, 2π over the hemisphere, steradians.
    double solidAngle() const;
};

/// Running sums of radiance samples projected to real SH (core/sh.h) in YCoCg, in double:
/// luma Y with lY bands, chroma Co and Cg with lC ≤ lY bands.
class ShProjectionSums {
public:
    ShProjectionSums(uint32_t bandsY, uint32_t bandsC);

    /// Adds RGB `radiance` arriving from unit `direction`: Σ += YCoCg(radiance)·y(direction).
    void add(const glm::vec3& direction, const glm::vec3& radiance);
    /// Multiplies every sum by `weight` (Ω/N turns N uniform samples over Ω into integrals).
    void scale(double weight);
    /// Sets every sum to zero.
    void clear();
    /// Writes the sums, rounded to float, as cache `cache` of `values` (same band counts).
    void store(CacheValues& values, size_t cache) const;

    uint32_t bandsY() const { return mBandsY; }
    uint32_t bandsC() const { return mBandsC; }
    const std::vector<double>& y() const { return mY; }    ///< lY² luma sums
    const std::vector<double>& co() const { return mCo; }  ///< lC² orange chroma sums
    const std::vector<double>& cg() const { return mCg; }  ///< lC² green chroma sums

private:
    uint32_t mBandsY;
    uint32_t mBandsC;
    std::vector<double> mY, mCo, mCg;
};

}  // namespace pic
