#include "bake/ref/probe_projection.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/color.h"
#include "core/error.h"
#include "core/geometry.h"
#include "core/sh.h"

namespace pic {

namespace {

constexpr double kPi = std::numbers::pi;
/// Fractional part of the golden ratio: consecutive multiples spread azimuths evenly.
constexpr double kGoldenFraction = 0.6180339887498949;

}  // namespace

glm::vec3 stratifiedDirection(uint32_t i, uint32_t n, float jitter, double phiOffset,
                              bool hemisphere) {
    double u = (double(i) + double(jitter)) / double(n);
    double z = hemisphere ? 1.0 - u : 1.0 - 2.0 * u;
    double turns = double(i) * kGoldenFraction + phiOffset;
    double phi = 2.0 * kPi * (turns - std::floor(turns));
    double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return glm::vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
}

ProbeFrame ProbeFrame::of(const Cache& cache) {
    if (cache.kind != gpu::kCacheKindLightmap) return ProbeFrame{};
    return about(glm::normalize(cache.normal), true);
}

ProbeFrame ProbeFrame::about(const glm::vec3& axis, bool hemisphere) {
    ProbeFrame frame;
    frame.normal = axis;
    orthonormalBasis(axis, frame.tangent, frame.bitangent);
    frame.hemisphere = hemisphere;
    return frame;
}

double ProbeFrame::solidAngle() const {
    return (hemisphere ? 2.0 : 4.0) * kPi;
}

ShProjectionSums::ShProjectionSums(uint32_t bandsY, uint32_t bandsC)
    : mBandsY(bandsY),
      mBandsC(bandsC),
      mY(size_t(shCount(int(bandsY))), 0.0),
      mCo(size_t(shCount(int(bandsC))), 0.0),
      mCg(size_t(shCount(int(bandsC))), 0.0) {
    PIC_CHECK(bandsC <= bandsY && bandsY <= uint32_t(kMaxShBands));
}

void ShProjectionSums::add(const glm::vec3& direction, const glm::vec3& radiance) {
    float basis[shCount(kMaxShBands)];
    const glm::vec3 yCoCg = rgbToYCoCg(radiance);
    shEvaluate(int(mBandsY), direction, basis);
    for (size_t j = 0; j < mY.size(); ++j) mY[j] += double(yCoCg.x) * basis[j];
    for (size_t j = 0; j < mCo.size(); ++j) {
        mCo[j] += double(yCoCg.y) * basis[j];
        mCg[j] += double(yCoCg.z) * basis[j];
    }
}

void ShProjectionSums::scale(double weight) {
    for (double& s : mY) s *= weight;
    for (size_t j = 0; j < mCo.size(); ++j) {
        mCo[j] *= weight;
        mCg[j] *= weight;
    }
}

void ShProjectionSums::clear() {
    std::fill(mY.begin(), mY.end(), 0.0);
    std::fill(mCo.begin(), mCo.end(), 0.0);
    std::fill(mCg.begin(), mCg.end(), 0.0);
}

void ShProjectionSums::store(CacheValues& values, size_t cache) const {
    PIC_CHECK(values.bandsY == mBandsY && values.bandsC == mBandsC);
    const size_t countY = mY.size(), countC = mCo.size();
    for (size_t j = 0; j < countY; ++j) values.y[cache * countY + j] = float(mY[j]);
    for (size_t j = 0; j < countC; ++j) {
        values.co[cache * countC + j] = float(mCo[j]);
        values.cg[cache * countC + j] = float(mCg[j]);
    }
}

}  // namespace pic
