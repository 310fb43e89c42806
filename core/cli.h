#pragma once
/// What every command-line front end repeats (ARCHITECTURE.md §5): the CLI11 parse step and
/// its exit codes, the global flags, error lines, the light-set file and the view of an image
/// (--camera … | --scene-camera N, --size WxH), spelled and checked the same way everywhere.

#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>
#include <glm/glm.hpp>

#include "core/error.h"
#include "core/image.h"
#include "core/scene.h"
#include "core/scene_objects.h"
#include "core/shade_params.h"

namespace pic {

/// Parses argv into `app`. Returns the exit code when the program should stop: 0 after --help
/// (printed on stdout), 2 after a usage error (CLI11's message on stderr); std::nullopt after a
/// successful parse.
std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv);

/// Adds --threads N (worker threads, 0 = all cores) and --quiet (no progress bars) to `app`,
/// applied to the process as they are parsed. Call it before adding subcommands: they fall
/// through to `app`, so the global flags may also follow a subcommand.
void addGlobalFlags(CLI::App& app);

/// Prints "PROGRAM: error: MESSAGE" on stderr; returns the error's exit code (1 or 2).
int reportError(std::string_view program, const Error& error);

/// pic's cache folder (downloaded scenes, the --target-error pilot's measurements):
/// $XDG_CACHE_HOME/pic, else ~/.cache/pic, else /tmp/pic-cache.
std::string defaultCacheDir();

/// Adds --device NAME: the Vulkan device whose name contains NAME (empty: a discrete GPU, else
/// an integrated one, else lavapipe).
CLI::Option* addDeviceOption(CLI::App& command, std::string& name);

/// Adds --lights FILE (a light set JSON; empty: the scene's own lights, as loadLightSet reads it).
CLI::Option* addLightsOption(CLI::App& command, std::string& path);

/// The view of an image as the command line gives it.
struct View {
    glm::uvec2 size{0};
    std::optional<Camera> camera;  ///< --camera; empty: the scene's sceneCameraIndex-th camera
    int sceneCameraIndex = 0;

    /// The camera in `scene`: --camera, else the scene's sceneCameraIndex-th (InvalidInput
    /// naming the index when the scene has fewer cameras).
    Result<Camera> cameraIn(const Scene& scene) const;
};

/// What a view falls back on where the user gives nothing.
struct ViewDefaults {
    std::string size;                ///< empty: --size is required
    std::optional<int> sceneCamera;  ///< empty: --camera or --scene-camera is required
};

/// --camera ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy | --scene-camera N (exclusive) and --size WxH.
class ViewFlags {
public:
    /// Adds the three options to `command`.
    void addTo(CLI::App& command, const ViewDefaults& defaults = {});
    /// The view after parsing, before any file is read: InvalidInput naming a bad --size or
    /// --camera text, or a missing flag that has no default.
    Result<View> toView() const;

private:
    ViewDefaults mDefaults;
    std::string mCameraText, mSizeText;
    int mSceneCamera = 0;
    CLI::Option* mCameraOption = nullptr;
    CLI::Option* mSceneCameraOption = nullptr;
    CLI::Option* mSizeOption = nullptr;
};

/// InvalidInput naming `option` unless `path` ends in one of `extensions` (".exr"; any case)
/// and its directory exists, so that a long run never ends in an unwritable output.
Result<void> checkOutputPath(const std::string& path,
                             std::initializer_list<std::string_view> extensions,
                             std::string_view option);

/// --out FILE (.exr linear float, .png sRGB, .hdr, .tif) and --exposure X (a factor applied
/// before PNG quantisation): where an image goes.
class ImageOutputFlags {
public:
    /// Adds the two options to `command`; --out marked required unless `required` is false
    /// (then check() asks for it).
    void addTo(CLI::App& command, bool required = true);
    /// InvalidInput naming a missing or unwritable --out or an --exposure that is not a finite
    /// number > 0; call it before any long work.
    Result<void> check() const;
    /// Writes `image` to --out with --exposure.
    Result<void> write(const Image& image) const;
    const std::string& path() const { return mPath; }

private:
    std::string mPath;
    float mExposure = 1.0f;
};

/// --component full|direct|indirect, --glossy N and --glossy-weight W (each needs the other):
/// what a view is shaded with (core/shade_params.h).
class ShadeFlags {
public:
    /// Adds the three options to `command`.
    void addTo(CLI::App& command);
    /// The parameters for an image of `size` with `samplesPerPixel` subsamples.
    ShadeParams toParams(glm::uvec2 size, uint32_t samplesPerPixel = 1) const;
    /// --component as given: "full", "direct" or "indirect".
    const std::string& component() const { return mComponent; }

private:
    std::string mComponent = "full";
    float mGlossyExponent = 0.0f;
    float mGlossyWeight = 0.0f;
};

/// --object FILE --transform tx,ty,tz,rx,ry,rz,s, repeatable, paired in order: dynamic
/// objects placed into a view (core/scene_objects.h).
class ObjectFlags {
public:
    /// Adds the two options to `command`.
    void addTo(CLI::App& command);
    /// The placements; InvalidInput when the counts differ or a transform does not parse.
    Result<std::vector<ObjectPlacement>> placements() const;

private:
    std::vector<std::string> mObjects;
    std::vector<std::string> mTransforms;
};

}  // namespace pic
