#include "render/gpu_runtime_flags.h"

#include "core/cli.h"
#include "render/passes/shadow_map_pass.h"

namespace pic {

void addGpuRuntimeFlags(CLI::App& command, GpuRuntimeOptions& options) {
    addDeviceOption(command, options.deviceName);
    command
        .add_option("--shadow-map-size", options.shadowMapSize,
                    "gpu backend: texels per side of each shadow-map layer (default 1024)")
        ->check(CLI::Range(gpu::kMinShadowMapSize, gpu::kMaxShadowMapSize));
    command
        .add_option_function<std::string>(
            "--shadow-sides",
            [&options](const std::string& sides) {
                options.shadowEqualFootprint = sides == "footprint";
            },
            "gpu backend: footprint (default; point and spot layers only as wide as gives the "
            "directional layer's texel at the median distance of the surfaces they light) or "
            "uniform (every layer --shadow-map-size wide)")
        ->check(CLI::IsMember({"footprint", "uniform"}));
    command
        .add_option_function<std::string>(
            "--direct-visibility",
            [&options](const std::string& text) {
                // The check below admits only the three names parseDirectVisibility knows.
                options.directVisibility = *gpu::parseDirectVisibility(text);
            },
            "gpu backend: where direct light's visibility comes from: shadow-maps, rays (one "
            "ray per surfel and light, traced on the host with Embree: exact) or auto (default: "
            "rays on a CPU device such as lavapipe, shadow maps on a GPU)")
        ->check(CLI::IsMember({"auto", "shadow-maps", "rays"}));
}

}  // namespace pic
