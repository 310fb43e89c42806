// Shadow-caster preparation (render/shadow_casters.h): welding, merging and simplifying casters
// with meshoptimizer, measuring them with point queries (rays/embree_scene.h), clustering and
// culling.

#include "render/shadow_casters.h"

#include <algorithm>
#include <array>
#include <limits>
#include <numeric>
#include <utility>

#include <meshoptimizer.h>

#include "core/parallel.h"
#include "rays/embree_scene.h"

namespace pic {
namespace {

/// The scene's corners welded by position and its triangles simplified by edge collapses
/// within `relativeError` of the extent meshoptimizer measures, open borders locked (no
/// cracks where one object's border meets another's).
Scene simplifiedCasters(const Scene& scene, float relativeError) {
    // Corners welded by position: the simplifier merges only across shared vertices.
    const size_t nV = scene.vertices.size();
    std::vector<float> positions(3 * nV);
    for (size_t v = 0; v < nV; ++v) {
        const glm::vec3& p = scene.vertices[v].position;
        positions[3 * v + 0] = p.x;
        positions[3 * v + 1] = p.y;
        positions[3 * v + 2] = p.z;
    }
    std::vector<uint32_t> remap(nV);
    const size_t unique = meshopt_generateVertexRemap(remap.data(), nullptr, nV, positions.data(),
                                                      nV, 3 * sizeof(float));
    std::vector<float> welded(3 * unique);
    meshopt_remapVertexBuffer(welded.data(), positions.data(), nV, 3 * sizeof(float), remap.data());
    std::vector<uint32_t> indices;
    indices.reserve(3 * scene.triangles.size());
    for (const Triangle& tri : scene.triangles)
        for (uint32_t v : tri.v) indices.push_back(remap[v]);

    std::vector<uint32_t> simplified(indices.size());
    simplified.resize(meshopt_simplify(simplified.data(), indices.data(), indices.size(),
                                       welded.data(), unique, 3 * sizeof(float), 0, relativeError,
                                       meshopt_SimplifyLockBorder, nullptr));

    Scene casters;
    casters.sourcePath = scene.sourcePath;
    casters.bounds = scene.bounds;
    casters.vertices.resize(unique);
    for (size_t v = 0; v < unique; ++v)
        casters.vertices[v].position = {welded[3 * v], welded[3 * v + 1], welded[3 * v + 2]};
    casters.triangles.resize(simplified.size() / 3);
    for (size_t t = 0; t < casters.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) casters.triangles[t].v[k] = simplified[3 * t + k];
    return casters;
}

/// The eight corners' extreme of the plane function a·(p, 1) over a box: the corner farthest
/// along the plane's normal (largest) or against it (smallest).
float planeMax(const glm::vec4& plane, const Aabb& box) {
    const glm::vec3 corner(plane.x >= 0.0f ? box.max.x : box.min.x,
                           plane.y >= 0.0f ? box.max.y : box.min.y,
                           plane.z >= 0.0f ? box.max.z : box.min.z);
    return glm::dot(glm::vec3(plane), corner) + plane.w;
}
float planeMin(const glm::vec4& plane, const Aabb& box) { return -planeMax(-plane, box); }

/// The clip volume's planes a·p ≥ 0 in world space (homogeneous p = (x, y, z, 1)), from the
/// rows of the matrix: w ± x, w ± y, z (Vulkan's near plane) and w − z.
std::array<glm::vec4, 6> clipPlanes(const glm::mat4& clipFromWorld) {
    const glm::mat4 rows = glm::transpose(clipFromWorld);  // rows[i] = row i
    return {rows[3] + rows[0], rows[3] - rows[0], rows[3] + rows[1],
            rows[3] - rows[1], rows[2],           rows[3] - rows[2]};
}

/// Whether `box` lies wholly outside one of `planes` (then nothing in it can be drawn).
bool outsideClip(const std::array<glm::vec4, 6>& planes, const Aabb& box) {
    for (const glm::vec4& plane : planes)
        if (planeMax(plane, box) < 0.0f) return true;
    return false;
}

}  // namespace

Scene mergeShadowCasters(const Scene& scene) {
    // Float rounding: coplanar triangles merge, curved surfaces keep their facets.
    return simplifiedCasters(scene, kCasterMergeError);
}

float surfaceDeviation(const Scene& fine, const Scene& coarse, float limit) {
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    if (fine.triangles.empty()) return 0.0f;
    if (coarse.triangles.empty()) return kInfinity;
    auto rays = EmbreeScene::create(coarse);
    if (!rays) return kInfinity;

    // Samples: every corner (once per triangle that uses it: cheap, and no index needed)
    // and every centroid.
    std::vector<float> worst(fine.triangles.size(), 0.0f);
    parallelFor(0, fine.triangles.size(), [&](size_t t) {
        const Triangle& tri = fine.triangles[t];
        const glm::vec3 a = fine.vertices[tri.v[0]].position, b = fine.vertices[tri.v[1]].position,
                        c = fine.vertices[tri.v[2]].position;
        for (const glm::vec3& p : {a, b, c, (a + b + c) / 3.0f})
            worst[t] = std::max(worst[t], (*rays)->nearestDistance(p, limit));
    });
    return *std::max_element(worst.begin(), worst.end());
}

Scene simplifyShadowCasters(const Scene& casters, float error) {
    std::vector<glm::vec3> positions(casters.vertices.size());
    for (size_t v = 0; v < positions.size(); ++v) positions[v] = casters.vertices[v].position;
    const float scale = positions.empty() ? 0.0f
                                          : meshopt_simplifyScale(&positions[0].x, positions.size(),
                                                                  sizeof(glm::vec3));
    return simplifiedCasters(casters, scale > 0.0f ? error / scale : 0.0f);
}

std::vector<TriangleCluster> buildTriangleClusters(const Scene& scene, uint32_t maxTriangles,
                                                   std::vector<uint32_t>& order,
                                                   const Solids* solids) {
    std::vector<glm::vec3> centroids(scene.triangles.size());
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const Triangle& tri = scene.triangles[t];
        centroids[t] = (scene.vertices[tri.v[0]].position + scene.vertices[tri.v[1]].position +
                        scene.vertices[tri.v[2]].position) / 3.0f;
    }
    order.resize(scene.triangles.size());
    std::iota(order.begin(), order.end(), 0u);
    const uint32_t leafSize = std::max(maxTriangles, 1u);
    auto inSolid = [&](uint32_t t) { return solids && solids->solidOf[t] != Solids::kOpen; };
    // Triangles of solids first, so that no cluster mixes them with open ones.
    const uint32_t solidEnd =
        uint32_t(std::stable_partition(order.begin(), order.end(), inSolid) - order.begin());

    // Median splits along the longest axis of the centroids' bounds until a range fits in
    // one cluster: compact boxes, which is what culling needs. Ranges are finished in index
    // order, so the clusters come out sorted.
    std::vector<TriangleCluster> clusters;
    std::vector<std::pair<uint32_t, uint32_t>> stack{{solidEnd, uint32_t(order.size())},
                                                     {0u, solidEnd}};
    while (!stack.empty()) {
        const auto [begin, end] = stack.back();
        stack.pop_back();
        if (end - begin <= leafSize) {
            if (end == begin) continue;
            TriangleCluster cluster{begin, end - begin, {}, {}};
            for (uint32_t i = begin; i < end; ++i) {
                for (uint32_t v : scene.triangles[order[i]].v)
                    cluster.bounds.extend(scene.vertices[v].position);
                if (inSolid(order[i]))
                    cluster.solidBounds.extend(solids->bounds[solids->solidOf[order[i]]]);
            }
            clusters.push_back(cluster);
            continue;
        }
        Aabb box;
        for (uint32_t i = begin; i < end; ++i) box.extend(centroids[order[i]]);
        const glm::vec3 extent = box.extent();
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
        const uint32_t middle = begin + (end - begin) / 2;
        std::nth_element(order.begin() + begin, order.begin() + middle, order.begin() + end,
                         [&](uint32_t a, uint32_t b) {
                             return centroids[a][axis] < centroids[b][axis] ||
                                    (centroids[a][axis] == centroids[b][axis] && a < b);
                         });
        stack.push_back({middle, end});  // popped second
        stack.push_back({begin, middle});
    }
    return clusters;
}

bool ShadowEye::outside(const Aabb& solidBounds) const {
    if (atInfinity) return true;
    return glm::any(glm::lessThan(position, solidBounds.min - margin)) ||
           glm::any(glm::greaterThan(position, solidBounds.max + margin));
}

float nearestClusterDepth(std::span<const TriangleCluster> clusters, const glm::mat4& clipFromWorld) {
    const auto planes = clipPlanes(clipFromWorld);
    const glm::vec4 w = glm::transpose(clipFromWorld)[3];  // view depth: w = row 3 · p
    float nearest = std::numeric_limits<float>::infinity();
    for (const TriangleCluster& cluster : clusters)
        if (!cluster.bounds.empty() && !outsideClip(planes, cluster.bounds))
            nearest = std::min(nearest, planeMin(w, cluster.bounds));
    return nearest;
}

std::vector<TriangleRange> visibleTriangleRanges(std::span<const TriangleCluster> clusters,
                                                 const glm::mat4& clipFromWorld,
                                                 const ShadowEye& eye) {
    const auto planes = clipPlanes(clipFromWorld);
    std::vector<TriangleRange> ranges;
    for (const TriangleCluster& cluster : clusters) {
        if (cluster.bounds.empty() || outsideClip(planes, cluster.bounds)) continue;
        const bool oneSided = !cluster.solidBounds.empty() && eye.outside(cluster.solidBounds);
        if (!ranges.empty() && ranges.back().oneSided == oneSided &&
            ranges.back().firstTriangle + ranges.back().triangleCount == cluster.firstTriangle)
            ranges.back().triangleCount += cluster.triangleCount;
        else
            ranges.push_back({cluster.firstTriangle, cluster.triangleCount, oneSided});
    }
    return ranges;
}

}  // namespace pic
