#include "bench/bench_common.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "bench/chart.h"
#include "core/cli.h"
#include "core/gltf_loader.h"

namespace pic {

namespace {

/// Creates the folder `path` goes into (the benchmarks' defaults are under out/); a failure
/// shows when the file is written.
void createParentDirectory(const std::string& path) {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    std::error_code ignored;
    if (!parent.empty()) std::filesystem::create_directories(parent, ignored);
}

}  // namespace

double median(std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

BakeOptions settingOptions(const std::string& setting, const std::string& linkMode,
                           uint32_t chromaBands) {
    BakeOptions options;
    const bool high = setting == "high";
    options.surfels = high ? 131072u : 32768u;
    options.links = high ? 254u : 128u;
    options.bandsY = high ? 4u : 3u;
    options.bandsC = chromaBands;
    options.linkMode = linkMode == "sh" ? LinkMode::Sh : LinkMode::Rtp;
    options.gridCaches = GridCaches::Volume;  // the paper's grid fills the space around the scene
    return options;
}

LightSet changedLights(const LightSet& base, int k, float step, const std::string& change) {
    LightSet lights = base;
    const float sign = (k % 2) ? 1.0f : -1.0f;
    const float offset = step * sign * float(1 + k % 3);
    if (change == "recolour") {
        for (Light& light : lights.lights) light.intensity *= 1.0f + 0.01f * sign * float(1 + k % 3);
        return lights;
    }
    // move-one: the first point or spot light (what dragging a lamp does), else the first.
    auto first = std::find_if(lights.lights.begin(), lights.lights.end(),
                              [](const Light& l) { return l.type != LightType::Directional; });
    if (first == lights.lights.end()) first = lights.lights.begin();
    for (auto it = lights.lights.begin(); it != lights.lights.end(); ++it) {
        if (change == "move-one" && it != first) continue;
        if (it->type == LightType::Directional)
            it->direction = glm::normalize(it->direction + glm::vec3(0.01f * offset / step, 0.0f, 0.0f));
        else
            it->position.x += offset;
    }
    return lights;
}

std::unique_ptr<BenchInputs> loadBenchInputs(const std::string& scenePath, const std::string& lightsPath) {
    auto inputs = std::make_unique<BenchInputs>();
    auto scene = loadScene(scenePath);
    if (!scene) {
        reportError(scene.error());
        return nullptr;
    }
    inputs->scene = std::move(*scene);
    auto lights = loadLightSet(lightsPath, inputs->scene);
    if (!lights) {
        reportError(lights.error());
        return nullptr;
    }
    inputs->lights = std::move(*lights);
    if (inputs->lights.lights.empty())
        std::fprintf(stderr, "picbench: warning: the light set has no punctual lights\n");
    // Built over the scene in its final place: the Embree scene keeps a pointer to it.
    auto rays = EmbreeScene::create(inputs->scene);
    if (!rays) {
        reportError(rays.error());
        return nullptr;
    }
    inputs->rays = std::move(*rays);
    return inputs;
}

int reportError(const Error& error) { return reportError("picbench", error); }

std::string chartPathFor(const std::string& jsonPath) {
    const std::string suffix = ".json";
    if (jsonPath.size() > suffix.size() && jsonPath.ends_with(suffix))
        return jsonPath.substr(0, jsonPath.size() - suffix.size()) + ".png";
    return jsonPath + ".png";
}

int writeChartFile(const Chart& chart, const std::string& path) {
    createParentDirectory(path);
    if (auto written = writeChart(chart, path); !written) return reportError(written.error());
    std::printf("written %s\n", path.c_str());
    return 0;
}

Image imagesSideBySide(const std::vector<const Image*>& images) {
    uint32_t width = 0, height = 0;
    for (const Image* image : images) {
        width += image->width;
        height = std::max(height, image->height);
    }
    Image out(width, height);
    uint32_t left = 0;
    for (const Image* image : images) {
        for (uint32_t y = 0; y < image->height; ++y)
            for (uint32_t x = 0; x < image->width; ++x) out.at(left + x, y) = image->at(x, y);
        left += image->width;
    }
    return out;
}

int writeJson(const nlohmann::ordered_json& json, const std::string& path) {
    createParentDirectory(path);
    std::ofstream out(path);
    out << json.dump(2) << "\n";
    if (!out) {
        std::fprintf(stderr, "picbench: error: could not write %s\n", path.c_str());
        return 1;
    }
    std::printf("written %s\n", path.c_str());
    return 0;
}

}  // namespace pic
