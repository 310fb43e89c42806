#include "tests/support/command.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

namespace pic::test {

namespace fs = std::filesystem;

ScratchDir::ScratchDir(const std::string& prefix) {
    const testing::TestInfo* test = testing::UnitTest::GetInstance()->current_test_info();
    std::string name = prefix + "_" + std::to_string(::getpid());
    if (test) name += std::string("_") + test->test_suite_name() + "_" + test->name();
    // Parameterised names hold '/'.
    for (char& c : name)
        if (c == '/') c = '_';
    mPath = fs::temp_directory_path() / name;
    fs::create_directories(mPath);
}

ScratchDir::~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(mPath, ignored);
}

std::string readFile(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

CommandResult runCommand(const std::string& commandLine, const fs::path& dir) {
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string command =
        commandLine + " >'" + out.string() + "' 2>'" + err.string() + "' </dev/null";
    const int status = std::system(command.c_str());
    CommandResult result;
    result.exitCode = status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = readFile(out);
    result.err = readFile(err);
    return result;
}

}  // namespace pic::test
