#pragma once
/// Loads glTF 2.0 files (.gltf and .glb) into the flat world-space Scene model.

#include <string>
#include <vector>

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
/// A buffer or image URI that leaves the scene's folder (absolute, "..", a URL) is refused
/// (InvalidInput) before any file it names is opened.
Result<Scene> loadScene(const std::string& path, const LoadOptions& options = {});

/// The files a glTF scene consists of, relative to the main file's folder: the main file's
/// name first, then every buffer and image URI that is not a data: URI, percent-decoded, each
/// once. What a copy of the scene elsewhere needs to load to the same Scene. InvalidInput for a
/// URI that leaves the folder (absolute, or with ".."), Corrupt for a file that is not glTF.
Result<std::vector<std::string>> sceneFiles(const std::string& path);

}  // namespace pic
