#include "core/cli.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/parallel.h"

namespace pic {
namespace {

/// parseCommandLine over `args` (the program name is added).
std::optional<int> parse(CLI::App& app, std::vector<std::string> args) {
    args.insert(args.begin(), "prog");
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    return parseCommandLine(app, int(argv.size()), argv.data());
}

/// A command with the view flags; `view(args)` parses and returns its view.
class ViewCommand {
public:
    explicit ViewCommand(const ViewDefaults& defaults = {}) { mFlags.addTo(mApp, defaults); }
    Result<View> view(const std::vector<std::string>& args) {
        std::optional<int> exit = parse(mApp, args);
        EXPECT_FALSE(exit) << "usage error, exit " << *exit;
        return mFlags.toView();
    }

private:
    CLI::App mApp{"view"};
    ViewFlags mFlags;
};

/// Expects `view` to be refused as InvalidInput with a message that contains `part`.
void expectRefused(const Result<View>& view, const std::string& part) {
    ASSERT_FALSE(view) << "accepted";
    EXPECT_EQ(view.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(view.error().message.find(part), std::string::npos) << view.error().message;
}

Scene sceneWithCameras(size_t count) {
    Scene scene;
    scene.sourcePath = "room.gltf";
    scene.cameras.resize(count);
    for (size_t i = 0; i < count; ++i) scene.cameras[i].name = "camera " + std::to_string(i);
    return scene;
}

TEST(CliParse, HelpExitsWithZero) {
    CLI::App app{"test"};
    addGlobalFlags(app);
    testing::internal::CaptureStdout();
    EXPECT_EQ(parse(app, {"--help"}), 0);
    const std::string help = testing::internal::GetCapturedStdout();
    EXPECT_NE(help.find("--threads"), std::string::npos) << help;
    EXPECT_NE(help.find("--quiet"), std::string::npos) << help;
}

TEST(CliParse, UsageErrorsExitWithTwoNamingTheValue) {
    CLI::App app{"test"};
    addGlobalFlags(app);
    testing::internal::CaptureStderr();
    EXPECT_EQ(parse(app, {"--no-such-flag"}), 2);
    EXPECT_NE(testing::internal::GetCapturedStderr().find("--no-such-flag"), std::string::npos);
    testing::internal::CaptureStderr();
    EXPECT_EQ(parse(app, {"--threads", "many"}), 2);
    EXPECT_NE(testing::internal::GetCapturedStderr().find("many"), std::string::npos);
    testing::internal::CaptureStderr();
    EXPECT_EQ(parse(app, {"--threads", "-3"}), 2);
    EXPECT_NE(testing::internal::GetCapturedStderr().find("-3"), std::string::npos);
}

TEST(CliParse, GlobalFlagsApplyAndMayFollowASubcommand) {
    CLI::App app{"test"};
    addGlobalFlags(app);
    app.add_subcommand("run", "a subcommand");
    EXPECT_EQ(parse(app, {"run", "--threads", "1", "--quiet"}), std::nullopt);
    EXPECT_EQ(workerCount(), 1);
    setWorkerCount(0);
}

TEST(CliParse, CameraAndSceneCameraExcludeEachOther) {
    CLI::App app{"test"};
    ViewFlags flags;
    flags.addTo(app);
    testing::internal::CaptureStderr();
    EXPECT_EQ(parse(app, {"--camera", "0,0,1,0,0,0,0,1,0,45", "--scene-camera", "0", "--size", "4x4"}),
              2);
    EXPECT_NE(testing::internal::GetCapturedStderr().find("--scene-camera"), std::string::npos);
}

TEST(CliView, ReadsCameraAndSize) {
    ViewCommand command;
    auto view = command.view({"--camera", "0,0.5,2, 0,0.5,0, 0,1,0, 40", "--size", "64x32"});
    ASSERT_TRUE(view) << view.error().message;
    EXPECT_EQ(view->size, glm::uvec2(64, 32));
    // --camera wins over the scene's cameras, even when the scene has none.
    auto camera = view->cameraIn(sceneWithCameras(0));
    ASSERT_TRUE(camera) << camera.error().message;
    EXPECT_EQ(camera->eye, glm::vec3(0.0f, 0.5f, 2.0f));
    EXPECT_EQ(camera->fovyDegrees, 40.0f);
}

TEST(CliView, RefusesBadCameraText) {
    ViewCommand wrongCount;
    expectRefused(wrongCount.view({"--camera", "1,2,3", "--size", "4x4"}), "1,2,3");
    ViewCommand notNumbers;
    expectRefused(notNumbers.view({"--camera", "0,0,1,0,0,0,0,1,0,wide", "--size", "4x4"}), "wide");
    ViewCommand zeroFov;
    expectRefused(zeroFov.view({"--camera", "0,0,1,0,0,0,0,1,0,0", "--size", "4x4"}),
                  "0,0,1,0,0,0,0,1,0,0");
    ViewCommand empty;
    expectRefused(empty.view({"--camera", "", "--size", "4x4"}), "--camera");
}

TEST(CliView, RefusesBadSizes) {
    for (const char* size : {"0x5", "5x", "20000x1", "abc", "5x0", "-5x5"}) {
        ViewCommand command;
        expectRefused(command.view({"--scene-camera", "0", "--size", size}), size);
    }
}

TEST(CliView, SizeAndCameraAreRequiredWithoutDefaults) {
    ViewCommand noSize;
    expectRefused(noSize.view({"--scene-camera", "0"}), "--size is required");
    ViewCommand noCamera;
    expectRefused(noCamera.view({"--size", "4x4"}), "one of --camera or --scene-camera is required");
}

TEST(CliView, DefaultsFillWhatIsNotGiven) {
    ViewCommand command({.size = "256x128", .sceneCamera = 1});
    auto view = command.view({});
    ASSERT_TRUE(view) << view.error().message;
    EXPECT_EQ(view->size, glm::uvec2(256, 128));
    EXPECT_FALSE(view->camera);
    auto camera = view->cameraIn(sceneWithCameras(2));
    ASSERT_TRUE(camera) << camera.error().message;
    EXPECT_EQ(camera->name, "camera 1");
    ViewCommand given({.size = "256x128", .sceneCamera = 1});
    auto first = given.view({"--scene-camera", "0", "--size", "8x8"});
    ASSERT_TRUE(first) << first.error().message;
    EXPECT_EQ(first->size, glm::uvec2(8, 8));
    EXPECT_EQ(first->cameraIn(sceneWithCameras(2))->name, "camera 0");
}

TEST(CliView, SceneCameraBeyondTheScenesIsRefusedNamingIt) {
    ViewCommand command;
    auto view = command.view({"--scene-camera", "3", "--size", "4x4"});
    ASSERT_TRUE(view) << view.error().message;
    auto camera = view->cameraIn(sceneWithCameras(2));
    ASSERT_FALSE(camera);
    EXPECT_EQ(camera.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(camera.error().message.find("--scene-camera 3"), std::string::npos)
        << camera.error().message;
    EXPECT_NE(camera.error().message.find("room.gltf"), std::string::npos) << camera.error().message;
    ViewCommand negative;
    auto below = negative.view({"--scene-camera", "-1", "--size", "4x4"});
    ASSERT_TRUE(below) << below.error().message;
    EXPECT_FALSE(below->cameraIn(sceneWithCameras(2)));
}

TEST(CliReport, PrefixesTheProgramAndReturnsTheExitCode) {
    testing::internal::CaptureStderr();
    EXPECT_EQ(reportError("picx", Error{ErrorCode::InvalidInput, "bad value 7"}), 2);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "picx: error: bad value 7\n");
    testing::internal::CaptureStderr();
    EXPECT_EQ(reportError("picx", Error{ErrorCode::Io, "disk full"}), 1);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "picx: error: disk full\n");
}

TEST(CliShade, FlagsGiveTheShadeParameters) {
    CLI::App app{"shade"};
    ShadeFlags flags;
    flags.addTo(app);
    ASSERT_EQ(parse(app, {"--component", "indirect", "--glossy", "32", "--glossy-weight", "0.5"}),
              std::nullopt);
    const ShadeParams params = flags.toParams({64, 48}, 4);
    EXPECT_EQ(params.width, 64u);
    EXPECT_EQ(params.height, 48u);
    EXPECT_EQ(params.component, ShadeComponent::Indirect);
    EXPECT_EQ(params.glossyExponent, 32.0f);
    EXPECT_EQ(params.glossyWeight, 0.5f);
    EXPECT_EQ(params.samplesPerPixel, 4u);
    EXPECT_EQ(flags.component(), "indirect");

    CLI::App defaults{"shade"};
    ShadeFlags none;
    none.addTo(defaults);
    ASSERT_EQ(parse(defaults, {}), std::nullopt);
    EXPECT_EQ(none.toParams({8, 8}).component, ShadeComponent::Full);
    EXPECT_EQ(none.toParams({8, 8}).glossyWeight, 0.0f);
}

TEST(CliShade, BadComponentAndGlossyAloneAreUsageErrors) {
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"--component", "specular"}, {"--glossy", "8"},
          {"--glossy-weight", "0.5"}, {"--glossy", "-1", "--glossy-weight", "1"}}) {
        CLI::App app{"shade"};
        ShadeFlags flags;
        flags.addTo(app);
        testing::internal::CaptureStderr();
        EXPECT_EQ(parse(app, args), 2) << args[0];
        testing::internal::GetCapturedStderr();
    }
}

TEST(CliOutput, OutAndExposureAreCheckedBeforeAnyWork) {
    auto checked = [](const std::vector<std::string>& args) {
        CLI::App app{"out"};
        ImageOutputFlags flags;
        flags.addTo(app, false);
        EXPECT_EQ(parse(app, args), std::nullopt);
        return flags.check();
    };
    EXPECT_TRUE(checked({"--out", "image.exr"}));
    EXPECT_TRUE(checked({"--out", "IMAGE.PNG", "--exposure", "4"}));
    const std::vector<std::pair<std::vector<std::string>, std::string>> refused = {
        {{}, "--out is required"},
        {{"--out", "image.jpg"}, "'.jpg'"},
        {{"--out", "no/such/folder/image.exr"}, "directory 'no/such/folder' does not exist"},
        {{"--out", "image.exr", "--exposure", "0"}, "--exposure 0"},
        {{"--out", "image.exr", "--exposure", "-2"}, "--exposure -2"},
    };
    for (const auto& [args, part] : refused) {
        const Result<void> result = checked(args);
        ASSERT_FALSE(result) << part;
        EXPECT_EQ(result.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(result.error().message.find(part), std::string::npos) << result.error().message;
    }
}

TEST(CliOutput, RequiredOutIsAUsageError) {
    CLI::App app{"out"};
    ImageOutputFlags flags;
    flags.addTo(app);
    testing::internal::CaptureStderr();
    EXPECT_EQ(parse(app, {}), 2);
    EXPECT_NE(testing::internal::GetCapturedStderr().find("--out"), std::string::npos);
}

}  // namespace
}  // namespace pic
