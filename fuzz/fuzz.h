#pragma once
/// What the fuzz targets share. Each target is one file defining LLVMFuzzerTestOneInput over
/// bytes an attacker could send or place (fuzz/README.md); it returns 0 for every input and
/// aborts (PIC_CHECK) when an invariant the code promises breaks, so that libFuzzer, or
/// the corpus replay CTest runs, reports it as a crash.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/error.h"

namespace pic::fuzz {

/// The input as text.
inline std::string_view text(const uint8_t* data, size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

/// A file of this process's own holding `bytes`, for the readers that take a path; rewritten
/// for every input. In /dev/shm when there is one, so that fuzzing does not wear a disk.
const std::string& scratchFile(std::string_view bytes, const char* extension);

}  // namespace pic::fuzz
