#pragma once
/// Shadow-caster preparation for the shadow-map pass (render/passes/shadow_map_pass.h), pure
/// CPU geometry: the scene's triangles welded and coplanar runs merged, coarser levels of
/// detail simplified and their distance from the scene measured, triangles split into
/// spatially compact clusters, and the clusters culled against a layer's clip volume.
/// The levels of detail are measured with Embree point queries (rays/embree_scene.h) when a
/// scene is loaded: that is why the engine, and so the thin client that shades with it, links
/// Embree (ARCHITECTURE.md §2 lets render/ depend on rays/).

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/scene.h"
#include "core/solids.h"

namespace pic {

/// Spatially close triangles, consecutive in the pass's index buffer: the unit of frustum
/// culling, so that a cube face rasterises only the part of the scene it can see.
struct TriangleCluster {
    uint32_t firstTriangle = 0;
    uint32_t triangleCount = 0;
    Aabb bounds;
    /// The union of the bounds of the solids its triangles belong to; empty when they are
    /// open (a cluster never mixes the two).
    Aabb solidBounds;
};

/// Triangles per cluster: small enough that a cube face skips most of a room, large enough
/// that one layer needs few draws.
inline constexpr uint32_t kShadowClusterTriangles = 128;

/// Relative error (of the scene's extent) up to which mergeShadowCasters collapses edges: float
/// rounding, so that only coplanar triangles merge.
inline constexpr float kCasterMergeError = 1e-6f;

/// The scene's triangles as shadow casters (positions only): corners welded by position and
/// runs of coplanar triangles merged into fewer, larger ones by meshoptimizer's edge-collapse
/// simplifier at kCasterMergeError, with open borders locked. The same surfaces.
Scene mergeShadowCasters(const Scene& scene);

/// `casters` (welded, as mergeShadowCasters returns them) simplified by edge collapses whose
/// error stays within `error` metres, open borders locked: a coarser level of detail.
Scene simplifyShadowCasters(const Scene& casters, float error);

/// How far the surface of `fine` strays from that of `coarse`, metres: the largest distance
/// from a sample of `fine` (its corners and centroids) to the nearest point of `coarse`,
/// found with Embree's point queries; +∞ when a sample has nothing of `coarse` within `limit`.
float surfaceDeviation(const Scene& fine, const Scene& coarse, float limit);

/// How far (in texels of the layer, at the caster's depth) a level of detail may move a
/// caster's surface. surfel lighting's shadow test moves the receiver one texel along its
/// normal and allows half a texel more, so a surface moved by half a texel neither shadows
/// itself nor moves a shadow's edge by more than the map's own resolution does.
inline constexpr float kCasterErrorPerTexel = 0.5f;

/// Coarser levels of detail are kept only when they have at most this fraction of the
/// triangles of the previous level (otherwise they would cost memory for nothing).
inline constexpr float kCasterLevelReduction = 0.75f;

/// Splits the scene's triangles into spatially compact clusters of at most `maxTriangles`
/// (median splits of their centroids); `order` receives the triangle indices in cluster order.
/// With `solids`, the triangles of solids come first and share no cluster with open ones.
std::vector<TriangleCluster> buildTriangleClusters(const Scene& scene, uint32_t maxTriangles,
                                                   std::vector<uint32_t>& order,
                                                   const Solids* solids = nullptr);

/// Where a layer's light sits, as far as solids are concerned.
struct ShadowEye {
    bool atInfinity = true;    ///< a directional light: outside every solid
    glm::vec3 position{0.0f};  ///< a point or spot light's position, metres
    /// Metres: solids closer to the light than this keep both faces, because the near plane
    /// may clip the faces where the light's rays enter them.
    float margin = 0.0f;

    /// Whether the light lies outside every solid within `solidBounds`.
    bool outside(const Aabb& solidBounds) const;
};

/// A run of triangles to draw: [firstTriangle, firstTriangle + triangleCount).
struct TriangleRange {
    uint32_t firstTriangle = 0;
    uint32_t triangleCount = 0;
    /// Triangles of solids the light sees from outside: their faces that look away from the
    /// light may be skipped.
    bool oneSided = false;
};

/// The clusters whose bounds can intersect the clip volume of `clipFromWorld` (Vulkan's:
/// −w ≤ x, y ≤ w, 0 ≤ z ≤ w), adjacent ones with the same sidedness merged into one range.
/// Conservative: a cluster is dropped only when its box lies wholly outside one of the six
/// planes.
std::vector<TriangleRange> visibleTriangleRanges(std::span<const TriangleCluster> clusters,
                                                 const glm::mat4& clipFromWorld,
                                                 const ShadowEye& eye = {});

/// The nearest view depth (metres; w of clip space) of the clusters whose bounds can meet
/// the clip volume of `clipFromWorld`, +∞ when none can.
float nearestClusterDepth(std::span<const TriangleCluster> clusters, const glm::mat4& clipFromWorld);

}  // namespace pic
