/// pic_gen_scenes: writes pic's procedural glTF test scenes and prints every file written.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "tests/scenes/scene_generator.h"

int main(int argc, char** argv) {
    using namespace pic::testscenes;
    const std::vector<std::string> known = testSceneNames();

    CLI::App app{"Writes pic's procedural glTF test scenes (NAME.gltf + NAME.bin)."};
    std::string outDir;
    SceneOptions options;
    std::vector<std::string> names;
    app.add_option("--out", outDir, "output folder, created if missing")->required();
    app.add_option("--atrium-triangles", options.atriumTriangles,
                   "triangle count the atrium aims at (met within 5 %)");
    app.add_option("names", names,
                   fmt::format("scenes to write (default: all of {})", fmt::join(known, ", ")));
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        return app.exit(error) == 0 ? 0 : 2;
    }

    // Check every name before writing anything.
    for (const std::string& name : names) {
        if (std::find(known.begin(), known.end(), name) == known.end()) {
            fmt::print(stderr, "pic_gen_scenes: unknown scene '{}' (known: {})\n", name,
                       fmt::join(known, ", "));
            return 2;
        }
    }
    if (names.empty()) names = known;

    for (const std::string& name : names) {
        const pic::Result<WrittenScene> written = generateTestScene(name, outDir, options);
        if (!written) {
            fmt::print(stderr, "pic_gen_scenes: {}: {}\n", name, written.error().message);
            return pic::exitCode(written.error());
        }
        for (const std::string& file : written->files) fmt::print("{}\n", file);
        fmt::print("{}: {} triangles\n", name, written->triangleCount);
    }
    return 0;
}
