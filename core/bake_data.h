#pragma once
/// Everything a bake produces, in memory. core/bake_file.h writes and reads it
/// (ARCHITECTURE.md §6); the runtime uploads its arrays to the GPU.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "shaders/shared/bake_layout.h"

namespace pic {

using gpu::Cache;
using gpu::kNoCache;
using gpu::kNoNode;
using gpu::kSpreadShareSteps;
using gpu::Node;
using gpu::RtpLink;
using gpu::Surfel;

/// How links store their transport factor (paper 000 §3.1 and §4.6).
enum class LinkMode : uint32_t {
    Sh = 0,   ///< SH-projected: lY² half-float coefficients per link
    Rtp = 1,  ///< runtime-projected: direction, cone and scalar factor per link
};

/// How the surfel hierarchy is built (paper 000 §4.3).
enum class HierarchyMethod : uint32_t {
    Agglomerative = 0,  ///< clustering with the paper's metric
    KdTree = 1,         ///< median-split kd-tree (fast)
    Visible = 2,        ///< the paper's clustering, keeping apart clusters that cannot see
                        ///< each other (bake/surfel_hierarchy.h)
};

/// The method's name in the CLI, the bake file and reports.
inline const char* hierarchyName(HierarchyMethod method) {
    switch (method) {
    case HierarchyMethod::Agglomerative:
        return "agglomerative";
    case HierarchyMethod::KdTree:
        return "kdtree";
    case HierarchyMethod::Visible:
        return "visible";
    }
    return "unknown";
}

/// Whose flux a link reads (bake/link_generation.h).
enum class LinkReads : uint32_t {
    Node = 0,     ///< the linked node's (paper 000)
    Visible = 1,  ///< the smallest descendant holding the part the cache sees, in the
                  ///< colour of that part (the link's tint)
};

/// How a cache's cut is refined (bake/link_generation.h).
enum class LinkCut : uint32_t {
    SolidAngle = 0,  ///< the node with the largest visible solid angle Ω first (paper 000)
    ErrorBound = 1,  ///< the node with the largest Ω·r (r its radius) first: the bound on the
                     ///< error of its model
};

inline const char* linkCutName(LinkCut cut) {
    return cut == LinkCut::SolidAngle ? "solid-angle" : "error";
}

/// Where grid caches go (bake/grid_caches.h).
enum class GridCaches : uint32_t {
    Surfaces = 0,  ///< only at the vertices that grid-shaded surfaces read (triangles too
                   ///< small for the light map): what a static scene's image needs
    Volume = 1,    ///< at every free vertex near geometry (paper 001 §5's occupied cells,
                   ///< dilated by one): dynamic objects near surfaces
    Space = 2,     ///< at every free vertex of the grid, inside rooms however far from
                   ///< geometry: dynamic objects anywhere (paper 000 §5.1)
};

/// The mode's name in the CLI, the bake file and reports.
inline const char* gridCachesName(GridCaches mode) {
    return mode == GridCaches::Space    ? "space"
           : mode == GridCaches::Volume ? "volume"
                                        : "surfaces";
}

/// The parameters a bake was made with, after defaults were resolved.
struct BakeParams {
    uint32_t surfels = 0;            ///< nS
    uint32_t linksPerCache = 0;      ///< nL
    uint32_t bandsY = 3;             ///< lY
    uint32_t bandsC = 3;             ///< lC ≤ lY
    float gridCell = 0.0f;           ///< metres
    GridCaches gridCaches = GridCaches::Surfaces;
    float lightmapTexel = 0.0f;      ///< metres
    LinkMode linkMode = LinkMode::Rtp;
    HierarchyMethod hierarchy = HierarchyMethod::Visible;
    uint32_t linkSamples = 16;       ///< visibility rays per node estimate while choosing the cut
    uint32_t linkFinalSamples = 64;  ///< visibility rays of a linked node's final estimate
    uint32_t exposureRays = 64;      ///< rays per surfel for the links' flux weights
                                     ///< (bake/surfel_exposure.h); 0: uniform node radiance
    uint32_t skyRays = 256;          ///< rays per surfel and per cache for the sky transfer
                                     ///< (bake/sky_transfer.h); 0: none, skies are refused
    LinkReads linkReads = LinkReads::Visible;
    LinkCut linkCut = LinkCut::ErrorBound;
    uint32_t relaxIterations = 4;    ///< surfel relaxation iterations
    uint64_t seed = 1;

    friend bool operator==(const BakeParams&, const BakeParams&) = default;
};

/// The sparse grid of caches: a cache index per grid vertex (kNoCache where none).
struct GridLayout {
    glm::vec3 origin{0.0f};      ///< metres, position of vertex (0, 0, 0)
    float cellSize = 0.0f;       ///< metres
    glm::uvec3 dims{0u};         ///< vertices per axis
    std::vector<uint32_t> cacheIndex;  ///< x + dims.x·(y + dims.y·z) → unique cache index
                                       ///< (kNoCache: no cache, read as zero radiance)
};

/// Light-map UV of triangles that are not light-mapped and are shaded from the grid.
inline constexpr float kNotLightmapped = -1.0f;

/// The light map: a cache index per texel and the light-map UVs of every triangle.
struct LightmapLayout {
    uint32_t width = 0;
    uint32_t height = 0;
    float texelSize = 0.0f;                ///< metres per texel on generated charts
    std::vector<uint32_t> cacheIndex;      ///< x + width·y → unique cache index (kNoCache: empty)
    std::vector<glm::vec2> triangleUvs;    ///< 3 per scene triangle, in [0,1]² of the atlas, or
                                           ///< kNotLightmapped for grid-shaded triangles
    uint32_t chartCount = 0;               ///< generated charts (0 when all meshes bring TEXCOORD_1)
};

/// Links of every unique cache; cache c owns entries [c·nL, (c+1)·nL).
struct LinkSet {
    LinkMode mode = LinkMode::Rtp;
    uint32_t linksPerCache = 0;
    uint32_t bands = 0;                    ///< SH bands stored per link (SH mode)
    std::vector<RtpLink> rtp;              ///< RTP mode: nC·nL links (padding: node 0, factor 0)
    std::vector<uint32_t> shNodes;         ///< SH mode: nC·nL node indices (padding: node 0, zero coefficients)
    std::vector<uint16_t> shCoefficients;  ///< SH mode: nC·nL·bands² half floats, 1/(m²·sr)
    std::vector<uint32_t> tint;            ///< both modes: nC·nL tints (core/color.h encodeLinkTint)
    std::vector<uint16_t> offset;          ///< both modes: nC·nL·3 binary16, metres: the centroid of
                                           ///< the part the link sees from its node's flux centroid
    std::vector<uint8_t> spreadShare;      ///< both modes: nC·nL codes (encodeSpreadShare): the
                                           ///< spread of the part the link sees over its node's
                                           ///< (render/node_spread.h)
};

/// The code of a spread share ρ ∈ [0, 1] (clamped; NaN → 0), ρ·63 rounded.
inline uint8_t encodeSpreadShare(float share) {
    const float clamped = share > 0.0f ? (share < 1.0f ? share : 1.0f) : 0.0f;
    return static_cast<uint8_t>(clamped * float(kSpreadShareSteps) + 0.5f);
}

/// The spread share of a code from encodeSpreadShare.
inline float decodeSpreadShare(uint8_t code) { return float(code) / float(kSpreadShareSteps); }

/// A complete bake.
struct BakeData {
    BakeParams params;
    uint64_t sceneHash = 0;
    std::vector<Surfel> surfels;           ///< nS, in hierarchy leaf order
    std::vector<float> surfelWeights;      ///< nS flux weights the links were made with
                                           ///< (bake/surfel_exposure.h; all 1: uniform)
    std::vector<Node> nodes;               ///< 2·nS − 1
    std::vector<uint32_t> levelOffsets;    ///< inner nodes of level k are [levelOffsets[k-1], levelOffsets[k])
    std::vector<Cache> caches;             ///< nC unique caches
    GridLayout grid;
    LightmapLayout lightmap;
    LinkSet links;
    /// Sky transfer (core/sky.h, bake/sky_transfer.h), empty when params.skyRays is 0:
    std::vector<float> surfelSky;  ///< nS·kSkyCoefficients: T_k = ∫ V·max(0, n·ω)·y_k per surfel
    std::vector<float> cacheSky;   ///< nC·skyValuesPerCache(params): v_k = ∫ V·y_k per cache
    std::map<std::string, std::string> defaults;  ///< parameter → how its default was chosen
};

}  // namespace pic
