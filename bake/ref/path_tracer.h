#pragma once
/// The reference path tracer of `picref` (ARCHITECTURE.md §5): unbiased Lambertian path tracing
/// of the pic scene model with next-event estimation for punctual lights, emissive triangles
/// and the sky, multiple importance sampling for emitters and the sky, and Russian roulette.
///
/// Paths are counted by their reflections: light that left a light, an emitter or the sky and
/// reflected off k surfaces before arriving at the path's origin. A camera sees emitters with
/// k = 0, direct light with k = 1 and indirect light with k ≥ 2; `--bounces B` keeps
/// k ≤ B + 1, the camera-visible surface's own reflection not being counted as a bounce.
///
/// The sky (LightSet::sky, core/sky.h) is the radiance of every ray that leaves the scene: a
/// ray that escapes after k reflections ends a path of k reflections, so the sky lighting the
/// camera-visible surface is direct light (k = 1, like a directional light) and the sky seen
/// in a reflection of it indirect light. Camera rays that escape stay black: pic's images
/// have no sky background (the client draws none), so neither does the reference. Each
/// surface vertex samples the sky by next-event estimation (bake/ref/sky_sampler.h; a shadow
/// ray that must escape unbounded) and by its BSDF-sampled continuation, weighted by the
/// power heuristic.

#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "bake/ref/sky_sampler.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/sampling.h"
#include "core/scene.h"
#include "core/sky.h"
#include "rays/embree_scene.h"

namespace pic {

/// What a path-traced image holds and how it is sampled.
struct PathTraceParams {
    /// Which paths count: Full = k ≥ 0 reflections (directly visible emitters included, the
    /// sky not: it is no background), Direct = exactly one reflection (the sky's included),
    /// Indirect = k ≥ 2 reflections, Cached = k ≥ 1 reflections less the punctual lights'
    /// single reflection: what pic's caches carry (the indirect light, the emitting surfaces'
    /// first reflection, paper 000 §4.4, and the sky's first reflection, which the client
    /// delivers through the caches' sky visibility, core/sky.h), equal to Indirect where no
    /// surface emits and there is no sky. Glossy = the glossy lobe's term alone.
    enum class Component { Full, Direct, Indirect, Cached, Glossy };

    uint32_t width = 0;
    uint32_t height = 0;
    uint32_t spp = 1;  ///< samples per pixel, jittered over the pixel (box filter)
    int bounces = -1;  ///< B ≥ 0 keeps paths of at most B + 1 reflections; −1: unlimited
    Component component = Component::Full;
    uint64_t seed = 1;
    /// A Phong lobe at the camera-visible surface, as the thin client adds it
    /// (core/shade_params.h): glossyWeight · ∫ L(ω) (n+1)/(2π) max(0, r·ω)^n dω over the
    /// directions above the surface, r the view ray's mirror direction about the normal facing
    /// the camera and L the radiance arriving from the scene's surfaces and the sky (a
    /// punctual light, being a point, is never inside a lobe). Added to Full, Indirect and
    /// Cached, where the client adds it to the cache term; Glossy is this term alone. Both 0:
    /// no lobe.
    float glossyExponent = 0.0f;
    float glossyWeight = 0.0f;
};

/// A direction drawn from the normalised Phong lobe (n+1)/(2π) max(0, axis·ω)^n about unit
/// `axis` with `exponent` n ≥ 0, from two uniform numbers in [0, 1): its density is the lobe.
glm::vec3 samplePhongLobe(const glm::vec3& axis, float exponent, float u1, float u2);

/// What a run of the path tracer did.
struct PathTraceStats {
    uint64_t samples = 0;   ///< paths traced
    uint64_t rejected = 0;  ///< paths whose estimate was NaN, infinite or negative (counted as 0)
    double seconds = 0.0;   ///< wall time of the tracing
};

/// Everything paths share: the scene, its Embree BVH, the light set, its resolved sky and the
/// distributions that sample emissive triangles (in proportion to area × emitted luminance),
/// the sky and light vertices. Thread-safe queries.
///
/// Strategies. Every path of k reflections is sampled by BSDF sampling (emission found by a
/// ray) and by next-event estimation (a shadow ray to a punctual light, to a sampled emitter
/// point or towards a sampled sky direction), weighted by the power heuristic where both
/// apply. Light that reflects off a spot lit by a nearby point or spot light (a lamp under a
/// ceiling) makes BSDF sampling alone noisy with rare, bright hits, so paths of k ≥ 2
/// reflections are also sampled from the light side: one light vertex per path (a ray from a
/// point or spot light chosen by power to the first surface it hits) connected to every
/// camera-path vertex, combined by MIS with BSDF sampling of that same vertex. The sky needs
/// none: its light arrives from afar, not from a bright spot nearby.
class PathTracer {
public:
    /// What the first ray of traceRadiance brings back when it leaves the scene: nothing for a
    /// camera's ray (no sky background), the sky for a ray from a point in the scene (a probe,
    /// a glossy lobe). Rays after a reflection always see the sky.
    enum class Escape { Black, Sky };

    /// A tracer of `lights` with its sky, if any, read through resolveSky next to the scene
    /// file (Scene::sourcePath): NotFound for a missing environment image, InvalidInput for a
    /// bad one. The scene and Embree scene must outlive the tracer.
    static Result<PathTracer> create(const Scene& scene, const EmbreeScene& rays,
                                     const LightSet& lights);

    /// The scene and Embree scene must outlive the tracer; the light set is copied. `sky` is
    /// the light set's resolved sky: present exactly when LightSet::sky is (checked).
    PathTracer(const Scene& scene, const EmbreeScene& rays, const LightSet& lights,
               std::optional<Sky> sky = std::nullopt);

    /// Monte Carlo estimate of the radiance arriving at `origin` from unit `direction`, counting
    /// paths of [min, max] reflections with min = 0, 1, 2 for Full, Direct, Indirect and
    /// max = `maxReflections` for Full and Indirect (−1: unlimited with Russian roulette),
    /// 1 for Direct (but at most `maxReflections`). The first ray starts at `origin` itself:
    /// callers on a surface offset it; `escape` says whether it sees the sky (a path of k = 0
    /// reflections, counted by Full). Never NaN, infinite or negative unless the scene is.
    glm::vec3 traceRadiance(const glm::vec3& origin, const glm::vec3& direction, int maxReflections,
                            PathTraceParams::Component component, Rng& rng,
                            Escape escape = Escape::Sky) const;

    /// One-sample estimate of the glossy lobe's term (PathTraceParams::glossyExponent, weight 1)
    /// at the surface the ray from `origin` along unit `direction` meets: one direction drawn
    /// from the lobe, the radiance arriving along it by paths of at most `maxReflections` − 1
    /// further reflections (−1: unlimited), the sky where it escapes. 0 where the ray misses or
    /// the direction is below the surface.
    glm::vec3 traceGlossy(const glm::vec3& origin, const glm::vec3& direction, float exponent,
                          int maxReflections, Rng& rng) const;

    /// Number of triangles that emit (with a non-zero emissive scale).
    size_t emitterCount() const { return mEmitters.size(); }

    const Scene& scene() const { return *mScene; }
    const EmbreeScene& rays() const { return *mRays; }
    const LightSet& lights() const { return mLights; }
    /// The resolved sky, if the light set has one.
    const Sky* sky() const { return mSky ? &mSky->sky() : nullptr; }

private:
    /// A surface point lit directly by a punctual light, sampled from that light.
    struct LightVertex {
        glm::vec3 position{0.0f};
        glm::vec3 normal{0.0f};  // unit, facing the light
        glm::vec3 weight{0.0f};  // reflected radiance (ρ/π)·E divided by areaPdf
        float areaPdf = 0.0f;    // density of the point per m² (light choice included)
    };
    struct Emitter {
        uint32_t triangle;
        float area;        // m²
        glm::vec3 normal;  // unit; the side it emits to
    };

    /// Emitted radiance of triangle t at (b1, b2) with its material's emissive scale.
    glm::vec3 emission(uint32_t t, float b1, float b2) const;
    /// Direct light (punctual lights, a sampled emitter point and a sampled sky direction)
    /// reflected at a surface point, per unit albedo: ∫ L_light cosθ / π. `bsdfAreaPdf` is the
    /// density per m² with which the previous vertex's BSDF sampling found this point, or
    /// negative when the point was not reached from a surface (no light-vertex strategy
    /// competes for its paths then).
    /// Without `punctual`, the emitters' and the sky's part alone.
    glm::vec3 directLight(const glm::vec3& position, const glm::vec3& normal, float bsdfAreaPdf,
                          Rng& rng, bool punctual = true) const;
    /// Light reflected once at `vertex` towards a surface point, per unit albedo of the point:
    /// the light-vertex strategy's MIS-weighted estimate.
    glm::vec3 connectLightVertex(const glm::vec3& position, const glm::vec3& normal,
                                 const LightVertex& vertex) const;
    /// Samples a light vertex, if the scene has point or spot lights and the ray hits something.
    std::optional<LightVertex> sampleLightVertex(Rng& rng) const;
    /// Density per m² with which sampleLightVertex finds the point at `distance` from light l
    /// in unit direction `fromLight`, its normal making cosine `cosLight` with the light.
    float lightVertexPdf(size_t l, const glm::vec3& fromLight, float distance,
                         float cosLight) const;
    /// Solid-angle density with which directLight samples the emitter point seen at distance
    /// `distance` on triangle t under cosine `cosLight` at the emitter.
    float emitterPdf(uint32_t t, float distance, float cosLight) const;
    /// The sky's light reflected at a surface point per unit albedo, from one sampled direction
    /// whose shadow ray, from `shadowOrigin`, must escape.
    glm::vec3 skyLight(const glm::vec3& shadowOrigin, const glm::vec3& normal, Rng& rng) const;

    const Scene* mScene;
    const EmbreeScene* mRays;
    LightSet mLights;
    std::optional<SkySampler> mSky;             // the light set's sky, if any
    std::vector<float> mMaterialEmissionScale;  // per material: LightSet emissive scale
    std::vector<Emitter> mEmitters;             // emissive triangles
    std::vector<float> mEmitterCdf;             // running sum of their selection probabilities
    std::vector<float> mEmitterAreaPdf;         // per scene triangle: selection probability / area
                                                // (area density of a sampled point), 0 if dark
    std::vector<uint32_t> mVertexLights;        // point and spot lights that seed light vertices
    std::vector<float> mVertexLightCdf;         // running sum of their selection probabilities
    std::vector<float> mVertexLightPdf;         // per light: selection probability × direction
                                                // density (1/sr, uniform over the sphere or the
                                                // outer cone); 0 for the others
};

/// True if every channel is finite and non-negative: the guard every estimate passes.
bool isValidRadiance(const glm::vec3& radiance);

/// Path-traces an image of `camera` with one independent random stream per pixel sample, so
/// the image depends on the seed only, not on the thread count. InvalidInput for zero sizes or
/// spp, bounces < −1, a negative or non-finite glossy exponent or weight, or the Glossy
/// component without a lobe; the sky's errors (PathTracer::create). Camera rays that escape are
/// black. Progress per row on stderr; `stats` (if given) receives the counts.
Result<Image> pathTrace(const Scene& scene, const EmbreeScene& rays, const LightSet& lights,
                        const Camera& camera, const PathTraceParams& params,
                        PathTraceStats* stats = nullptr);

}  // namespace pic
