#pragma once
/// Next-event estimation of the sky in the reference path tracer (bake/ref/path_tracer.h).
///
/// With an environment image the sky is importance-sampled texel by texel: a texel is drawn in
/// proportion to its luminance × solid angle (a marginal distribution over rows, then a
/// conditional one over the row's columns) and a direction uniformly in solid angle inside it
/// (cos θ uniform between the row's edges), so the solid-angle density is the texel's
/// luminance over Σ luminance·Ω of all texels: exactly proportional to the luminance of the
/// piecewise-constant radiance Sky::radiance returns. (The usual luminance × sin θ weights with
/// density p(u, v) / (2π² sin θ) are this with the row's exact solid angle in place of
/// sin θ·Δθ, which keeps the density finite at the poles.) A constant sky has no bright part
/// to find: it is sampled cosine-weighted about the surface normal, as the Lambertian BSDF is.

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "core/sky.h"

namespace pic {

/// Cosine-weighted direction about unit normal `n` (density cos θ / π) from two uniform
/// numbers in [0, 1).
glm::vec3 sampleCosineHemisphere(const glm::vec3& n, float u1, float u2);

/// Draws directions towards a sky for a surface point and evaluates their density.
/// Immutable after construction, so thread-safe.
class SkySampler {
public:
    /// A direction, the sky's radiance along it and its solid-angle density (0: no sample).
    struct Sample {
        glm::vec3 direction{0.0f};
        glm::vec3 radiance{0.0f};
        float pdf = 0.0f;
    };

    /// Builds the texel distribution of `sky`'s environment, if it has one (W·H floats).
    explicit SkySampler(Sky sky);

    /// A direction for a surface point with unit normal `normal` from four uniform numbers in
    /// [0, 1); it may point below the surface (the caller's cosine is then ≤ 0).
    Sample sample(const glm::vec3& normal, float u1, float u2, float u3, float u4) const;
    /// Solid-angle density with which sample() draws unit `direction` at a surface with unit
    /// `normal`.
    float pdf(const glm::vec3& normal, const glm::vec3& direction) const;

    /// The sky's radiance along unit `direction`.
    glm::vec3 radiance(const glm::vec3& direction) const { return mSky.radiance(direction); }
    const Sky& sky() const { return mSky; }

private:
    /// Luminance of texel (x, y) over Σ luminance·Ω: its solid-angle density.
    float texelPdf(uint32_t x, uint32_t y) const;

    Sky mSky;
    uint32_t mWidth = 0, mHeight = 0;  // of the environment; 0 for a constant sky
    double mTotal = 0.0;               // Σ luminance·Ω over the texels, W/(m²·sr)·sr
    std::vector<float> mRowCdf;        // H running sums over rows of luminance·Ω, last 1
    std::vector<float> mColumnCdf;     // W·H running sums within each row, each row's last 1
};

}  // namespace pic
