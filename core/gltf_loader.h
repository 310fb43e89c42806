#pragma once
/// Loads glTF 2.0 files (.gltf and .glb) into the flat world-space Scene model.

#include <string>

#include "core/error.h"
#include "core/scene.h"

namespace pic {

/// What a caller needs from the file beyond it being valid glTF.
struct LoadOptions {
    bool requireGeometry = true;  ///< fail with InvalidInput when no triangle survives loading
};

/// Reads the glTF's default scene: triangles instanced under their node transforms, the
/// materials they use with decoded linear textures, KHR_lights_punctual lights and perspective
/// cameras. Same file, same Scene (and hash). Errors name the offending mesh, light or image.
Result<Scene> loadScene(const std::string& path, const LoadOptions& options = {});

}  // namespace pic
