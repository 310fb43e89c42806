#include "core/cli.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "core/camera.h"
#include "core/image.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv) {
    try {
        app.parse(argc, argv);
        return std::nullopt;
    } catch (const CLI::ParseError& e) {
        // --help ends parsing as an "error" with exit code 0; app.exit prints it on stdout and
        // every real error on stderr.
        return app.exit(e) == 0 ? 0 : 2;
    }
}

void addGlobalFlags(CLI::App& app) {
    app.fallthrough();
    app.add_option_function<int>("--threads", [](const int& threads) { setWorkerCount(threads); },
                                 "worker threads (0 = all cores)")
        ->check(CLI::NonNegativeNumber);
    app.add_flag_callback("--quiet", [] { Progress::setEnabled(false); }, "no progress bars");
}

int reportError(std::string_view program, const Error& error) {
    fmt::print(stderr, "{}: error: {}\n", program, error.message);
    return exitCode(error);
}

std::string defaultCacheDir() {
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
        return (std::filesystem::path(xdg) / "pic").string();
    if (const char* home = std::getenv("HOME"); home && *home)
        return (std::filesystem::path(home) / ".cache" / "pic").string();
    return "/tmp/pic-cache";
}

CLI::Option* addDeviceOption(CLI::App& command, std::string& name) {
    return command.add_option("--device", name,
                              "Vulkan device whose name contains this (default: a discrete GPU, "
                              "else integrated, else lavapipe)");
}

CLI::Option* addLightsOption(CLI::App& command, std::string& path) {
    return command.add_option("--lights", path, "light set JSON (default: the scene's lights)");
}

Result<Camera> View::cameraIn(const Scene& scene) const {
    if (camera) return *camera;
    return sceneCamera(scene, sceneCameraIndex);
}

void ViewFlags::addTo(CLI::App& command, const ViewDefaults& defaults) {
    mDefaults = defaults;
    mSizeText = defaults.size;
    mSceneCamera = defaults.sceneCamera.value_or(0);
    mCameraOption = command.add_option(
        "--camera", mCameraText,
        "pinhole camera ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy (eye, target, up, vertical field of view "
        "in degrees)");
    mSceneCameraOption = command.add_option(
        "--scene-camera", mSceneCamera,
        defaults.sceneCamera
            ? fmt::format("the glTF's N-th camera (0-based; default {})", *defaults.sceneCamera)
            : std::string("the glTF's N-th camera (0-based)"));
    mCameraOption->excludes(mSceneCameraOption);
    mSizeOption = command.add_option("--size", mSizeText,
                                     defaults.size.empty()
                                         ? std::string("image size WxH")
                                         : fmt::format("image size WxH (default {})", defaults.size));
}

Result<View> ViewFlags::toView() const {
    if (mSizeOption->count() == 0 && mDefaults.size.empty())
        return fail(ErrorCode::InvalidInput, "--size is required");
    View view;
    PIC_TRY_ASSIGN(view.size, parseImageSize(mSizeText));
    if (mCameraOption->count() > 0) {
        PIC_TRY_ASSIGN(view.camera, parseCamera(mCameraText));
    } else if (mSceneCameraOption->count() == 0 && !mDefaults.sceneCamera) {
        return fail(ErrorCode::InvalidInput, "one of --camera or --scene-camera is required");
    }
    view.sceneCameraIndex = mSceneCamera;
    return view;
}

Result<void> checkOutputPath(const std::string& path,
                             std::initializer_list<std::string_view> extensions,
                             std::string_view option) {
    namespace fs = std::filesystem;
    std::string extension = fs::path(path).extension().string();
    for (char& ch : extension) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (std::find(extensions.begin(), extensions.end(), extension) == extensions.end())
        return fail(ErrorCode::InvalidInput, "{} '{}' has extension '{}'; expected one of {}",
                    option, path, extension, fmt::join(extensions, ", "));
    const fs::path directory = fs::path(path).parent_path();
    std::error_code ec;
    if (!directory.empty() && !fs::is_directory(directory, ec))
        return fail(ErrorCode::InvalidInput, "{} '{}': directory '{}' does not exist", option, path,
                    directory.string());
    return {};
}

void ImageOutputFlags::addTo(CLI::App& command, bool required) {
    command.add_option("--out", mPath, "image to write (.exr linear float, .png sRGB, .hdr, .tif)")
        ->required(required);
    command.add_option("--exposure", mExposure, "factor applied before PNG quantisation (default 1)");
}

Result<void> ImageOutputFlags::check() const {
    if (mPath.empty()) return fail(ErrorCode::InvalidInput, "--out is required");
    PIC_TRY(checkOutputPath(mPath, {".exr", ".png", ".hdr", ".tif", ".tiff"}, "--out"));
    if (!(std::isfinite(mExposure) && mExposure > 0.0f))
        return fail(ErrorCode::InvalidInput, "--exposure {} must be a finite number > 0",
                    mExposure);
    return {};
}

Result<void> ImageOutputFlags::write(const Image& image) const {
    return writeImage(mPath, image, mExposure);
}

void ShadeFlags::addTo(CLI::App& command) {
    command.add_option("--component", mComponent,
                       "what the image holds: full (default), direct, indirect, or glossy (the "
                       "--glossy lobe's part of the indirect light alone)")
        ->check(CLI::IsMember({"full", "direct", "indirect", "glossy"}));
    auto* glossy = command.add_option("--glossy", mGlossyExponent,
                                      "Phong exponent of an added glossy lobe (> 0)")
                       ->check(CLI::PositiveNumber);
    auto* glossyWeight = command.add_option("--glossy-weight", mGlossyWeight,
                                            "factor on the glossy lobe's radiance (≥ 0)")
                             ->check(CLI::NonNegativeNumber);
    glossy->needs(glossyWeight);
    glossyWeight->needs(glossy);
}

void ObjectFlags::addTo(CLI::App& command) {
    command.add_option("--object", mObjects,
                       "a glTF model not in the bake, shaded from the grid caches (repeatable; "
                       "each needs its --transform)");
    command.add_option("--transform", mTransforms,
                       "tx,ty,tz,rx,ry,rz,s: where the --object of the same position goes "
                       "(metres; degrees about x, then y, then z; uniform scale)");
}

Result<std::vector<ObjectPlacement>> ObjectFlags::placements() const {
    return parseObjectFlags(mObjects, mTransforms);
}

ShadeParams ShadeFlags::toParams(glm::uvec2 size, uint32_t samplesPerPixel) const {
    ShadeParams params;
    params.width = size.x;
    params.height = size.y;
    params.component = mComponent == "direct"     ? ShadeComponent::Direct
                       : mComponent == "indirect" ? ShadeComponent::Indirect
                       : mComponent == "glossy"   ? ShadeComponent::Glossy
                                                  : ShadeComponent::Full;
    params.glossyExponent = mGlossyExponent;
    params.glossyWeight = mGlossyWeight;
    params.samplesPerPixel = samplesPerPixel;
    return params;
}

}  // namespace pic
