#pragma once
/// Running the project's command-line tools from tests: each test gets a scratch directory of
/// its own, and a command's exit code and output come back as strings.

#include <filesystem>
#include <string>

namespace pic::test {

/// A fresh directory under the system's temp folder, named after `prefix`, the process and
/// the running test; removed with everything in it when the object goes.
class ScratchDir {
public:
    explicit ScratchDir(const std::string& prefix);
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    const std::filesystem::path& path() const { return mPath; }
    /// `name` inside the directory.
    std::filesystem::path operator/(const std::string& name) const { return mPath / name; }

private:
    std::filesystem::path mPath;
};

struct CommandResult {
    int exitCode = -1;  ///< the process's exit status; −1 when it did not exit normally
    std::string out;    ///< standard output
    std::string err;    ///< standard error
};

/// Runs `commandLine` through the shell (arguments quoted by the caller) with standard input
/// from /dev/null; its output goes through files in `dir`.
CommandResult runCommand(const std::string& commandLine, const std::filesystem::path& dir);

/// The whole file, or "" when it cannot be read.
std::string readFile(const std::filesystem::path& path);

}  // namespace pic::test
