#pragma once
/// `picbench stability`: the failure cases of paper 000 §5.2 and paper 001 §7 measured against
/// path tracing (light leaking through a thin wall or slab, a small spot, opposite colours), a
/// light moving over a furnished room for temporal flicker, and random light sets checked for
/// NaN, infinite or negative radiance in the caches and in shaded pixels (ARCHITECTURE.md §7).
/// The metrics are functions of their own so the stability tests run the same code on small
/// bakes.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "bake/bake.h"
#include "core/bake_data.h"
#include "core/cache_values.h"
#include "core/error.h"
#include "core/image.h"
#include "core/light_set.h"
#include "core/scene.h"
#include "rays/embree_scene.h"

namespace pic {

/// How each case's images are made.
struct StabilitySettings {
    glm::uvec2 size{64, 48};      ///< image size of every case
    uint32_t spp = 256;           ///< path-traced reference samples per pixel; 0: no reference
    uint32_t probeSamples = 256;  ///< directions per ideal cache; 0: no ideal caches
    uint32_t shadeSpp = 2;        ///< subsamples per pixel shading from the caches
    uint64_t seed = 1;            ///< path tracer and probe seed
};

/// A baked scene relit by the CPU twin (progressive bounces), with its ideal caches when
/// settings.probeSamples > 0. The scene, rays and bake must outlive it.
struct RelitScene {
    const Scene* scene = nullptr;
    const EmbreeScene* rays = nullptr;
    const BakeData* bake = nullptr;
    LightSet lights;
    CacheValues linked;
    std::optional<CacheValues> ideal;
};

/// Relights `scene` with `lights` on a fresh CPU twin, and path-traces its ideal caches if asked.
Result<RelitScene> relightScene(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                                const LightSet& lights, const StabilitySettings& settings);

/// The indirect component of one view: shaded from the linked caches, from the ideal caches
/// (when relit with them) and path-traced (when settings.spp > 0).
struct ViewImages {
    Image linked;
    std::optional<Image> ideal;
    std::optional<Image> reference;
};

/// The indirect images of `camera`'s view at settings.size.
Result<ViewImages> indirectView(const RelitScene& relit, const Camera& camera,
                                const StabilitySettings& settings);

/// Mean luminance of an image's pixels (0 for an empty image).
double meanLuminance(const Image& image);

/// Light leaking into a sealed, unlit room: mean indirect luminance seen from the dark side
/// over that seen from the lit side, per source. The reference's is 0 up to its noise.
struct LeakResult {
    ViewImages dark, lit;
    double linked = 0.0;
    std::optional<double> ideal, reference;
};

/// The leak of `relit` seen from a camera in the dark room and one in the lit room.
Result<LeakResult> measureLeak(const RelitScene& relit, const Camera& darkSide,
                               const Camera& litSide, const StabilitySettings& settings);

/// Colour fidelity of an image against a reference: over the pixels holding at least
/// `minShare` of the reference's mean luminance, the luminance-weighted mean of half the L1
/// distance between chromaticities rgb/(r+g+b) (0 = same colour, 1 = disjoint), and the
/// luminance-weighted share of pixels whose dominant channel of red and green agrees with the
/// reference where the reference's |r − g|/(r + g) ≥ 0.2 (1 = every hue kept).
struct ChromaStats {
    double error = 0.0;
    double hueAgreement = 0.0;
};

/// The chroma error and hue agreement of `image` against `reference` (same size).
Result<ChromaStats> chromaStats(const Image& image, const Image& reference, float minShare = 0.05f);

/// The per-frame figures of an image sequence: mean luminance of each frame and the mean
/// absolute per-pixel change of luminance from the previous frame, relative to the two frames'
/// mean luminance (0 for frame 0); the flicker index is the mean of the changes over frames
/// 1…n−1. A light moving smoothly changes the image smoothly too, which the index counts as
/// well; `roughness`, the same mean of the second difference |L(t+1) − 2·L(t) + L(t−1)|
/// relative to the frame's mean luminance over frames 1…n−2 (0 with fewer than 3 frames),
/// leaves out what changes linearly and keeps popping.
struct FlickerSeries {
    std::vector<double> mean;
    std::vector<double> change;
    double index = 0.0;
    double roughness = 0.0;
    double peak = 0.0;  ///< the largest frame-to-frame change: the worst jump
};

/// The flicker series of `frames` (all the same size; at least two).
Result<FlickerSeries> flickerSeries(const std::vector<Image>& frames);

/// A point light's positions on a closed loop through the scene: an ellipse about the bounds'
/// centre with semi-axes 21–39 % of the extent along x and z, at 60–80 % of the height with a
/// ±5 % wobble, its size, height and phase drawn from `seed`; `steps` positions a step apart.
std::vector<glm::vec3> movingLightPath(const Scene& scene, uint64_t seed, uint32_t steps);

/// One moving point light (the scene's own lights removed) of intensity
/// 2 W/sr × (diagonal / 5 m)², rendered at each position of movingLightPath: the linked
/// indirect sequence and, when settings.probeSamples > 0, the ideal-cache sequence (the same
/// probe seed every step, so its Monte Carlo noise does not flicker by itself).
/// How a client that blends cache versions (core/cache_blend.h) sees the moving light: a
/// version arrives every update interval, the client draws `framesPerUpdate` frames per
/// interval, evenly spaced from the arrival on.
struct BlendedFlicker {
    double intervals = 0.0;  ///< blend time in update intervals (0: every version at once)
    FlickerSeries frames;    ///< over every drawn frame
    /// Mean over the frames of the drawn caches' distance from the newest version (mean
    /// absolute luminance difference of the images over the newest's mean): the lag.
    double lag = 0.0;
};

struct MovingLightResult {
    std::vector<glm::vec3> path;
    FlickerSeries linked;
    std::optional<FlickerSeries> ideal;
    std::vector<BlendedFlicker> blended;  ///< one per blend time asked for
    Image firstLinked;  ///< the first linked frame, for people
};

/// Moves the light `steps` steps along movingLightPath(scene, pathSeed) seen from `camera`;
/// with `blendIntervals`, also draws the linked caches as a blending client would at each
/// blend time, `framesPerUpdate` frames per version.
Result<MovingLightResult> runMovingLight(const Scene& scene, const EmbreeScene& rays,
                                         const BakeData& bake, const Camera& camera, uint32_t steps,
                                         uint64_t pathSeed, const StabilitySettings& settings,
                                         const std::vector<double>& blendIntervals = {},
                                         uint32_t framesPerUpdate = 4);

/// Why cache values are invalid, or nullopt when they are valid: every coefficient finite;
/// each RGB channel's band 0 (its mean radiance) ≥ 0; the luma evaluated in 256 directions
/// ≥ its mean × the most negative value a projection to lY bands of any non-negative function
/// can take (minNonNegativeProjection), each up to a float rounding tolerance.
std::optional<std::string> invalidCacheValues(const CacheValues& values);

/// Why an image is invalid (a NaN, infinite or negative channel, naming the pixel), or nullopt.
std::optional<std::string> invalidPixels(const Image& image);

/// min over directions of Σ_{l<bands} (2l+1)·P_l(cos θ): the lowest a band-limited projection
/// of a non-negative function on the sphere reaches, as a multiple of its mean (1 for one band,
/// −1.8 for three). Computed on a fine grid of cos θ.
double minNonNegativeProjection(int bands);

/// One light set that failed the checks.
struct RandomSetFailure {
    std::string scene;
    uint64_t seed = 0;
    std::string reason;
};

/// Relights a baked scene with randomLightSet(scene, seed) for every seed (CPU twin,
/// progressive bounces), checks the caches (invalidCacheValues) and a `size` image shaded at
/// full (invalidPixels) from the scene's camera 0, and reports every failing seed. An error
/// only when something cannot run at all.
Result<std::vector<RandomSetFailure>> checkRandomLightSets(
    const Scene& scene, const EmbreeScene& rays, const BakeData& bake, const std::string& name,
    const std::vector<uint64_t>& seeds, glm::uvec2 size);

/// What `picbench stability` runs.
struct StabilityParams {
    std::string sceneDir = "build/scenes";  ///< the generated test scenes
    std::vector<std::string> cases{"leak", "spot", "colors", "moving", "random"};
    BakeOptions bake;
    StabilitySettings settings;
    uint32_t steps = 60;  ///< moving light
    std::string movingScene = "furnished_room";
    uint32_t movingProbeSamples = 128;  ///< directions per ideal cache at each moving-light step
    /// Blend times of a client drawing the moving light, in update intervals (BlendedFlicker).
    std::vector<double> blendIntervals{0.0, 1.0, 2.0, 4.0};
    uint32_t framesPerUpdate = 4;  ///< frames the blending client draws per version
    uint32_t randomSets = 1000;
    glm::uvec2 randomSize{32, 24};
    std::vector<std::string> randomScenes{"cornell",    "cornell_area",    "closed_box",
                                          "two_floors", "opposite_colors", "small_spot",
                                          "thin_wall",  "furnished_room",  "furnished_study"};
    std::string jsonPath = "out/stability/stability.json";
};

/// Runs the suite, prints a table, writes the JSON and PNGs beside it (a chart of the moving
/// light, side-by-side images per case); exit code 1 when a random light set failed (no NaN,
/// Inf or negative radiance may ever reach a client), 2 for bad input.
int runStabilityBenchmark(const StabilityParams& params);

}  // namespace pic
