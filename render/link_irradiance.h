#pragma once
/// Link irradiance (paper 000 eq. 3, §4.6): what a link adds to its light-map cache's
/// irradiance along the cache's normal per unit of its node's flux, fixed at bake time. The
/// GPU's links carry it (render/passes/cache_lighting_pass.h) and the CPU twin's link table
/// holds it (render/cpu/cache_lighting.h LinkTable).

#include <cstddef>

#include "core/bake_data.h"

namespace pic {

/// What link `slot` of `bake` adds to its cache's irradiance along the cache's normal n per
/// unit of its node's flux (LinkTable::irradiance): the link's lY-band projection convolved
/// with the clamped cosine at n, Σ_l K_l·Σ_m c_lm·y_lm(n) — for an RTP link's cone
/// factor·Σ_l K_l·K_l(α)·(2l + 1)/(4π)·P_l(n·d) by the addition theorem. The luma's irradiance
/// from the same links, so that no colour loses the chroma's higher bands; 0 for a grid cache's
/// links, which have no normal. (The cone's exact clamped cosine read 1–2 % more light than
/// these bands in the white rooms, and the path tracer sided with the bands.)
float linkIrradiance(const BakeData& bake, size_t slot);

}  // namespace pic
