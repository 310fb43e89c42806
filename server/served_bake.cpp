#include "server/served_bake.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/bake_file.h"
#include "core/frame_codec.h"
#include "core/gltf_loader.h"
#include "core/hash.h"
#include "core/light_set.h"
#include "render/cpu_runtime.h"
#include "render/gpu_runtime.h"
#include "render/sky_lighting.h"
#include "server/web_scene.h"

namespace pic {

namespace {

namespace fs = std::filesystem;

Result<std::string> readFile(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    if (!file) return fail(ErrorCode::NotFound, "cannot open '{}'", path);
    std::string bytes{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    if (file.bad()) return fail(ErrorCode::Io, "could not read '{}'", path);
    return bytes;
}

template <class T>
std::string bytesOf(const std::vector<T>& values) {
    std::string bytes(values.size() * sizeof(T), '\0');
    if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
    return bytes;
}

}  // namespace

Result<std::unique_ptr<ServedBake>> ServedBake::load(const std::string& bakePath,
                                                     const std::string& scenePath,
                                                     const ServeOptions& options) {
    std::unique_ptr<ServedBake> served(new ServedBake());
    PIC_TRY_ASSIGN(served->mScene, loadScene(scenePath));
    // The cheap header check first: a bake of another scene is refused before its arrays load.
    PIC_TRY_ASSIGN(BakeFileInfo info, inspectBakeFile(bakePath));
    PIC_TRY(checkSceneMatches(info, served->mScene.hash, scenePath));
    PIC_TRY_ASSIGN(served->mBake, readBakeFile(bakePath));
    PIC_TRY(checkRuntimeBake(served->mScene, served->mBake));
    PIC_TRY_ASSIGN(std::string bakeBytes, readFile(bakePath));
    served->mId = fmt::format("{:016x}", hashBytes(bakeBytes.data(), bakeBytes.size()));

    PIC_TRY_ASSIGN(served->mRays, EmbreeScene::create(served->mScene));
    if (options.backend == "gpu") {
        PIC_TRY_ASSIGN(auto gpu, GpuRuntime::create(served->mScene, *served->mRays, served->mBake,
                                                    options.bounces, options.gpu));
        served->mDevice = gpu->context().deviceName();
        served->mDirectVisibility = gpu::directVisibilityName(gpu->directVisibility());
        served->mRuntime = std::move(gpu);
    } else if (options.backend == "cpu") {
        PIC_TRY_ASSIGN(served->mRuntime, createCpuRuntime(served->mScene, *served->mRays,
                                                          served->mBake, options.bounces));
    } else {
        return fail(ErrorCode::InvalidInput, "backend must be \"gpu\" or \"cpu\", got \"{}\"",
                    options.backend);
    }

    PIC_TRY(served->warmUp());

    v1::BakeSummary& summary = served->mSummary;
    summary.set_bake_id(served->mId);
    summary.set_scene_name(fs::path(scenePath).filename().string());
    summary.set_scene_hash(served->mScene.hash);
    summary.set_triangles(uint32_t(served->mScene.triangles.size()));
    summary.set_surfels(uint32_t(served->mBake.surfels.size()));
    summary.set_caches(uint32_t(served->mBake.caches.size()));
    summary.set_links_per_cache(served->mBake.params.linksPerCache);
    summary.set_link_mode(served->mBake.params.linkMode == LinkMode::Sh ? "sh" : "rtp");
    PIC_TRY(served->buildAssets(scenePath));
    return served;
}

Result<void> ServedBake::buildAssets(const std::string& scenePath) {
    v1::SceneHeader& header = mHeader;
    header.set_bake_id(mId);
    header.set_scene_hash(mScene.hash);
    header.set_bands_y(mBake.params.bandsY);
    header.set_bands_c(mBake.params.bandsC);
    v1::GridLayout& grid = *header.mutable_grid();
    grid.mutable_origin()->set_x(mBake.grid.origin.x);
    grid.mutable_origin()->set_y(mBake.grid.origin.y);
    grid.mutable_origin()->set_z(mBake.grid.origin.z);
    grid.set_cell_size(mBake.grid.cellSize);
    grid.set_dims_x(mBake.grid.dims.x);
    grid.set_dims_y(mBake.grid.dims.y);
    grid.set_dims_z(mBake.grid.dims.z);
    header.set_lightmap_width(mBake.lightmap.width);
    header.set_lightmap_height(mBake.lightmap.height);
    header.set_caches(uint32_t(mBake.caches.size()));

    const auto add = [&](std::string name, std::string bytes) {
        v1::AssetInfo& asset = *header.add_assets();
        asset.set_name(std::move(name));
        asset.set_size(bytes.size());
        header.set_total_bytes(header.total_bytes() + bytes.size());
        mAssetBytes.push_back(std::move(bytes));
    };
    PIC_TRY_ASSIGN(std::vector<std::string> files, sceneFiles(scenePath));
    const fs::path folder = fs::path(scenePath).parent_path();
    header.set_scene_file("scene/" + files.front());
    for (const std::string& file : files) {
        PIC_TRY_ASSIGN(std::string bytes, readFile((folder / file).string()));
        add("scene/" + file, std::move(bytes));
    }
    add("layout/triangle_uvs", bytesOf(mBake.lightmap.triangleUvs));
    add("layout/grid_caches", bytesOf(mBake.grid.cacheIndex));
    add("layout/lightmap_caches", bytesOf(mBake.lightmap.cacheIndex));
    return {};
}

const Result<std::string>& ServedBake::webScene() const {
    std::call_once(mWebSceneBuilt, [&] {
        const auto start = std::chrono::steady_clock::now();
        mWebScene = webSceneOf(mScene, mBake, mId);
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        if (mWebScene)
            std::fprintf(stderr,
                         "picserver: bake %s: the browsers' scene takes %zu bytes (%.0f ms)\n",
                         mId.c_str(), mWebScene->size(), ms);
        else
            std::fprintf(stderr, "picserver: bake %s: no browsers' scene: %s\n", mId.c_str(),
                         mWebScene.error().message.c_str());
    });
    return mWebScene;
}

Result<void> ServedBake::warmUp() {
    const auto start = std::chrono::steady_clock::now();
    PIC_TRY(mRuntime->setLights(defaultLightSet(mScene)));
    mWarmUpMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return {};
}

Result<void> ServedBake::checkLights(const LightSet& lights) const {
    PIC_TRY(checkRuntimeLights(lights, mScene));
    return checkSkyLights(lights, mScene, mBake);
}

Result<void> ServedBake::relight(const LightSet& lights, UpdateStats& stats, HalfFrame& frame,
                                 const BounceObserver& observer) {
    std::lock_guard lock(mRuntimeMutex);
    PIC_TRY_ASSIGN(const CacheValues* values, mRuntime->setLights(lights, &stats, observer));
    frame = halfFrameOf(*values);
    return {};
}

}  // namespace pic
