#include "bake/surfel_placement.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "bake/surfel_grid.h"
#include "core/geometry.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/sampling.h"

namespace pic {

namespace {

/// Uniform point on a triangle from a point of the unit square (barycentric b1, b2).
glm::vec2 squareToTriangle(float u, float v) {
    float su = std::sqrt(u);
    return {su * (1.0f - v), su * v};
}

/// One Jacobi step of tangential repulsion: each surfel moves away from neighbours closer
/// than the ideal spacing, within its tangent plane, and stays on its own triangle.
void relaxOnce(const Scene& scene, std::vector<Surfel>& surfels, float spacing) {
    SurfelGrid grid(surfels, spacing);
    std::vector<glm::vec3> moved(surfels.size());
    parallelFor(0, surfels.size(), [&](size_t i) {
        const Surfel& s = surfels[i];
        glm::vec3 push(0.0f);
        grid.forNeighbours(s.position, [&](const SurfelGrid::Entry& o) {
            if (o.index == i) return;
            // Surfels on the other side of a thin wall do not repel each other; those across
            // a crease do, so that edges push surfels away as much as neighbours in the plane
            // (without it, surfels pile up on the edges of their triangles).
            if (glm::dot(s.normal, o.normal) < -0.5f) return;
            glm::vec3 d = s.position - o.position;
            float dist = glm::length(d);
            if (dist >= spacing || dist <= 0.0f) return;
            push += d / dist * (spacing - dist);
        });
        // Keep the move in the tangent plane and small enough to converge.
        push -= s.normal * glm::dot(push, s.normal);
        glm::vec3 p = s.position + 0.25f * push;
        // A move that would leave the surfel's triangle is not taken: clamping it to the
        // border instead would pile surfels up along edges and thin them out beside.
        const Triangle& t = scene.triangles[s.triangle];
        glm::vec3 w = barycentric(p, scene.vertices[t.v[0]].position, scene.vertices[t.v[1]].position,
                                  scene.vertices[t.v[2]].position);
        moved[i] = glm::all(glm::greaterThanEqual(w, glm::vec3(0.0f))) ? p : s.position;
    }, 256);
    for (size_t i = 0; i < surfels.size(); ++i) surfels[i].position = moved[i];
}

}  // namespace

Result<std::vector<Surfel>> placeSurfels(const Scene& scene, const SurfelParams& params) {
    if (params.count == 0)
        return fail(ErrorCode::InvalidInput, "surfel count must be positive, got {}", params.count);
    if (scene.triangles.empty() || !(scene.totalArea > 0.0))
        return fail(ErrorCode::InvalidInput, "scene '{}' has no surface area to place surfels on",
                    scene.sourcePath);

    const uint32_t nS = params.count;
    const double surfelArea = scene.totalArea / nS;
    const float radius = static_cast<float>(std::sqrt(surfelArea / std::numbers::pi));

    // Sample triangles proportionally to area: surfel k is spawned in the triangle whose
    // cumulative-area interval contains (k + 0.5)·a, so small triangles accumulate their
    // area until they spawn one (paper 000 §4.2). Surfels of one triangle take consecutive
    // Halton points, which spreads them evenly inside it.
    std::vector<uint32_t> triangleOf(nS);
    {
        double cumulative = 0.0;
        uint32_t next = 0;
        for (uint32_t t = 0; t < scene.triangles.size() && next < nS; ++t) {
            cumulative += scene.triangleArea(t);
            while (next < nS && (next + 0.5) * surfelArea <= cumulative) triangleOf[next++] = t;
        }
        // Rounding in the running sum can leave the last surfel unassigned.
        for (; next < nS; ++next) triangleOf[next] = static_cast<uint32_t>(scene.triangles.size() - 1);
    }

    Rng rng(params.seed, 0x5eed5u);
    const float offsetU = rng.uniform(), offsetV = rng.uniform();  // Cranley-Patterson rotation
    std::vector<Surfel> surfels(nS);
    parallelFor(0, nS, [&](size_t k) {
        uint32_t t = triangleOf[k];
        float u = static_cast<float>(radicalInverse(2, k + 1)) + offsetU;
        float v = static_cast<float>(radicalInverse(3, k + 1)) + offsetV;
        glm::vec2 b = squareToTriangle(u - std::floor(u), v - std::floor(v));
        const Triangle& tri = scene.triangles[t];
        const glm::vec3& a = scene.vertices[tri.v[0]].position;
        Surfel& s = surfels[k];
        s.position = a + b.x * (scene.vertices[tri.v[1]].position - a) +
                     b.y * (scene.vertices[tri.v[2]].position - a);
        s.normal = scene.triangleNormal(t);
        s.area = static_cast<float>(surfelArea);
        s.radius = radius;
        s.triangle = t;
        s.material = tri.material;
    }, 1024);

    Progress progress("surfel relaxation", params.relaxIterations);
    const float spacing = 2.0f * radius;
    for (uint32_t it = 0; it < params.relaxIterations; ++it) {
        relaxOnce(scene, surfels, spacing);
        progress.advance();
    }
    progress.finish();

    // Albedo and emission averaged over the surfel's disc footprint on its triangle plane,
    // sampled on a Fibonacci spiral (points outside the triangle extrapolate its UVs).
    const uint32_t footprint = std::max(1u, params.footprintSamples);
    parallelFor(0, nS, [&](size_t k) {
        Surfel& s = surfels[k];
        const Triangle& tri = scene.triangles[s.triangle];
        const glm::vec3& a = scene.vertices[tri.v[0]].position;
        const glm::vec3& b = scene.vertices[tri.v[1]].position;
        const glm::vec3& c = scene.vertices[tri.v[2]].position;
        glm::vec3 tangent, bitangent;
        orthonormalBasis(s.normal, tangent, bitangent);
        glm::vec3 albedo(0.0f), emission(0.0f);
        for (uint32_t j = 0; j < footprint; ++j) {
            float r = s.radius * std::sqrt((j + 0.5f) / footprint);
            float phi = j * 2.39996323f;  // golden angle
            glm::vec3 p = s.position + r * (std::cos(phi) * tangent + std::sin(phi) * bitangent);
            glm::vec3 w = barycentric(p, a, b, c);
            albedo += scene.albedoAt(s.triangle, w.y, w.z);
            emission += scene.emissionAt(s.triangle, w.y, w.z);
        }
        s.albedo = glm::clamp(albedo / static_cast<float>(footprint), 0.0f, 1.0f);
        s.emission = glm::max(emission / static_cast<float>(footprint), 0.0f);
    }, 1024);
    return surfels;
}

}  // namespace pic
