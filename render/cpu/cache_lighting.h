#pragma once
/// Cache lighting, CPU twin (paper 000 Figure 2 step 4, eq. 3, §4.6 and §4.8): the incident
/// radiance of every cache as the sum over its nL links of node flux × transport, in YCoCg with
/// lY bands for Y and lC ≤ lY bands for Co and Cg.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake_data.h"
#include "core/cache_values.h"
#include "render/node_spread.h"

namespace pic {

/// Links unpacked once per bake, indexed like LinkSet::tint (link j of cache c at c·nL + j):
/// everything of a link but its node's flux is fixed at bake time, so a runtime decodes, once
/// instead of at every update, where in its node's box each link reads the node's spread and,
/// for runtime-projected links, the direction and the cone's zonal factors K_l(α) (core/sh.h
/// coneZonal).
struct LinkTable {
    uint32_t bands = 0;                 ///< lY
    std::vector<glm::vec3> points;      ///< nC·nL box coordinates of LinkSet::offset in the
                                        ///< link's node (render/node_spread.h encodeBoxPoint)
    std::vector<float> concentrationWeight;  ///< nC·nL: 1 − the link's spread share
                                             ///< (LinkSet::spreadShare)
    /// RTP: the unit directions cache → node, x, y and z each nC·nL (and a few zeros past the
    /// end, as `weights`), link-minor so that consecutive links load as one vector.
    std::array<std::vector<float>, 3> directions;
    /// RTP: band weights factor·K_l(α) of link j in band l at l·nC·nL + j; 0 for padding.
    std::vector<float> weights;
    /// nC·nL (and kLinkLanes zeros past the end): linkIrradiance of every link
    /// (render/link_irradiance.h).
    std::vector<float> irradiance;
};

/// Unpacks the links of `bake` for its lY bands, their offsets in the boxes of `spread`
/// (nodeSpread(bake)).
LinkTable unpackLinks(const BakeData& bake, const NodeSpread& spread);

/// A node's light as its links read it (render/node_spread.h). A linear node holds, in YCoCg, its
/// limited flux spread's flux at the box centre and the change per box coordinate (column k:
/// centre ∘ the slopes along axis k), so that a link at box point u reads centre + spread·u.
/// An exponential node holds, per RGB channel, its spread's centre, slopes (column k: the RGB
/// slopes along axis k) and ln Z, so that a link at u with spread share ρ reads
/// centre ∘ exp(spread·u − (1 − ρ)·concentration). One cache line each: links fetch their
/// nodes scattered.
struct alignas(64) NodeLight {
    glm::vec3 centre{0.0f};
    glm::mat3 spread{0.0f};
    glm::vec3 concentration{0.0f};
    uint32_t exponential = 0;
};

/// The node light of every node from its flux spread (render/node_spread.h pullFluxSpread:
/// `centreFlux`, W per RGB channel, `slopes`, `concentration`, `exponential`) into `out`
/// (same size).
void nodeLight(std::span<const glm::vec3> centreFlux, std::span<const glm::mat3> slopes,
               std::span<const glm::vec3> concentration, std::span<const uint8_t> exponential,
               std::span<NodeLight> out);

/// Lights every cache of the bake from its nodes' light (nodeLight, 2nS − 1 nodes) into `out`
/// (resized to nC caches with the bake's lY, lC): L = Σ_links Φ_link·transport in YCoCg
/// (core/color.h), in W/(m²·sr). Φ_link is the node's flux spread at the link's box point u
/// times the link's tint, centre·(1 + slopes·u)·tint per RGB channel.
///   SH links: transport = the link's lY² half-float coefficients; Y takes all of them, Co and
///             Cg the first lC².
///   RTP links: transport = factor·K_l(α)·y_lm(direction), the projection of the node's cone
///             (core/sh.h shAddCone), from the unpacked table; Y to lY bands, Co and Cg to lC
///             bands.
/// Padding links contribute nothing. Nothing is clamped: radiance is as linear as the flux,
/// and the limited spread is ≥ 0 over every node's box. `out.irradiance` takes every cache's
/// Σ_links Φ_link·LinkTable::irradiance (0 for grid caches). `table` must be
/// unpackLinks(bake, ·).
void lightCaches(const BakeData& bake, std::span<const NodeLight> light, const LinkTable& table,
                 CacheValues& out);

/// lightCaches with the spread and the table computed on the way (one-off use; a runtime
/// keeps them): `nodeFlux` must be pulled.
void lightCaches(const BakeData& bake, std::span<const glm::vec3> nodeFlux, CacheValues& out);

}  // namespace pic
