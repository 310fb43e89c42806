#include "bake/ref/sky_sampler.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "core/color.h"
#include "core/geometry.h"

namespace pic {

namespace {

constexpr double kPiDouble = std::numbers::pi;
constexpr float kPi = std::numbers::pi_v<float>;

/// Index of the bin of running sums `cdf` (last 1) that uniform `u` falls in.
uint32_t findBin(const float* cdf, uint32_t count, float u) {
    const uint32_t index = uint32_t(std::upper_bound(cdf, cdf + count, u) - cdf);
    return std::min(index, count - 1);
}

}  // namespace

glm::vec3 sampleCosineHemisphere(const glm::vec3& n, float u1, float u2) {
    const float r = std::sqrt(u1);
    const float phi = 2.0f * kPi * u2;
    const float z = std::sqrt(std::max(0.0f, 1.0f - u1));
    glm::vec3 t, b;
    orthonormalBasis(n, t, b);
    return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + z * n);
}

SkySampler::SkySampler(Sky sky) : mSky(std::move(sky)) {
    const Image* environment = mSky.environment();
    if (!environment || environment->width == 0 || environment->height == 0) return;
    const uint32_t width = environment->width, height = environment->height;
    // Row y spans polar angles [πy/H, π(y+1)/H]; each of its texels covers the solid angle
    // 2π/W·(cos θ0 − cos θ1). Sums run in double: a large image has ~10⁸ texels.
    std::vector<double> rowWeights(height, 0.0);
    std::vector<float> columnCdf(size_t(width) * height, 0.0f);
    double total = 0.0;
    for (uint32_t y = 0; y < height; ++y) {
        const double solidAngle =
            2.0 * kPiDouble / width *
            (std::cos(kPiDouble * y / height) - std::cos(kPiDouble * (y + 1) / height));
        double running = 0.0;
        float* row = &columnCdf[size_t(y) * width];
        for (uint32_t x = 0; x < width; ++x) {
            running += double(luminance(mSky.texelRadiance(x, y)));
            row[x] = float(running);
        }
        // Normalise the row's running sums; a dark row keeps zeros and is never chosen.
        if (running > 0.0) {
            for (uint32_t x = 0; x < width; ++x) row[x] = float(double(row[x]) / running);
            row[width - 1] = 1.0f;
        }
        rowWeights[y] = running * solidAngle;
        total += rowWeights[y];
    }
    // A black sky has nothing to sample: sample() and pdf() then answer 0.
    if (!(total > 0.0) || !std::isfinite(total)) return;
    mRowCdf.resize(height);
    double running = 0.0;
    for (uint32_t y = 0; y < height; ++y) {
        running += rowWeights[y];
        mRowCdf[y] = float(running / total);
    }
    mRowCdf.back() = 1.0f;
    mColumnCdf = std::move(columnCdf);
    mTotal = total;
    mWidth = width;
    mHeight = height;
}

float SkySampler::texelPdf(uint32_t x, uint32_t y) const {
    return float(double(luminance(mSky.texelRadiance(x, y))) / mTotal);
}

SkySampler::Sample SkySampler::sample(const glm::vec3& normal, float u1, float u2, float u3,
                                      float u4) const {
    Sample s;
    if (!mSky.environment()) {
        s.direction = sampleCosineHemisphere(normal, u1, u2);
        s.radiance = mSky.scale();
        s.pdf = std::max(0.0f, glm::dot(normal, s.direction)) / kPi;
        return s;
    }
    if (mWidth == 0) return s;
    // A texel: its row by the marginal distribution, its column by the row's conditional one.
    const uint32_t y = findBin(mRowCdf.data(), mHeight, u1);
    const uint32_t x = findBin(&mColumnCdf[size_t(y) * mWidth], mWidth, u2);
    // Float round-off may leave a dark bin a sliver of probability; it has no density.
    s.pdf = texelPdf(x, y);
    if (!(s.pdf > 0.0f)) return Sample{};
    // Uniform in solid angle inside the texel: azimuth uniform, cos θ uniform between the
    // row's edges.
    const double cos0 = std::cos(kPiDouble * y / mHeight);
    const double cos1 = std::cos(kPiDouble * (y + 1) / mHeight);
    const double cosTheta = cos0 - double(u4) * (cos0 - cos1);
    const float v = std::clamp(float(std::acos(std::clamp(cosTheta, -1.0, 1.0)) / kPiDouble),
                               float(y) / float(mHeight), float(y + 1) / float(mHeight));
    s.direction = mSky.direction((float(x) + u3) / float(mWidth), v);
    s.radiance = mSky.texelRadiance(x, y);
    return s;
}

float SkySampler::pdf(const glm::vec3& normal, const glm::vec3& direction) const {
    if (!mSky.environment()) return std::max(0.0f, glm::dot(normal, direction)) / kPi;
    if (mWidth == 0) return 0.0f;
    // The texel Sky::radiance reads along this direction.
    const glm::vec2 uv = mSky.uv(direction);
    const uint32_t x = std::min(uint32_t(uv.x * float(mWidth)), mWidth - 1);
    const uint32_t y = std::min(uint32_t(uv.y * float(mHeight)), mHeight - 1);
    return texelPdf(x, y);
}

}  // namespace pic
