#include "bake/lightmap_charts.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>
#include <span>

#include <tbb/parallel_sort.h>

#include "core/geometry.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

namespace {

// A triangle joins a planar chart when its normal is within this angle of the chart's seed
// normal: coplanar-ish and facing the same way, so projecting it onto the chart plane
// changes its area by less than 1.5 %.
constexpr double kChartNormalToleranceDegrees = 10.0;
// Vertices closer than this fraction of the scene diagonal are welded when finding shared
// edges (flat-shaded meshes duplicate every vertex per face).
constexpr double kWeldTolerance = 1e-5;
// Extents are rounded up to whole texels after removing this much float noise, so a 1 m
// quad at 0.1 m texels is 10 texels wide, not 11. The rest of the rounding (at least half a
// texel minus this) is room for the dilation's reach slack in lightmap_caches.cpp.
constexpr double kExtentSlack = 1e-3;
// Hull edge directions closer than this are one candidate for the chart's rotation.
constexpr double kRotationStepRadians = 0.25 * std::numbers::pi / 180.0;
constexpr uint32_t kMaxPadding = 64;
// Keeps every linear texel index x + width·y inside uint32.
constexpr uint32_t kMaxAtlasLimit = 32768;
// The packer first tries an atlas sqrt(rectangle area) × kAtlasSlack wide and widens it
// by kAtlasGrowth while the shelves come out taller than the maximum.
constexpr double kAtlasSlack = 1.1;
constexpr double kAtlasGrowth = 1.2;
// Texel-size suggestions assume the packer wastes at most this fraction of the atlas.
constexpr double kPackingOverhead = 1.3;

constexpr uint32_t kNoChart = 0xFFFFFFFFu;

/// A rectangle of charted triangles before packing; corners live in `local`.
struct ChartPiece {
    std::vector<uint32_t> triangles;
    glm::dvec2 extent{0.0};  // texels, padding excluded
    bool fromUv1 = false;
};

/// x rounded up to three significant digits, for suggestions that must not fall short.
double roundUpSignificant(double x) {
    double step = std::pow(10.0, std::floor(std::log10(x)) - 2.0);
    return std::ceil(x / step) * step;
}

/// Whole texels a chart extent needs.
double texelSpan(double extent) {
    return std::max(0.0, std::ceil(extent - kExtentSlack));
}

Result<void> checkInput(const Scene& scene, const LightmapChartParams& params) {
    if (!(params.texelSize > 0.0f) || !std::isfinite(params.texelSize))
        return fail(ErrorCode::InvalidInput,
                    "light-map texel size must be a positive number of metres, got {}",
                    params.texelSize);
    if (params.padding < 1 || params.padding > kMaxPadding)
        return fail(ErrorCode::InvalidInput,
                    "light-map chart padding must be 1 to {} texels (bilinear lookups read one "
                    "texel beyond a chart), got {}",
                    kMaxPadding, params.padding);
    if (params.maxAtlasSize < 2 * params.padding + 1 || params.maxAtlasSize > kMaxAtlasLimit)
        return fail(ErrorCode::InvalidInput,
                    "light-map maximum atlas size must be {} to {} texels, got {}",
                    2 * params.padding + 1, kMaxAtlasLimit, params.maxAtlasSize);
    for (size_t v = 0; v < scene.vertices.size(); ++v) {
        const glm::vec3& p = scene.vertices[v].position;
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return fail(ErrorCode::InvalidInput, "vertex {} has a non-finite position ({}, {}, {})",
                        v, p.x, p.y, p.z);
    }
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const Triangle& tri = scene.triangles[t];
        for (uint32_t v : tri.v)
            if (v >= scene.vertices.size())
                return fail(ErrorCode::InvalidInput,
                            "triangle {} uses vertex {} but the scene has {} vertices", t, v,
                            scene.vertices.size());
    }
    for (const Primitive& primitive : scene.primitives)
        if (uint64_t{primitive.firstTriangle} + primitive.triangleCount > scene.triangles.size())
            return fail(ErrorCode::InvalidInput,
                        "primitive '{}' covers triangles [{}, {}) but the scene has {}",
                        primitive.name, primitive.firstTriangle,
                        uint64_t{primitive.firstTriangle} + primitive.triangleCount,
                        scene.triangles.size());
    return {};
}

/// Builds the chart of a primitive laid out by TEXCOORD_1, or returns false when its
/// TEXCOORD_1 is unusable (zero or non-finite UV area) and it needs generated charts.
bool layoutUv1Primitive(const Scene& scene, const Primitive& primitive,
                        std::span<const double> triangleArea, double texelSize,
                        std::vector<glm::vec2>& local, ChartPiece& piece) {
    double worldArea = 0.0;
    double uvArea = 0.0;
    glm::dvec2 uvMin(std::numeric_limits<double>::max());
    glm::dvec2 uvMax(-std::numeric_limits<double>::max());
    for (uint32_t t = primitive.firstTriangle;
         t < primitive.firstTriangle + primitive.triangleCount; ++t) {
        const Triangle& tri = scene.triangles[t];
        glm::dvec2 uv[3];
        for (int k = 0; k < 3; ++k) {
            uv[k] = glm::dvec2(scene.vertices[tri.v[k]].uv1);
            uvMin = glm::min(uvMin, uv[k]);
            uvMax = glm::max(uvMax, uv[k]);
        }
        glm::dvec2 e1 = uv[1] - uv[0];
        glm::dvec2 e2 = uv[2] - uv[0];
        uvArea += 0.5 * std::abs(e1.x * e2.y - e1.y * e2.x);
        worldArea += triangleArea[t];
    }
    if (!(uvArea > 0.0) || !std::isfinite(uvArea) || !(worldArea > 0.0)) return false;

    // One UV unit spans sqrt(world area / UV area) metres on average.
    double texelsPerUv = std::sqrt(worldArea / uvArea) / texelSize;
    piece.extent = (uvMax - uvMin) * texelsPerUv;
    piece.fromUv1 = true;
    piece.triangles.resize(primitive.triangleCount);
    std::iota(piece.triangles.begin(), piece.triangles.end(), primitive.firstTriangle);
    for (uint32_t t : piece.triangles)
        for (int k = 0; k < 3; ++k)
            local[3 * t + k] = glm::vec2(
                (glm::dvec2(scene.vertices[scene.triangles[t].v[k]].uv1) - uvMin) * texelsPerUv);
    return true;
}

/// Welded vertex id per scene vertex: vertices in the same cell of a grid with the weld
/// tolerance get the same id.
std::vector<uint32_t> weldVertices(const Scene& scene) {
    Aabb bounds;
    for (const Vertex& v : scene.vertices) bounds.extend(v.position);
    double tolerance = std::max(kWeldTolerance * bounds.diagonal(), 1e-12);
    size_t n = scene.vertices.size();
    std::vector<std::pair<uint64_t, uint32_t>> keys(n);
    parallelFor(
        0, n,
        [&](size_t v) {
            glm::dvec3 q =
                glm::round(glm::dvec3(scene.vertices[v].position - bounds.min) / tolerance);
            keys[v] = {static_cast<uint64_t>(q.x) | static_cast<uint64_t>(q.y) << 21 |
                           static_cast<uint64_t>(q.z) << 42,
                       static_cast<uint32_t>(v)};
        },
        4096);
    tbb::parallel_sort(keys.begin(), keys.end());
    std::vector<uint32_t> weld(n);
    uint32_t id = 0;
    for (size_t i = 0; i < n; ++i) {
        if (i > 0 && keys[i].first != keys[i - 1].first) ++id;
        weld[keys[i].second] = id;
    }
    return weld;
}

/// Groups the triangles with `generated` set into planar charts by flood fill over shared
/// edges. Returns the triangles of chart c as members[offsets[c], offsets[c+1]).
void floodFillCharts(const Scene& scene, const std::vector<uint8_t>& generated,
                     const std::vector<glm::dvec3>& normal, std::vector<uint32_t>& members,
                     std::vector<uint32_t>& offsets) {
    size_t n = scene.triangles.size();
    std::vector<uint32_t> weld = weldVertices(scene);

    // Edges keyed by their welded end points; sorting puts triangles sharing an edge next
    // to each other. The slot (3·triangle + edge) makes the order total, hence deterministic.
    struct EdgeEntry {
        uint64_t key;
        uint32_t slot;
        bool operator<(const EdgeEntry& o) const {
            return key != o.key ? key < o.key : slot < o.slot;
        }
    };
    std::vector<EdgeEntry> edges;
    edges.reserve(3 * n);
    for (uint32_t t = 0; t < n; ++t) {
        if (!generated[t]) continue;
        const Triangle& tri = scene.triangles[t];
        for (uint32_t k = 0; k < 3; ++k) {
            uint32_t a = weld[tri.v[k]];
            uint32_t b = weld[tri.v[(k + 1) % 3]];
            if (a == b) continue;
            edges.push_back({uint64_t{std::min(a, b)} << 32 | std::max(a, b), 3 * t + k});
        }
    }
    tbb::parallel_sort(edges.begin(), edges.end());
    // For every edge slot, the range of sorted entries sharing its key.
    std::vector<glm::uvec2> edgeRun(3 * n, glm::uvec2(0));
    for (size_t i = 0; i < edges.size();) {
        size_t j = i + 1;
        while (j < edges.size() && edges[j].key == edges[i].key) ++j;
        for (size_t e = i; e < j; ++e)
            edgeRun[edges[e].slot] = glm::uvec2(static_cast<uint32_t>(i), static_cast<uint32_t>(j));
        i = j;
    }

    // Flood fill from the lowest unassigned triangle; a chart's members are contiguous.
    double cosTolerance = std::cos(kChartNormalToleranceDegrees * std::numbers::pi / 180.0);
    std::vector<uint32_t> chartOf(n, kNoChart);
    members.clear();
    members.reserve(n);
    offsets.assign(1, 0);
    for (uint32_t seed = 0; seed < n; ++seed) {
        if (!generated[seed] || chartOf[seed] != kNoChart) continue;
        uint32_t chart = static_cast<uint32_t>(offsets.size() - 1);
        size_t head = members.size();
        chartOf[seed] = chart;
        members.push_back(seed);
        const glm::dvec3& seedNormal = normal[seed];
        bool degenerate = seedNormal == glm::dvec3(0.0);
        while (!degenerate && head < members.size()) {
            uint32_t t = members[head++];
            for (uint32_t k = 0; k < 3; ++k) {
                glm::uvec2 run = edgeRun[3 * t + k];
                for (uint32_t e = run.x; e < run.y; ++e) {
                    uint32_t u = edges[e].slot / 3;
                    if (chartOf[u] != kNoChart || !generated[u]) continue;
                    if (glm::dot(normal[u], seedNormal) < cosTolerance) continue;
                    chartOf[u] = chart;
                    members.push_back(u);
                }
            }
        }
        offsets.push_back(static_cast<uint32_t>(members.size()));
    }
}

/// Area of the padded bounding rectangle of `points` seen in a frame rotated by `angle`.
double rotatedRectArea(std::span<const glm::dvec2> points, double angle, double padding) {
    glm::dvec2 u(std::cos(angle), std::sin(angle));
    glm::dvec2 lo(std::numeric_limits<double>::max());
    glm::dvec2 hi(-std::numeric_limits<double>::max());
    for (const glm::dvec2& p : points) {
        glm::dvec2 r(u.x * p.x + u.y * p.y, -u.y * p.x + u.x * p.y);
        lo = glm::min(lo, r);
        hi = glm::max(hi, r);
    }
    glm::dvec2 size = hi - lo;
    return (size.x + 2.0 * padding) * (size.y + 2.0 * padding);
}

/// Rotation of a chart's plane coordinates that minimises its padded bounding rectangle.
/// The minimum-area rectangle has a side along an edge of the convex hull, so only hull
/// edge directions are tried; angle 0 wins ties to keep axis-aligned walls aligned.
double bestChartRotation(std::vector<glm::dvec2> points, double padding) {
    std::sort(points.begin(), points.end(), [](const glm::dvec2& a, const glm::dvec2& b) {
        return a.x != b.x ? a.x < b.x : a.y < b.y;
    });
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3) return 0.0;

    // Andrew's monotone chain.
    auto cross = [](const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
        return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    };
    std::vector<glm::dvec2> hull(2 * points.size());
    size_t k = 0;
    for (size_t i = 0; i < points.size(); ++i) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    for (size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1);

    constexpr double kQuarter = 0.5 * std::numbers::pi;
    std::vector<double> angles;
    angles.reserve(hull.size());
    for (size_t i = 0; i < hull.size(); ++i) {
        glm::dvec2 d = hull[(i + 1) % hull.size()] - hull[i];
        double a = std::fmod(std::atan2(d.y, d.x), kQuarter);
        if (a < 0.0) a += kQuarter;
        if (a > kQuarter - kRotationStepRadians) a = 0.0;
        angles.push_back(a);
    }
    std::sort(angles.begin(), angles.end());

    double bestAngle = 0.0;
    double bestArea = rotatedRectArea(hull, 0.0, padding);
    double last = 0.0;
    for (double a : angles) {
        if (a - last < kRotationStepRadians) continue;
        last = a;
        double area = rotatedRectArea(hull, a, padding);
        if (area < bestArea * (1.0 - 1e-9)) {
            bestArea = area;
            bestAngle = a;
        }
    }
    return bestAngle;
}

/// Splits a chart at the median centroid along the longer axis until every piece fits
/// `limit` texels. `items` index the chart's triangles, whose plane corners are
/// corners[3·item + k]; pieces hold items until the caller maps them to scene triangles.
void splitChart(std::vector<uint32_t> items, const std::vector<glm::dvec2>& corners, double limit,
                std::vector<ChartPiece>& pieces) {
    glm::dvec2 lo(std::numeric_limits<double>::max());
    glm::dvec2 hi(-std::numeric_limits<double>::max());
    for (uint32_t i : items)
        for (int k = 0; k < 3; ++k) {
            lo = glm::min(lo, corners[3 * i + k]);
            hi = glm::max(hi, corners[3 * i + k]);
        }
    glm::dvec2 extent = hi - lo;
    if (items.size() == 1 || (texelSpan(extent.x) <= limit && texelSpan(extent.y) <= limit)) {
        pieces.push_back({std::move(items), extent, false});
        return;
    }
    int axis = extent.x >= extent.y ? 0 : 1;
    auto centroid = [&](uint32_t i) {
        return corners[3 * i][axis] + corners[3 * i + 1][axis] + corners[3 * i + 2][axis];
    };
    auto half = items.begin() + static_cast<std::ptrdiff_t>(items.size() / 2);
    std::nth_element(items.begin(), half, items.end(), [&](uint32_t a, uint32_t b) {
        double ca = centroid(a);
        double cb = centroid(b);
        return ca != cb ? ca < cb : a < b;
    });
    std::vector<uint32_t> upper(half, items.end());
    items.erase(half, items.end());
    splitChart(std::move(items), corners, limit, pieces);
    splitChart(std::move(upper), corners, limit, pieces);
}

/// Projects one planar chart onto its plane in texels, rotates it to its smallest padded
/// rectangle, splits it if it exceeds `limit` and writes each piece's local corners.
std::vector<ChartPiece> layoutPlanarChart(const Scene& scene, std::span<const uint32_t> triangles,
                                          const std::vector<glm::dvec3>& normal,
                                          std::span<const double> triangleArea, double texelSize,
                                          uint32_t padding, double limit,
                                          std::vector<glm::vec2>& local) {
    // The chart plane's normal is the area-weighted mean of its triangles' normals.
    glm::dvec3 n(0.0);
    for (uint32_t t : triangles) n += normal[t] * triangleArea[t];
    n = glm::length(n) > 0.0 ? glm::normalize(n) : normal[triangles[0]];
    if (n == glm::dvec3(0.0)) n = glm::dvec3(0.0, 0.0, 1.0);
    glm::vec3 tangentF, bitangentF;
    orthonormalBasis(glm::vec3(n), tangentF, bitangentF);
    glm::dvec3 tangent(tangentF), bitangent(bitangentF);

    std::vector<glm::dvec2> corners(3 * triangles.size());
    for (size_t i = 0; i < triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            glm::dvec3 p(scene.vertices[scene.triangles[triangles[i]].v[k]].position);
            corners[3 * i + k] =
                glm::dvec2(glm::dot(p, tangent), glm::dot(p, bitangent)) / texelSize;
        }

    double angle = bestChartRotation(corners, padding);
    glm::dvec2 u(std::cos(angle), std::sin(angle));
    glm::dvec2 lo(std::numeric_limits<double>::max());
    glm::dvec2 hi(-std::numeric_limits<double>::max());
    for (glm::dvec2& c : corners) {
        c = glm::dvec2(u.x * c.x + u.y * c.y, -u.y * c.x + u.x * c.y);
        lo = glm::min(lo, c);
        hi = glm::max(hi, c);
    }
    // Lay the rectangle on its long side: shelves of a height-sorted packer stay flat.
    glm::dvec2 extent = hi - lo;
    bool turn = extent.y > extent.x;
    for (glm::dvec2& c : corners) {
        c -= lo;
        if (turn) c = glm::dvec2(extent.y - c.y, c.x);
    }

    std::vector<uint32_t> items(triangles.size());
    std::iota(items.begin(), items.end(), 0u);
    std::vector<ChartPiece> pieces;
    splitChart(std::move(items), corners, limit, pieces);

    // Corners relative to each piece's lower corner. Each triangle belongs to one chart,
    // so this task is the only writer of its entries in `local`.
    for (ChartPiece& piece : pieces) {
        glm::dvec2 pieceLo(std::numeric_limits<double>::max());
        for (uint32_t i : piece.triangles)
            for (int k = 0; k < 3; ++k) pieceLo = glm::min(pieceLo, corners[3 * i + k]);
        for (uint32_t& i : piece.triangles) {
            uint32_t t = triangles[i];
            for (int k = 0; k < 3; ++k) local[3 * t + k] = glm::vec2(corners[3 * i + k] - pieceLo);
            i = t;
        }
    }
    return pieces;
}

/// Atlas rectangle origins from a deterministic shelf packer, or nothing if they do not
/// fit maxSize².
struct Packing {
    uint32_t width = 0;
    uint32_t height = 0;
    std::vector<glm::uvec2> origins;
};

std::optional<Packing> packShelves(const std::vector<glm::uvec2>& sizes, uint32_t maxSize) {
    Packing packing;
    packing.origins.resize(sizes.size());
    if (sizes.empty()) return packing;
    std::vector<uint32_t> order(sizes.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        if (sizes[a].y != sizes[b].y) return sizes[a].y > sizes[b].y;
        if (sizes[a].x != sizes[b].x) return sizes[a].x > sizes[b].x;
        return a < b;
    });
    double area = 0.0;
    uint32_t widest = 0;
    for (const glm::uvec2& s : sizes) {
        area += double(s.x) * s.y;
        widest = std::max(widest, s.x);
        if (s.x > maxSize || s.y > maxSize) return std::nullopt;
    }
    double width =
        std::clamp(std::ceil(std::sqrt(area) * kAtlasSlack), double(widest), double(maxSize));
    for (;;) {
        uint32_t atlasWidth = static_cast<uint32_t>(width);
        uint64_t x = 0, y = 0, shelfHeight = 0, usedWidth = 0;
        for (uint32_t i : order) {
            if (x + sizes[i].x > atlasWidth) {
                y += shelfHeight;
                x = 0;
                shelfHeight = 0;
            }
            packing.origins[i] = glm::uvec2(static_cast<uint32_t>(x), static_cast<uint32_t>(y));
            x += sizes[i].x;
            usedWidth = std::max(usedWidth, x);
            shelfHeight = std::max<uint64_t>(shelfHeight, sizes[i].y);
        }
        if (y + shelfHeight <= maxSize) {
            packing.width = static_cast<uint32_t>(usedWidth);
            packing.height = static_cast<uint32_t>(y + shelfHeight);
            return packing;
        }
        if (atlasWidth >= maxSize) return std::nullopt;
        width = std::min(double(maxSize), std::ceil(width * kAtlasGrowth));
    }
}

/// Padded rectangle size of a piece in texels.
glm::uvec2 rectSize(const glm::dvec2& extent, uint32_t padding) {
    return glm::uvec2(static_cast<uint32_t>(std::min(texelSpan(extent.x), 1e9)) + 2 * padding,
                      static_cast<uint32_t>(std::min(texelSpan(extent.y), 1e9)) + 2 * padding);
}

/// Smallest texel size (in steps of 10 %) at which the pieces' rectangles would likely fit
/// maxSize²; 0 if their padding alone is too much at any texel size.
double suggestTexelSize(const std::vector<ChartPiece>& pieces, const LightmapChartParams& params) {
    double budget = double(params.maxAtlasSize) * params.maxAtlasSize / kPackingOverhead;
    double padded = 2.0 * params.padding + 1.0;
    if (double(pieces.size()) * padded * padded > budget) return 0.0;
    for (double scale = 1.1; scale < 1e6; scale *= 1.1) {
        double area = 0.0;
        bool fits = true;
        for (const ChartPiece& piece : pieces) {
            glm::dvec2 size(texelSpan(piece.extent.x / scale) + 2.0 * params.padding,
                            texelSpan(piece.extent.y / scale) + 2.0 * params.padding);
            fits = fits && size.x <= params.maxAtlasSize && size.y <= params.maxAtlasSize;
            area += size.x * size.y;
        }
        if (fits && area <= budget) return roundUpSignificant(params.texelSize * scale);
    }
    return 0.0;
}

Error atlasTooSmall(const std::vector<ChartPiece>& pieces, const LightmapChartParams& params) {
    double suggestion = suggestTexelSize(pieces, params);
    if (suggestion == 0.0)
        return Error{ErrorCode::InvalidInput,
                     fmt::format("light-map charts do not fit a {0}×{0} atlas at any texel size: "
                                 "{1} charts with {2} texels of padding each are too many",
                                 params.maxAtlasSize, pieces.size(), params.padding)};
    return Error{ErrorCode::InvalidInput,
                 fmt::format("light-map texel size {} m is too small for the scene: its {} charts "
                             "do not fit a {}×{} atlas; use a texel size of {:.3g} m or more",
                             params.texelSize, pieces.size(), params.maxAtlasSize,
                             params.maxAtlasSize, suggestion)};
}

}  // namespace

Result<LightmapCharts> buildLightmapCharts(const Scene& scene, const LightmapChartParams& params) {
    if (auto ok = checkInput(scene, params); !ok) return std::unexpected(ok.error());
    size_t n = scene.triangles.size();
    double texelSize = params.texelSize;

    // Geometric normal (zero for degenerate triangles) and area of every triangle.
    std::vector<glm::dvec3> normal(n);
    std::vector<double> area(n);
    parallelFor(
        0, n,
        [&](size_t t) {
            const Triangle& tri = scene.triangles[t];
            glm::dvec3 p0(scene.vertices[tri.v[0]].position);
            glm::dvec3 c = glm::cross(glm::dvec3(scene.vertices[tri.v[1]].position) - p0,
                                      glm::dvec3(scene.vertices[tri.v[2]].position) - p0);
            double length = glm::length(c);
            normal[t] = length > 0.0 ? c / length : glm::dvec3(0.0);
            area[t] = 0.5 * length;
        },
        4096);

    // The charts' content alone must fit the atlas; this also bounds the work below.
    double contentTexels = std::accumulate(area.begin(), area.end(), 0.0) / (texelSize * texelSize);
    double atlasTexels = double(params.maxAtlasSize) * params.maxAtlasSize;
    if (contentTexels > atlasTexels)
        return fail(
            ErrorCode::InvalidInput,
            "light-map texel size {} m is too small for the scene: its surfaces need {:.3g} "
            "texels, more than a {}×{} atlas holds; use a texel size of {:.3g} m or more",
            params.texelSize, contentTexels, params.maxAtlasSize, params.maxAtlasSize,
            roundUpSignificant(texelSize *
                               std::sqrt(contentTexels * kPackingOverhead / atlasTexels)));

    std::vector<glm::vec2> local(3 * n);  // corner positions inside their piece, texels
    std::vector<ChartPiece> pieces;

    // Primitives with TEXCOORD_1 keep their layout, one chart each.
    std::vector<uint8_t> generated(n, 1);
    uint32_t uv1Primitives = 0;
    for (const Primitive& primitive : scene.primitives) {
        if (!primitive.hasUv1 || primitive.triangleCount == 0) continue;
        ChartPiece piece;
        if (!layoutUv1Primitive(scene, primitive, area, texelSize, local, piece)) continue;
        for (uint32_t t : piece.triangles) {
            if (!generated[t])
                return fail(ErrorCode::InvalidInput,
                            "primitive '{}' shares triangle {} with another primitive",
                            primitive.name, t);
            generated[t] = 0;
        }
        pieces.push_back(std::move(piece));
        ++uv1Primitives;
    }

    // All other triangles form planar charts.
    std::vector<uint32_t> members;
    std::vector<uint32_t> offsets;
    floodFillCharts(scene, generated, normal, members, offsets);
    size_t planarCharts = offsets.size() - 1;
    std::vector<std::vector<ChartPiece>> planarPieces(planarCharts);
    double limit = double(params.maxAtlasSize - 2 * params.padding);
    parallelFor(
        0, planarCharts,
        [&](size_t c) {
            std::span<const uint32_t> triangles(members.data() + offsets[c],
                                                offsets[c + 1] - offsets[c]);
            planarPieces[c] = layoutPlanarChart(scene, triangles, normal, area, texelSize,
                                                params.padding, limit, local);
        },
        16);
    for (std::vector<ChartPiece>& chartPieces : planarPieces)
        for (ChartPiece& piece : chartPieces) pieces.push_back(std::move(piece));

    // Pack the padded rectangles.
    std::vector<glm::uvec2> sizes(pieces.size());
    for (size_t i = 0; i < pieces.size(); ++i)
        sizes[i] = rectSize(pieces[i].extent, params.padding);
    std::optional<Packing> packing = packShelves(sizes, params.maxAtlasSize);
    if (!packing) return std::unexpected(atlasTooSmall(pieces, params));

    LightmapCharts charts;
    charts.width = packing->width;
    charts.height = packing->height;
    charts.texelSize = params.texelSize;
    charts.padding = params.padding;
    charts.chartCount = static_cast<uint32_t>(pieces.size()) - uv1Primitives;
    charts.uv1Primitives = uv1Primitives;
    charts.charts.resize(pieces.size());
    charts.triangleChart.assign(n, kNoChart);
    charts.triangleUvs.resize(3 * n);
    glm::vec2 atlasSize(float(charts.width), float(charts.height));
    parallelFor(
        0, pieces.size(),
        [&](size_t c) {
            glm::uvec2 origin = packing->origins[c];
            charts.charts[c] = {origin.x, origin.y, sizes[c].x, sizes[c].y, pieces[c].fromUv1};
            glm::vec2 content = glm::vec2(origin) + float(params.padding);
            for (uint32_t t : pieces[c].triangles) {
                charts.triangleChart[t] = static_cast<uint32_t>(c);
                for (int k = 0; k < 3; ++k)
                    charts.triangleUvs[3 * t + k] = (content + local[3 * t + k]) / atlasSize;
            }
        },
        16);
    return charts;
}

uint32_t repackLightmapCharts(LightmapCharts& charts, const std::vector<uint8_t>& keep) {
    PIC_CHECK_EQ(keep.size(), charts.charts.size());
    // Kept charts move by whole texels, so their texel centres stay where they were on the
    // surface; a packing of fewer rectangles of the same sizes always fits again.
    std::vector<uint32_t> kept;
    std::vector<glm::uvec2> sizes;
    for (uint32_t c = 0; c < charts.charts.size(); ++c)
        if (keep[c]) {
            kept.push_back(c);
            sizes.emplace_back(charts.charts[c].width, charts.charts[c].height);
        }
    std::optional<Packing> packing =
        packShelves(sizes, std::max({charts.width, charts.height, 1u}));
    if (!packing) return 0;

    std::vector<glm::ivec2> shift(charts.charts.size(), glm::ivec2(0));
    for (size_t i = 0; i < kept.size(); ++i) {
        LightmapChart& chart = charts.charts[kept[i]];
        shift[kept[i]] = glm::ivec2(packing->origins[i]) - glm::ivec2(chart.x, chart.y);
        chart.x = packing->origins[i].x;
        chart.y = packing->origins[i].y;
    }
    const glm::dvec2 oldSize(charts.width, charts.height);
    const glm::dvec2 newSize(std::max(packing->width, 1u), std::max(packing->height, 1u));
    uint32_t dropped = 0;
    for (size_t t = 0; t < charts.triangleChart.size(); ++t) {
        uint32_t c = charts.triangleChart[t];
        for (int k = 0; k < 3; ++k) {
            glm::vec2& uv = charts.triangleUvs[3 * t + k];
            uv = keep[c] ? glm::vec2((glm::dvec2(uv) * oldSize + glm::dvec2(shift[c])) / newSize)
                         : glm::vec2(kNotLightmapped);
        }
        dropped += keep[c] ? 0 : 1;
    }
    for (uint32_t c = 0; c < charts.charts.size(); ++c)
        if (!keep[c]) charts.charts[c] = LightmapChart{0, 0, 0, 0, charts.charts[c].fromUv1};
    charts.width = static_cast<uint32_t>(newSize.x);
    charts.height = static_cast<uint32_t>(newSize.y);
    return dropped;
}

}  // namespace pic
