#pragma once
/// The fixture of the picbench tests: picbench run as users run it (--quiet), in a scratch
/// directory of the test's own.

#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "tests/support/command.h"

namespace pic::test {

class PicbenchTest : public ::testing::Test {
protected:
    /// `scratchPrefix` names the scratch directory (ScratchDir).
    explicit PicbenchTest(const std::string& scratchPrefix) : mDir(scratchPrefix) {}

    /// Runs picbench with `args`; returns its exit code, stderr in `err`.
    int run(const std::string& args, std::string& err) {
        CommandResult result =
            runCommand(std::string(PIC_PICBENCH) + " --quiet " + args, mDir.path());
        err = std::move(result.err);
        return result.exitCode;
    }

    /// A small bake of the Cornell box (4,096 surfels, 32 links) in the scratch directory: its
    /// path, empty (with the failure added) when picbake fails.
    std::string smallCornellBake() {
        const std::string path = (mDir.path() / "cornell.pic").string();
        CommandResult baked = runCommand(std::string(PIC_PICBAKE) + " --quiet bake " +
                                             cornellScene() + " -o " + path +
                                             " --surfels 4096 --links 32",
                                         mDir.path());
        EXPECT_EQ(baked.exitCode, 0) << baked.err;
        return baked.exitCode == 0 ? path : std::string();
    }
    static std::string cornellScene() { return std::string(PIC_TEST_SCENE_DIR) + "/cornell.gltf"; }

    ScratchDir mDir;
};

}  // namespace pic::test
