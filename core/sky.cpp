#include "core/sky.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>

#include <glm/gtc/constants.hpp>

#include "core/color.h"
#include "core/sh.h"

namespace pic {

namespace {

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n from Chebyshev guesses).
void gaussLegendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
    nodes.assign(size_t(n), 0.0);
    weights.assign(size_t(n), 0.0);
    for (int i = 0; i < n; ++i) {
        double x = std::cos(glm::pi<double>() * (i + 0.75) / (n + 0.5));
        double derivative = 1.0;
        for (int iteration = 0; iteration < 100; ++iteration) {
            double p0 = 1.0, p1 = x;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            derivative = n * (x * p1 - p0) / (x * x - 1.0);
            const double step = p1 / derivative;
            x -= step;
            if (std::abs(step) < 1e-15) break;
        }
        nodes[size_t(i)] = x;
        weights[size_t(i)] = 2.0 / ((1.0 - x * x) * derivative * derivative);
    }
}

struct EnvironmentKey {
    std::string path;
    std::filesystem::file_time_type modified;
    auto operator<=>(const EnvironmentKey&) const = default;
};

}  // namespace

size_t skyValuesPerCache(const BakeParams& params) {
    return params.skyRays ? size_t(shCount(skyVisibilityBands(int(params.bandsY)))) : 0;
}

glm::vec3 skyDirection(float u, float v) {
    const float theta = glm::pi<float>() * v;
    const float phi = glm::two_pi<float>() * u;
    const float sinTheta = std::sin(theta);
    return {sinTheta * std::sin(phi), std::cos(theta), -sinTheta * std::cos(phi)};
}

glm::vec2 skyUv(const glm::vec3& direction) {
    const float v = std::acos(std::clamp(direction.y, -1.0f, 1.0f)) / glm::pi<float>();
    float u = std::atan2(direction.x, -direction.z) / glm::two_pi<float>();
    if (u < 0.0f) u += 1.0f;
    if (u >= 1.0f) u -= 1.0f;
    return {u, v};
}

Result<std::shared_ptr<const Image>> loadEnvironment(const std::string& scenePath,
                                                     const std::string& name) {
    const std::filesystem::path path = std::filesystem::path(scenePath).parent_path() / name;
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        return fail(ErrorCode::NotFound, "environment {} does not exist (\"{}\" is read from the "
                    "scene's folder)", path.string(), name);
    const EnvironmentKey key{std::filesystem::weakly_canonical(path, ec).string(),
                             std::filesystem::last_write_time(path, ec)};

    static std::mutex mutex;
    static std::map<EnvironmentKey, std::weak_ptr<const Image>> loaded;
    {
        std::lock_guard lock(mutex);
        if (auto it = loaded.find(key); it != loaded.end())
            if (std::shared_ptr<const Image> image = it->second.lock()) return image;
    }
    PIC_TRY_ASSIGN(Image image, readImage(path.string()));
    if (image.width > kMaxEnvironmentSide || image.height > kMaxEnvironmentSide)
        return fail(ErrorCode::InvalidInput, "environment {} is {}x{}; at most {} texels a side",
                    path.string(), image.width, image.height, kMaxEnvironmentSide);
    for (uint32_t y = 0; y < image.height; ++y)
        for (uint32_t x = 0; x < image.width; ++x) {
            const glm::vec3 texel = image.at(x, y);
            if (!(std::isfinite(texel.x) && std::isfinite(texel.y) && std::isfinite(texel.z)) || glm::any(glm::lessThan(texel, glm::vec3(0.0f))))
                return fail(ErrorCode::InvalidInput,
                            "environment {} has texel ({}, {}) = ({}, {}, {}); radiance must be "
                            "finite and ≥ 0",
                            path.string(), x, y, texel.x, texel.y, texel.z);
        }
    auto shared = std::make_shared<const Image>(std::move(image));
    std::lock_guard lock(mutex);
    loaded[key] = shared;
    return shared;
}

Sky::Sky(glm::vec3 radiance, std::shared_ptr<const Image> environment, float rotationDegrees)
    : mRadiance(radiance),
      mEnvironment(std::move(environment)),
      mCos(std::cos(glm::radians(rotationDegrees))),
      mSin(std::sin(glm::radians(rotationDegrees))) {}

glm::vec3 Sky::direction(float u, float v) const {
    const glm::vec3 d = skyDirection(u, v);
    // Counter-clockwise about +Y seen from above: (x, z) → (x cos r + z sin r, −x sin r + z cos r).
    return {d.x * mCos + d.z * mSin, d.y, -d.x * mSin + d.z * mCos};
}

glm::vec2 Sky::uv(const glm::vec3& direction) const {
    // The inverse rotation.
    const glm::vec3 d{direction.x * mCos - direction.z * mSin, direction.y,
                      direction.x * mSin + direction.z * mCos};
    return skyUv(d);
}

glm::vec3 Sky::texelRadiance(uint32_t x, uint32_t y) const {
    return mEnvironment ? mRadiance * mEnvironment->at(x, y) : mRadiance;
}

glm::vec3 Sky::radiance(const glm::vec3& direction) const {
    if (!mEnvironment) return mRadiance;
    const glm::vec2 texel = uv(direction);
    const uint32_t x = std::min(uint32_t(texel.x * float(mEnvironment->width)), mEnvironment->width - 1);
    const uint32_t y = std::min(uint32_t(texel.y * float(mEnvironment->height)), mEnvironment->height - 1);
    return texelRadiance(x, y);
}

std::array<glm::vec3, kSkyCoefficients> Sky::project() const {
    std::array<glm::vec3, kSkyCoefficients> sh{};
    if (!mEnvironment) {
        sh[0] = 2.0f * std::sqrt(glm::pi<float>()) * mRadiance;
        return sh;
    }
    // Texel by texel: a row between polar angles θ0 and θ1 spans 2π/W·(cos θ0 − cos θ1) per
    // texel; the basis is read at the texel's centre direction. Summed in double per row.
    const uint32_t width = mEnvironment->width, height = mEnvironment->height;
    std::array<glm::dvec3, kSkyCoefficients> sum{};
    float basis[kSkyCoefficients];
    for (uint32_t y = 0; y < height; ++y) {
        const double theta0 = glm::pi<double>() * y / height;
        const double theta1 = glm::pi<double>() * (y + 1) / height;
        const double solidAngle = glm::two_pi<double>() / width * (std::cos(theta0) - std::cos(theta1));
        std::array<glm::dvec3, kSkyCoefficients> row{};
        for (uint32_t x = 0; x < width; ++x) {
            const glm::vec3 d = direction((x + 0.5f) / float(width), (y + 0.5f) / float(height));
            shEvaluate(kSkyBands, d, basis);
            const glm::dvec3 radiance(mEnvironment->at(x, y));
            for (int k = 0; k < kSkyCoefficients; ++k) row[size_t(k)] += radiance * double(basis[k]);
        }
        for (int k = 0; k < kSkyCoefficients; ++k) sum[size_t(k)] += row[size_t(k)] * solidAngle;
    }
    for (int k = 0; k < kSkyCoefficients; ++k) sh[size_t(k)] = mRadiance * glm::vec3(sum[size_t(k)]);
    return sh;
}

Result<Sky> resolveSky(const SkyLight& sky, const std::string& scenePath) {
    std::shared_ptr<const Image> environment;
    if (!sky.environment.empty()) {
        PIC_TRY_ASSIGN(environment, loadEnvironment(scenePath, sky.environment));
    }
    return Sky(sky.intensity * sky.color, std::move(environment), sky.rotationDegrees);
}

std::vector<float> gauntCoefficients(int bandsI, int bandsK) {
    const int countI = shCount(bandsI), countK = shCount(bandsK);
    // The product is a polynomial of degree ≤ (bandsI − 1) + (kSkyBands − 1) + (bandsK − 1) in
    // x, y, z: Gauss–Legendre in z with n nodes is exact to degree 2n − 1, and equally spaced
    // azimuths are exact for trigonometric degree below their count.
    const int degree = bandsI + kSkyBands + bandsK - 3;
    const int nodesZ = degree / 2 + 1;
    const int nodesPhi = degree + 1;
    std::vector<double> z, w;
    gaussLegendre(nodesZ, z, w);
    std::vector<double> sum(size_t(countI) * kSkyCoefficients * size_t(countK), 0.0);
    float basis[kMaxShBands * kMaxShBands];
    const int bandsMax = std::max({bandsI, bandsK, kSkyBands});
    for (int iz = 0; iz < nodesZ; ++iz)
        for (int ip = 0; ip < nodesPhi; ++ip) {
            const double phi = glm::two_pi<double>() * (ip + 0.5) / nodesPhi;
            const double s = std::sqrt(std::max(0.0, 1.0 - z[size_t(iz)] * z[size_t(iz)]));
            shEvaluate(bandsMax, glm::vec3(float(s * std::cos(phi)), float(s * std::sin(phi)),
                                           float(z[size_t(iz)])),
                       basis);
            const double weight = w[size_t(iz)] * glm::two_pi<double>() / nodesPhi;
            for (int i = 0; i < countI; ++i)
                for (int j = 0; j < kSkyCoefficients; ++j) {
                    const double ij = weight * double(basis[i]) * double(basis[j]);
                    double* out = &sum[(size_t(i) * kSkyCoefficients + size_t(j)) * size_t(countK)];
                    for (int k = 0; k < countK; ++k) out[k] += ij * double(basis[k]);
                }
        }
    std::vector<float> gaunt(sum.size());
    for (size_t i = 0; i < sum.size(); ++i)
        gaunt[i] = std::abs(sum[i]) < 1e-7 ? 0.0f : float(sum[i]);  // quadrature zeros
    return gaunt;
}

SkyCacheWeights skyCacheWeights(const std::array<glm::vec3, kSkyCoefficients>& skySh, int bandsY,
                                int bandsC) {
    SkyCacheWeights out;
    out.bandsY = bandsY;
    out.bandsC = bandsC;
    out.visibilityBands = skyVisibilityBands(bandsY);
    const int countK = shCount(out.visibilityBands);
    // One table per bake's band counts: computed once per process.
    static std::mutex mutex;
    static std::map<std::pair<int, int>, std::vector<float>> tables;
    const std::vector<float>* gaunt;
    {
        std::lock_guard lock(mutex);
        auto [it, inserted] = tables.try_emplace({bandsY, out.visibilityBands});
        if (inserted) it->second = gauntCoefficients(bandsY, out.visibilityBands);
        gaunt = &it->second;
    }
    std::array<glm::vec3, kSkyCoefficients> ycocg;
    for (int j = 0; j < kSkyCoefficients; ++j) ycocg[size_t(j)] = rgbToYCoCg(skySh[size_t(j)]);
    auto fold = [&](int bands, int channel, std::vector<float>& weights) {
        weights.assign(size_t(shCount(bands)) * size_t(countK), 0.0f);
        for (int i = 0; i < shCount(bands); ++i)
            for (int j = 0; j < kSkyCoefficients; ++j) {
                const float s = ycocg[size_t(j)][channel];
                if (s == 0.0f) continue;
                const float* g = &(*gaunt)[(size_t(i) * kSkyCoefficients + size_t(j)) * size_t(countK)];
                for (int k = 0; k < countK; ++k) weights[size_t(i) * size_t(countK) + size_t(k)] += s * g[k];
            }
    };
    fold(bandsY, 0, out.y);
    fold(bandsC, 1, out.co);
    fold(bandsC, 2, out.cg);
    return out;
}

}  // namespace pic
