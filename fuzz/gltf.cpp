// glTF 2.0 scenes (.gltf text or .glb): what a user loads into picbake, picref and picserver,
// and what a scene someone else made may hold.

#include <cmath>
#include <filesystem>

#include "core/gltf_loader.h"
#include "fuzz/fuzz.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace pic;
    const std::string& path = fuzz::scratchFile(fuzz::text(data, size), ".gltf");
    if (auto scene = loadScene(path)) {
        // What the bake and the runtime index without checking.
        for (const Triangle& t : scene->triangles)
            for (uint32_t v : t.v) PIC_CHECK(v < scene->vertices.size());
        for (const Vertex& v : scene->vertices)
            PIC_CHECK(std::isfinite(v.position.x) && std::isfinite(v.position.y) &&
                           std::isfinite(v.position.z));
    }
    // The files a server hands to thin clients: never outside the scene's folder.
    if (auto files = sceneFiles(path))
        for (const std::string& file : *files) {
            const std::filesystem::path relative(file);
            PIC_CHECK(!file.empty() && !relative.is_absolute());
            for (const auto& part : relative) PIC_CHECK(part != "..");
        }
    return 0;
}
