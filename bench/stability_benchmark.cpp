#include "bench/stability_benchmark.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <numbers>

#include <nlohmann/json.hpp>

#include "bake/ref/path_tracer.h"
#include "bake/ref/probes.h"
#include "bench/bench_common.h"
#include "core/cache_blend.h"
#include "core/color.h"
#include "core/gltf_loader.h"
#include "core/progress.h"
#include "bench/random_lights.h"
#include "core/sampling.h"
#include "core/sh.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"

namespace pic {

namespace {

using Json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Directions the luma of every cache is evaluated in: a Fibonacci sphere (even coverage, no
/// randomness).
constexpr int kCheckDirections = 256;

/// Relative tolerance of the cache checks: the runtime stores links and caches as binary16
/// on the GPU backend (2^-11 relative rounding per coefficient); two such roundings of every
/// coefficient, summed over the coefficients' magnitudes, bound the error of a
/// reconstruction.
constexpr double kCacheTolerance = 2.0 * 0x1p-11;

ShadeParams indirectShade(glm::uvec2 size, uint32_t spp) {
    ShadeParams shade;
    shade.width = size.x;
    shade.height = size.y;
    shade.samplesPerPixel = spp;
    shade.component = ShadeComponent::Indirect;
    return shade;
}

}  // namespace

Result<RelitScene> relightScene(const Scene& scene, const EmbreeScene& rays, const BakeData& bake,
                                const LightSet& lights, const StabilitySettings& settings) {
    RelitScene relit{&scene, &rays, &bake, lights, {}, std::nullopt};
    PIC_TRY_ASSIGN(std::unique_ptr<Runtime> runtime,
                   createCpuRuntime(scene, rays, bake, BounceParams{}));
    PIC_TRY_ASSIGN(const CacheValues* values, runtime->setLights(lights));
    relit.linked = *values;
    if (settings.probeSamples > 0) {
        ProbeParams probe;
        probe.samples = settings.probeSamples;
        probe.seed = settings.seed;
        PIC_TRY_ASSIGN(relit.ideal, pathTraceProbes(scene, rays, bake, lights, probe));
    }
    return relit;
}

Result<ViewImages> indirectView(const RelitScene& relit, const Camera& camera,
                                const StabilitySettings& settings) {
    const ShadeParams shade = indirectShade(settings.size, settings.shadeSpp);
    ViewImages view;
    PIC_TRY_ASSIGN(view.linked, shadeFromCaches(*relit.scene, *relit.rays, *relit.bake,
                                                relit.linked, relit.lights, camera, shade));
    if (relit.ideal) {
        PIC_TRY_ASSIGN(view.ideal, shadeFromCaches(*relit.scene, *relit.rays, *relit.bake,
                                                   *relit.ideal, relit.lights, camera, shade));
    }
    if (settings.spp > 0) {
        PathTraceParams trace;
        trace.width = settings.size.x;
        trace.height = settings.size.y;
        trace.spp = settings.spp;
        trace.seed = settings.seed;
        trace.component = PathTraceParams::Component::Indirect;
        PIC_TRY_ASSIGN(view.reference,
                       pathTrace(*relit.scene, *relit.rays, relit.lights, camera, trace));
    }
    return view;
}

double meanLuminance(const Image& image) {
    if (image.pixels.empty()) return 0.0;
    double sum = 0.0;
    for (const glm::vec3& p : image.pixels) sum += luminance(p);
    return sum / double(image.pixels.size());
}

Result<LeakResult> measureLeak(const RelitScene& relit, const Camera& darkSide,
                               const Camera& litSide, const StabilitySettings& settings) {
    LeakResult leak;
    PIC_TRY_ASSIGN(leak.dark, indirectView(relit, darkSide, settings));
    PIC_TRY_ASSIGN(leak.lit, indirectView(relit, litSide, settings));
    const auto ratio = [&](const Image& dark, const Image& lit) -> Result<double> {
        const double litMean = meanLuminance(lit);
        if (!(litMean > 0.0))
            return fail(ErrorCode::InvalidInput,
                        "leak: the lit side's view (camera '{}') receives no indirect light "
                        "(mean luminance {})",
                        litSide.name, litMean);
        return meanLuminance(dark) / litMean;
    };
    PIC_TRY_ASSIGN(leak.linked, ratio(leak.dark.linked, leak.lit.linked));
    if (leak.dark.ideal) {
        PIC_TRY_ASSIGN(leak.ideal, ratio(*leak.dark.ideal, *leak.lit.ideal));
    }
    if (leak.dark.reference) {
        PIC_TRY_ASSIGN(leak.reference, ratio(*leak.dark.reference, *leak.lit.reference));
    }
    return leak;
}

Result<ChromaStats> chromaStats(const Image& image, const Image& reference, float minShare) {
    if (image.width != reference.width || image.height != reference.height)
        return fail(ErrorCode::InvalidInput, "chroma: image {}x{} against reference {}x{}",
                    image.width, image.height, reference.width, reference.height);
    const double floor = double(minShare) * meanLuminance(reference);
    double weightSum = 0.0, errorSum = 0.0, hueWeight = 0.0, hueAgree = 0.0;
    for (size_t i = 0; i < reference.pixels.size(); ++i) {
        const glm::dvec3 ref(reference.pixels[i]);
        const glm::dvec3 ours(image.pixels[i]);
        const double weight = luminance(reference.pixels[i]);
        if (!(weight > floor) || !(weight > 0.0)) continue;
        const double refSum = ref.r + ref.g + ref.b;
        const double ourSum = ours.r + ours.g + ours.b;
        // A black pixel where the reference has light has lost its colour entirely.
        const double distance = ourSum > 0.0 ? 0.5 * (std::abs(ours.r / ourSum - ref.r / refSum) +
                                                      std::abs(ours.g / ourSum - ref.g / refSum) +
                                                      std::abs(ours.b / ourSum - ref.b / refSum))
                                             : 1.0;
        weightSum += weight;
        errorSum += weight * distance;
        const double refHue = (ref.r - ref.g) / std::max(ref.r + ref.g, 1e-30);
        if (std::abs(refHue) >= 0.2) {
            hueWeight += weight;
            if ((ours.r - ours.g) * refHue > 0.0) hueAgree += weight;
        }
    }
    if (!(weightSum > 0.0))
        return fail(ErrorCode::InvalidInput, "chroma: the reference has no lit pixel");
    return ChromaStats{errorSum / weightSum, hueWeight > 0.0 ? hueAgree / hueWeight : 1.0};
}

Result<FlickerSeries> flickerSeries(const std::vector<Image>& frames) {
    if (frames.size() < 2)
        return fail(ErrorCode::InvalidInput, "flicker needs at least 2 frames, got {}",
                    frames.size());
    FlickerSeries series;
    for (size_t t = 0; t < frames.size(); ++t) {
        const Image& frame = frames[t];
        if (frame.width != frames[0].width || frame.height != frames[0].height)
            return fail(ErrorCode::InvalidInput, "flicker: frame {} is {}x{}, frame 0 {}x{}", t,
                        frame.width, frame.height, frames[0].width, frames[0].height);
        series.mean.push_back(meanLuminance(frame));
        if (t == 0) {
            series.change.push_back(0.0);
            continue;
        }
        double change = 0.0;
        for (size_t i = 0; i < frame.pixels.size(); ++i)
            change += std::abs(double(luminance(frame.pixels[i])) -
                               double(luminance(frames[t - 1].pixels[i])));
        change /= double(frame.pixels.size());
        const double level = 0.5 * (series.mean[t] + series.mean[t - 1]);
        // Two black frames do not change.
        series.change.push_back(level > 0.0 ? change / level : 0.0);
        series.index += series.change.back();
        series.peak = std::max(series.peak, series.change.back());
    }
    series.index /= double(frames.size() - 1);
    for (size_t t = 1; t + 1 < frames.size(); ++t) {
        double second = 0.0;
        for (size_t i = 0; i < frames[t].pixels.size(); ++i)
            second += std::abs(double(luminance(frames[t + 1].pixels[i])) -
                               2.0 * double(luminance(frames[t].pixels[i])) +
                               double(luminance(frames[t - 1].pixels[i])));
        second /= double(frames[t].pixels.size());
        if (series.mean[t] > 0.0) series.roughness += second / series.mean[t];
    }
    if (frames.size() > 2) series.roughness /= double(frames.size() - 2);
    return series;
}

std::vector<glm::vec3> movingLightPath(const Scene& scene, uint64_t seed, uint32_t steps) {
    Rng rng(seed, 0x6d6f76696e67ull);
    const glm::vec3 extent = scene.bounds.extent();
    const glm::vec3 center = scene.bounds.center();
    const float ax = (0.21f + 0.18f * rng.uniform()) * extent.x;
    const float az = (0.21f + 0.18f * rng.uniform()) * extent.z;
    const float height = scene.bounds.min.y + (0.6f + 0.2f * rng.uniform()) * extent.y;
    const float wobble = 0.05f * extent.y;
    const float phase = 2.0f * std::numbers::pi_v<float> * rng.uniform();
    const float wobblePhase = 2.0f * std::numbers::pi_v<float> * rng.uniform();
    std::vector<glm::vec3> path;
    for (uint32_t k = 0; k < steps; ++k) {
        const float theta = phase + 2.0f * std::numbers::pi_v<float> * float(k) / float(steps);
        path.emplace_back(center.x + ax * std::cos(theta),
                          height + wobble * std::sin(2.0f * theta + wobblePhase),
                          center.z + az * std::sin(theta));
    }
    return path;
}

Result<MovingLightResult> runMovingLight(const Scene& scene, const EmbreeScene& rays,
                                         const BakeData& bake, const Camera& camera, uint32_t steps,
                                         uint64_t pathSeed, const StabilitySettings& settings,
                                         const std::vector<double>& blendIntervals,
                                         uint32_t framesPerUpdate) {
    if (steps < 2)
        return fail(ErrorCode::InvalidInput, "the moving light needs at least 2 steps, got {}",
                    steps);
    if (framesPerUpdate < 1)
        return fail(ErrorCode::InvalidInput, "frames per update must be at least 1, got 0");
    for (const double intervals : blendIntervals) PIC_TRY(CacheBlend::check(intervals));
    MovingLightResult result;
    result.path = movingLightPath(scene, pathSeed, steps);
    PIC_TRY_ASSIGN(std::unique_ptr<Runtime> runtime,
                   createCpuRuntime(scene, rays, bake, BounceParams{}));
    const float diagonal = scene.bounds.diagonal();
    LightSet lights;
    Light lamp;
    lamp.id = "moving_lamp";
    lamp.type = LightType::Point;
    lamp.intensity = 2.0f * (diagonal / 5.0f) * (diagonal / 5.0f);
    lights.lights = {lamp};
    const ShadeParams shade = indirectShade(settings.size, settings.shadeSpp);
    ProbeParams probe;
    probe.samples = settings.probeSamples;
    probe.seed = settings.seed;
    std::vector<Image> linked, ideal;
    std::vector<CacheValues> versions;  // for the blending client
    Progress progress("moving light", steps);
    for (uint32_t k = 0; k < steps; ++k) {
        lights.lights[0].position = result.path[k];
        PIC_TRY_ASSIGN(const CacheValues* values, runtime->setLights(lights));
        PIC_TRY_ASSIGN(Image image,
                       shadeFromCaches(scene, rays, bake, *values, lights, camera, shade));
        linked.push_back(std::move(image));
        if (!blendIntervals.empty()) versions.push_back(*values);
        if (settings.probeSamples > 0) {
            PIC_TRY_ASSIGN(CacheValues probes, pathTraceProbes(scene, rays, bake, lights, probe));
            PIC_TRY_ASSIGN(Image idealImage,
                           shadeFromCaches(scene, rays, bake, probes, lights, camera, shade));
            ideal.push_back(std::move(idealImage));
        }
        progress.advance();
    }
    progress.finish();
    PIC_TRY_ASSIGN(result.linked, flickerSeries(linked));
    if (!ideal.empty()) {
        PIC_TRY_ASSIGN(result.ideal, flickerSeries(ideal));
    }
    // The client: version k arrives at time k (in update intervals) and frame j of its
    // interval is drawn at k + j / framesPerUpdate. Only the cache term is drawn, so the
    // light's own position is that of the newest version throughout.
    for (const double intervals : blendIntervals) {
        CacheBlend blend(intervals);
        std::vector<Image> frames;
        double lag = 0.0;
        Progress blending(fmt::format("moving light, blend {} intervals", intervals),
                          steps * framesPerUpdate);
        for (uint32_t k = 0; k < steps; ++k) {
            lights.lights[0].position = result.path[k];
            PIC_TRY(blend.push(versions[k], double(k)));
            const double newest = meanLuminance(linked[k]);
            for (uint32_t j = 0; j < framesPerUpdate; ++j) {
                const CacheValues* shown = blend.at(double(k) + double(j) / framesPerUpdate);
                PIC_TRY_ASSIGN(Image frame,
                               shadeFromCaches(scene, rays, bake, *shown, lights, camera, shade));
                double distance = 0.0;
                for (size_t i = 0; i < frame.pixels.size(); ++i)
                    distance += std::abs(double(luminance(frame.pixels[i])) -
                                         double(luminance(linked[k].pixels[i])));
                distance /= double(frame.pixels.size());
                lag += newest > 0.0 ? distance / newest : 0.0;
                frames.push_back(std::move(frame));
                blending.advance();
            }
        }
        blending.finish();
        BlendedFlicker out;
        out.intervals = intervals;
        PIC_TRY_ASSIGN(out.frames, flickerSeries(frames));
        out.lag = lag / double(frames.size());
        result.blended.push_back(std::move(out));
    }
    result.firstLinked = std::move(linked.front());
    return result;
}

double minNonNegativeProjection(int bands) {
    // f(x) = Σ (2l+1)·P_l(x), the delta's projection times 4π; Legendre's recurrence per x.
    constexpr int kSteps = 200000;
    double lowest = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= kSteps; ++i) {
        const double x = -1.0 + 2.0 * double(i) / kSteps;
        double previous = 1.0, current = x, sum = bands >= 1 ? 1.0 : 0.0;
        if (bands >= 2) sum += 3.0 * x;
        for (int l = 1; l + 1 < bands; ++l) {
            const double next =
                (double(2 * l + 1) * x * current - double(l) * previous) / double(l + 1);
            previous = current;
            current = next;
            sum += double(2 * (l + 1) + 1) * current;
        }
        lowest = std::min(lowest, sum);
    }
    return lowest;
}

std::optional<std::string> invalidCacheValues(const CacheValues& values) {
    const size_t countY = size_t(shCount(int(values.bandsY)));
    const size_t countC = size_t(shCount(int(values.bandsC)));
    const size_t caches = values.cacheCount();
    if (values.bandsY < 1 || values.bandsC < 1 || values.bandsC > values.bandsY ||
        values.bandsY > uint32_t(kMaxShBands) || values.y.size() != caches * countY ||
        values.co.size() != caches * countC || values.cg.size() != caches * countC)
        return fmt::format("cache values have bands {} / {} and {} / {} / {} coefficients",
                           values.bandsY, values.bandsC, values.y.size(), values.co.size(),
                           values.cg.size());
    // Every direction's basis values, once.
    static const std::vector<std::vector<float>> basis = [] {
        std::vector<std::vector<float>> out(kCheckDirections,
                                            std::vector<float>(shCount(kMaxShBands)));
        const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
        for (int k = 0; k < kCheckDirections; ++k) {
            const double z = 1.0 - (2.0 * k + 1.0) / kCheckDirections;
            const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
            const glm::vec3 d(float(r * std::cos(golden * k)), float(r * std::sin(golden * k)),
                              float(z));
            shEvaluate(kMaxShBands, glm::normalize(d), out[k].data());
        }
        return out;
    }();
    const double lowest = minNonNegativeProjection(int(values.bandsY));
    const double y00 = 0.5 / std::sqrt(std::numbers::pi);
    for (size_t c = 0; c < caches; ++c) {
        const float* y = &values.y[c * countY];
        const float* co = &values.co[c * countC];
        const float* cg = &values.cg[c * countC];
        double magnitude = 0.0;
        for (size_t i = 0; i < countY; ++i) {
            if (!std::isfinite(y[i]))
                return fmt::format("cache {}: luma coefficient {} is {}", c, i, y[i]);
            magnitude += std::abs(y[i]);
        }
        for (size_t i = 0; i < countC; ++i)
            if (!std::isfinite(co[i]) || !std::isfinite(cg[i]))
                return fmt::format("cache {}: chroma coefficient {} is Co {} Cg {}", c, i, co[i],
                                   cg[i]);
        // Band 0 of each RGB channel is that channel's mean radiance: never below 0.
        const glm::vec3 rgb0 = yCoCgToRgb(glm::vec3(y[0], co[0], cg[0]));
        const double tolerance0 =
            kCacheTolerance * (std::abs(y[0]) + std::abs(co[0]) + std::abs(cg[0]));
        for (int channel = 0; channel < 3; ++channel)
            if (rgb0[channel] < -tolerance0)
                return fmt::format("cache {}: band 0 of channel {} is {} (Y {}, Co {}, Cg {})", c,
                                   "RGB"[channel], rgb0[channel], y[0], co[0], cg[0]);
        // The luma in every direction: no lower than a projection of non-negative light.
        const double mean = double(y[0]) * y00;
        const double bound = lowest * mean - kCacheTolerance * magnitude;
        for (int k = 0; k < kCheckDirections; ++k) {
            double radiance = 0.0;
            for (size_t i = 0; i < countY; ++i) radiance += double(y[i]) * basis[k][i];
            if (radiance < bound)
                return fmt::format(
                    "cache {}: luma {} in direction {} is below {} ({} × its mean {})", c, radiance,
                    k, bound, lowest, mean);
        }
    }
    return std::nullopt;
}

std::optional<std::string> invalidPixels(const Image& image) {
    for (uint32_t y = 0; y < image.height; ++y)
        for (uint32_t x = 0; x < image.width; ++x) {
            const glm::vec3& p = image.at(x, y);
            for (int c = 0; c < 3; ++c)
                if (!std::isfinite(p[c]) || p[c] < 0.0f)
                    return fmt::format("pixel ({}, {}) channel {} is {}", x, y, "RGB"[c], p[c]);
        }
    return std::nullopt;
}

Result<std::vector<RandomSetFailure>> checkRandomLightSets(
    const Scene& scene, const EmbreeScene& rays, const BakeData& bake, const std::string& name,
    const std::vector<uint64_t>& seeds, glm::uvec2 size) {
    if (scene.cameras.empty())
        return fail(ErrorCode::InvalidInput, "random light sets: scene '{}' has no camera", name);
    PIC_TRY_ASSIGN(std::unique_ptr<Runtime> runtime,
                   createCpuRuntime(scene, rays, bake, BounceParams{}));
    ShadeParams shade;
    shade.width = size.x;
    shade.height = size.y;
    shade.component = ShadeComponent::Full;
    std::vector<RandomSetFailure> failures;
    for (const uint64_t seed : seeds) {
        PIC_TRY_ASSIGN(LightSet lights, randomLightSet(scene, seed));
        // A runtime that refuses a valid light set fails it too.
        auto values = runtime->setLights(lights);
        if (!values) {
            failures.push_back({name, seed, "setLights: " + values.error().message});
            continue;
        }
        if (auto bad = invalidCacheValues(**values)) {
            failures.push_back({name, seed, *bad});
            continue;
        }
        auto image = shadeFromCaches(scene, rays, bake, **values, lights, scene.cameras[0], shade);
        if (!image) {
            failures.push_back({name, seed, "shading: " + image.error().message});
            continue;
        }
        if (auto bad = invalidPixels(*image)) failures.push_back({name, seed, *bad});
    }
    return failures;
}

// ---------------------------------------------------------------------------------------------
// The benchmark.

namespace {

/// A generated scene with its rays and bake, made once per run.
struct LoadedScene {
    Scene scene;
    std::unique_ptr<EmbreeScene> rays;
    BakeData bake;
    double bakeSeconds = 0.0;
};

class SceneCache {
public:
    SceneCache(std::string dir, BakeOptions options) : mDir(std::move(dir)), mOptions(options) {}

    Result<const LoadedScene*> get(const std::string& name) {
        auto& slot = mScenes[name];
        if (slot) return slot.get();
        const std::string path = (std::filesystem::path(mDir) / (name + ".gltf")).string();
        auto loaded = std::make_unique<LoadedScene>();
        PIC_TRY_ASSIGN(loaded->scene, loadScene(path));
        PIC_TRY_ASSIGN(loaded->rays, EmbreeScene::create(loaded->scene));
        std::fprintf(stderr, "picbench: baking %s …\n", name.c_str());
        const Clock::time_point start = Clock::now();
        BakeReport report;
        PIC_TRY_ASSIGN(loaded->bake, runBake(loaded->scene, mOptions, report));
        loaded->bakeSeconds = secondsSince(start);
        slot = std::move(loaded);
        return slot.get();
    }

private:
    std::string mDir;
    BakeOptions mOptions;
    std::map<std::string, std::unique_ptr<LoadedScene>> mScenes;
};

Json bakeJson(const BakeData& bake, double seconds) {
    return {{"surfels", bake.params.surfels},
            {"links_per_cache", bake.params.linksPerCache},
            {"bands_y", bake.params.bandsY},
            {"bands_c", bake.params.bandsC},
            {"grid_cell", bake.params.gridCell},
            {"unique_caches", bake.caches.size()},
            {"seconds", seconds}};
}

Json optionalJson(const std::optional<double>& value) {
    return value ? Json(*value) : Json(nullptr);
}

/// The case's view written for people: linked | ideal | path traced, at the reference's
/// exposure (or the linked image's, without one) times `gain`.
Result<void> writeViewPng(const std::string& path, const ViewImages& view,
                          const Image* exposureFrom = nullptr, float gain = 1.0f) {
    std::vector<const Image*> images{&view.linked};
    if (view.ideal) images.push_back(&*view.ideal);
    if (view.reference) images.push_back(&*view.reference);
    const Image& exposureImage =
        exposureFrom ? *exposureFrom : (view.reference ? *view.reference : view.linked);
    const double mean = meanLuminance(exposureImage);
    return writeImage(path, imagesSideBySide(images),
                      gain * (mean > 0.0 ? float(0.25 / mean) : 1.0f));
}

/// A camera of `scene` by index, or a clear error.
Result<Camera> sceneCamera(const LoadedScene& loaded, const std::string& name, size_t index) {
    if (index >= loaded.scene.cameras.size())
        return fail(ErrorCode::InvalidInput, "scene '{}' has {} cameras; camera {} is needed", name,
                    loaded.scene.cameras.size(), index);
    return loaded.scene.cameras[index];
}

/// Targets the figures are held to (docs/accuracy.md says why each).
constexpr double kLeakTarget = 0.01;    ///< dark side ≤ 1 % of the lit side
constexpr double kSpotTarget = 0.85;    ///< linked ÷ path-traced mean ≥ 0.85
constexpr double kHueTarget = 0.95;     ///< hue kept on ≥ 95 % of the coloured light
constexpr double kFlickerTarget = 1.2;  ///< linked flicker ≤ 1.2 × the ideal caches'
/// The leak images show the dark side this much brighter than the lit side's exposure.
constexpr float kLeakImageGain = 10.0f;

struct Runner {
    const StabilityParams& params;
    SceneCache scenes;
    std::string base;  ///< JSON path without ".json": images go beside it
    Json json;
    bool randomFailed = false;

    Result<void> leak() {
        Json cases = Json::array();
        const Camera lowerRoom{
            "lower_room", {1.8f, 1.6f, 1.8f}, {-1.5f, 0.8f, -1.5f}, {0.0f, 1.0f, 0.0f}, 70.0f};
        for (const auto& [name, litIndex] :
             {std::pair{"thin_wall", 1}, std::pair{"two_floors", -1}}) {
            const Clock::time_point start = Clock::now();
            PIC_TRY_ASSIGN(const LoadedScene* loaded, scenes.get(name));
            PIC_TRY_ASSIGN(Camera dark, sceneCamera(*loaded, name, 0));
            Camera lit = lowerRoom;
            if (litIndex >= 0) {
                PIC_TRY_ASSIGN(lit, sceneCamera(*loaded, name, size_t(litIndex)));
            }
            PIC_TRY_ASSIGN(RelitScene relit,
                           relightScene(loaded->scene, *loaded->rays, loaded->bake,
                                        defaultLightSet(loaded->scene), params.settings));
            PIC_TRY_ASSIGN(LeakResult leak, measureLeak(relit, dark, lit, params.settings));
            const std::string png = base + "_leak_" + name + ".png";
            // The dark side at 10× the lit side's exposure: a leak shows as light it should
            // not have.
            PIC_TRY(writeViewPng(png, leak.dark,
                                 leak.lit.reference ? &*leak.lit.reference : &leak.lit.linked,
                                 kLeakImageGain));
            std::printf(
                "  leak %-16s dark ÷ lit indirect: linked %.5f, ideal %s, path traced %s (target ≤ "
                "%.2f)\n",
                name, leak.linked, leak.ideal ? fmt::format("{:.5f}", *leak.ideal).c_str() : "—",
                leak.reference ? fmt::format("{:.5f}", *leak.reference).c_str() : "—", kLeakTarget);
            cases.push_back(
                {{"scene", name},
                 {"dark_camera", dark.name},
                 {"lit_camera", lit.name},
                 {"bake", bakeJson(loaded->bake, loaded->bakeSeconds)},
                 {"dark_over_lit",
                  {{"linked", leak.linked},
                   {"ideal", optionalJson(leak.ideal)},
                   {"reference", optionalJson(leak.reference)}}},
                 {"lit_mean",
                  {{"linked", meanLuminance(leak.lit.linked)},
                   {"ideal", leak.lit.ideal ? Json(meanLuminance(*leak.lit.ideal)) : Json(nullptr)},
                   {"reference", leak.lit.reference ? Json(meanLuminance(*leak.lit.reference))
                                                    : Json(nullptr)}}},
                 {"target_max", kLeakTarget},
                 {"within_target", leak.linked <= kLeakTarget},
                 {"image", png},
                 {"image_gain", kLeakImageGain},
                 {"seconds", secondsSince(start)}});
        }
        json["leak"] = cases;
        return {};
    }

    Result<void> spot() {
        const Clock::time_point start = Clock::now();
        PIC_TRY_ASSIGN(const LoadedScene* loaded, scenes.get("small_spot"));
        PIC_TRY_ASSIGN(Camera camera, sceneCamera(*loaded, "small_spot", 0));
        PIC_TRY_ASSIGN(RelitScene relit,
                       relightScene(loaded->scene, *loaded->rays, loaded->bake,
                                    defaultLightSet(loaded->scene), params.settings));
        PIC_TRY_ASSIGN(ViewImages view, indirectView(relit, camera, params.settings));
        // Means of the three images and the two ratios to the reference, where there are.
        const double linked = meanLuminance(view.linked);
        std::optional<double> ideal, reference, ratio, idealRatio;
        if (view.ideal) ideal = meanLuminance(*view.ideal);
        if (view.reference) reference = meanLuminance(*view.reference);
        if (reference && *reference > 0.0) {
            ratio = linked / *reference;
            if (ideal) idealRatio = *ideal / *reference;
        }
        const std::string png = base + "_spot.png";
        PIC_TRY(writeViewPng(png, view));
        std::printf(
            "  spot small_spot       indirect mean ÷ path traced: linked %s, ideal %s (target ≥ "
            "%.2f)\n",
            ratio ? fmt::format("{:.4f}", *ratio).c_str() : "—",
            idealRatio ? fmt::format("{:.4f}", *idealRatio).c_str() : "—", kSpotTarget);
        json["spot"] = {{"scene", "small_spot"},
                        {"bake", bakeJson(loaded->bake, loaded->bakeSeconds)},
                        {"indirect_mean",
                         {{"linked", linked},
                          {"ideal", optionalJson(ideal)},
                          {"reference", optionalJson(reference)}}},
                        {"over_reference",
                         {{"linked", optionalJson(ratio)}, {"ideal", optionalJson(idealRatio)}}},
                        {"target_min", kSpotTarget},
                        {"within_target", ratio ? Json(*ratio >= kSpotTarget) : Json(nullptr)},
                        {"image", png},
                        {"seconds", secondsSince(start)}};
        return {};
    }

    Result<void> colors() {
        const Clock::time_point start = Clock::now();
        PIC_TRY_ASSIGN(const LoadedScene* loaded, scenes.get("opposite_colors"));
        PIC_TRY_ASSIGN(Camera camera, sceneCamera(*loaded, "opposite_colors", 0));
        PIC_TRY_ASSIGN(RelitScene relit,
                       relightScene(loaded->scene, *loaded->rays, loaded->bake,
                                    defaultLightSet(loaded->scene), params.settings));
        PIC_TRY_ASSIGN(ViewImages view, indirectView(relit, camera, params.settings));
        if (!view.reference)
            return fail(ErrorCode::InvalidInput,
                        "the colours case needs a path-traced reference (--spp > 0)");
        PIC_TRY_ASSIGN(ChromaStats linked, chromaStats(view.linked, *view.reference));
        std::optional<ChromaStats> ideal;
        if (view.ideal) {
            PIC_TRY_ASSIGN(ideal, chromaStats(*view.ideal, *view.reference));
        }
        const std::string png = base + "_colors.png";
        PIC_TRY(writeViewPng(png, view));
        std::printf(
            "  colors opposite_colors chroma error: linked %.4f, ideal %s; hue kept: linked %.4f, "
            "ideal %s (target ≥ %.2f)\n",
            linked.error, ideal ? fmt::format("{:.4f}", ideal->error).c_str() : "—",
            linked.hueAgreement, ideal ? fmt::format("{:.4f}", ideal->hueAgreement).c_str() : "—",
            kHueTarget);
        const auto statsJson = [](const ChromaStats& s) {
            return Json{{"chroma_error", s.error}, {"hue_agreement", s.hueAgreement}};
        };
        json["colors"] = {{"scene", "opposite_colors"},
                          {"bake", bakeJson(loaded->bake, loaded->bakeSeconds)},
                          {"linked", statsJson(linked)},
                          {"ideal", ideal ? statsJson(*ideal) : Json(nullptr)},
                          {"target_hue_agreement_min", kHueTarget},
                          {"within_target", linked.hueAgreement >= kHueTarget},
                          {"image", png},
                          {"seconds", secondsSince(start)}};
        return {};
    }

    Result<void> moving() {
        const Clock::time_point start = Clock::now();
        PIC_TRY_ASSIGN(const LoadedScene* loaded, scenes.get(params.movingScene));
        PIC_TRY_ASSIGN(Camera camera, sceneCamera(*loaded, params.movingScene, 0));
        StabilitySettings settings = params.settings;
        settings.probeSamples = params.movingProbeSamples;
        PIC_TRY_ASSIGN(MovingLightResult moving,
                       runMovingLight(loaded->scene, *loaded->rays, loaded->bake, camera,
                                      params.steps, params.settings.seed, settings,
                                      params.blendIntervals, params.framesPerUpdate));
        Json out{{"scene", params.movingScene},
                 {"bake", bakeJson(loaded->bake, loaded->bakeSeconds)},
                 {"steps", params.steps},
                 {"probe_samples", settings.probeSamples},
                 {"linked_flicker", moving.linked.index}};
        Chart chart;
        chart.title = fmt::format("Moving light, {} steps through {}: indirect light per frame",
                                  params.steps, params.movingScene);
        chart.xLabel = "step";
        chart.yLabel = "frame mean / sequence mean; mean |change| / frame mean";
        const auto addSeries = [&](const FlickerSeries& s, const std::string& name,
                                   glm::vec3 color) {
            double average = 0.0;
            for (double m : s.mean) average += m;
            average /= double(s.mean.size());
            ChartSeries mean{name + " caches: frame mean", color};
            ChartSeries change{name + " caches: frame-to-frame change", color, {}, {}, true};
            for (size_t t = 0; t < s.mean.size(); ++t) {
                mean.points.push_back({double(t), average > 0.0 ? s.mean[t] / average : 0.0});
                if (t > 0) change.points.push_back({double(t), s.change[t]});
            }
            chart.series.push_back(mean);
            chart.series.push_back(change);
        };
        addSeries(moving.linked, "linked", glm::vec3(0.15f, 0.4f, 0.8f));
        if (moving.ideal) {
            addSeries(*moving.ideal, "ideal", glm::vec3(0.85f, 0.45f, 0.1f));
            const double ratio =
                moving.ideal->index > 0.0 ? moving.linked.index / moving.ideal->index : 0.0;
            out["ideal_flicker"] = moving.ideal->index;
            out["excess"] = moving.linked.index - moving.ideal->index;
            out["ratio"] = ratio;
            out["linked_roughness"] = moving.linked.roughness;
            out["ideal_roughness"] = moving.ideal->roughness;
            out["roughness_ratio"] = moving.ideal->roughness > 0.0
                                         ? moving.linked.roughness / moving.ideal->roughness
                                         : 0.0;
            out["target_ratio_max"] = kFlickerTarget;
            out["within_target"] = ratio <= kFlickerTarget;
            std::printf(
                "  moving %-15s flicker: linked %.5f, ideal %.5f, ratio %.3f (target ≤ %.1f); "
                "roughness: linked %.5f, ideal %.5f\n",
                params.movingScene.c_str(), moving.linked.index, moving.ideal->index, ratio,
                kFlickerTarget, moving.linked.roughness, moving.ideal->roughness);
        } else {
            std::printf("  moving %-15s flicker: linked %.5f (no ideal caches)\n",
                        params.movingScene.c_str(), moving.linked.index);
        }
        out["linked_roughness"] = moving.linked.roughness;
        out["linked_peak"] = moving.linked.peak;
        Json blended = Json::array();
        for (const BlendedFlicker& b : moving.blended) {
            blended.push_back({{"blend_intervals", b.intervals},
                               {"frames_per_update", params.framesPerUpdate},
                               {"flicker", b.frames.index},
                               {"roughness", b.frames.roughness},
                               {"peak", b.frames.peak},
                               {"lag", b.lag},
                               {"change", b.frames.change}});
            std::printf("  moving %-15s client blending over %g intervals, %u frames per "
                        "version: flicker %.5f, roughness %.5f, largest change %.5f, lag %.5f\n",
                        params.movingScene.c_str(), b.intervals, params.framesPerUpdate,
                        b.frames.index, b.frames.roughness, b.frames.peak, b.lag);
        }
        out["blended"] = std::move(blended);
        out["frames"] = {{"linked_mean", moving.linked.mean},
                         {"linked_change", moving.linked.change}};
        if (moving.ideal) {
            out["frames"]["ideal_mean"] = moving.ideal->mean;
            out["frames"]["ideal_change"] = moving.ideal->change;
        }
        Json path = Json::array();
        for (const glm::vec3& p : moving.path) path.push_back({p.x, p.y, p.z});
        out["path"] = path;
        const std::string chartPath = base + "_moving.png";
        if (auto written = writeChart(chart, chartPath); !written)
            return std::unexpected(written.error());
        out["chart"] = chartPath;
        out["seconds"] = secondsSince(start);
        json["moving"] = out;
        return {};
    }

    Result<void> random() {
        const Clock::time_point start = Clock::now();
        const size_t sceneCount = params.randomScenes.size();
        if (sceneCount == 0)
            return fail(ErrorCode::InvalidInput, "no scenes for the random light sets");
        std::vector<RandomSetFailure> failures;
        Json perScene = Json::object();
        for (size_t s = 0; s < sceneCount; ++s) {
            const std::string& name = params.randomScenes[s];
            std::vector<uint64_t> seeds;
            for (uint64_t i = s; i < params.randomSets; i += sceneCount)
                seeds.push_back(params.settings.seed + i);
            if (seeds.empty()) continue;
            PIC_TRY_ASSIGN(const LoadedScene* loaded, scenes.get(name));
            const Clock::time_point sceneStart = Clock::now();
            PIC_TRY_ASSIGN(std::vector<RandomSetFailure> found,
                           checkRandomLightSets(loaded->scene, *loaded->rays, loaded->bake, name,
                                                seeds, params.randomSize));
            perScene[name] = {{"sets", seeds.size()},
                              {"failures", found.size()},
                              {"seconds", secondsSince(sceneStart)}};
            std::fprintf(stderr, "picbench: %s: %zu random light sets, %zu failed\n", name.c_str(),
                         seeds.size(), found.size());
            failures.insert(failures.end(), found.begin(), found.end());
        }
        Json failing = Json::array();
        for (const RandomSetFailure& f : failures)
            failing.push_back({{"scene", f.scene}, {"seed", f.seed}, {"reason", f.reason}});
        std::printf("  random %u light sets over %zu scenes: %zu failed (NaN, Inf or negative)\n",
                    params.randomSets, sceneCount, failures.size());
        for (const RandomSetFailure& f : failures)
            std::printf("    %s seed %llu: %s\n", f.scene.c_str(), (unsigned long long)f.seed,
                        f.reason.c_str());
        json["random"] = {
            {"sets", params.randomSets},
            {"first_seed", params.settings.seed},
            {"image_size", fmt::format("{}x{}", params.randomSize.x, params.randomSize.y)},
            {"scenes", perScene},
            {"failures", failures.size()},
            {"failing", failing},
            {"seconds", secondsSince(start)}};
        randomFailed = !failures.empty();
        return {};
    }
};

}  // namespace

int runStabilityBenchmark(const StabilityParams& params) {
    for (const std::string& c : params.cases)
        if (c != "leak" && c != "spot" && c != "colors" && c != "moving" && c != "random")
            return reportError(
                fail(ErrorCode::InvalidInput,
                     "unknown stability case '{}' (known: leak, spot, colors, moving, random)", c)
                    .error());
    const std::string jsonPath = params.jsonPath;
    std::error_code ec;
    const std::filesystem::path parent = std::filesystem::path(jsonPath).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    const std::string suffix = ".json";
    const std::string base =
        jsonPath.ends_with(suffix) ? jsonPath.substr(0, jsonPath.size() - suffix.size()) : jsonPath;
    Runner runner{params, SceneCache(params.sceneDir, params.bake), base, Json::object(), false};
    const StabilitySettings& s = params.settings;
    runner.json["settings"] = {
        {"scene_dir", params.sceneDir}, {"size", fmt::format("{}x{}", s.size.x, s.size.y)},
        {"reference_spp", s.spp},       {"probe_samples", s.probeSamples},
        {"shade_spp", s.shadeSpp},      {"seed", s.seed}};
    const Clock::time_point start = Clock::now();
    std::printf("picbench stability (%ux%u, reference %u spp, %u directions per ideal cache)\n",
                s.size.x, s.size.y, s.spp, s.probeSamples);
    for (const std::string& c : params.cases) {
        const Result<void> ran = c == "leak"     ? runner.leak()
                                 : c == "spot"   ? runner.spot()
                                 : c == "colors" ? runner.colors()
                                 : c == "moving" ? runner.moving()
                                                 : runner.random();
        if (!ran) return reportError(ran.error());
    }
    runner.json["seconds"] = secondsSince(start);
    if (int exit = writeJson(runner.json, jsonPath); exit != 0) return exit;
    return runner.randomFailed ? 1 : 0;
}

}  // namespace pic
