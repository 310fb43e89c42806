#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <unistd.h>

#include "fuzz/fuzz.h"

namespace pic::fuzz {

const std::string& scratchFile(std::string_view bytes, const char* extension) {
    // Removed when the process exits normally (a crash leaves it for the post-mortem).
    struct Directory {
        std::filesystem::path path;
        Directory() {
            const std::filesystem::path base = std::filesystem::is_directory("/dev/shm")
                                                   ? std::filesystem::path("/dev/shm")
                                                   : std::filesystem::temp_directory_path();
            path = base / fmt::format("pic_fuzz_{}", ::getpid());
            std::filesystem::create_directories(path);
        }
        ~Directory() {
            std::error_code ec;
            std::filesystem::remove_all(path, ec);
        }
    };
    static const Directory scratch;
    const std::string directory = scratch.path.string();
    static std::string path;
    path = fmt::format("{}/input{}", directory, extension);
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
}

}  // namespace pic::fuzz
