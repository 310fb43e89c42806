#include "bake/target_error.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>

#include "bake/grid_caches.h"
#include "bake/ref/path_tracer.h"
#include "core/hash.h"
#include "core/image.h"
#include "core/sh.h"
#include "render/cpu/cache_shading.h"
#include "render/cpu_runtime.h"

namespace pic {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

/// A pilot reference: the mean of two halves and its own noise.
struct PilotReference {
    Camera camera;
    Image image;
    double noise = 0.0;
};

const char* axisName(TargetAxis axis) {
    switch (axis) {
        case TargetAxis::Surfels: return "nS";
        case TargetAxis::Links: return "nL";
        case TargetAxis::BandsY: return "lY";
        case TargetAxis::BandsC: return "lC";
        case TargetAxis::GridCell: return "grid cell";
        case TargetAxis::Texel: return "texel";
        case TargetAxis::LinkSamples: return "link samples";
    }
    return "?";
}

/// Levels from `values` (any order, duplicates allowed), cheapest first: ascending counts, or
/// descending sizes where `coarserIsCheaper`.
TargetAxisLevels makeAxis(TargetAxis axis, std::vector<double> values, double base, bool coarserIsCheaper) {
    values.push_back(base);
    std::sort(values.begin(), values.end());
    values.erase(std::unique(values.begin(), values.end()), values.end());
    if (coarserIsCheaper) std::reverse(values.begin(), values.end());
    TargetAxisLevels levels{axis, values, 0};
    levels.base = size_t(std::find(values.begin(), values.end(), base) - values.begin());
    return levels;
}

/// SH coefficients a cache holds: lY² of luminance and lC² of each chroma channel.
double coefficientsPerCache(const BakeParams& p) {
    return double(shCount(int(p.bandsY)) + 2 * shCount(int(p.bandsC)));
}

/// The cost model's features: link reads, link reads · coefficients, surfels, 1.
std::array<double, 4> costFeatures(double caches, double links, double coefficients, double surfels) {
    return {caches * links, caches * links * coefficients, surfels, 1.0};
}

/// Solves the n × n system `a` x = `b` by Gaussian elimination with partial pivoting; false
/// when singular.
bool solve(std::vector<std::vector<double>> a, std::vector<double> b, std::vector<double>& x) {
    const size_t n = b.size();
    for (size_t c = 0; c < n; ++c) {
        size_t pivot = c;
        for (size_t r = c + 1; r < n; ++r)
            if (std::abs(a[r][c]) > std::abs(a[pivot][c])) pivot = r;
        if (std::abs(a[pivot][c]) < 1e-12) return false;
        std::swap(a[c], a[pivot]);
        std::swap(b[c], b[pivot]);
        for (size_t r = c + 1; r < n; ++r) {
            const double f = a[r][c] / a[c][c];
            for (size_t k = c; k < n; ++k) a[r][k] -= f * a[c][k];
            b[r] -= f * b[c];
        }
    }
    x.assign(n, 0.0);
    for (size_t r = n; r-- > 0;) {
        double s = b[r];
        for (size_t k = r + 1; k < n; ++k) s -= a[r][k] * x[k];
        x[r] = s / a[r][r];
    }
    return true;
}

/// The non-negative least-squares fit of ms to the features of the measured rungs, in relative
/// terms (a cheap bake's ms counts as much as a dear one's): the subset of features with
/// non-negative coefficients that leaves the least residual.
TargetCostModel fitCost(const std::vector<TargetRung>& rungs) {
    std::vector<std::array<double, 4>> rows;
    std::vector<double> ms;
    for (const TargetRung& r : rungs) {
        if (!(r.updateMs > 0.0)) continue;
        rows.push_back(costFeatures(double(r.caches), r.params.linksPerCache, coefficientsPerCache(r.params),
                                    r.params.surfels));
        ms.push_back(r.updateMs);
    }
    TargetCostModel best;
    double bestResidual = std::numeric_limits<double>::infinity();
    for (unsigned subset = 1; subset < 16; ++subset) {
        std::vector<size_t> used;
        for (size_t f = 0; f < 4; ++f)
            if (subset & (1u << f)) used.push_back(f);
        if (used.size() > rows.size()) continue;
        // Weighted normal equations: each row divided by its ms.
        const size_t n = used.size();
        std::vector<std::vector<double>> a(n, std::vector<double>(n, 0.0));
        std::vector<double> b(n, 0.0), x;
        for (size_t i = 0; i < rows.size(); ++i)
            for (size_t p = 0; p < n; ++p) {
                const double fp = rows[i][used[p]] / ms[i];
                b[p] += fp;  // target ms[i] / ms[i] = 1
                for (size_t q = 0; q < n; ++q) a[p][q] += fp * rows[i][used[q]] / ms[i];
            }
        if (!solve(a, b, x)) continue;
        if (std::any_of(x.begin(), x.end(), [](double v) { return v < 0.0; })) continue;
        TargetCostModel model;
        for (size_t p = 0; p < n; ++p) model.coefficients[used[p]] = x[p];
        double residual = 0.0;
        for (size_t i = 0; i < rows.size(); ++i) {
            double predicted = 0.0;
            for (size_t f = 0; f < 4; ++f) predicted += model.coefficients[f] * rows[i][f];
            residual += (predicted / ms[i] - 1.0) * (predicted / ms[i] - 1.0);
        }
        if (residual < bestResidual - 1e-12) bestResidual = residual, best = model;
    }
    return best;
}

/// What identifies a rung among the pilot's bakes of one base: its settings.
std::string rungKey(const BakeOptions& o) {
    return fmt::format("nS {} nL {} lY {} lC {} cell {:.6g} texel {:.6g} samples {}", o.surfels.value_or(0),
                       o.links.value_or(0), o.bandsY.value_or(0), o.bandsC.value_or(0), o.gridCell.value_or(0.0f),
                       o.lightmapTexel.value_or(0.0f), o.linkSamples);
}

/// The pilot's cache: its references and every rung it measured, in one JSON file whose name
/// hashes what they depend on.
class PilotCache {
public:
    PilotCache(const std::string& dir, const Scene& scene, const BakeOptions& base, const LightSet& lights,
               const std::vector<Camera>& views, const TargetErrorParams& params) {
        if (dir.empty()) return;
        std::string what = fmt::format(
            "pic pilot 3|{}|{}|{}x{} {} {}|{} {} {} {} {} {} {} {} {} {} {} {} {}", scene.hash, toJson(lights),
            params.size.x, params.size.y, params.spp, params.shadeSpp, base.surfels.value_or(0),
            base.links.value_or(0), base.bandsY.value_or(0), base.bandsC.value_or(0), base.gridCell.value_or(0.0f),
            base.lightmapTexel.value_or(0.0f), uint32_t(base.linkMode), uint32_t(base.hierarchy), base.linkSamples,
            base.linkFinalSamples, base.exposureRays, uint32_t(base.linkReads), uint32_t(base.linkCut));
        what += fmt::format("|{} {} {} {} {}", base.relaxIterations, base.seed, uint32_t(base.gridCaches),
                            base.skyRays, views.size());
        for (const Camera& c : views)
            what += fmt::format("|{} {} {} {} {} {} {} {} {} {}", c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y,
                                c.target.z, c.up.x, c.up.y, c.up.z, c.fovyDegrees);
        mPath = (fs::path(dir) / "pilot" / fmt::format("{:016x}.json", hashBytes(what.data(), what.size()))).string();
        if (std::ifstream in(mPath); in) {
            Json json = Json::parse(in, nullptr, false);
            if (json.is_object()) mJson = std::move(json);
        }
        if (!mJson.is_object()) mJson = Json::object();
        mJson["scene"] = scene.sourcePath;
    }

    const std::string& path() const { return mPath; }

    std::optional<std::vector<PilotReference>> references(const std::vector<Camera>& views) const {
        if (!mJson.contains("references") || mJson["references"].size() != views.size()) return std::nullopt;
        std::vector<PilotReference> out;
        for (size_t v = 0; v < views.size(); ++v) {
            const Json& r = mJson["references"][v];
            PilotReference reference{views[v], Image(r.value("width", 0u), r.value("height", 0u)), r.value("noise", 0.0)};
            const Json& pixels = r["pixels"];
            if (!pixels.is_array() || pixels.size() != 3 * reference.image.pixels.size()) return std::nullopt;
            for (size_t i = 0; i < reference.image.pixels.size(); ++i)
                reference.image.pixels[i] = {pixels[3 * i].get<float>(), pixels[3 * i + 1].get<float>(),
                                             pixels[3 * i + 2].get<float>()};
            out.push_back(std::move(reference));
        }
        return out;
    }

    void storeReferences(const std::vector<PilotReference>& references) {
        if (mPath.empty()) return;
        Json list = Json::array();
        for (const PilotReference& r : references) {
            std::vector<float> pixels;
            for (const glm::vec3& p : r.image.pixels) pixels.insert(pixels.end(), {p.r, p.g, p.b});
            list.push_back({{"noise", r.noise}, {"width", r.image.width}, {"height", r.image.height}, {"pixels", pixels}});
        }
        mJson["references"] = std::move(list);
        save();
    }

    std::optional<TargetRung> rung(const std::string& key) const {
        if (!mJson.contains("rungs") || !mJson["rungs"].contains(key)) return std::nullopt;
        const Json& j = mJson["rungs"][key];
        TargetRung r;
        r.params.surfels = j.value("surfels", 0u);
        r.params.linksPerCache = j.value("links", 0u);
        r.params.bandsY = j.value("bands_y", 0u);
        r.params.bandsC = j.value("bands_c", 0u);
        r.params.gridCell = j.value("grid_cell", 0.0f);
        r.params.lightmapTexel = j.value("lightmap_texel", 0.0f);
        r.params.linkSamples = j.value("link_samples", 0u);
        r.caches = j.value("caches", size_t{0});
        r.gridCaches = j.value("grid_caches", r.caches);
        r.bakeSeconds = j.value("bake_seconds", 0.0);
        r.updateMs = j.value("update_ms", 0.0);
        r.measured = j.value("measured_rmse", 0.0);
        r.error = j.value("error", 0.0);
        r.viewErrors = j.value("view_errors", std::vector<double>{});
        r.cached = true;
        if (r.params.surfels == 0 || r.caches == 0 || r.viewErrors.empty()) return std::nullopt;
        return r;
    }

    void storeRung(const std::string& key, const TargetRung& r) {
        if (mPath.empty()) return;
        mJson["rungs"][key] = {{"surfels", r.params.surfels},         {"links", r.params.linksPerCache},
                               {"bands_y", r.params.bandsY},          {"bands_c", r.params.bandsC},
                               {"grid_cell", r.params.gridCell},      {"lightmap_texel", r.params.lightmapTexel},
                               {"link_samples", r.params.linkSamples}, {"caches", r.caches},
                               {"grid_caches", r.gridCaches},
                               {"bake_seconds", r.bakeSeconds},       {"update_ms", r.updateMs},
                               {"measured_rmse", r.measured},         {"error", r.error},
                               {"view_errors", r.viewErrors}};
        save();
    }

private:
    /// Written whole to a temporary file and renamed over the old one; a cache that cannot be
    /// written only costs the next pilot its time, so the pilot warns once and goes on.
    void save() {
        std::error_code ec;
        fs::create_directories(fs::path(mPath).parent_path(), ec);
        const std::string tmp = mPath + ".tmp";
        {
            std::ofstream out(tmp);
            out << mJson.dump() << "\n";
            if (!out) ec = std::make_error_code(std::errc::io_error);
        }
        if (!ec) fs::rename(tmp, mPath, ec);
        if (ec && !mWarned) {
            std::fprintf(stderr, "picbake: warning: could not write the pilot cache %s (%s)\n", mPath.c_str(),
                         ec.message().c_str());
            mWarned = true;
        }
    }

    std::string mPath;
    Json mJson;
    bool mWarned = false;
};

}  // namespace

double TargetCostModel::predict(double caches, double links, double coefficientsPerCache, double surfels) const {
    const auto f = costFeatures(caches, links, coefficientsPerCache, surfels);
    double ms = 0.0;
    for (size_t i = 0; i < 4; ++i) ms += coefficients[i] * f[i];
    return ms;
}

Image meanOfHalves(const Image& a, const Image& b) {
    PIC_CHECK(a.pixels.size() == b.pixels.size());
    Image mean(a.width, a.height);
    for (size_t i = 0; i < mean.pixels.size(); ++i) mean.pixels[i] = 0.5f * (a.pixels[i] + b.pixels[i]);
    return mean;
}

double halvesNoise(const Image& a, const Image& b) {
    PIC_CHECK(a.pixels.size() == b.pixels.size());
    double sum = 0.0, level = 0.0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        const glm::dvec3 d = glm::dvec3(a.pixels[i]) - glm::dvec3(b.pixels[i]);
        sum += glm::dot(d, d);
        level += 0.5 * double(a.pixels[i].r + a.pixels[i].g + a.pixels[i].b + b.pixels[i].r +
                              b.pixels[i].g + b.pixels[i].b);
    }
    const double n = 3.0 * double(a.pixels.size());
    return level > 0.0 ? std::sqrt(sum / n) / 2.0 / (level / n) : 0.0;
}

std::vector<TargetAxisLevels> targetAxes(const Scene& scene, const BakeOptions& base) {
    std::map<std::string, std::string> unused;
    auto resolved = resolveBakeParams(scene, base, unused);
    if (!resolved) return {};
    const BakeParams& d = *resolved;
    auto surfels = [&](double s) { return double(std::max<uint32_t>(256, uint32_t(std::lround(d.surfels * s)))); };
    auto links = [&](double s) { return double(std::clamp<uint32_t>(uint32_t(std::lround(d.linksPerCache * s)), 8, 4096)); };
    std::vector<double> bandsY, bandsC, samples;
    if (d.bandsY >= 3) bandsY.push_back(d.bandsY - 1);  // two bands at least: l = 1 carries direction
    for (uint32_t c = 1; c <= std::min(d.bandsC + 1, d.bandsY); ++c) bandsC.push_back(c);
    samples.push_back(std::min(4u, d.linkSamples));
    samples.push_back(std::max(64u, d.linkSamples));
    const double cell = d.gridCell, texel = d.lightmapTexel;
    return {makeAxis(TargetAxis::Surfels, {surfels(0.125), surfels(0.25), surfels(0.5), surfels(2.0)}, d.surfels, false),
            makeAxis(TargetAxis::Links, {links(0.125), links(0.25), links(0.5), links(2.0)}, d.linksPerCache, false),
            makeAxis(TargetAxis::BandsY, bandsY, d.bandsY, false),
            makeAxis(TargetAxis::BandsC, bandsC, d.bandsC, false),
            makeAxis(TargetAxis::GridCell, {4.0 * cell, 2.0 * cell, 0.5 * cell}, cell, true),
            makeAxis(TargetAxis::Texel, {4.0 * texel, 2.0 * texel, 0.5 * texel}, texel, true),
            makeAxis(TargetAxis::LinkSamples, samples, d.linkSamples, false)};
}

BakeOptions targetOptions(const BakeOptions& base, const std::vector<TargetAxisLevels>& axes,
                          const TargetLevels& levels) {
    BakeOptions o = base;
    for (size_t a = 0; a < axes.size(); ++a) {
        const double v = axes[a].values[levels[a]];
        switch (axes[a].axis) {
            case TargetAxis::Surfels: o.surfels = uint32_t(v); break;
            case TargetAxis::Links: o.links = uint32_t(v); break;
            case TargetAxis::BandsY: o.bandsY = uint32_t(v); break;
            case TargetAxis::BandsC: o.bandsC = uint32_t(v); break;
            case TargetAxis::GridCell: o.gridCell = float(v); break;
            case TargetAxis::Texel: o.lightmapTexel = float(v); break;
            case TargetAxis::LinkSamples: o.linkSamples = uint32_t(v); break;
        }
    }
    if (o.bandsY && o.bandsC) o.bandsC = std::min(*o.bandsC, *o.bandsY);
    return o;
}

std::string targetLevelsName(const std::vector<TargetAxisLevels>& axes, const TargetLevels& levels) {
    std::vector<std::string> parts;
    for (size_t a = 0; a < axes.size(); ++a) {
        if (levels[a] == axes[a].base) continue;
        const double v = axes[a].values[levels[a]], b = axes[a].values[axes[a].base];
        switch (axes[a].axis) {
            case TargetAxis::Surfels:
            case TargetAxis::GridCell:
            case TargetAxis::Texel: parts.push_back(fmt::format("{} x{:.3g}", axisName(axes[a].axis), v / b)); break;
            default: parts.push_back(fmt::format("{} {:g}", axisName(axes[a].axis), v)); break;
        }
    }
    return parts.empty() ? "base" : fmt::format("{}", fmt::join(parts, ", "));
}

namespace {

/// Whether a view can measure a relative error: its eye is not inside a solid (as the grid's
/// caches test it) and a small cached-light image of it is not black.
Result<bool> seesIndirectLight(const Scene& scene, const EmbreeScene& rays, const LightSet& lights,
                               const Camera& camera) {
    static const std::vector<glm::vec3> directions = sphereDirections(64);
    if (insideSolid(scene, rays, camera.eye, directions)) return false;
    PathTraceParams trace;
    trace.width = 16;
    trace.height = 12;
    trace.spp = 16;
    trace.component = PathTraceParams::Component::Cached;
    PIC_TRY_ASSIGN(Image image, pathTrace(scene, rays, lights, camera, trace));
    double sum = 0.0;
    for (const glm::vec3& p : image.pixels) sum += double(p.r + p.g + p.b);
    return sum > 0.0;
}

}  // namespace

Result<std::vector<Camera>> pilotViews(const Scene& scene, const EmbreeScene& rays, const LightSet& lights,
                                       std::vector<std::string>& how) {
    std::vector<Camera> views;
    std::vector<std::string> skipped;
    for (size_t i = 0; i < scene.cameras.size() && views.size() < 2; ++i) {
        const std::string name =
            fmt::format("scene camera {}{}", i, scene.cameras[i].name.empty() ? "" : " (" + scene.cameras[i].name + ")");
        PIC_TRY_ASSIGN(bool sees, seesIndirectLight(scene, rays, lights, scene.cameras[i]));
        if (!sees) {
            skipped.push_back(name);
            continue;
        }
        views.push_back(scene.cameras[i]);
        how.push_back(name);
    }
    if (!views.empty()) return views;
    // No camera that sees indirect light: a person standing in the scene and turning round,
    // at the middle of the bounds, then at each lamp, then in the lower and upper half of the
    // bounds; the first four views that see indirect light.
    const glm::vec3 centre = scene.bounds.center(), extent = scene.bounds.extent();
    std::vector<std::pair<glm::vec3, std::string>> eyes{{centre, "the centre of the bounds"}};
    for (const Light& light : lights.lights)
        if (light.type != LightType::Directional)
            eyes.emplace_back(light.position, fmt::format("light '{}'", light.id));
    eyes.emplace_back(centre - glm::vec3(0.0f, 0.25f * extent.y, 0.0f), "the lower half of the bounds");
    eyes.emplace_back(centre + glm::vec3(0.0f, 0.25f * extent.y, 0.0f), "the upper half of the bounds");
    const std::string note = scene.cameras.empty()
                                 ? " (the scene has no camera)"
                                 : fmt::format(" ({} see{} no indirect light)", fmt::join(skipped, ", "),
                                               skipped.size() == 1 ? "s" : "");
    const std::pair<glm::vec3, const char*> turns[] = {
        {{1.0f, 0.0f, 0.0f}, "+x"}, {{-1.0f, 0.0f, 0.0f}, "-x"}, {{0.0f, 0.0f, 1.0f}, "+z"}, {{0.0f, 0.0f, -1.0f}, "-z"}};
    for (const auto& [eye, where] : eyes) {
        for (const auto& [direction, name] : turns) {
            if (views.size() == 4) return views;
            Camera camera;
            camera.eye = eye;
            camera.target = eye + direction * std::max(extent.x, extent.z) * 0.5f - glm::vec3(0.0f, 0.1f * extent.y, 0.0f);
            camera.fovyDegrees = 70.0f;
            PIC_TRY_ASSIGN(bool sees, seesIndirectLight(scene, rays, lights, camera));
            if (!sees) continue;
            views.push_back(camera);
            how.push_back(fmt::format("from {} along {}{}", where, name, note));
        }
    }
    if (views.empty())
        return fail(ErrorCode::InvalidInput,
                    "no view of scene '{}' sees indirect light under these lights (tried its cameras, its middle and "
                    "its lamps): give the pilot one with --pilot-camera",
                    scene.sourcePath);
    return views;
}

Result<TargetChoice> chooseBakeForTarget(const Scene& scene, const BakeOptions& base,
                                         const TargetErrorParams& params) {
    if (!(params.error > 0.0 && params.error <= 10.0))
        return fail(ErrorCode::InvalidInput, "--target-error must be a relative RMSE in (0, 10], got {}", params.error);
    if (params.budgetMs && !(*params.budgetMs > 0.0))
        return fail(ErrorCode::InvalidInput, "--budget-ms must be a positive number of milliseconds, got {}",
                    *params.budgetMs);
    const Clock::time_point pilotStart = Clock::now();
    PIC_TRY_ASSIGN(LightSet lights, loadLightSet(params.lightsPath, scene));
    PIC_TRY_ASSIGN(std::unique_ptr<EmbreeScene> rays, EmbreeScene::create(scene));
    const std::vector<TargetAxisLevels> axes = targetAxes(scene, base);
    if (axes.empty()) {
        std::map<std::string, std::string> unused;
        PIC_TRY(resolveBakeParams(scene, base, unused));  // names what does not resolve
        return fail(ErrorCode::InvalidInput, "the bake settings of scene '{}' do not resolve", scene.sourcePath);
    }
    TargetChoice choice;
    const double goal = params.safety * params.error;

    std::vector<Camera> cameras = params.cameras;
    if (cameras.empty()) {
        PIC_TRY_ASSIGN(cameras, pilotViews(scene, *rays, lights, choice.views));
    } else
        for (size_t i = 0; i < cameras.size(); ++i) choice.views.push_back(fmt::format("--pilot-camera {}", i));
    PilotCache cache(params.cacheDir, scene, base, lights, cameras, params);
    choice.cachePath = cache.path();

    // The pilot's references, each traced in two independent halves.
    std::vector<PilotReference> references;
    if (auto kept = cache.references(cameras)) {
        references = std::move(*kept);
        std::fprintf(stderr, "picbake: target: pilot references kept in %s\n", cache.path().c_str());
    } else {
        for (size_t v = 0; v < cameras.size(); ++v) {
            PathTraceParams trace;
            trace.width = params.size.x;
            trace.height = params.size.y;
            trace.spp = std::max(params.spp / 2, 1u);
            trace.component = PathTraceParams::Component::Cached;
            std::fprintf(stderr, "picbake: target: path tracing the pilot reference of %s (%ux%u, %u spp) …\n",
                         choice.views[v].c_str(), params.size.x, params.size.y, params.spp);
            trace.seed = 1;
            PIC_TRY_ASSIGN(Image a, pathTrace(scene, *rays, lights, cameras[v], trace));
            trace.seed = 2;
            PIC_TRY_ASSIGN(Image b, pathTrace(scene, *rays, lights, cameras[v], trace));
            references.push_back({cameras[v], meanOfHalves(a, b), halvesNoise(a, b)});
        }
        cache.storeReferences(references);
    }
    for (const PilotReference& r : references) choice.noise += r.noise / double(references.size());

    ShadeParams shade;
    shade.width = params.size.x;
    shade.height = params.size.y;
    shade.samplesPerPixel = params.shadeSpp;
    shade.component = ShadeComponent::Indirect;
    auto inBudget = [&](double ms) { return !params.budgetMs || ms <= *params.budgetMs; };

    TargetLevels baseLevels{};
    for (size_t a = 0; a < axes.size(); ++a) baseLevels[a] = uint8_t(axes[a].base);
    // The base's bake and runtime: every other rung's updates are timed in turns with the
    // base's, so that a busy spell of the machine slows both and their ratio stands.
    struct TimingBase {
        std::unique_ptr<BakeData> bake;
        BakeReport report;
        std::unique_ptr<Runtime> runtime;
        double ms = 0.0;  ///< median of 5 updates
    };
    std::optional<TimingBase> timingBase;
    auto timeUpdate = [&](Runtime& runtime) -> Result<double> {
        const Clock::time_point update = Clock::now();
        PIC_TRY(runtime.setLights(lights));
        return 1e3 * secondsSince(update);
    };
    auto makeTimingBase = [&]() -> Result<void> {
        TimingBase t;
        t.bake = std::make_unique<BakeData>();
        PIC_TRY_ASSIGN(*t.bake, runBake(scene, targetOptions(base, axes, baseLevels), t.report));
        PIC_TRY_ASSIGN(t.runtime, createCpuRuntime(scene, *rays, *t.bake, BounceParams{}));
        std::vector<double> ms;
        for (int k = 0; k < 5; ++k) {
            PIC_TRY_ASSIGN(double m, timeUpdate(*t.runtime));
            ms.push_back(m);
        }
        t.ms = median(ms);
        timingBase = std::move(t);
        return {};
    };

    // Measures one combination (from the cache where it was measured before); keeps the bake
    // of the latest one baked in `lastBake`.
    std::optional<std::pair<TargetLevels, std::unique_ptr<BakeData>>> lastBake;
    BakeReport lastReport;
    auto measure = [&](const TargetLevels& levels, const char* kind) -> Result<TargetRung> {
        const BakeOptions options = targetOptions(base, axes, levels);
        const std::string key = rungKey(options);
        TargetRung rung;
        if (auto kept = cache.rung(key)) {
            rung = *kept;
        } else {
            std::fprintf(stderr, "picbake: target: baking %s …\n", targetLevelsName(axes, levels).c_str());
            if (!timingBase) {
                const Clock::time_point start = Clock::now();
                PIC_TRY(makeTimingBase());
                if (levels == baseLevels) rung.bakeSeconds = secondsSince(start);
            }
            const BakeData* bake = timingBase->bake.get();
            Runtime* runtime = timingBase->runtime.get();
            std::unique_ptr<BakeData> own;
            std::unique_ptr<Runtime> ownRuntime;
            BakeReport report;
            if (levels == baseLevels) {
                rung.updateMs = timingBase->ms;
            } else {
                const Clock::time_point start = Clock::now();
                own = std::make_unique<BakeData>();
                PIC_TRY_ASSIGN(*own, runBake(scene, options, report));
                rung.bakeSeconds = secondsSince(start);
                PIC_TRY_ASSIGN(ownRuntime, createCpuRuntime(scene, *rays, *own, BounceParams{}));
                bake = own.get();
                runtime = ownRuntime.get();
                std::vector<double> ratios;
                for (int k = 0; k < 5; ++k) {
                    PIC_TRY_ASSIGN(double baseMs, timeUpdate(*timingBase->runtime));
                    PIC_TRY_ASSIGN(double ms, timeUpdate(*runtime));
                    ratios.push_back(ms / std::max(baseMs, 1e-6));
                }
                rung.updateMs = median(ratios) * timingBase->ms;
            }
            rung.params = bake->params;
            rung.caches = bake->caches.size();
            rung.gridCaches = size_t(std::count_if(bake->caches.begin(), bake->caches.end(), [](const Cache& c) {
                return c.kind == gpu::kCacheKindGrid;
            }));
            PIC_TRY_ASSIGN(const CacheValues* values, runtime->setLights(lights));
            // Over the views: the root mean square of their errors, the relative RMSE of all
            // their pixels together where their levels are alike.
            for (const PilotReference& reference : references) {
                PIC_TRY_ASSIGN(Image image, shadeFromCaches(scene, *rays, *bake, *values, lights, reference.camera, shade));
                PIC_TRY_ASSIGN(ImageError e, compareImages(image, reference.image));
                const double truth2 = std::max(e.relativeRmse * e.relativeRmse - reference.noise * reference.noise, 0.0);
                rung.viewErrors.push_back(std::sqrt(truth2));
                rung.error += truth2 / double(references.size());
                rung.measured += e.relativeRmse * e.relativeRmse / double(references.size());
            }
            rung.error = std::sqrt(rung.error);
            rung.measured = std::sqrt(rung.measured);
            cache.storeRung(key, rung);
            if (own) {
                ownRuntime.reset();
                lastBake.emplace(levels, std::move(own));
                lastReport = std::move(report);
            }
        }
        rung.name = targetLevelsName(axes, levels);
        rung.kind = kind;
        rung.levels = levels;
        rung.meets = inBudget(rung.updateMs) && rung.error <= goal;
        std::fprintf(stderr, "picbake: target:   %s: %zu caches, error %.4f against the truth (measured %.4f), "
                     "%.1f ms per update%s%s\n", rung.name.c_str(), rung.caches, rung.error, rung.measured,
                     rung.updateMs, rung.cached ? " (kept)" : "",
                     rung.meets ? ": within the goal" : inBudget(rung.updateMs) ? "" : ": over the budget");
        return rung;
    };

    // The base, then each setting alone at each of its cheaper levels, and at its dearer ones
    // where the base misses the goal.
    PIC_TRY_ASSIGN(TargetRung baseRung, measure(baseLevels, "base"));
    choice.rungs.push_back(baseRung);
    const bool dearer = baseRung.error > goal;
    // single[a][l]: the rung with axis a at level l and every other at the base.
    std::vector<std::vector<std::optional<size_t>>> single(axes.size());
    // Where no surface reads the grid and nothing else may (--grid-caches surfaces), the base
    // keeps no grid cache and its cell changes nothing: it is left where it is.
    const bool gridUnread = base.gridCaches == GridCaches::Surfaces && baseRung.gridCaches == 0;
    if (gridUnread)
        std::fprintf(stderr, "picbake: target: no surface reads the grid, so its cell stays at the base's\n");
    for (size_t a = 0; a < axes.size(); ++a) {
        single[a].resize(axes[a].values.size());
        single[a][axes[a].base] = 0;
        if (gridUnread && axes[a].axis == TargetAxis::GridCell) continue;
        for (size_t l = 0; l < axes[a].values.size(); ++l) {
            if (l == axes[a].base || (l > axes[a].base && !dearer)) continue;
            TargetLevels levels = baseLevels;
            levels[a] = uint8_t(l);
            PIC_TRY_ASSIGN(TargetRung rung, measure(levels, "single"));
            choice.rungs.push_back(rung);
            single[a][l] = choice.rungs.size() - 1;
        }
    }
    // The corner where every setting is at its cheapest: the cost model's anchor at the cheap
    // end (a base's update is mostly link reads; the corner's shows what is left).
    TargetLevels corner{};
    for (size_t a = 0; a < axes.size(); ++a)
        if (gridUnread && axes[a].axis == TargetAxis::GridCell) corner.at(a) = axes[a].base;
    if (corner != baseLevels && std::none_of(choice.rungs.begin(), choice.rungs.end(),
                                             [&](const TargetRung& r) { return r.levels == corner; })) {
        PIC_TRY_ASSIGN(TargetRung rung, measure(corner, "corner"));
        choice.rungs.push_back(rung);
    }
    choice.cost = fitCost(choice.rungs);

    // The models over every combination of measured levels, view by view.
    const size_t views = references.size();
    std::vector<double> e0(views);
    for (size_t v = 0; v < views; ++v) e0[v] = baseRung.viewErrors[v] * baseRung.viewErrors[v];
    struct Candidate {
        TargetLevels levels;
        // Per view, Σ of the settings' squared-error changes below and above 0.
        std::vector<double> gain, loss;
        double ms = 0.0;
        bool struck = false;
    };
    std::vector<Candidate> candidates;
    auto predictMs = [&](const BakeParams& p, double caches) {
        return choice.cost.predict(caches, p.linksPerCache, coefficientsPerCache(p), p.surfels);
    };
    TargetLevels levels{};
    std::function<void(size_t)> enumerate = [&](size_t a) {
        if (a == axes.size()) {
            Candidate c{levels, std::vector<double>(views, 0.0), std::vector<double>(views, 0.0)};
            double caches = double(baseRung.caches);
            for (size_t k = 0; k < axes.size(); ++k) {
                const TargetRung& s = choice.rungs[*single[k][levels[k]]];
                for (size_t v = 0; v < views; ++v) {
                    const double delta = s.viewErrors[v] * s.viewErrors[v] - e0[v];
                    // A cheaper setting cannot help and a dearer one cannot hurt, but for noise.
                    if (levels[k] < axes[k].base)
                        c.loss[v] += std::max(delta, 0.0);
                    else
                        c.gain[v] += std::min(delta, 0.0);
                }
                if (axes[k].axis == TargetAxis::GridCell || axes[k].axis == TargetAxis::Texel)
                    caches += double(s.caches) - double(baseRung.caches);
            }
            const BakeOptions o = targetOptions(base, axes, levels);
            BakeParams p = baseRung.params;
            p.surfels = *o.surfels, p.linksPerCache = *o.links, p.bandsY = *o.bandsY, p.bandsC = *o.bandsC;
            c.ms = predictMs(p, std::max(caches, 1.0));
            candidates.push_back(c);
            return;
        }
        for (size_t l = 0; l < axes[a].values.size(); ++l) {
            if (!single[a][l]) continue;
            levels[a] = uint8_t(l);
            enumerate(a + 1);
        }
    };
    enumerate(0);
    choice.combinations = candidates.size();
    // The predicted error over the views, as the measured one is taken.
    auto predicted = [&](const Candidate& c) {
        double sum = 0.0;
        for (size_t v = 0; v < views; ++v) sum += std::max(e0[v] + choice.errorScale * c.loss[v] + c.gain[v], 0.0);
        return std::sqrt(sum / double(views));
    };
    std::sort(candidates.begin(), candidates.end(), [&](const Candidate& x, const Candidate& y) {
        if (x.ms != y.ms) return x.ms < y.ms;
        return predicted(x) < predicted(y);
    });
    for (TargetRung& r : choice.rungs) r.predictedMs = predictMs(r.params, double(r.caches));
    auto measuredIndex = [&](const TargetLevels& l) -> std::optional<size_t> {
        for (size_t i = 0; i < choice.rungs.size(); ++i)
            if (choice.rungs[i].levels == l) return i;
        return std::nullopt;
    };
    // The cheapest measured rung within the goal, by the cost model.
    auto bestMeasured = [&]() -> std::optional<size_t> {
        std::optional<size_t> best;
        for (size_t i = 0; i < choice.rungs.size(); ++i)
            if (choice.rungs[i].meets && (!best || choice.rungs[i].predictedMs < choice.rungs[*best].predictedMs)) best = i;
        return best;
    };
    // Bakes and measures a combination the models chose; returns it as added to the rungs.
    auto checkCandidate = [&](const Candidate& candidate) -> Result<TargetRung> {
        PIC_TRY_ASSIGN(TargetRung rung, measure(candidate.levels, "check"));
        rung.predictedError = predicted(candidate);
        rung.predictedMs = predictMs(rung.params, double(rung.caches));
        choice.rungs.push_back(rung);
        return rung;
    };
    for (uint32_t check = 0; check < params.maxChecks; ++check) {
        const Candidate* next = nullptr;
        for (const Candidate& c : candidates) {
            if (c.struck || measuredIndex(c.levels) || predicted(c) > goal || !inBudget(c.ms)) continue;
            next = &c;
            break;
        }
        const std::optional<size_t> measuredBest = bestMeasured();
        if (!next || (measuredBest && choice.rungs[*measuredBest].predictedMs <= next->ms)) break;
        const Candidate candidate = *next;
        PIC_TRY_ASSIGN(const TargetRung rung, checkCandidate(candidate));
        if (rung.meets) continue;  // the next round finds it the cheapest measured
        // A miss: the settings' losses add up to more than they did alone, by this much at
        // least, and no combination cheaper on every setting can do better.
        double loss = 0.0, rest = 0.0;
        for (size_t v = 0; v < views; ++v) {
            loss += candidate.loss[v];
            rest += rung.viewErrors[v] * rung.viewErrors[v] - e0[v] - candidate.gain[v];
        }
        if (loss > 0.0) choice.errorScale = std::max(choice.errorScale, rest / loss);
        for (Candidate& c : candidates) {
            bool cheaperEverywhere = true;
            for (size_t a = 0; a < axes.size(); ++a) cheaperEverywhere = cheaperEverywhere && c.levels[a] <= candidate.levels[a];
            c.struck = c.struck || cheaperEverywhere;
        }
    }

    // Nothing within the goal: bake the combination predicted most accurate within the
    // budget, which may still reach it and otherwise comes closest.
    if (!bestMeasured()) {
        const Candidate* closest = nullptr;
        for (const Candidate& c : candidates)
            if (!measuredIndex(c.levels) && inBudget(c.ms) && (!closest || predicted(c) < predicted(*closest)))
                closest = &c;
        if (closest) PIC_TRY(checkCandidate(*closest));
    }

    // The choice: the cheapest measured rung within the goal; failing that, the most accurate
    // one within the budget; failing that, the cheapest.
    if (auto best = bestMeasured()) {
        choice.chosen = *best;
        choice.met = true;
    } else {
        std::optional<size_t> accurate, cheapest;
        for (size_t i = 0; i < choice.rungs.size(); ++i) {
            const TargetRung& r = choice.rungs[i];
            if (inBudget(r.updateMs) && (!accurate || r.error < choice.rungs[*accurate].error)) accurate = i;
            if (!cheapest || r.predictedMs < choice.rungs[*cheapest].predictedMs) cheapest = i;
        }
        choice.chosen = accurate ? *accurate : *cheapest;
    }
    const TargetRung& chosen = choice.rungs[choice.chosen];
    if (lastBake && lastBake->first == chosen.levels) {
        choice.bake = std::move(*lastBake->second);
        choice.report = std::move(lastReport);
    } else if (timingBase && chosen.levels == baseLevels) {
        timingBase->runtime.reset();
        choice.bake = std::move(*timingBase->bake);
        choice.report = std::move(timingBase->report);
    } else {
        std::fprintf(stderr, "picbake: target: baking the choice, %s …\n", chosen.name.c_str());
        PIC_TRY_ASSIGN(BakeData bake, runBake(scene, targetOptions(base, axes, chosen.levels), choice.report));
        choice.bake = std::move(bake);
    }
    choice.pilotSeconds = secondsSince(pilotStart);
    return choice;
}

nlohmann::ordered_json targetJson(const TargetChoice& choice, const TargetErrorParams& params) {
    nlohmann::ordered_json rungs = nlohmann::ordered_json::array();
    for (const TargetRung& r : choice.rungs) {
        nlohmann::ordered_json j = {{"name", r.name},
                                    {"kind", r.kind},
                                    {"surfels", r.params.surfels},
                                    {"links", r.params.linksPerCache},
                                    {"bands", {{"y", r.params.bandsY}, {"c", r.params.bandsC}}},
                                    {"grid_cell", r.params.gridCell},
                                    {"lightmap_texel", r.params.lightmapTexel},
                                    {"link_samples", r.params.linkSamples},
                                    {"caches", r.caches},
                               {"grid_caches", r.gridCaches},
                                    {"bake_seconds", r.bakeSeconds},
                                    {"update_ms", r.updateMs},
                                    {"modelled_update_ms", r.predictedMs},
                                    {"measured_rmse", r.measured},
                                    {"error", r.error}};
        if (r.predictedError) j["predicted_error"] = *r.predictedError;
        j["meets"] = r.meets;
        j["kept"] = r.cached;
        rungs.push_back(std::move(j));
    }
    const TargetRung& chosen = choice.rungs[choice.chosen];
    return {{"error", params.error},
            {"budget_ms", params.budgetMs ? nlohmann::ordered_json(*params.budgetMs) : nlohmann::ordered_json(nullptr)},
            {"component", "indirect"},
            {"met", choice.met},
            {"chosen", chosen.name},
            {"predicted_error", chosen.error},
            {"predicted_update_ms", chosen.updateMs},
            {"safety", params.safety},
            {"models", {{"combinations", choice.combinations},
                        {"error_scale", choice.errorScale},
                        {"cost_ms_per", {{"link_read", choice.cost.coefficients[0]},
                                         {"link_read_coefficient", choice.cost.coefficients[1]},
                                         {"surfel", choice.cost.coefficients[2]},
                                         {"update", choice.cost.coefficients[3]}}}}},
            {"pilot", {{"size", fmt::format("{}x{}", params.size.x, params.size.y)},
                       {"reference_spp", params.spp},
                       {"reference_noise", choice.noise},
                       {"views", choice.views},
                       {"lights", params.lightsPath.empty() ? "scene" : params.lightsPath},
                       {"cache", choice.cachePath},
                       {"seconds", choice.pilotSeconds}}},
            {"rungs", rungs}};
}

}  // namespace pic
