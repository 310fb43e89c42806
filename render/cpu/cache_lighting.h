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

/// Runtime-projected links unpacked once per bake, indexed like LinkSet::rtp (link j of cache c
/// at c·nL + j): everything of a link but its node's flux is fixed at bake time, so a runtime
/// decodes the direction and evaluates the cone's zonal factors K_l(α) (core/sh.h coneZonal)
/// once instead of at every update.
struct RtpLinkTable {
    uint32_t bands = 0;                 ///< lY
    std::vector<glm::vec3> directions;  ///< nC·nL unit directions cache → node
    std::vector<float> weights;         ///< nC·nL·lY band weights factor·K_l(α); 0 for padding
};

/// Unpacks the RTP links of `links` for lY = bandsY bands.
RtpLinkTable unpackRtpLinks(const LinkSet& links, uint32_t bandsY);

/// Lights every cache of the bake from `nodeFlux` (2nS − 1 nodes, W per RGB channel) into
/// `out` (resized to nC caches with the bake's lY, lC): each node's flux is converted to YCoCg
/// (core/color.h) and L = Σ_links Φ_node·transport, in W/(m²·sr).
///   SH links: transport = the link's lY² half-float coefficients; Y takes all of them, Co and
///             Cg the first lC².
///   RTP links: transport = factor·K_l(α)·y_lm(direction), the projection of the node's cone
///             (core/sh.h shAddCone), from the unpacked `rtp` table; Y to lY bands, Co and Cg
///             to lC bands.
/// Padding links contribute nothing. Nothing is clamped: radiance is as linear as the flux.
/// `rtp` must be unpackRtpLinks(bake.links, lY) for RTP bakes and is ignored for SH bakes.
void lightCaches(const BakeData& bake, std::span<const glm::vec3> nodeFlux,
                 const RtpLinkTable& rtp, CacheValues& out);

/// lightCaches unpacking the RTP links on the way (one-off use; a runtime keeps the table).
void lightCaches(const BakeData& bake, std::span<const glm::vec3> nodeFlux, CacheValues& out);

}  // namespace pic
