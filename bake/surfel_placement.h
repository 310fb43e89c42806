#pragma once
/// Surfel placement (paper 000 §4.2): nS equal-area surfels spread over all triangles
/// proportionally to area with a Halton sequence, then relaxed along the surfaces.

#include <cstdint>
#include <vector>

#include "core/bake_data.h"
#include "core/error.h"
#include "core/scene.h"

namespace pic {

struct SurfelParams {
    uint32_t count = 32768;        ///< nS
    uint32_t relaxIterations = 4;  ///< tangential repulsion steps
    uint32_t footprintSamples = 16;  ///< material samples averaged per surfel
    uint64_t seed = 1;
};

/// Places `params.count` surfels; their areas sum to the scene's area.
Result<std::vector<Surfel>> placeSurfels(const Scene& scene, const SurfelParams& params);

}  // namespace pic
