#include "render/cpu/cache_lighting.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include <glm/gtc/matrix_access.hpp>

#include "core/color.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/sh.h"
#include "render/link_irradiance.h"
#include "render/node_spread.h"

namespace pic {
namespace {

/// Caches per task: a cache costs nL links.
constexpr size_t kCacheGrain = 16;

/// How many links ahead cache lighting prefetches a link's node light.
constexpr size_t kPrefetchLinks = 8;

/// Runtime-projected links are summed kLinkLanes at a time, as one vector of floats (GCC
/// vector extensions: one SSE register, which baseline x86-64 has), in blocks of kLinkBlock.
constexpr size_t kLinkLanes = 4;
constexpr size_t kLinkBlock = 64;
using LinkLanes = float __attribute__((vector_size(kLinkLanes * sizeof(float))));

inline LinkLanes loadLanes(const float* values) {
    LinkLanes lanes;
    std::memcpy(&lanes, values, sizeof(lanes));
    return lanes;
}

/// Every binary16 pattern as float. The GPU reads half links natively; on the CPU one 256 KiB
/// table lookup per coefficient is cheaper than converting bits in the inner loop.
const float* halfTable() {
    static const std::vector<float> table = [] {
        std::vector<float> values(size_t{1} << 16);
        for (size_t bits = 0; bits < values.size(); ++bits)
            values[bits] = halfToFloat(static_cast<uint16_t>(bits));
        return values;
    }();
    return table.data();
}

/// Calls body(std::integral_constant<int, B>{}) with B = bands ∈ [1, kMaxShBands]: the cache
/// kernels take lY as a template argument so that their coefficient loops unroll and the
/// accumulators stay in registers.
template <class Body>
void withBands(uint32_t bands, Body&& body) {
    switch (bands) {
    case 1:
        return body(std::integral_constant<int, 1>{});
    case 2:
        return body(std::integral_constant<int, 2>{});
    case 3:
        return body(std::integral_constant<int, 3>{});
    case 4:
        return body(std::integral_constant<int, 4>{});
    case 5:
        return body(std::integral_constant<int, 5>{});
    case 6:
        return body(std::integral_constant<int, 6>{});
    case 7:
        return body(std::integral_constant<int, 7>{});
    case 8:
        return body(std::integral_constant<int, 8>{});
    default:
        PIC_CHECK(bands >= 1 && bands <= uint32_t(kMaxShBands));
    }
}

/// Incident radiance of one cache with lY = BandsY, accumulated locally and stored once.
template <int BandsY>
struct CacheSh {
    static constexpr int kCountY = shCount(BandsY);
    std::array<float, kCountY> y{};
    std::array<float, kCountY> co{};  // only the first lC² are used
    std::array<float, kCountY> cg{};
    glm::vec3 alongNormal{0.0f};  // YCoCg irradiance along a light-map cache's normal

    /// Stores cache c (lC² chroma coefficients, and its irradiance along its normal) into out. Band
    /// 0 of each RGB channel is that channel's mean radiance, a sum of non-negative fluxes; where
    /// they cancel to nothing, the spread's and YCoCg's rounding can leave a channel a few ulps
    /// below 0, which is raised to 0 (shaders/cache_lighting.comp does the same).
    void store(size_t c, int countC, CacheValues& out) {
        const glm::vec3 band0 = yCoCgToRgb(glm::vec3(y[0], co[0], cg[0]));
        if (band0.r < 0.0f || band0.g < 0.0f || band0.b < 0.0f) {
            const glm::vec3 raised = rgbToYCoCg(glm::max(band0, glm::vec3(0.0f)));
            y[0] = raised.x, co[0] = raised.y, cg[0] = raised.z;
        }
        float* dstY = out.y.data() + c * kCountY;
        float* dstCo = out.co.data() + c * countC;
        float* dstCg = out.cg.data() + c * countC;
        for (int i = 0; i < kCountY; ++i) {
            PIC_DCHECK(std::isfinite(y[i]));
            dstY[i] = y[i];
        }
        for (int i = 0; i < countC; ++i) {
            PIC_DCHECK(std::isfinite(co[i]) && std::isfinite(cg[i]));
            dstCo[i] = co[i];
            dstCg[i] = cg[i];
        }
        // A sum of non-negative terms but for YCoCg's rounding, as band 0 above.
        out.irradiance[c] = glm::max(yCoCgToRgb(alongNormal), glm::vec3(0.0f));
    }
};

/// e^x per component for the exponential spread's reads, |x| ≤ 87: 2^t = 2^n·2^f, n = t
/// rounded, with 2^f = e^{f·ln 2} by its Taylor series to degree 6 on |f| ≤ 1/2: within
/// 4·10⁻⁶ of e^x for |x| ≤ 80 (the rounding of x·log₂e), branch-free, so that the fifth of the
/// atrium's links that read an exponential node do not wait on three calls of expf each.
inline glm::vec3 exponential(const glm::vec3& x) {
    glm::vec3 out;
    for (int c = 0; c < 3; ++c) {
        const float t = std::clamp(x[c], -87.0f, 87.0f) * 1.44269504f;  // log2 e
        const float whole = std::floor(t + 0.5f), f = (t - whole) * 0.693147181f;
        const float p =
            1.0f +
            f * (1.0f +
                 f * (0.5f + f * (1.0f / 6.0f +
                                  f * (1.0f / 24.0f + f * (1.0f / 120.0f + f * (1.0f / 720.0f))))));
        const int32_t bits = (int32_t(whole) + 127) << 23;
        float scale;
        std::memcpy(&scale, &bits, sizeof(scale));
        out[c] = p * scale;
    }
    return out;
}

/// The YCoCg flux a link carries: its node's spread at the link's box point times the
/// link's tint. Through a linear node neutral links (81 % of the atrium's) stay in YCoCg, where
/// the spread is linear too; tinted ones multiply in RGB, as do exponential nodes.
inline glm::vec3 linkFlux(const NodeLight& node, uint32_t tint, const glm::vec3& point,
                          float concentrationWeight) {
    if (node.exponential) {
        const glm::vec3 rgb =
            node.centre * exponential(node.spread * point - concentrationWeight * node.concentration);
        return rgbToYCoCg(tint == kNeutralLinkTint ? rgb : rgb * decodeLinkTint(tint));
    }
    const glm::vec3 flux = node.centre + node.spread * point;
    if (tint == kNeutralLinkTint) return flux;
    return rgbToYCoCg(glm::max(yCoCgToRgb(flux), glm::vec3(0.0f)) * decodeLinkTint(tint));
}

/// Eq. 3 with SH-projected links: L = Σ Φ_node · tint · c_link.
template <int BandsY>
void lightCachesSh(const BakeData& bake, std::span<const NodeLight> light, const LinkTable& table,
                   CacheValues& out) {
    constexpr int countY = shCount(BandsY);
    const int countC = shCount(int(out.bandsC));
    const LinkSet& links = bake.links;
    const size_t nL = links.linksPerCache;
    const float* half = halfTable();
    parallelFor(
        0, bake.caches.size(),
        [&](size_t c) {
            CacheSh<BandsY> sh;
            for (size_t slot = c * nL; slot < (c + 1) * nL; ++slot) {
                // Padding links hold zero coefficients; the file format also allows kNoNode there.
                const uint32_t node = links.shNodes[slot];
                if (node == kNoNode) continue;
                const glm::vec3 flux = linkFlux(light[node], links.tint[slot], table.points[slot],
                                                table.concentrationWeight[slot]);
                sh.alongNormal += flux * table.irradiance[slot];
                const uint16_t* coefficients = links.shCoefficients.data() + slot * countY;
                // Luma takes all lY² coefficients, chroma the low lC² only (paper 000 §4.8).
                for (int i = 0; i < countY; ++i) {
                    const float k = half[coefficients[i]];
                    sh.y[i] += flux.x * k;
                    if (i < countC) {
                        sh.co[i] += flux.y * k;
                        sh.cg[i] += flux.z * k;
                    }
                }
            }
            sh.store(c, countC, out);
        },
        kCacheGrain);
}

/// Eq. 3 with runtime-projected links (§4.6): L = Σ Φ_node · tint · factor · K_l(α) ·
/// y_lm(direction). In blocks of a cache's links: first each link's flux, scalar (its node is
/// scattered and may be exponential), then the basis and the sums kLinkLanes links at a time.
template <int BandsY>
void lightCachesRtp(const BakeData& bake, std::span<const NodeLight> light, const LinkTable& table,
                    CacheValues& out) {
    constexpr int countY = shCount(BandsY);
    const int bandsC = int(out.bandsC);
    const LinkSet& links = bake.links;
    const size_t nL = links.linksPerCache, nLinks = links.rtp.size();
    parallelFor(
        0, bake.caches.size(),
        [&, bandsC](size_t c) {
            alignas(32) std::array<std::array<float, kLinkBlock>, 3> flux;  // Y, Co, Cg
            LinkLanes sumY[countY] = {}, sumCo[countY] = {}, sumCg[countY] = {};
            LinkLanes alongNormal[3] = {};  // Y, Co, Cg
            const size_t end = (c + 1) * nL;
            for (size_t begin = c * nL; begin < end; begin += kLinkBlock) {
                const size_t count = std::min(kLinkBlock, end - begin);
                for (size_t j = 0; j < count; ++j) {
                    const size_t slot = begin + j;
                    // The nodes are scattered: fetch a later link's ahead of its use.
                    if (slot + kPrefetchLinks < end)
                        __builtin_prefetch(&light[links.rtp[slot + kPrefetchLinks].node]);
                    // Padding links (factor 0, zero weights) read no node.
                    const glm::vec3 f =
                        table.weights[slot] == 0.0f
                            ? glm::vec3(0.0f)
                            : linkFlux(light[links.rtp[slot].node], links.tint[slot],
                                       table.points[slot], table.concentrationWeight[slot]);
                    flux[0][j] = f.x, flux[1][j] = f.y, flux[2][j] = f.z;
                }
                // The last lanes of a short block take the next links' directions and weights
                // (the table holds kLinkLanes more) with no flux: they add exact zeros.
                std::fill_n(flux[0].begin() + count, kLinkBlock - count, 0.0f);
                std::fill_n(flux[1].begin() + count, kLinkBlock - count, 0.0f);
                std::fill_n(flux[2].begin() + count, kLinkBlock - count, 0.0f);
                for (size_t j = 0; j < count; j += kLinkLanes) {
                    const size_t slot = begin + j;
                    LinkLanes basis[countY];
                    shEvaluateLanes<BandsY>(loadLanes(&table.directions[0][slot]),
                                            loadLanes(&table.directions[1][slot]),
                                            loadLanes(&table.directions[2][slot]), basis);
                    const LinkLanes fluxY = loadLanes(&flux[0][j]), fluxCo = loadLanes(&flux[1][j]),
                                    fluxCg = loadLanes(&flux[2][j]);
                    const LinkLanes e = loadLanes(&table.irradiance[slot]);
                    alongNormal[0] += fluxY * e;
                    alongNormal[1] += fluxCo * e;
                    alongNormal[2] += fluxCg * e;
                    for (int l = 0; l < BandsY; ++l) {
                        const LinkLanes w = loadLanes(&table.weights[size_t(l) * nLinks + slot]);
                        const LinkLanes y = fluxY * w;
                        for (int i = l * l; i < (l + 1) * (l + 1); ++i) sumY[i] += y * basis[i];
                        if (l < bandsC) {
                            const LinkLanes co = fluxCo * w, cg = fluxCg * w;
                            for (int i = l * l; i < (l + 1) * (l + 1); ++i) {
                                sumCo[i] += co * basis[i];
                                sumCg[i] += cg * basis[i];
                            }
                        }
                    }
                }
            }
            CacheSh<BandsY> sh;
            for (int i = 0; i < countY; ++i)
                for (size_t k = 0; k < kLinkLanes; ++k) {
                    sh.y[i] += sumY[i][k];
                    sh.co[i] += sumCo[i][k];
                    sh.cg[i] += sumCg[i][k];
                }
            for (int i = 0; i < 3; ++i)
                for (size_t k = 0; k < kLinkLanes; ++k) sh.alongNormal[i] += alongNormal[i][k];
            sh.store(c, shCount(bandsC), out);
        },
        kCacheGrain);
}

}  // namespace

LinkTable unpackLinks(const BakeData& bake, const NodeSpread& spread) {
    const LinkSet& links = bake.links;
    const uint32_t bandsY = bake.params.bandsY;
    PIC_CHECK(bandsY >= 1 && bandsY <= uint32_t(kMaxShBands));
    PIC_CHECK_EQ(links.offset.size(), links.tint.size() * 3);
    PIC_CHECK_EQ(links.spreadShare.size(), links.tint.size());
    PIC_CHECK_EQ(spread.centroid.size(), bake.nodes.size());
    LinkTable table;
    table.bands = bandsY;
    const bool rtp = links.mode == LinkMode::Rtp;
    PIC_CHECK_EQ((rtp ? links.rtp.size() : links.shNodes.size()), links.tint.size());
    table.points.resize(links.tint.size());
    table.concentrationWeight.resize(links.tint.size());
    // kLinkLanes zeros past the end, as `weights`, for the RTP kernel's last short block.
    table.irradiance.assign(links.tint.size() + kLinkLanes, 0.0f);
    parallelFor(
        0, links.tint.size(),
        [&](size_t slot) {
            const uint32_t node = rtp ? links.rtp[slot].node : links.shNodes[slot];
            if (node >= bake.nodes.size()) return;  // SH padding may name kNoNode
            glm::vec3 offset;
            for (int i = 0; i < 3; ++i) offset[i] = halfToFloat(links.offset[slot * 3 + i]);
            // Through the code the GPU's links carry, so both backends read the same point.
            table.points[slot] = decodeBoxPoint(encodeBoxPoint(spread, node, offset));
            table.concentrationWeight[slot] = 1.0f - decodeSpreadShare(links.spreadShare[slot]);
            table.irradiance[slot] = linkIrradiance(bake, slot);
        },
        4096);
    if (!rtp) return table;
    // SoA, so that kLinkLanes links load as one vector each; kLinkLanes more past the end for
    // the last cache's short block, zero.
    const size_t nLinks = links.rtp.size();
    for (auto& component : table.directions) component.assign(nLinks + kLinkLanes, 0.0f);
    table.weights.assign(bandsY * nLinks + kLinkLanes, 0.0f);
    parallelFor(
        0, nLinks,
        [&](size_t slot) {
            const RtpLink& link = links.rtp[slot];
            const glm::vec3 direction = decodeOctahedral(link.directionOct);
            for (int k = 0; k < 3; ++k) table.directions[k][slot] = direction[k];
            std::array<double, kMaxShBands> cone;
            coneZonalBands(int(bandsY), double(link.oneMinusCosAlpha), cone.data());
            for (uint32_t l = 0; l < bandsY; ++l)
                table.weights[l * nLinks + slot] = float(double(link.factor) * cone[l]);
        },
        1024);
    return table;
}

void nodeLight(std::span<const glm::vec3> centreFlux, std::span<const glm::mat3> slopes,
               std::span<const glm::vec3> concentration, std::span<const uint8_t> exponential,
               std::span<NodeLight> out) {
    PIC_CHECK_EQ(slopes.size(), centreFlux.size());
    PIC_CHECK_EQ(concentration.size(), centreFlux.size());
    PIC_CHECK_EQ(exponential.size(), centreFlux.size());
    PIC_CHECK_EQ(out.size(), centreFlux.size());
    parallelFor(
        0, centreFlux.size(),
        [&](size_t n) {
            const glm::vec3 centre = centreFlux[n];
            NodeLight& light = out[n];
            light.exponential = exponential[n];
            light.concentration = concentration[n];
            if (light.exponential) {
                light.centre = centre;
                light.spread = glm::transpose(slopes[n]);
                return;
            }
            light.centre = rgbToYCoCg(centre);
            for (int k = 0; k < 3; ++k)
                light.spread[k] = rgbToYCoCg(centre * glm::row(slopes[n], k));
        },
        4096);
}

void lightCaches(const BakeData& bake, std::span<const NodeLight> light, const LinkTable& table,
                 CacheValues& out) {
    PIC_CHECK_EQ(light.size(), bake.nodes.size());
    const uint32_t bandsY = bake.params.bandsY, bandsC = bake.params.bandsC;
    const size_t nC = bake.caches.size();
    if (out.bandsY != bandsY || out.bandsC != bandsC || out.cacheCount() != nC)
        out = CacheValues::zeros(nC, bandsY, bandsC);
    out.irradiance.resize(nC);

    const size_t nLinks = nC * bake.links.linksPerCache;
    PIC_CHECK_EQ(bake.links.tint.size(), nLinks);
    PIC_CHECK_EQ(table.bands, bandsY);
    PIC_CHECK_EQ(table.points.size(), nLinks);
    PIC_CHECK_EQ(table.irradiance.size(), nLinks + kLinkLanes);
    if (bake.links.mode == LinkMode::Sh) {
        PIC_CHECK_EQ(bake.links.bands, bandsY);
        PIC_CHECK_EQ(bake.links.shNodes.size(), nLinks);
        PIC_CHECK_EQ(bake.links.shCoefficients.size(), nLinks * bandsY * bandsY);
        withBands(bandsY, [&](auto bands) {
            lightCachesSh<decltype(bands)::value>(bake, light, table, out);
        });
    } else {
        PIC_CHECK_EQ(bake.links.rtp.size(), nLinks);
        PIC_CHECK_EQ(table.directions[0].size(), nLinks + kLinkLanes);
        withBands(bandsY, [&](auto bands) {
            lightCachesRtp<decltype(bands)::value>(bake, light, table, out);
        });
    }
}

void lightCaches(const BakeData& bake, std::span<const glm::vec3> nodeFlux, CacheValues& out) {
    const NodeSpread spread = nodeSpread(bake);
    std::vector<glm::mat3> moment(nodeFlux.size()), slopes(nodeFlux.size());
    std::vector<glm::vec3> centre(nodeFlux.size()), concentration(nodeFlux.size());
    std::vector<uint8_t> exponential(nodeFlux.size());
    pullFluxSpread(bake, spread, nodeFlux, moment, centre, slopes, concentration, exponential);
    std::vector<NodeLight> light(nodeFlux.size());
    nodeLight(centre, slopes, concentration, exponential, light);
    lightCaches(bake, light, unpackLinks(bake, spread), out);
}

}  // namespace pic
