#include "bake/grid_caches.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

namespace {

/// Separating-axis test of triangle abc against the axis-aligned box centre ± half
/// (Akenine-Möller 2001): the 13 axes are the box normals, the triangle normal and the
/// 9 edge cross products.
bool triangleOverlapsBox(glm::vec3 a, glm::vec3 b, glm::vec3 c, const glm::vec3& centre,
                         const glm::vec3& half) {
    a -= centre;
    b -= centre;
    c -= centre;
    const glm::vec3 edges[3] = {b - a, c - b, a - c};
    for (int i = 0; i < 3; ++i) {
        for (int axisIndex = 0; axisIndex < 3; ++axisIndex) {
            glm::vec3 unit(0.0f);
            unit[axisIndex] = 1.0f;
            glm::vec3 axis = glm::cross(unit, edges[i]);
            float pa = glm::dot(a, axis), pb = glm::dot(b, axis), pc = glm::dot(c, axis);
            float r = half.x * std::abs(axis.x) + half.y * std::abs(axis.y) + half.z * std::abs(axis.z);
            if (std::min({pa, pb, pc}) > r || std::max({pa, pb, pc}) < -r) return false;
        }
    }
    for (int k = 0; k < 3; ++k)
        if (std::min({a[k], b[k], c[k]}) > half[k] || std::max({a[k], b[k], c[k]}) < -half[k])
            return false;
    glm::vec3 n = glm::cross(edges[0], edges[1]);
    float r = half.x * std::abs(n.x) + half.y * std::abs(n.y) + half.z * std::abs(n.z);
    return std::abs(glm::dot(n, a)) <= r;
}

/// GridCaches::Surfaces: keeps the caches that the corners of the `read` cells hold (a point
/// in a cell interpolates its 8 corners), numbered again from `firstCacheIndex` in order;
/// every other vertex gets kNoCache.
void keepReadCaches(GridCacheSet& set, const std::vector<std::atomic<uint8_t>>& read,
                    glm::uvec3 cells, uint32_t firstCacheIndex) {
    GridLayout& grid = set.layout;
    std::vector<uint8_t> vertexRead(grid.cacheIndex.size(), 0);
    for (uint32_t z = 0; z < cells.z; ++z)
        for (uint32_t y = 0; y < cells.y; ++y)
            for (uint32_t x = 0; x < cells.x; ++x) {
                if (!read[x + cells.x * (y + uint64_t(cells.y) * z)].load(std::memory_order_relaxed)) continue;
                for (uint32_t corner = 0; corner < 8; ++corner)
                    vertexRead[(x + (corner & 1)) +
                               grid.dims.x * ((y + ((corner >> 1) & 1)) + uint64_t(grid.dims.y) * (z + (corner >> 2)))] = 1;
            }
    std::vector<uint32_t> remap(set.caches.size(), kNoCache);
    for (size_t v = 0; v < vertexRead.size(); ++v)
        if (vertexRead[v] && grid.cacheIndex[v] != kNoCache) remap[grid.cacheIndex[v] - firstCacheIndex] = 0;
    uint32_t kept = 0;
    for (size_t c = 0; c < set.caches.size(); ++c) {
        if (remap[c] == kNoCache) continue;
        remap[c] = kept;
        set.caches[kept++] = set.caches[c];
    }
    set.unread = static_cast<uint32_t>(set.caches.size() - kept);
    set.caches.resize(kept);
    for (size_t v = 0; v < vertexRead.size(); ++v) {
        uint32_t& index = grid.cacheIndex[v];
        index = vertexRead[v] && index != kNoCache ? firstCacheIndex + remap[index - firstCacheIndex] : kNoCache;
    }
}

}  // namespace

std::vector<glm::vec3> sphereDirections(uint32_t n) {
    std::vector<glm::vec3> dirs(n);
    for (uint32_t i = 0; i < n; ++i) {
        float z = 1.0f - (2.0f * i + 1.0f) / n;
        float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        float phi = i * 2.39996323f;
        dirs[i] = {r * std::cos(phi), r * std::sin(phi), z};
    }
    return dirs;
}

bool insideSolid(const Scene& scene, const EmbreeScene& rays, const glm::vec3& p,
                 std::span<const glm::vec3> directions) {
    size_t back = 0, front = 0;
    for (const glm::vec3& d : directions) {
        auto hit = rays.intersect(p, d, 0.0f, std::numeric_limits<float>::infinity());
        if (!hit) continue;
        if (hit->backFace && !scene.materials[scene.triangles[hit->triangle].material].doubleSided)
            ++back;
        else
            ++front;
    }
    return back * 4 > directions.size() || front == 0;
}

Result<GridCacheSet> placeGridCaches(const Scene& scene, const EmbreeScene& rays,
                                     uint32_t firstCacheIndex, const GridCacheParams& params) {
    const float cell = params.cellSize;
    if (!(cell > 0.0f) || !std::isfinite(cell))
        return fail(ErrorCode::InvalidInput, "grid cell size must be a positive number of metres, got {}", cell);
    // Vertices sit half a cell off the scene's bounding planes so that axis-aligned walls
    // on the bounds never pass through a cache; one extra cell on each side holds the dilation.
    GridCacheSet result;
    GridLayout& grid = result.layout;
    grid.cellSize = cell;
    grid.origin = scene.bounds.min - glm::vec3(1.5f * cell);
    glm::vec3 span = scene.bounds.extent() + glm::vec3(3.0f * cell);
    glm::uvec3 cells = glm::uvec3(glm::ceil(span / cell));
    grid.dims = cells + glm::uvec3(1);
    uint64_t vertexCount = uint64_t(grid.dims.x) * grid.dims.y * grid.dims.z;
    if (vertexCount > params.maxVertices)
        return fail(ErrorCode::InvalidInput,
                    "grid cell size {} m gives {}×{}×{} vertices for a scene of {:.3g}×{:.3g}×{:.3g} m; "
                    "use a larger --grid-cell",
                    cell, grid.dims.x, grid.dims.y, grid.dims.z, span.x, span.y, span.z);

    auto cellIndex = [&](glm::uvec3 c) { return c.x + cells.x * (c.y + uint64_t(cells.y) * c.z); };
    auto vertexIndex = [&](glm::uvec3 v) { return v.x + grid.dims.x * (v.y + uint64_t(grid.dims.y) * v.z); };

    // 1. Cells containing or touching a triangle. Each triangle marks its own cells;
    //    writes of the value 1 from several threads are benign with relaxed atomics.
    const bool surfaces = params.mode == GridCaches::Surfaces;
    if (surfaces && params.gridShaded.size() != scene.triangles.size())
        return fail(ErrorCode::InvalidInput, "grid-shaded flags for {} triangles, the scene has {}",
                    params.gridShaded.size(), scene.triangles.size());
    std::vector<std::atomic<uint8_t>> occupied(uint64_t(cells.x) * cells.y * cells.z);
    // Surfaces mode: cells holding a grid-shaded triangle, whose corners its points read.
    std::vector<std::atomic<uint8_t>> read(surfaces ? occupied.size() : 0);
    const glm::vec3 half(0.5f * cell);
    {
        Progress progress("grid occupancy", scene.triangles.size());
        parallelForChunks(0, scene.triangles.size(), [&](size_t begin, size_t end) {
            for (size_t t = begin; t < end; ++t) {
                const Triangle& tri = scene.triangles[t];
                const bool shadedFromGrid = surfaces && params.gridShaded[t];
                glm::vec3 p[3];
                Aabb box;
                for (int k = 0; k < 3; ++k) box.extend(p[k] = scene.vertices[tri.v[k]].position);
                glm::uvec3 lo = glm::uvec3(glm::clamp(glm::floor((box.min - grid.origin) / cell), glm::vec3(0.0f), glm::vec3(cells - 1u)));
                glm::uvec3 hi = glm::uvec3(glm::clamp(glm::floor((box.max - grid.origin) / cell), glm::vec3(0.0f), glm::vec3(cells - 1u)));
                for (uint32_t z = lo.z; z <= hi.z; ++z)
                    for (uint32_t y = lo.y; y <= hi.y; ++y)
                        for (uint32_t x = lo.x; x <= hi.x; ++x) {
                            glm::vec3 centre = grid.origin + (glm::vec3(x, y, z) + 0.5f) * cell;
                            const uint64_t index = cellIndex({x, y, z});
                            auto& flag = occupied[index];
                            const bool known = flag.load(std::memory_order_relaxed) &&
                                               (!shadedFromGrid || read[index].load(std::memory_order_relaxed));
                            if (known || !triangleOverlapsBox(p[0], p[1], p[2], centre, half)) continue;
                            flag.store(1, std::memory_order_relaxed);
                            if (shadedFromGrid) read[index].store(1, std::memory_order_relaxed);
                        }
            }
            progress.advance(end - begin);
        }, 512);
    }

    // 2. One-cell dilation, then every corner of a dilated cell needs a cache; in Space mode
    //    every vertex does, and the inside test below keeps those in open space.
    std::vector<uint8_t> needed(vertexCount, params.mode == GridCaches::Space ? 1 : 0);
    for (uint32_t z = 0; z < cells.z && params.mode != GridCaches::Space; ++z)
        for (uint32_t y = 0; y < cells.y; ++y)
            for (uint32_t x = 0; x < cells.x; ++x) {
                bool near = false;
                for (int dz = -1; dz <= 1 && !near; ++dz)
                    for (int dy = -1; dy <= 1 && !near; ++dy)
                        for (int dx = -1; dx <= 1 && !near; ++dx) {
                            glm::ivec3 n = glm::ivec3(x, y, z) + glm::ivec3(dx, dy, dz);
                            if (glm::any(glm::lessThan(n, glm::ivec3(0))) ||
                                glm::any(glm::greaterThanEqual(n, glm::ivec3(cells))))
                                continue;
                            near = occupied[cellIndex(glm::uvec3(n))].load(std::memory_order_relaxed);
                        }
                if (!near) continue;
                for (uint32_t corner = 0; corner < 8; ++corner)
                    needed[vertexIndex({x + (corner & 1), y + ((corner >> 1) & 1), z + (corner >> 2)})] = 1;
            }

    // 3. Inside-solid test: from inside closed geometry (or behind single-sided walls) most
    //    rays meet back faces first. Double-sided materials have no inside.
    std::vector<uint64_t> candidates;
    for (uint64_t v = 0; v < vertexCount; ++v)
        if (needed[v]) candidates.push_back(v);
    const std::vector<glm::vec3> dirs = sphereDirections(params.insideRays);
    std::vector<uint8_t> inside(candidates.size(), 0);
    {
        Progress progress("grid inside test", candidates.size());
        parallelFor(0, candidates.size(), [&](size_t i) {
            uint64_t v = candidates[i];
            glm::uvec3 c(v % grid.dims.x, (v / grid.dims.x) % grid.dims.y, v / (uint64_t(grid.dims.x) * grid.dims.y));
            glm::vec3 p = grid.origin + glm::vec3(c) * cell;
            // Inside when more than a quarter of the sphere shows back faces, and useless when
            // no front face is in sight (e.g. outside a closed room).
            inside[i] = insideSolid(scene, rays, p, dirs);
            if ((i & 1023) == 0) progress.advance(std::min<size_t>(1024, candidates.size() - i));
        }, 64);
    }

    // 4. Unique caches at free vertices, in vertex order.
    grid.cacheIndex.assign(vertexCount, kNoCache);
    for (size_t i = 0; i < candidates.size(); ++i) {
        if (inside[i]) {
            ++result.insideSolid;
            continue;
        }
        uint64_t v = candidates[i];
        glm::uvec3 c(v % grid.dims.x, (v / grid.dims.x) % grid.dims.y, v / (uint64_t(grid.dims.x) * grid.dims.y));
        Cache cache{};
        cache.position = grid.origin + glm::vec3(c) * cell;
        cache.kind = gpu::kCacheKindGrid;
        cache.normal = glm::vec3(0.0f);
        cache.texel = static_cast<uint32_t>(v);
        grid.cacheIndex[v] = firstCacheIndex + static_cast<uint32_t>(result.caches.size());
        result.caches.push_back(cache);
    }

    // 5. Needed vertices inside geometry copy the cache of their nearest free neighbour, so
    //    trilinear lookups next to walls never blend in an unlit or missing value.
    std::vector<uint32_t> filled = grid.cacheIndex;
    for (size_t i = 0; i < candidates.size(); ++i) {
        if (!inside[i]) continue;
        uint64_t v = candidates[i];
        glm::ivec3 c(v % grid.dims.x, (v / grid.dims.x) % grid.dims.y, v / (uint64_t(grid.dims.x) * grid.dims.y));
        int bestDistance = 4;
        uint32_t best = kNoCache;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    glm::ivec3 n = c + glm::ivec3(dx, dy, dz);
                    if (glm::any(glm::lessThan(n, glm::ivec3(0))) ||
                        glm::any(glm::greaterThanEqual(n, glm::ivec3(grid.dims))))
                        continue;
                    uint32_t index = grid.cacheIndex[vertexIndex(glm::uvec3(n))];
                    int distance = std::abs(dx) + std::abs(dy) + std::abs(dz);
                    if (index != kNoCache && distance < bestDistance) {
                        bestDistance = distance;
                        best = index;
                    }
                }
        if (best != kNoCache) {
            filled[v] = best;
            ++result.duplicates;
        }
    }
    grid.cacheIndex = std::move(filled);
    if (surfaces) keepReadCaches(result, read, cells, firstCacheIndex);
    return result;
}

}  // namespace pic
