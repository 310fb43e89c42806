#include "bake/ref/path_tracer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/color.h"
#include "core/geometry.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

/// Russian roulette starts once a path has reflected this many times.
constexpr int kRouletteReflections = 3;
/// Upper bound of the roulette survival probability, so that every path ends with probability
/// one even where albedos reach 1.
constexpr float kMaxSurvival = 0.95f;

/// Power heuristic (β = 2) weight of a strategy with density `pdf` > 0 against one with
/// `other`; written with the ratio so that infinite densities give 0 or 1, never NaN.
float powerHeuristic(float pdf, float other) {
    if (!(pdf > 0.0f)) return 0.0f;
    float ratio = other / pdf;
    return 1.0f / (1.0f + ratio * ratio);
}

/// 1 − cos α without cancellation for small angles.
float oneMinusCos(float angle) {
    float s = std::sin(0.5f * angle);
    return 2.0f * s * s;
}

/// Solid angle a point or spot light emits into: the sphere, or the spot's outer cone.
float emittingSolidAngle(const Light& light) {
    return light.type == LightType::Spot ? 2.0f * kPi * oneMinusCos(light.outerConeAngle)
                                         : 4.0f * kPi;
}

bool hasLobe(const PathTraceParams& params) {
    return params.glossyExponent > 0.0f && params.glossyWeight > 0.0f;
}

float maxComponent(const glm::vec3& v) {
    return std::max(v.x, std::max(v.y, v.z));
}

}  // namespace

glm::vec3 samplePhongLobe(const glm::vec3& axis, float exponent, float u1, float u2) {
    // The lobe's density over cos α = c is (n+1)·c^n on [0, 1] (the azimuth uniform), whose
    // inverse CDF is c = u^(1/(n+1)).
    const float c = std::pow(u1, 1.0f / (exponent + 1.0f));
    const float r = std::sqrt(std::max(0.0f, 1.0f - c * c));
    const float phi = 2.0f * kPi * u2;
    glm::vec3 t, b;
    orthonormalBasis(axis, t, b);
    return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + c * axis);
}

bool isValidRadiance(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && v.x >= 0.0f &&
           v.y >= 0.0f && v.z >= 0.0f;
}

Result<PathTracer> PathTracer::create(const Scene& scene, const EmbreeScene& rays,
                                      const LightSet& lights) {
    std::optional<Sky> sky;
    if (lights.sky) {
        PIC_TRY_ASSIGN(sky, resolveSky(*lights.sky, scene.sourcePath));
    }
    return PathTracer(scene, rays, lights, std::move(sky));
}

PathTracer::PathTracer(const Scene& scene, const EmbreeScene& rays, const LightSet& lights,
                       std::optional<Sky> sky)
    : mScene(&scene), mRays(&rays), mLights(lights) {
    // A light set's sky must have been resolved (its environment read) by the caller.
    PIC_CHECK(lights.sky.has_value() == sky.has_value());
    if (sky) mSky.emplace(std::move(*sky));
    mMaterialEmissionScale.resize(scene.materials.size());
    for (size_t m = 0; m < scene.materials.size(); ++m)
        mMaterialEmissionScale[m] = lights.emissiveScaleOf(scene.materials[m].name);

    // Emitters are chosen in proportion to area × luminance of the material's emission (the
    // emissive texture only modulates it), so bright and large emitters get most samples.
    mEmitterAreaPdf.assign(scene.triangles.size(), 0.0f);
    std::vector<double> weights;
    double total = 0.0;
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        uint32_t m = scene.triangles[t].material;
        glm::vec3 emitted = scene.materials[m].emission * mMaterialEmissionScale[m];
        float area = scene.triangleArea(t);
        if (!(maxComponent(emitted) > 0.0f) || !(area > 0.0f)) continue;
        double weight = double(area) * std::max(double(luminance(emitted)), 1e-12);
        mEmitters.push_back({t, area, scene.triangleNormal(t)});
        weights.push_back(weight);
        total += weight;
    }
    mEmitterCdf.resize(mEmitters.size());
    double running = 0.0;
    for (size_t i = 0; i < mEmitters.size(); ++i) {
        running += weights[i];
        mEmitterCdf[i] = static_cast<float>(running / total);
        mEmitterAreaPdf[mEmitters[i].triangle] =
            static_cast<float>(weights[i] / total / mEmitters[i].area);
    }
    if (!mEmitterCdf.empty()) mEmitterCdf.back() = 1.0f;

    // Light vertices start at point and spot lights chosen in proportion to emitted power
    // (intensity × luminance of the colour × solid angle of the sphere or the outer cone).
    mVertexLightPdf.assign(lights.lights.size(), 0.0f);
    std::vector<double> powers;
    double totalPower = 0.0;
    for (uint32_t l = 0; l < lights.lights.size(); ++l) {
        const Light& light = lights.lights[l];
        if (light.type == LightType::Directional) continue;
        float solidAngle = emittingSolidAngle(light);
        double power = double(light.intensity) * double(luminance(light.color)) * solidAngle;
        if (!(power > 0.0) || !std::isfinite(power) || !(solidAngle > 0.0f)) continue;
        mVertexLights.push_back(l);
        powers.push_back(power);
        totalPower += power;
    }
    running = 0.0;
    for (size_t i = 0; i < mVertexLights.size(); ++i) {
        running += powers[i];
        mVertexLightCdf.push_back(static_cast<float>(running / totalPower));
        mVertexLightPdf[mVertexLights[i]] = static_cast<float>(powers[i] / totalPower) /
                                            emittingSolidAngle(lights.lights[mVertexLights[i]]);
    }
    if (!mVertexLightCdf.empty()) mVertexLightCdf.back() = 1.0f;
}

glm::vec3 PathTracer::emission(uint32_t t, float b1, float b2) const {
    return mScene->emissionAt(t, b1, b2) * mMaterialEmissionScale[mScene->triangles[t].material];
}

float PathTracer::emitterPdf(uint32_t t, float distance, float cosLight) const {
    return mEmitterAreaPdf[t] * distance * distance / cosLight;
}

float PathTracer::lightVertexPdf(size_t l, const glm::vec3& fromLight, float distance,
                                 float cosLight) const {
    const Light& light = mLights.lights[l];
    if (light.type == LightType::Spot &&
        glm::dot(fromLight, light.direction) < std::cos(light.outerConeAngle))
        return 0.0f;
    return mVertexLightPdf[l] * cosLight / (distance * distance);
}

std::optional<PathTracer::LightVertex> PathTracer::sampleLightVertex(Rng& rng) const {
    if (mVertexLights.empty()) return std::nullopt;
    float u = rng.uniform();
    size_t index = size_t(std::upper_bound(mVertexLightCdf.begin(), mVertexLightCdf.end(), u) -
                          mVertexLightCdf.begin());
    const uint32_t l = mVertexLights[std::min(index, mVertexLights.size() - 1)];
    const Light& light = mLights.lights[l];
    // Uniform over the sphere, or over the spot's outer cone around its direction.
    float cosTheta = light.type == LightType::Point
                         ? 1.0f - 2.0f * rng.uniform()
                         : 1.0f - rng.uniform() * oneMinusCos(light.outerConeAngle);
    float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
    float phi = 2.0f * kPi * rng.uniform();
    glm::vec3 axis = light.type == LightType::Point ? glm::vec3(0.0f, 0.0f, 1.0f) : light.direction;
    glm::vec3 t, b;
    orthonormalBasis(axis, t, b);
    glm::vec3 fromLight = glm::normalize(sinTheta * std::cos(phi) * t +
                                         sinTheta * std::sin(phi) * b + cosTheta * axis);

    std::optional<RayHit> hit = mRays->intersect(light.position, fromLight, 0.0f, kInfinity);
    if (!hit) return std::nullopt;
    LightVertex vertex;
    vertex.position = light.position + hit->t * fromLight;
    vertex.normal = hit->backFace ? -hit->geometricNormal : hit->geometricNormal;
    glm::vec3 albedo = mScene->albedoAt(hit->triangle, hit->b1, hit->b2);
    glm::vec3 toLight;
    float distance = 0.0f;
    glm::vec3 irradiance =
        lightIrradiance(light, vertex.position, vertex.normal, toLight, distance);
    if (!(maxComponent(albedo * irradiance) > 0.0f)) return std::nullopt;
    vertex.areaPdf = lightVertexPdf(l, fromLight, distance, glm::dot(vertex.normal, toLight));
    if (!(vertex.areaPdf > 0.0f) || !std::isfinite(vertex.areaPdf)) return std::nullopt;
    vertex.weight = albedo / kPi * irradiance / vertex.areaPdf;
    return vertex;
}

glm::vec3 PathTracer::connectLightVertex(const glm::vec3& position, const glm::vec3& normal,
                                         const LightVertex& vertex) const {
    const float epsilon = mRays->epsilon();
    glm::vec3 toVertex = vertex.position - position;
    float distance2 = glm::dot(toVertex, toVertex);
    float distance = std::sqrt(distance2);
    if (!(distance > 2.0f * epsilon)) return glm::vec3(0.0f);
    glm::vec3 direction = toVertex / distance;
    // Both points must face each other, the vertex from its lit side (two-sided reflection
    // returns light to the side it came from).
    float cosHere = glm::dot(normal, direction);
    float cosThere = -glm::dot(vertex.normal, direction);
    if (cosHere <= 0.0f || cosThere <= 0.0f) return glm::vec3(0.0f);
    if (mRays->occluded(position + epsilon * normal, direction, 0.0f, distance - 2.0f * epsilon))
        return glm::vec3(0.0f);
    float geometry = cosHere * cosThere / distance2;
    // The competing strategy reaches the vertex by cosine-weighted sampling from here.
    float bsdfAreaPdf = cosHere / kPi * cosThere / distance2;
    return vertex.weight * (geometry / kPi) * powerHeuristic(vertex.areaPdf, bsdfAreaPdf);
}

glm::vec3 PathTracer::directLight(const glm::vec3& position, const glm::vec3& normal,
                                  float bsdfAreaPdf, Rng& rng, bool punctual) const {
    const float epsilon = mRays->epsilon();
    const glm::vec3 shadowOrigin = position + epsilon * normal;
    glm::vec3 direct(0.0f);

    // Punctual lights are deltas: each one is evaluated exactly, with one shadow ray. When this
    // point was reached from a surface, the light-vertex strategy samples the same path too.
    for (size_t l = 0; punctual && l < mLights.lights.size(); ++l) {
        glm::vec3 toLight;
        float distance = kInfinity;
        glm::vec3 irradiance =
            lightIrradiance(mLights.lights[l], position, normal, toLight, distance);
        if (!(maxComponent(irradiance) > 0.0f)) continue;
        if (mRays->occluded(shadowOrigin, toLight, 0.0f, std::max(0.0f, distance - epsilon)))
            continue;
        float weight = 1.0f;
        if (bsdfAreaPdf >= 0.0f && mVertexLightPdf[l] > 0.0f)
            weight = powerHeuristic(
                bsdfAreaPdf, lightVertexPdf(l, -toLight, distance, glm::dot(normal, toLight)));
        direct += irradiance * (weight / kPi);
    }

    // The sky is no delta: one sampled direction, shared with BSDF sampling by MIS.
    if (mSky) direct += skyLight(shadowOrigin, normal, rng);

    if (mEmitters.empty()) return direct;
    // One emitter point: a triangle by the CDF, then a uniform point on it (square-root warp).
    float u = rng.uniform();
    size_t index =
        size_t(std::upper_bound(mEmitterCdf.begin(), mEmitterCdf.end(), u) - mEmitterCdf.begin());
    const Emitter& emitter = mEmitters[std::min(index, mEmitters.size() - 1)];
    float su = std::sqrt(rng.uniform());
    float u2 = rng.uniform();
    float b1 = su * (1.0f - u2), b2 = su * u2;
    const Triangle& tri = mScene->triangles[emitter.triangle];
    glm::vec3 point = (1.0f - b1 - b2) * mScene->vertices[tri.v[0]].position +
                      b1 * mScene->vertices[tri.v[1]].position +
                      b2 * mScene->vertices[tri.v[2]].position;
    glm::vec3 toPoint = point - position;
    float distance = glm::length(toPoint);
    if (!(distance > 2.0f * epsilon)) return direct;
    glm::vec3 wi = toPoint / distance;
    float cosSurface = glm::dot(normal, wi);
    // Emitters radiate from their front side only.
    float cosLight = -glm::dot(emitter.normal, wi);
    if (cosSurface <= 0.0f || cosLight <= 0.0f) return direct;
    float lightPdf = emitterPdf(emitter.triangle, distance, cosLight);
    if (!(lightPdf > 0.0f) || !std::isfinite(lightPdf)) return direct;
    if (mRays->occluded(shadowOrigin, wi, 0.0f, distance - 2.0f * epsilon)) return direct;
    float bsdfPdf = cosSurface / kPi;
    direct += emission(emitter.triangle, b1, b2) * (cosSurface / kPi / lightPdf) *
              powerHeuristic(lightPdf, bsdfPdf);
    return direct;
}

glm::vec3 PathTracer::skyLight(const glm::vec3& shadowOrigin, const glm::vec3& normal,
                               Rng& rng) const {
    const float u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform(), u4 = rng.uniform();
    const SkySampler::Sample sample = mSky->sample(normal, u1, u2, u3, u4);
    const float cosSurface = glm::dot(normal, sample.direction);
    if (!(sample.pdf > 0.0f) || cosSurface <= 0.0f || !(maxComponent(sample.radiance) > 0.0f))
        return glm::vec3(0.0f);
    // The sky is only where nothing blocks the ray, however far.
    if (mRays->occluded(shadowOrigin, sample.direction, 0.0f, kInfinity)) return glm::vec3(0.0f);
    const float bsdfPdf = cosSurface / kPi;
    return sample.radiance * (cosSurface / kPi / sample.pdf) *
           powerHeuristic(sample.pdf, bsdfPdf);
}

glm::vec3 PathTracer::traceRadiance(const glm::vec3& origin, const glm::vec3& direction,
                                    int maxReflections, PathTraceParams::Component component,
                                    Rng& rng, Escape escape) const {
    using Component = PathTraceParams::Component;
    // Paths of k reflections count for k in [minK, maxK]; maxK < 0 means unlimited.
    const int minK = component == Component::Full ? 0
                     : component == Component::Direct || component == Component::Cached ? 1
                                                                                          : 2;
    int maxK = maxReflections < 0 ? -1 : maxReflections;
    if (component == Component::Direct) maxK = maxK < 0 ? 1 : std::min(maxK, 1);
    const bool unlimited = maxK < 0;
    if (!unlimited && maxK < minK) return glm::vec3(0.0f);

    const float epsilon = mRays->epsilon();
    // One light vertex serves every vertex of the path; only paths of k ≥ 2 reflections use it.
    std::optional<LightVertex> lightVertex;
    if (unlimited || maxK >= 2) lightVertex = sampleLightVertex(rng);
    glm::vec3 radiance(0.0f);
    glm::vec3 throughput(1.0f);
    glm::vec3 rayOrigin = origin;
    glm::vec3 rayDirection = direction;
    float bsdfPdf = 0.0f;  // solid-angle density of rayDirection; unused for the first ray
    glm::vec3 previousNormal(0.0f);  // of the vertex rayDirection leaves; unused for the first

    // k counts the reflections of the path so far, i.e. before the vertex this ray finds.
    for (int k = 0;; ++k) {
        std::optional<RayHit> hit = mRays->intersect(rayOrigin, rayDirection, 0.0f, kInfinity);
        if (!hit) {
            // The sky ends a path of k reflections. After a reflection next-event estimation
            // at the previous vertex sampled the same path (it ran it because k >= minK); the
            // first ray sees it only where the caller asks (no background behind a camera).
            if (mSky && k >= minK && (k > 0 || escape == Escape::Sky)) {
                float weight = 1.0f;
                if (k > 0)
                    weight = powerHeuristic(bsdfPdf, mSky->pdf(previousNormal, rayDirection));
                radiance += throughput * mSky->radiance(rayDirection) * weight;
            }
            break;
        }
        const uint32_t t = hit->triangle;

        // Emission seen by this ray ends a path of k reflections. After a reflection the same
        // path was also sampled by next-event estimation at the previous vertex (that vertex
        // ran it because k >= minK), so both strategies share it by the power heuristic.
        if (k >= minK && !hit->backFace && mEmitterAreaPdf[t] > 0.0f) {
            float weight = 1.0f;
            if (k > 0) {
                float cosLight = -glm::dot(hit->geometricNormal, rayDirection);
                weight = powerHeuristic(bsdfPdf, emitterPdf(t, hit->t, cosLight));
            }
            radiance += throughput * emission(t, hit->b1, hit->b2) * weight;
        }

        // Reflecting here makes the path k + 1 reflections long.
        if (!unlimited && k + 1 > maxK) break;
        glm::vec3 albedo = mScene->albedoAt(t, hit->b1, hit->b2);
        if (!(maxComponent(albedo) > 0.0f)) break;
        // Two-sided reflection: shade with the geometric normal facing the arriving ray.
        glm::vec3 normal = hit->backFace ? -hit->geometricNormal : hit->geometricNormal;
        glm::vec3 position = rayOrigin + hit->t * rayDirection;

        // Density per m² of this point under the previous vertex's BSDF sampling.
        float bsdfAreaPdf = -1.0f;
        if (k > 0)
            bsdfAreaPdf = bsdfPdf * std::abs(glm::dot(hit->geometricNormal, rayDirection)) /
                          (hit->t * hit->t);
        // Cached paths leave out the punctual lights reflected once: pic lights those exactly.
        if (k + 1 >= minK)
            radiance += throughput * albedo *
                        directLight(position, normal, bsdfAreaPdf, rng, component != Component::Cached || k > 0);
        if (lightVertex && k + 2 >= minK && (unlimited || k + 2 <= maxK))
            radiance += throughput * albedo * connectLightVertex(position, normal, *lightVertex);
        // Without emitters or a sky the continuation can only add longer paths than allowed.
        if (!unlimited && k + 1 == maxK && mEmitters.empty() && !mSky) break;

        // Lambertian BRDF ρ/π sampled by cosθ/π: the throughput gains exactly ρ.
        throughput *= albedo;
        if (k + 1 >= kRouletteReflections) {
            float survival = std::min(maxComponent(throughput), kMaxSurvival);
            if (rng.uniform() >= survival) break;
            throughput /= survival;
        }
        float u1 = rng.uniform(), u2 = rng.uniform();
        rayDirection = sampleCosineHemisphere(normal, u1, u2);
        bsdfPdf = glm::dot(normal, rayDirection) / kPi;
        if (!(bsdfPdf > 0.0f)) break;
        previousNormal = normal;
        rayOrigin = position + epsilon * normal;
    }
    return radiance;
}

glm::vec3 PathTracer::traceGlossy(const glm::vec3& origin, const glm::vec3& direction,
                                  float exponent, int maxReflections, Rng& rng) const {
    const std::optional<RayHit> hit =
        mRays->intersect(origin, direction, 0.0f, std::numeric_limits<float>::infinity());
    if (!hit) return glm::vec3(0.0f);
    // The side the camera sees reflects, as in the client (render/cpu/cache_shading.h).
    const glm::vec3 normal = hit->backFace ? -hit->geometricNormal : hit->geometricNormal;
    const glm::vec3 position = origin + hit->t * direction;
    const glm::vec3 mirror = glm::reflect(direction, normal);
    const float u1 = rng.uniform(), u2 = rng.uniform();
    const glm::vec3 incoming = samplePhongLobe(mirror, exponent, u1, u2);
    // The surface itself blocks the directions below it.
    if (glm::dot(incoming, normal) <= 0.0f) return glm::vec3(0.0f);
    const int further = maxReflections < 0 ? -1 : maxReflections - 1;
    // The lobe's direction sees the sky where it escapes: a path of one reflection.
    return traceRadiance(position + mRays->epsilon() * normal, incoming, further,
                         PathTraceParams::Component::Full, rng, Escape::Sky);
}

Result<Image> pathTrace(const Scene& scene, const EmbreeScene& rays, const LightSet& lights,
                        const Camera& camera, const PathTraceParams& params,
                        PathTraceStats* stats) {
    if (params.width == 0 || params.height == 0)
        return fail(ErrorCode::InvalidInput, "image size {}x{} is empty", params.width,
                    params.height);
    if (params.spp == 0)
        return fail(ErrorCode::InvalidInput, "samples per pixel must be at least 1, got 0");
    if (params.bounces < -1)
        return fail(ErrorCode::InvalidInput, "bounces must be -1 (unlimited) or >= 0, got {}",
                    params.bounces);
    if (!(params.glossyExponent >= 0.0f && std::isfinite(params.glossyExponent) &&
          params.glossyWeight >= 0.0f && std::isfinite(params.glossyWeight)))
        return fail(ErrorCode::InvalidInput,
                    "glossy exponent {} and weight {} must be finite and ≥ 0",
                    params.glossyExponent, params.glossyWeight);
    using Component = PathTraceParams::Component;
    if (params.component == Component::Glossy && !hasLobe(params))
        return fail(ErrorCode::InvalidInput,
                    "the glossy component needs a lobe: exponent and weight > 0, got {} and {}",
                    params.glossyExponent, params.glossyWeight);
    const bool lobe = hasLobe(params) && params.component != Component::Direct;

    auto start = std::chrono::steady_clock::now();
    PIC_TRY_ASSIGN(const PathTracer tracer, PathTracer::create(scene, rays, lights));
    CameraRays cameraRays(camera, params.width, params.height);
    // The camera-visible surface's reflection is not a bounce (ARCHITECTURE.md §5).
    const int maxReflections = params.bounces < 0 ? -1 : params.bounces + 1;
    Image image(params.width, params.height);
    std::vector<uint64_t> rejectedPerRow(params.height, 0);

    Progress progress("path tracing", params.height);
    parallelFor(
        0, params.height,
        [&](size_t y) {
            uint64_t rejected = 0;
            for (uint32_t x = 0; x < params.width; ++x) {
                const uint64_t pixel = uint64_t(y) * params.width + x;
                glm::dvec3 sum(0.0);
                for (uint32_t s = 0; s < params.spp; ++s) {
                    // One stream per (seed, pixel, sample): independent of the thread schedule.
                    Rng rng(params.seed, pixel * params.spp + s);
                    float jx = rng.uniform(), jy = rng.uniform();
                    glm::vec3 direction = cameraRays.direction(float(x) + jx, float(y) + jy);
                    glm::vec3 radiance =
                        params.component == Component::Glossy
                            ? glm::vec3(0.0f)
                            : tracer.traceRadiance(cameraRays.origin(), direction,
                                                   maxReflections, params.component, rng,
                                                   PathTracer::Escape::Black);
                    if (lobe)
                        radiance += params.glossyWeight *
                                    tracer.traceGlossy(cameraRays.origin(), direction,
                                                       params.glossyExponent, maxReflections, rng);
                    if (!isValidRadiance(radiance)) {
                        ++rejected;
                        continue;
                    }
                    sum += glm::dvec3(radiance);
                }
                image.at(x, uint32_t(y)) = glm::vec3(sum / double(params.spp));
            }
            rejectedPerRow[y] = rejected;
            progress.advance();
        },
        1);
    progress.finish();

    if (stats) {
        stats->samples = uint64_t(params.width) * params.height * params.spp;
        stats->rejected = 0;
        for (uint64_t r : rejectedPerRow) stats->rejected += r;
        stats->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return image;
}

}  // namespace pic
