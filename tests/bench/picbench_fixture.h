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

    ScratchDir mDir;
};

}  // namespace pic::test
