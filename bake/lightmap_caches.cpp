#include "bake/lightmap_caches.h"

#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <span>

#include "core/geometry.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

namespace {

// Cache positions are lifted this many rays.epsilon() along the normal so that visibility
// rays from a cache start in front of its own surface.
constexpr float kLiftEpsilons = 2.0f;
// A normal ray hitting anything closer than this many epsilons means the point is covered
// (e.g. a floor texel under a box whose bottom sits a hair above the floor).
constexpr float kCoveredEpsilons = 10.0f;
// Barycentric slack so texel centres exactly on an edge count as inside.
constexpr double kInsideSlack = 1e-9;
// Dilation reaches this much (in texels) beyond the padding: a lookup exactly on a chart's
// edge reads, with weight zero, a texel whose centre is one texel away, and float UVs put
// that centre a hair further. The rectangle's rounding slack leaves room for it.
constexpr double kReachSlack = 0.05;

/// Unit probe directions in a (tangent, bitangent, normal) frame: the normal, 8 rays 10°
/// above the tangent plane (they find walls standing on the surface) and 8 at 45°.
constexpr size_t kProbeCount = 17;
const std::array<glm::vec3, kProbeCount>& probeDirections() {
    static const std::array<glm::vec3, kProbeCount> directions = [] {
        std::array<glm::vec3, kProbeCount> d{};
        d[0] = glm::vec3(0.0f, 0.0f, 1.0f);
        const double elevation[2] = {10.0, 45.0};
        for (int ring = 0; ring < 2; ++ring)
            for (int i = 0; i < 8; ++i) {
                double e = elevation[ring] * std::numbers::pi / 180.0;
                double a = (i + 0.5 * ring) * std::numbers::pi / 4.0;
                d[1 + 8 * ring + i] =
                    glm::vec3(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
            }
        return d;
    }();
    return directions;
}

/// Offsets (in texels, nearest first) of the points tried when a texel centre is enclosed.
constexpr std::array<glm::dvec2, 12> kRelocationOffsets = {{
    {-0.25, -0.25},
    {0.25, -0.25},
    {-0.25, 0.25},
    {0.25, 0.25},
    {0.0, -0.4},
    {-0.4, 0.0},
    {0.4, 0.0},
    {0.0, 0.4},
    {-0.4, -0.4},
    {0.4, -0.4},
    {-0.4, 0.4},
    {0.4, 0.4},
}};

/// Barycentric points (b1, b2) tried on a triangle that covers no texel centre.
constexpr std::array<glm::dvec2, 4> kCentroidCandidates = {{
    {1.0 / 3.0, 1.0 / 3.0},
    {1.0 / 6.0, 1.0 / 6.0},
    {2.0 / 3.0, 1.0 / 6.0},
    {1.0 / 6.0, 2.0 / 3.0},
}};

double cross2(const glm::dvec2& a, const glm::dvec2& b) {
    return a.x * b.y - a.y * b.x;
}

/// A triangle in atlas texel coordinates.
struct AtlasTriangle {
    glm::dvec2 p[3];
    double area2 = 0.0;  // twice the signed area

    /// Barycentrics (b1, b2) of point c.
    glm::dvec2 barycentric(const glm::dvec2& c) const {
        return glm::dvec2(cross2(c - p[0], p[2] - p[0]), cross2(p[1] - p[0], c - p[0])) / area2;
    }
    bool contains(const glm::dvec2& c) const {
        if (area2 == 0.0) return false;
        glm::dvec2 b = barycentric(c);
        return b.x >= -kInsideSlack && b.y >= -kInsideSlack && 1.0 - b.x - b.y >= -kInsideSlack;
    }
    /// True if the triangle reaches the square of half-size r around c (separating axes:
    /// the caller iterates only centres inside the triangle's bounds grown by r, which
    /// covers the x and y axes; the edge normals remain).
    bool reachesSquare(const glm::dvec2& c, double r) const {
        for (int k = 0; k < 3; ++k) {
            glm::dvec2 e = p[(k + 1) % 3] - p[k];
            glm::dvec2 m(-e.y, e.x);
            double a = glm::dot(m, p[0]);
            double b = glm::dot(m, p[1]);
            double d = glm::dot(m, p[2]);
            double lo = std::min({a, b, d});
            double hi = std::max({a, b, d});
            double centre = glm::dot(m, c);
            double reach = r * (std::abs(m.x) + std::abs(m.y));
            if (hi < centre - reach || lo > centre + reach) return false;
        }
        return true;
    }
};

/// A texel's candidate cache before the enclosure test.
struct Sample {
    uint32_t texel = 0;  // local index in the chart's rectangle
    uint32_t triangle = 0;
    bool centroid = false;  // the triangle covers no texel centre
};

/// One chart's unique caches and its rectangle's texel → cache map.
struct ChartCaches {
    std::vector<Cache> caches;    // texel = local index until merged
    std::vector<uint32_t> owner;  // per local texel: index into caches or kNoCache
    uint32_t duplicates = 0;
    uint32_t relocated = 0;
    uint32_t rejected = 0;
};

/// The scene-side data every chart task reads.
struct Placement {
    const Scene& scene;
    const EmbreeScene& rays;
    const LightmapCharts& charts;
    std::vector<glm::vec3> normal;  // unit geometric normal per triangle, zero if degenerate
};

/// True if a cache at `origin` with normal n would sit inside or under other geometry:
/// its normal ray hits something within kCoveredEpsilons, or more of its probe rays see
/// back faces of single-sided triangles than front faces (000 Fig. 9a).
bool isEnclosed(const Placement& placement, const glm::vec3& origin, const glm::vec3& n) {
    glm::vec3 tangent, bitangent;
    orthonormalBasis(n, tangent, bitangent);

    const Scene& scene = placement.scene;
    float covered = kCoveredEpsilons * placement.rays.epsilon();
    int front = 0;
    int back = 0;
    const auto& directions = probeDirections();
    for (size_t i = 0; i < directions.size(); ++i) {
        const glm::vec3& d = directions[i];
        glm::vec3 direction = glm::normalize(tangent * d.x + bitangent * d.y + n * d.z);
        std::optional<RayHit> hit = placement.rays.intersect(
            origin, direction, 0.0f, std::numeric_limits<float>::infinity());
        if (!hit) continue;
        if (i == 0 && hit->t < covered) return true;
        const Material& material = scene.materials[scene.triangles[hit->triangle].material];
        if (hit->backFace && !material.doubleSided)
            ++back;
        else
            ++front;
        // Stop once the remaining rays cannot change the vote.
        int remaining = int(directions.size() - 1 - i);
        if (back > front + remaining || front >= back + remaining) break;
    }
    return back > front;
}

/// World position at barycentrics (b1, b2) of triangle t.
glm::dvec3 pointOn(const Scene& scene, uint32_t t, const glm::dvec2& b) {
    const Triangle& tri = scene.triangles[t];
    return glm::dvec3(scene.vertices[tri.v[0]].position) * (1.0 - b.x - b.y) +
           glm::dvec3(scene.vertices[tri.v[1]].position) * b.x +
           glm::dvec3(scene.vertices[tri.v[2]].position) * b.y;
}

/// Rasterises, tests and dilates one chart.
ChartCaches placeChart(const Placement& placement, uint32_t chartIndex,
                       std::span<const uint32_t> triangles) {
    const Scene& scene = placement.scene;
    const LightmapCharts& charts = placement.charts;
    const LightmapChart& chart = charts.charts[chartIndex];
    const uint32_t w = chart.width;
    const uint32_t h = chart.height;
    const double radius = charts.padding + kReachSlack;
    const glm::dvec2 atlasSize(charts.width, charts.height);
    auto atlasTriangle = [&](uint32_t t) {
        AtlasTriangle at;
        for (int k = 0; k < 3; ++k) at.p[k] = glm::dvec2(charts.triangleUvs[3 * t + k]) * atlasSize;
        at.area2 = cross2(at.p[1] - at.p[0], at.p[2] - at.p[0]);
        return at;
    };

    // Claim texel centres (first triangle wins) and mark the texels bilinear lookups on
    // the chart can read: centres within `padding` texels (plus the reach slack) of a
    // triangle.
    constexpr uint32_t kFree = 0xFFFFFFFFu;
    std::vector<uint32_t> claim(size_t{w} * h, kFree);
    std::vector<uint8_t> fromCentroid(size_t{w} * h, 0);
    std::vector<uint8_t> needed(size_t{w} * h, 0);
    std::vector<uint8_t> coversCentre(triangles.size(), 0);
    for (size_t i = 0; i < triangles.size(); ++i) {
        uint32_t t = triangles[i];
        if (placement.normal[t] == glm::vec3(0.0f)) continue;
        AtlasTriangle at = atlasTriangle(t);
        glm::dvec2 lo = glm::min(glm::min(at.p[0], at.p[1]), at.p[2]);
        glm::dvec2 hi = glm::max(glm::max(at.p[0], at.p[1]), at.p[2]);
        int x0 = std::max<int>(int(chart.x), int(std::ceil(lo.x - radius - 0.5)));
        int x1 = std::min<int>(int(chart.x + w) - 1, int(std::floor(hi.x + radius - 0.5)));
        int y0 = std::max<int>(int(chart.y), int(std::ceil(lo.y - radius - 0.5)));
        int y1 = std::min<int>(int(chart.y + h) - 1, int(std::floor(hi.y + radius - 0.5)));
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                glm::dvec2 centre(x + 0.5, y + 0.5);
                size_t local = size_t(x - chart.x) + size_t(y - chart.y) * w;
                if (!needed[local] && at.reachesSquare(centre, radius)) needed[local] = 1;
                if (!at.contains(centre)) continue;
                coversCentre[i] = 1;
                if (claim[local] == kFree) claim[local] = t;
            }
    }
    // A triangle covering no centre gets its centroid's texel when that is free, so every
    // triangle of a light-mapped chart is represented. A chart none of whose triangles
    // covers a centre is too small for the light map: it is shaded from the grid, like
    // detailed geometry in paper 000 §3.2, instead of costing one cache per triangle.
    const bool lightmapped =
        std::any_of(coversCentre.begin(), coversCentre.end(), [](uint8_t c) { return c != 0; });
    for (size_t i = 0; lightmapped && i < triangles.size(); ++i) {
        uint32_t t = triangles[i];
        if (coversCentre[i] || placement.normal[t] == glm::vec3(0.0f)) continue;
        AtlasTriangle at = atlasTriangle(t);
        glm::dvec2 c = (at.p[0] + at.p[1] + at.p[2]) / 3.0;
        int x = std::clamp(int(std::floor(c.x)), int(chart.x), int(chart.x + w) - 1);
        int y = std::clamp(int(std::floor(c.y)), int(chart.y), int(chart.y + h) - 1);
        size_t local = size_t(x - chart.x) + size_t(y - chart.y) * w;
        needed[local] = 1;
        if (claim[local] != kFree) continue;
        claim[local] = t;
        fromCentroid[local] = 1;
    }

    std::vector<Sample> samples;
    for (uint32_t local = 0; local < claim.size(); ++local)
        if (claim[local] != kFree)
            samples.push_back({local, claim[local], fromCentroid[local] != 0});

    // Enclosure test of each sample, relocating within the texel if needed.
    enum class Outcome : uint8_t { Placed, Relocated, Rejected };
    std::vector<Outcome> outcome(samples.size());
    std::vector<Cache> candidates(samples.size());
    float lift = kLiftEpsilons * placement.rays.epsilon();
    parallelFor(
        0, samples.size(),
        [&](size_t s) {
            const Sample& sample = samples[s];
            const glm::vec3& n = placement.normal[sample.triangle];
            auto tryPoint = [&](const glm::dvec2& b) {
                glm::dvec2 clamped = glm::clamp(b, 0.0, 1.0);
                if (clamped.x + clamped.y > 1.0) clamped /= clamped.x + clamped.y;
                glm::vec3 position = glm::vec3(pointOn(scene, sample.triangle, clamped)) + lift * n;
                if (isEnclosed(placement, position, n)) return false;
                candidates[s] = Cache{position, gpu::kCacheKindLightmap, n, sample.texel};
                return true;
            };
            if (sample.centroid) {
                for (size_t k = 0; k < kCentroidCandidates.size(); ++k)
                    if (tryPoint(kCentroidCandidates[k])) {
                        outcome[s] = k == 0 ? Outcome::Placed : Outcome::Relocated;
                        return;
                    }
                outcome[s] = Outcome::Rejected;
                return;
            }
            AtlasTriangle at = atlasTriangle(sample.triangle);
            glm::dvec2 centre(chart.x + sample.texel % w + 0.5, chart.y + sample.texel / w + 0.5);
            if (tryPoint(at.barycentric(centre))) {
                outcome[s] = Outcome::Placed;
                return;
            }
            for (const glm::dvec2& offset : kRelocationOffsets) {
                glm::dvec2 point = centre + offset;
                if (at.contains(point) && tryPoint(at.barycentric(point))) {
                    outcome[s] = Outcome::Relocated;
                    return;
                }
            }
            outcome[s] = Outcome::Rejected;
        },
        16);

    ChartCaches result;
    result.owner.assign(claim.size(), kNoCache);
    for (size_t s = 0; s < samples.size(); ++s) {
        if (outcome[s] == Outcome::Rejected) {
            ++result.rejected;
            continue;
        }
        if (outcome[s] == Outcome::Relocated) ++result.relocated;
        result.owner[samples[s].texel] = static_cast<uint32_t>(result.caches.size());
        result.caches.push_back(candidates[s]);
    }

    // Seam dilation: a breadth-first search from the filled texels in row-major order,
    // visiting neighbours in a fixed order, gives each needed empty texel the cache of a
    // nearest (8-neighbour rings) filled texel of this chart.
    std::vector<uint32_t> queue;
    queue.reserve(claim.size());
    for (uint32_t local = 0; local < result.owner.size(); ++local)
        if (result.owner[local] != kNoCache) queue.push_back(local);
    constexpr int kNeighbours[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0},
                                       {1, 0},   {-1, 1}, {0, 1},  {1, 1}};
    for (size_t head = 0; head < queue.size(); ++head) {
        uint32_t local = queue[head];
        int x = int(local % w);
        int y = int(local / w);
        for (const auto& d : kNeighbours) {
            int nx = x + d[0];
            int ny = y + d[1];
            if (nx < 0 || ny < 0 || nx >= int(w) || ny >= int(h)) continue;
            uint32_t next = uint32_t(nx) + uint32_t(ny) * w;
            if (!needed[next] || result.owner[next] != kNoCache) continue;
            result.owner[next] = result.owner[local];
            ++result.duplicates;
            queue.push_back(next);
        }
    }
    return result;
}

Result<void> checkInput(const Scene& scene, const LightmapCharts& charts, uint32_t firstCacheIndex,
                        const LightmapCacheParams& params) {
    size_t n = scene.triangles.size();
    if (params.texelSize != charts.texelSize)
        return fail(ErrorCode::InvalidInput,
                    "light-map texel size {} m differs from the {} m the charts were built for",
                    params.texelSize, charts.texelSize);
    if (charts.triangleUvs.size() != 3 * n || charts.triangleChart.size() != n)
        return fail(ErrorCode::InvalidInput,
                    "light-map charts cover {} triangles but the scene has {}",
                    charts.triangleChart.size(), n);
    if (uint64_t{charts.width} * charts.height >= kNoCache)
        return fail(ErrorCode::InvalidInput, "light-map atlas {}×{} has too many texels",
                    charts.width, charts.height);
    for (size_t c = 0; c < charts.charts.size(); ++c) {
        const LightmapChart& chart = charts.charts[c];
        if (uint64_t{chart.x} + chart.width > charts.width ||
            uint64_t{chart.y} + chart.height > charts.height)
            return fail(ErrorCode::InvalidInput,
                        "light-map chart {} ({}×{} at {}, {}) lies outside the {}×{} atlas", c,
                        chart.width, chart.height, chart.x, chart.y, charts.width, charts.height);
    }
    for (size_t t = 0; t < n; ++t) {
        if (charts.triangleChart[t] >= charts.charts.size())
            return fail(ErrorCode::InvalidInput, "triangle {} has light-map chart {} of {}", t,
                        charts.triangleChart[t], charts.charts.size());
        if (scene.triangles[t].material >= scene.materials.size())
            return fail(ErrorCode::InvalidInput,
                        "triangle {} uses material {} but the scene has {} materials", t,
                        scene.triangles[t].material, scene.materials.size());
    }
    if (firstCacheIndex >= kNoCache)
        return fail(ErrorCode::InvalidInput, "first light-map cache index {} is out of range",
                    firstCacheIndex);
    return {};
}

}  // namespace

Result<LightmapCacheSet> placeLightmapCaches(const Scene& scene, const EmbreeScene& rays,
                                             LightmapCharts charts, uint32_t firstCacheIndex,
                                             const LightmapCacheParams& params) {
    PIC_CHECK(&rays.scene() == &scene);
    if (auto ok = checkInput(scene, charts, firstCacheIndex, params); !ok)
        return std::unexpected(ok.error());
    size_t n = scene.triangles.size();

    Placement placement{scene, rays, charts, std::vector<glm::vec3>(n, glm::vec3(0.0f))};
    parallelFor(
        0, n,
        [&](size_t t) {
            uint32_t triangle = static_cast<uint32_t>(t);
            if (scene.triangleArea(triangle) > 0.0f)
                placement.normal[t] = scene.triangleNormal(triangle);
        },
        4096);

    // Triangles of each chart in scene order (counting sort).
    size_t chartTotal = charts.charts.size();
    std::vector<uint32_t> chartStart(chartTotal + 1, 0);
    for (uint32_t c : charts.triangleChart) ++chartStart[c + 1];
    for (size_t c = 0; c < chartTotal; ++c) chartStart[c + 1] += chartStart[c];
    std::vector<uint32_t> chartTriangles(n);
    {
        std::vector<uint32_t> fill(chartStart.begin(), chartStart.end() - 1);
        for (uint32_t t = 0; t < n; ++t) chartTriangles[fill[charts.triangleChart[t]]++] = t;
    }

    std::vector<ChartCaches> perChart(chartTotal);
    Progress progress("light-map caches", chartTotal);
    parallelFor(
        0, chartTotal,
        [&](size_t c) {
            std::span<const uint32_t> triangles(chartTriangles.data() + chartStart[c],
                                                chartStart[c + 1] - chartStart[c]);
            perChart[c] = placeChart(placement, static_cast<uint32_t>(c), triangles);
            progress.advance();
        },
        1);
    progress.finish();

    // Charts without any cache (too small for a texel centre, or buried in other geometry)
    // leave the light map and are shaded from the grid; the rest are packed again.
    LightmapCacheSet set;
    {
        std::vector<uint8_t> keep(chartTotal);
        for (size_t c = 0; c < chartTotal; ++c) keep[c] = !perChart[c].caches.empty();
        set.gridShadedTriangles = repackLightmapCharts(charts, keep);
    }

    // Unique caches are numbered by chart, then by texel; every chart writes only the
    // texels of its own rectangle.
    std::vector<uint32_t> cacheBase(chartTotal + 1, 0);
    for (size_t c = 0; c < chartTotal; ++c) {
        cacheBase[c + 1] = cacheBase[c] + static_cast<uint32_t>(perChart[c].caches.size());
        set.duplicateTexels += perChart[c].duplicates;
        set.relocated += perChart[c].relocated;
        set.rejected += perChart[c].rejected;
    }
    uint64_t uniqueCount = cacheBase[chartTotal];
    if (uint64_t{firstCacheIndex} + uniqueCount >= kNoCache)
        return fail(ErrorCode::InvalidInput,
                    "{} light-map caches after the first index {} overflow the cache index range",
                    uniqueCount, firstCacheIndex);
    set.caches.resize(uniqueCount);
    set.layout.cacheIndex.assign(size_t{charts.width} * charts.height, kNoCache);
    parallelFor(
        0, chartTotal,
        [&](size_t c) {
            const LightmapChart& chart = charts.charts[c];
            const ChartCaches& result = perChart[c];
            auto atlasTexel = [&](uint32_t local) {
                return (chart.x + local % chart.width) +
                       size_t{charts.width} * (chart.y + local / chart.width);
            };
            for (size_t i = 0; i < result.caches.size(); ++i) {
                Cache cache = result.caches[i];
                cache.texel = static_cast<uint32_t>(atlasTexel(cache.texel));
                set.caches[cacheBase[c] + i] = cache;
            }
            for (uint32_t local = 0; local < result.owner.size(); ++local)
                if (result.owner[local] != kNoCache)
                    set.layout.cacheIndex[atlasTexel(local)] =
                        firstCacheIndex + cacheBase[c] + result.owner[local];
        },
        16);

    set.layout.width = charts.width;
    set.layout.height = charts.height;
    set.layout.texelSize = charts.texelSize;
    set.layout.triangleUvs = std::move(charts.triangleUvs);
    set.layout.chartCount = charts.chartCount;
    return set;
}

}  // namespace pic
