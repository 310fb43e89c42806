// The GPU backend's command-line flags (render/gpu_runtime_flags.h): each writes its field of
// GpuRuntimeOptions, the defaults are the options' own, bad values are usage errors.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/cli.h"
#include "render/gpu_runtime_flags.h"

namespace pic {
namespace {

/// Parses `args` into fresh options; the exit code parseCommandLine gave, if any.
std::optional<int> parse(std::vector<std::string> args, GpuRuntimeOptions& options) {
    CLI::App app{"gpu"};
    addGpuRuntimeFlags(app, options);
    args.insert(args.begin(), "prog");
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    return parseCommandLine(app, int(argv.size()), argv.data());
}

TEST(GpuRuntimeFlags, EachFlagWritesItsOption) {
    GpuRuntimeOptions options;
    ASSERT_EQ(parse({"--device", "llvmpipe", "--shadow-map-size", "512", "--shadow-sides",
                     "uniform", "--direct-visibility", "shadow-maps"},
                    options),
              std::nullopt);
    EXPECT_EQ(options.deviceName, "llvmpipe");
    EXPECT_EQ(options.shadowMapSize, 512u);
    EXPECT_FALSE(options.shadowEqualFootprint);
    EXPECT_EQ(options.directVisibility, gpu::DirectVisibility::ShadowMaps);

    GpuRuntimeOptions rays;
    ASSERT_EQ(parse({"--direct-visibility", "rays", "--shadow-sides", "footprint"}, rays),
              std::nullopt);
    EXPECT_EQ(rays.directVisibility, gpu::DirectVisibility::Rays);
    EXPECT_TRUE(rays.shadowEqualFootprint);
}

TEST(GpuRuntimeFlags, DefaultsAreTheOptionsOwn) {
    GpuRuntimeOptions options;
    options.directVisibility = gpu::DirectVisibility::Rays;
    ASSERT_EQ(parse({"--direct-visibility", "auto"}, options), std::nullopt);
    EXPECT_EQ(options.directVisibility, std::nullopt);

    GpuRuntimeOptions untouched;
    ASSERT_EQ(parse({}, untouched), std::nullopt);
    const GpuRuntimeOptions defaults;
    EXPECT_EQ(untouched.deviceName, defaults.deviceName);
    EXPECT_EQ(untouched.shadowMapSize, defaults.shadowMapSize);
    EXPECT_EQ(untouched.shadowEqualFootprint, defaults.shadowEqualFootprint);
    EXPECT_EQ(untouched.directVisibility, defaults.directVisibility);
}

TEST(GpuRuntimeFlags, BadValuesAreUsageErrorsNamingThem) {
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"--shadow-map-size", "8"}, {"--shadow-map-size", "16385"},
          {"--shadow-sides", "wide"}, {"--direct-visibility", "raytraced"}}) {
        GpuRuntimeOptions options;
        testing::internal::CaptureStderr();
        EXPECT_EQ(parse(args, options), 2) << args[0];
        const std::string message = testing::internal::GetCapturedStderr();
        EXPECT_NE(message.find(args[1]), std::string::npos) << message;
    }
}

}  // namespace
}  // namespace pic
