#pragma once
/// Deterministic random and low-discrepancy numbers for the bake.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include <glm/glm.hpp>

namespace pic {

/// Radical inverse of `index` in base `base` (the Halton sequence's coordinate), in [0, 1).
inline double radicalInverse(uint32_t base, uint64_t index) {
    double inverseBase = 1.0 / base;
    double factor = inverseBase;
    double result = 0.0;
    while (index > 0) {
        result += static_cast<double>(index % base) * factor;
        index /= base;
        factor *= inverseBase;
    }
    return result;
}

/// SplitMix64 step: a fast, well-mixed hash of a 64-bit value.
inline uint64_t mixBits(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

/// A small deterministic generator (SplitMix64) seeded from several keys.
class Rng {
public:
    explicit Rng(uint64_t seed, uint64_t stream = 0) : mState(mixBits(seed ^ mixBits(stream))) {}
    uint64_t next() {
        mState += 0x9E3779B97F4A7C15ull;
        uint64_t z = mState;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    /// Uniform float in [0, 1).
    float uniform() { return static_cast<float>(next() >> 40) * 0x1.0p-24f; }

private:
    uint64_t mState;
};

/// Uniform direction on the unit sphere from two uniform numbers in [0, 1): z = 1 − 2u₁,
/// azimuth 2πu₂ (Archimedes: equal z slices hold equal solid angle).
inline glm::vec3 sampleUniformSphere(float u1, float u2) {
    const float z = 1.0f - 2.0f * u1;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const float phi = 2.0f * std::numbers::pi_v<float> * u2;
    return glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
}

}  // namespace pic
