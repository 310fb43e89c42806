#pragma once
/// Cache lighting, CPU twin (paper 000 Figure 2 step 4, eq. 3, §4.6 and §4.8): the incident
/// radiance of every cache as the sum over its nL links of node flux × transport, in YCoCg with
/// lY bands for Y and lC ≤ lY bands for Co and Cg.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_values.h"

namespace pic {

/// Links unpacked once per bake, indexed like LinkSet::tint (link j of cache c at c·nL + j):
/// everything of a link but its node's flux is fixed at bake time, so a runtime decodes the
/// offsets and, for runtime-projected links, the direction and the cone's zonal factors K_l(α)
/// (core/sh.h coneZonal) once instead of at every update.
struct LinkTable {
    uint32_t bands = 0;                 ///< lY
    std::vector<glm::vec3> offsets;     ///< nC·nL LinkSet::offset, metres
    std::vector<glm::vec3> directions;  ///< RTP: nC·nL unit directions cache → node
    std::vector<float> weights;         ///< RTP: nC·nL·lY band weights factor·K_l(α); 0 for padding
};

/// Unpacks the links of `links` for lY = bandsY bands.
LinkTable unpackLinks(const LinkSet& links, uint32_t bandsY);

/// Lights every cache of the bake from `nodeFlux` (2nS − 1 nodes, W per RGB channel) into
/// `out` (resized to nC caches with the bake's lY, lC): L = Σ_links Φ_link·transport in YCoCg
/// (core/color.h), in W/(m²·sr). Φ_link is the node's flux times the link's tint and, with
/// `nodeGradient` (render/cpu/pull.h pullFluxGradients; empty: the node's mean), its linear
/// spread at the link's offset, max(0, 1 + r_c·d) per channel.
///   SH links: transport = the link's lY² half-float coefficients; Y takes all of them, Co and
///             Cg the first lC².
///   RTP links: transport = factor·K_l(α)·y_lm(direction), the projection of the node's cone
///             (core/sh.h shAddCone), from the unpacked table; Y to lY bands, Co and Cg to lC
///             bands.
/// Padding links contribute nothing. Nothing is clamped but the spread: radiance is as linear
/// as the flux. `table` must be unpackLinks(bake.links, lY).
void lightCaches(const BakeData& bake, std::span<const glm::vec3> nodeFlux,
                 std::span<const glm::mat3> nodeGradient, const LinkTable& table,
                 CacheValues& out);

/// lightCaches with the spread and the table computed on the way (one-off use; a runtime
/// keeps them): `nodeFlux` must be pulled.
void lightCaches(const BakeData& bake, std::span<const glm::vec3> nodeFlux, CacheValues& out);

}  // namespace pic
