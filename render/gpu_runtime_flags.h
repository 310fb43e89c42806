#pragma once
/// The GPU backend's command-line flags, spelled and checked the same way by every program
/// that builds a GpuRuntime from them (picserver, picref shade).

#include <CLI/CLI.hpp>

#include "render/gpu_runtime.h"

namespace pic {

/// Adds --device NAME, --shadow-map-size N, --shadow-sides footprint|uniform and
/// --direct-visibility auto|shadow-maps|rays to `command`, each writing its field of
/// `options` as it is parsed (their defaults are the fields' values).
void addGpuRuntimeFlags(CLI::App& command, GpuRuntimeOptions& options);

}  // namespace pic
